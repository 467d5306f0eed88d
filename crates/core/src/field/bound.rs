//! The bound toolkit: a function's range and Lipschitz constant over a region, and the
//! rules by which they compose. The field's node cache ([`super::NodeInfo`]), the
//! elevation tree (Génevaux et al. 2015 §7.3) and the geology (Paris et al. 2019 §4) all
//! bound their nodes with these rules, so each rule is written, and proved, once.
//!
//! Every rule is sound when its inputs are: if `f` and `g` take their values in
//! `f.range`, `g.range` and are `f.lipschitz`, `g.lipschitz`-Lipschitz over a region, the
//! result holds the combination's values and slopes over the same region. Warps are the
//! caller's half of the job: it bounds the child over the region the warp reads (the
//! region grown by the warp's reach), then [`Bound::warped`] multiplies the slope.

use std::ops::Add;

use super::bounds::Interval;

/// A range and a Lipschitz bound valid over some region.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bound {
    /// Every value lies in it.
    pub range: Interval,
    /// `|f(p) − f(q)| ≤ lipschitz · |p − q|` for `p`, `q` in the region (`+∞` across a jump).
    pub lipschitz: f32,
}

impl Bound {
    /// The zero function.
    pub const ZERO: Bound = Bound {
        range: Interval::ZERO,
        lipschitz: 0.0,
    };

    /// A range and a slope.
    pub fn new(range: Interval, lipschitz: f32) -> Bound {
        Bound { range, lipschitz }
    }

    /// The constant `v`.
    pub fn constant(v: f32) -> Bound {
        Bound::new(Interval::point(v), 0.0)
    }

    /// `k·f`.
    pub fn scale(self, k: f32) -> Bound {
        Bound::new(self.range.scale(k), self.lipschitz * k.abs())
    }

    /// `f + c`.
    pub fn shift(self, c: f32) -> Bound {
        Bound::new(self.range.shift(c), self.lipschitz)
    }

    /// `clamp(f, lo, hi)`: a clamp is 1-Lipschitz, so the slope stays.
    pub fn clamp(self, lo: f32, hi: f32) -> Bound {
        let r = self.range;
        Bound::new(
            Interval::new(r.lo.clamp(lo, hi), r.hi.clamp(lo, hi)),
            self.lipschitz,
        )
    }

    /// `f ∘ w` for a map `w` of Lipschitz constant `l`, `self` being `f`'s bound over the
    /// region `w` maps into.
    pub fn warped(self, l: f32) -> Bound {
        Bound::new(self.range, self.lipschitz * l)
    }

    /// The range widened to hold 0: a node whose support is bounded is 0 outside it.
    pub fn hull_zero(self) -> Bound {
        Bound::new(self.range.hull(Interval::ZERO), self.lipschitz)
    }

    /// `f·g`: the range's extreme products, and the product rule
    /// `L ≤ sup|f| L_g + sup|g| L_f`.
    pub fn product(self, o: Bound) -> Bound {
        let (a, b) = (self.range, o.range);
        let prods = [a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi];
        let lo = prods.iter().copied().fold(f32::INFINITY, f32::min);
        let hi = prods.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        Bound::new(
            Interval::new(lo, hi),
            magnitude(a) * o.lipschitz + magnitude(b) * self.lipschitz,
        )
    }

    /// `max(f, g)`: as steep as the steeper.
    pub fn max(self, o: Bound) -> Bound {
        Bound::new(self.range.max(o.range), self.lipschitz.max(o.lipschitz))
    }

    /// `min(f, g)`: as steep as the steeper.
    pub fn min(self, o: Bound) -> Bound {
        Bound::new(self.range.min(o.range), self.lipschitz.max(o.lipschitz))
    }

    /// `(1 − w)·f + w·g` for a weight `w ∈ [0, 1]` with range `w` and slope `l_w`:
    /// `∇ = (1 − w)∇f + w∇g + (g − f)∇w`, so `L ≤ max(L_f, L_g) + sup|g − f| · l_w`. Where
    /// the weight is 0 (or 1) all over, the result is `f` (or `g`).
    pub fn mix(self, by: Bound, w: Interval, l_w: f32) -> Bound {
        if w.hi <= 0.0 {
            self
        } else if w.lo >= 1.0 {
            by
        } else {
            let gap = gap(self.range, by.range);
            Bound::new(
                self.range.hull(by.range),
                mix_lipschitz(w, self.lipschitz, by.lipschitz, gap, l_w),
            )
        }
    }
}

impl Add for Bound {
    type Output = Bound;

    /// `f + g`.
    fn add(self, o: Bound) -> Bound {
        Bound::new(self.range + o.range, self.lipschitz + o.lipschitz)
    }
}

/// The slope rule of [`Bound::mix`] alone, for callers that know a tighter `gap ≥
/// sup|g − f|` than the ranges' [`gap`].
pub fn mix_lipschitz(w: Interval, l_f: f32, l_g: f32, gap: f32, l_w: f32) -> f32 {
    if w.hi <= 0.0 {
        l_f
    } else if w.lo >= 1.0 {
        l_g
    } else {
        l_f.max(l_g) + gap * l_w
    }
}

/// `sup |x|` over `r`.
pub fn magnitude(r: Interval) -> f32 {
    r.lo.abs().max(r.hi.abs())
}

/// `sup |b − a|` for `a ∈ from`, `b ∈ to`.
pub fn gap(from: Interval, to: Interval) -> f32 {
    (to.hi - from.lo).max(from.hi - to.lo).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples `f` and `g` of known bounds on a line and checks each rule's result holds
    /// the combination's values and difference quotients.
    #[test]
    fn the_rules_hold_sampled_functions() {
        let f = |x: f32| 2.0 * x.sin() + 0.5; // range [-1.5, 2.5], L 2
        let g = |x: f32| 0.5 * (3.0 * x).cos(); // range [-0.5, 0.5], L 1.5
        let w = |x: f32| (x * 0.25).sin() * 0.5 + 0.5; // [0, 1], L 0.125
        let (bf, bg) = (
            Bound::new(Interval::new(-1.5, 2.5), 2.0),
            Bound::new(Interval::new(-0.5, 0.5), 1.5),
        );
        type Rule = (&'static str, Bound, Box<dyn Fn(f32) -> f32>);
        let rules: [Rule; 7] = [
            ("sum", bf + bg, Box::new(move |x| f(x) + g(x))),
            ("product", bf.product(bg), Box::new(move |x| f(x) * g(x))),
            ("scale", bf.scale(-3.0), Box::new(move |x| -3.0 * f(x))),
            ("max", bf.max(bg), Box::new(move |x| f(x).max(g(x)))),
            ("min", bf.min(bg), Box::new(move |x| f(x).min(g(x)))),
            (
                "clamp",
                bf.clamp(0.0, 1.0),
                Box::new(move |x| f(x).clamp(0.0, 1.0)),
            ),
            (
                "mix",
                bf.mix(bg, Interval::new(0.0, 1.0), 0.125),
                Box::new(move |x| (1.0 - w(x)) * f(x) + w(x) * g(x)),
            ),
        ];
        for (name, b, h) in &rules {
            let mut prev = h(0.0);
            for i in 1..20_000 {
                let x = i as f32 * 0.003;
                let v = h(x);
                assert!(b.range.contains(v), "{name}: {v} outside {:?}", b.range);
                let slope = (v - prev).abs() / 0.003;
                assert!(
                    slope <= b.lipschitz * 1.01,
                    "{name}: slope {slope} > {}",
                    b.lipschitz
                );
                prev = v;
            }
        }
        // A slope bound a rule forgets fails: the product without the product rule's
        // second term.
        let naive = magnitude(bf.range) * bg.lipschitz;
        assert!((1..20_000).any(|i| {
            let (x0, x1) = ((i - 1) as f32 * 0.003, i as f32 * 0.003);
            ((f(x1) * g(x1)) - (f(x0) * g(x0))).abs() / 0.003 > naive
        }));
    }

    #[test]
    fn a_mix_with_a_settled_weight_is_one_side() {
        let (a, b) = (
            Bound::constant(1.0),
            Bound::new(Interval::new(3.0, 4.0), 2.0),
        );
        assert_eq!(a.mix(b, Interval::ZERO, 9.0), a);
        assert_eq!(a.mix(b, Interval::point(1.0), 9.0), b);
        assert_eq!(a.mix(b, Interval::new(0.0, 1.0), 1.0).lipschitz, 2.0 + 3.0);
    }
}

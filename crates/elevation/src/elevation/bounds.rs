//! Bounds of elevation-tree nodes over a rectangle (Génevaux et al. 2015 §7.3): ranges of
//! `f` and `α` and Lipschitz bounds `λ_f`, `λ_α` valid for pairs of points inside it.
//! Children whose weight is 0 over the rectangle drop out, so local bounds are far below
//! the global ones in a large blend.
//!
//! * **Blend**: with `∇f = (Σ α_i ∇f_i + Σ ∇α_i (f_i − f) + ∇w₀ (b − f)) / W`,
//!   `W = max(S, T) ≥ T`, `w₀ = W − S`, and `Σ α_i ≤ W`:
//!   `λ_f ≤ max_i λ_i + D Σ_i λ_{α_i} / T` with `D` the width of the hull of the children's
//!   ranges (and `b` where `S < T` can happen); `λ_α ≤ Σ λ_{α_i}`. The paper's Appendix
//!   bound `max λ_i + max λ_{α_i} sup|f_A − f_B|` drops the factor `1 / (α_A + α_B)` of
//!   `∇β`, which is unbounded where both weights vanish; the floor `T` is what bounds it.
//! * **Add**: `λ_f ≤ λ_A + β (max a_B · λ_B + sup|f_B| λ_{α_B})`.
//! * **Replace**: `λ_f ≤ max(λ_A, λ_B) + sup|f_B − f_A| λ_{α_B}`.
//! * **Warp**: the child's bounds over the rectangle grown by the warp's reach, times the
//!   warp's Lipschitz bound.

use super::lod::Lod;
use super::node::{BLEND_FLOOR, Kind, Node};
use crate::field::{Bound, Interval, Rect};

/// Bounds of a node over a rectangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Range and Lipschitz bound of `f`.
    pub f: Bound,
    /// Range and Lipschitz bound of `α`.
    pub a: Bound,
}

/// The rounding margin on the composed slopes.
const MARGIN: f32 = 1.000_1;

impl Node {
    /// Bounds over `r` at level of detail `lod`.
    pub fn bounds(&self, r: &Rect, lod: &Lod) -> Bounds {
        match &self.kind {
            Kind::Primitive(p) => {
                let (f, a) = p.ranges_over(r, lod);
                let on = a.hi > 0.0;
                Bounds {
                    f: Bound::new(f, p.lipschitz_f(lod)),
                    a: Bound::new(a, if on { p.lipschitz_a() } else { 0.0 }),
                }
            }
            Kind::Blend(b) => {
                // The weighted mean of the children: its own rule (module docs).
                let (mut f, mut lf, mut s) = (Interval::EMPTY, 0.0f32, Bound::ZERO);
                let mut visit = |c: &Node| {
                    if !c.support.overlaps(r) {
                        return;
                    }
                    let x = c.bounds(r, lod);
                    if x.a.range.hi <= 0.0 {
                        return;
                    }
                    f = f.hull(x.f.range);
                    lf = lf.max(x.f.lipschitz);
                    s = s + x.a;
                };
                match &b.index {
                    Some(ix) => ix
                        .over(r)
                        .into_iter()
                        .for_each(|i| visit(&b.children[i as usize])),
                    None => b.children.iter().for_each(&mut visit),
                }
                if s.range.lo < BLEND_FLOOR {
                    f = f.hull(Interval::point(b.base));
                }
                let lf = (lf + f.width() * s.lipschitz / BLEND_FLOOR) * MARGIN;
                Bounds {
                    f: Bound::new(f, lf),
                    a: s,
                }
            }
            Kind::Add { a, b, size } => {
                let x = a.bounds(r, lod);
                let beta = size.map_or(1.0, |s| lod.filter(s));
                if beta == 0.0 || !b.support.overlaps(r) {
                    return x;
                }
                let y = b.bounds(r, lod);
                if y.a.range.hi <= 0.0 {
                    return x;
                }
                // f_A + β min(α_B, 1) f_B.
                let w = y.a.clamp(f32::NEG_INFINITY, 1.0);
                let f = x.f + w.product(y.f).scale(beta);
                Bounds {
                    f: Bound::new(f.range, f.lipschitz * MARGIN),
                    ..x
                }
            }
            Kind::Replace { a, b } => {
                let x = a.bounds(r, lod);
                if !b.support.overlaps(r) {
                    return x;
                }
                let y = b.bounds(r, lod);
                if y.a.range.hi <= 0.0 {
                    return x;
                }
                // (1 − w) f_A + w f_B with w = min(α_B, 1).
                let w = y.a.clamp(f32::NEG_INFINITY, 1.0);
                let f = x.f.mix(y.f, w.range, w.lipschitz);
                Bounds {
                    f: Bound::new(f.range, f.lipschitz * MARGIN),
                    ..x
                }
            }
            Kind::Warp { child, warp } => {
                let x = child.bounds(&r.dilate(warp.reach()), lod);
                let l = warp.lipschitz();
                Bounds {
                    f: x.f.warped(l),
                    a: x.a.warped(l),
                }
            }
        }
    }
}

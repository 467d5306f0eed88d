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
use crate::field::{Interval, Rect};

/// Bounds of a node over a rectangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Range of `f`.
    pub f: Interval,
    /// Range of `α`.
    pub a: Interval,
    /// Lipschitz bound of `f`.
    pub lf: f32,
    /// Lipschitz bound of `α`.
    pub la: f32,
}

impl Node {
    /// Bounds over `r` at level of detail `lod`.
    pub fn bounds(&self, r: &Rect, lod: &Lod) -> Bounds {
        match &self.kind {
            Kind::Primitive(p) => {
                let (f, a) = p.ranges_over(r, lod);
                let on = a.hi > 0.0;
                Bounds {
                    f,
                    a,
                    lf: p.lipschitz_f(lod),
                    la: if on { p.lipschitz_a() } else { 0.0 },
                }
            }
            Kind::Blend(b) => {
                let (mut f, mut s, mut lf, mut la) =
                    (Interval::EMPTY, Interval::ZERO, 0.0f32, 0.0f32);
                let mut visit = |c: &Node| {
                    if !c.support.overlaps(r) {
                        return;
                    }
                    let x = c.bounds(r, lod);
                    if x.a.hi <= 0.0 {
                        return;
                    }
                    f = f.hull(x.f);
                    s = Interval::new(s.lo + x.a.lo, s.hi + x.a.hi);
                    lf = lf.max(x.lf);
                    la += x.la;
                };
                match &b.index {
                    Some(ix) => ix
                        .over(r)
                        .into_iter()
                        .for_each(|i| visit(&b.children[i as usize])),
                    None => b.children.iter().for_each(&mut visit),
                }
                if s.lo < BLEND_FLOOR {
                    f = f.hull(Interval::point(b.base));
                }
                Bounds {
                    f,
                    a: s,
                    lf: (lf + f.width() * la / BLEND_FLOOR) * 1.000_1,
                    la,
                }
            }
            Kind::Add { a, b, size } => {
                let x = a.bounds(r, lod);
                let beta = size.map_or(1.0, |s| lod.filter(s));
                if beta == 0.0 || !b.support.overlaps(r) {
                    return x;
                }
                let y = b.bounds(r, lod);
                if y.a.hi <= 0.0 {
                    return x;
                }
                let (w0, w1) = (y.a.lo.min(1.0), y.a.hi.min(1.0));
                let prods = [w0 * y.f.lo, w0 * y.f.hi, w1 * y.f.lo, w1 * y.f.hi];
                let lo = prods.iter().copied().fold(f32::INFINITY, f32::min) * beta;
                let hi = prods.iter().copied().fold(f32::NEG_INFINITY, f32::max) * beta;
                let fb = y.f.lo.abs().max(y.f.hi.abs());
                Bounds {
                    f: Interval::new(x.f.lo + lo, x.f.hi + hi),
                    lf: (x.lf + beta * (w1 * y.lf + fb * y.la)) * 1.000_1,
                    ..x
                }
            }
            Kind::Replace { a, b } => {
                let x = a.bounds(r, lod);
                if !b.support.overlaps(r) {
                    return x;
                }
                let y = b.bounds(r, lod);
                if y.a.hi <= 0.0 {
                    return x;
                }
                let f = if y.a.lo >= 1.0 { y.f } else { x.f.hull(y.f) };
                let d = (y.f.hi - x.f.lo).max(x.f.hi - y.f.lo).max(0.0);
                Bounds {
                    f,
                    lf: (x.lf.max(y.lf) + d * y.la) * 1.000_1,
                    ..x
                }
            }
            Kind::Warp { child, warp } => {
                let x = child.bounds(&r.dilate(warp.reach()), lod);
                let l = warp.lipschitz();
                Bounds {
                    lf: x.lf * l,
                    la: x.la * l,
                    ..x
                }
            }
        }
    }
}

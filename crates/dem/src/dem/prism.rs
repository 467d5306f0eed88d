//! The prism that closes an implicitized elevation into a solid (Paris et al. 2019 §5.1):
//! `P = (Ω ⊖ B(R)) × Δz` and `f_P(p) = 2T · g(d(p, P) / R)`, shared by the leaves that
//! implicitize an elevation — the raster [`super::HeightfieldField`] and the elevation
//! tree's `ElevationField`. The distance to `P` is written
//! `√(d_xy² + d_z²)`, with `d_xy = max(0, R − e(xy))` from the clearance `e` of Ω (see
//! `implicit.rs` for why this is exact on convex domains and a lower bound elsewhere).

use glam::{Vec2, Vec3};

use crate::field::falloff::{ISO, wyvill, wyvill_d};
use crate::field::{Interval, ZBands};

/// `√(1 − 2^(−1/3))`: `g(x) = ½` at this `x`, so `f_P = T` at distance `R·D_STAR` from `P`.
const D_STAR: f32 = 0.454_202;

/// The prism of falloff `r` over the vertical extent `dz`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prism {
    /// Falloff distance `R` (> 0).
    pub r: f32,
    /// The prism's vertical extent `Δz`.
    pub dz: Interval,
}

impl Prism {
    /// Vertical distance from `z` to `Δz` (0 inside).
    #[inline]
    pub fn dist_z(&self, z: f32) -> f32 {
        (self.dz.lo - z).max(z - self.dz.hi).max(0.0)
    }

    /// `f_P` from the horizontal distance `dxy` to the eroded domain and the height `z`.
    #[inline]
    pub fn value(&self, dxy: f32, z: f32) -> f32 {
        let dz = self.dist_z(z);
        let d2 = dxy * dxy + dz * dz;
        if d2 == 0.0 {
            2.0 * ISO
        } else {
            2.0 * ISO * wyvill(d2.sqrt() / self.r)
        }
    }

    /// `(f_P, ∇f_P)` from `dxy` and its horizontal gradient `g_dxy`.
    pub fn value_grad(&self, dxy: f32, g_dxy: Vec2, z: f32) -> (f32, Vec3) {
        let (dz, gdz) = if z < self.dz.lo {
            (self.dz.lo - z, -1.0)
        } else if z > self.dz.hi {
            (z - self.dz.hi, 1.0)
        } else {
            (0.0, 0.0)
        };
        let d = dxy.hypot(dz);
        if d == 0.0 {
            (2.0 * ISO, Vec3::ZERO)
        } else {
            let (g, dg) = wyvill_d(d / self.r);
            let gd = (dxy * g_dxy).extend(dz * gdz) / d;
            (2.0 * ISO * g, gd * (2.0 * ISO * dg / self.r))
        }
    }

    /// Range of the distance to `P` over a box, from the clearance range `e` of its
    /// footprint and its z range.
    pub fn dist_range(&self, e: Interval, z: Interval) -> Interval {
        let dxy = Interval::new((self.r - e.hi).max(0.0), (self.r - e.lo).max(0.0));
        let dz_lo = if z.overlaps(&self.dz) {
            0.0
        } else {
            self.dist_z(z.lo).min(self.dist_z(z.hi))
        };
        let dz_hi = self.dist_z(z.lo).max(self.dist_z(z.hi));
        Interval::new(dxy.lo.hypot(dz_lo), dxy.hi.hypot(dz_hi))
    }

    /// A float tolerance for bands around elevations of magnitude `m`.
    #[inline]
    pub fn eps(&self, m: f32) -> f32 {
        1e-5 * (m + self.r)
    }

    /// The z-bands of `min(σ(h − z), f_P)` over a footprint whose clearance range is `e`
    /// and elevation range `h`, searched inside `z`: the terrain `z = h` and the prism's
    /// walls and floor below it (none where `f_P < T` over the whole footprint).
    pub fn z_bands(&self, e: Interval, h: Interval, z: Interval, out: &mut ZBands) {
        let d_star = D_STAR * self.r * (1.0 + 1e-5);
        let dxy = Interval::new((self.r - e.hi).max(0.0), (self.r - e.lo).max(0.0));
        if e.hi <= 0.0 || dxy.lo > d_star || h.is_empty() {
            return;
        }
        let eps = self.eps(h.lo.abs().max(h.hi.abs()));
        // the terrain itself, z = h
        out.push(Interval::new(h.lo - eps, h.hi + eps).intersect(z));
        // the prism's walls and floor, f_P = T below the terrain
        let lower = self.dz.lo - (d_star * d_star - dxy.lo * dxy.lo).max(0.0).sqrt();
        let upper = if dxy.hi >= d_star {
            h.hi.min(self.dz.hi)
        } else {
            self.dz.lo - (d_star * d_star - dxy.hi * dxy.hi).max(0.0).sqrt()
        };
        let eps = self.eps(lower.abs().max(upper.abs()));
        out.push(Interval::new(lower - eps, upper + eps).intersect(z));
    }
}

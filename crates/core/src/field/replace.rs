//! The replace operator's partition of unity: a feature that stands in for the terrain
//! inside a box, with a smooth transition back to the terrain near the box's faces.
//!
//! ```text
//!   f(p) = f_base(p) + w(p)·(f_by(p) − f_base(p)) = (1 − w)·f_base + w·f_by
//!   w(p) = 1 − g(d(p) / W)        d(p): distance from p to the region's nearest face
//!                                 inside the region, 0 outside; g Wyvill's falloff
//! ```
//!
//! `w` is 0 outside the region and on its faces, rises smoothly over the transition
//! width `W` and is 1 in the core (the region shrunk by `W`): outside the region the
//! node *is* its base, in the core it *is* its replacement. Where the replacement
//! reproduces the base near the faces (a terrain-aware Feature Volume) the transition is
//! invisible. `w` is `WYVILL_MAX_SLOPE / W`-Lipschitz (`d` is 1-Lipschitz), so
//! `|∇f| ≤ max(L_base, L_by) + |f_by − f_base|·WYVILL_MAX_SLOPE / W`.

use glam::Vec3;

use super::bounds::{Aabb, Interval};
use super::falloff::{WYVILL_MAX_SLOPE, wyvill, wyvill_d};

/// Where a replacement holds: a region and the width of the transition inside its faces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transition {
    region: Aabb,
    width: f32,
}

impl Transition {
    /// The weight of `region` with a transition `width` metres wide inside its faces
    /// (clamped to half the region's smallest side, so the core is never inverted).
    pub fn new(region: Aabb, width: f32) -> Self {
        let width = width.min(0.5 * region.size().min_element()).max(1e-6);
        Transition { region, width }
    }

    /// The region: `w = 0` outside.
    pub fn region(&self) -> &Aabb {
        &self.region
    }

    /// The transition width.
    pub fn width(&self) -> f32 {
        self.width
    }

    /// The core, where `w = 1`.
    pub fn core(&self) -> Aabb {
        self.region.dilate(-self.width)
    }

    /// `max |∇w|`.
    pub fn lipschitz(&self) -> f32 {
        WYVILL_MAX_SLOPE / self.width
    }

    /// Per axis, the signed distance to the nearer of the region's two faces (positive
    /// inside).
    #[inline]
    fn face_distances(&self, p: Vec3) -> Vec3 {
        (p - self.region.min).min(self.region.max - p)
    }

    /// `d(p)`: the distance to the region's nearest face, positive inside, negative
    /// outside (where it is a lower bound of minus the distance to the box). It is
    /// 1-Lipschitz: over a ball `B(c, r)` it lies in `d(c) ± r`.
    #[inline]
    pub fn depth(&self, p: Vec3) -> f32 {
        self.face_distances(p).min_element()
    }

    /// The weight at depth `d`: 0 outside, `1 − g(d / W)` across the transition, 1 in
    /// the core; non-decreasing.
    #[inline]
    pub fn ramp(&self, d: f32) -> f32 {
        if d <= 0.0 {
            0.0
        } else {
            1.0 - wyvill(d / self.width)
        }
    }

    /// `w(p)`.
    #[inline]
    pub fn weight(&self, p: Vec3) -> f32 {
        self.ramp(self.depth(p))
    }

    /// `(w(p), ∇w(p))`; the gradient of the nearest face's distance at the creases.
    pub fn weight_grad(&self, p: Vec3) -> (f32, Vec3) {
        let dist = self.face_distances(p);
        let d = dist.min_element();
        if d <= 0.0 || d >= self.width {
            return ((d > 0.0) as u8 as f32, Vec3::ZERO);
        }
        let axis = (0..3).fold(0, |a, i| if dist[i] < dist[a] { i } else { a });
        // ∂d/∂p_axis is +1 near the min face, −1 near the max face.
        let toward_min = p[axis] - self.region.min[axis] <= self.region.max[axis] - p[axis];
        let mut g = Vec3::ZERO;
        g[axis] = if toward_min { 1.0 } else { -1.0 };
        let (v, dv) = wyvill_d(d / self.width);
        (1.0 - v, g * (-dv / self.width))
    }

    /// The range of `w` over `b`.
    pub fn interval(&self, b: &Aabb) -> Interval {
        // Per axis, the face distance is a tent over the box's span: its minimum at one
        // end, its maximum at the region's middle when the span holds it.
        let (mut lo, mut hi) = (f32::INFINITY, f32::INFINITY);
        for a in 0..3 {
            let (r0, r1) = (self.region.min[a], self.region.max[a]);
            let tent = |x: f32| (x - r0).min(r1 - x);
            let (b0, b1) = (b.min[a], b.max[a]);
            lo = lo.min(tent(b0).min(tent(b1)));
            let mid = 0.5 * (r0 + r1);
            hi = hi.min(tent(mid.clamp(b0, b1)));
        }
        Interval::new(self.ramp(lo), self.ramp(hi))
    }

    /// The range of `(1 − w)·a + w·b` for `a ∈ base`, `b ∈ by` and `w ∈ w`.
    pub fn mix_interval(w: Interval, base: Interval, by: Interval) -> Interval {
        // Linear in w for fixed values: the extremes are at w's ends.
        let at = |w: f32| {
            Interval::new(
                base.lo + w * (by.lo - base.lo),
                base.hi + w * (by.hi - base.hi),
            )
        };
        at(w.lo).hull(at(w.hi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t() -> Transition {
        Transition::new(
            Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(100.0, 60.0, 40.0)),
            10.0,
        )
    }

    #[test]
    fn weight_is_a_smooth_partition_of_the_box() {
        let t = t();
        assert_eq!(t.weight(Vec3::new(-1.0, 30.0, 20.0)), 0.0);
        assert_eq!(t.weight(Vec3::new(0.0, 30.0, 20.0)), 0.0);
        assert_eq!(t.weight(Vec3::new(50.0, 30.0, 20.0)), 1.0);
        assert_eq!(t.weight(Vec3::new(10.0, 30.0, 20.0)), 1.0);
        let w = t.weight(Vec3::new(5.0, 30.0, 20.0));
        assert!(w > 0.0 && w < 1.0, "{w}");
        // Gradients against differences, away from the creases.
        for p in [
            Vec3::new(3.0, 30.0, 20.0),
            Vec3::new(97.0, 30.0, 20.0),
            Vec3::new(50.0, 55.0, 20.0),
            Vec3::new(50.0, 30.0, 4.0),
        ] {
            let (v, g) = t.weight_grad(p);
            assert_eq!(v, t.weight(p));
            let e = 1e-2;
            let fd = Vec3::new(
                t.weight(p + Vec3::X * e) - t.weight(p - Vec3::X * e),
                t.weight(p + Vec3::Y * e) - t.weight(p - Vec3::Y * e),
                t.weight(p + Vec3::Z * e) - t.weight(p - Vec3::Z * e),
            ) / (2.0 * e);
            assert!((g - fd).length() < 1e-3, "{p}: {g} vs {fd}");
            assert!(g.length() <= t.lipschitz());
        }
    }

    #[test]
    fn weight_interval_contains_samples() {
        let t = t();
        let boxes = [
            Aabb::new(Vec3::new(-5.0, 10.0, 5.0), Vec3::new(4.0, 20.0, 9.0)),
            Aabb::new(Vec3::new(20.0, 20.0, 15.0), Vec3::new(80.0, 40.0, 25.0)),
            Aabb::new(
                Vec3::new(-50.0, -50.0, -50.0),
                Vec3::new(150.0, 150.0, 150.0),
            ),
            Aabb::new(Vec3::new(95.0, 55.0, 35.0), Vec3::new(99.0, 59.0, 39.0)),
        ];
        for b in boxes {
            let iv = t.interval(&b);
            for i in 0..=10 {
                for j in 0..=10 {
                    for k in 0..=10 {
                        let f = Vec3::new(i as f32, j as f32, k as f32) / 10.0;
                        let p = b.min + (b.max - b.min) * f;
                        let w = t.weight(p);
                        assert!(iv.lo <= w && w <= iv.hi, "{b:?}: {w} not in {iv:?}");
                    }
                }
            }
        }
        assert_eq!(t.interval(&boxes[1]), Interval::new(1.0, 1.0));
    }
}

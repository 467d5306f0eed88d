//! The plane skeleton: a finite square patch, so the primitive's support is compact.

use glam::{Mat3, Vec3};

use super::{Project, outer};
use crate::field::bounds::Aabb;

/// The filled square `{point + a·u + b·v : |a|, |b| ≤ half}` of the plane through `point`
/// with unit `normal`. The in-plane axes `(u, v)` are `normal.any_orthonormal_pair()`;
/// for a normal along ±z they are ±x and ±y, so a horizontal patch is axis-aligned.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanePatch {
    point: Vec3,
    u: Vec3,
    v: Vec3,
    half: f32,
}

impl PlanePatch {
    /// The patch; `normal` must be a unit vector, `half > 0`.
    pub fn new(point: Vec3, normal: Vec3, half: f32) -> Self {
        let (u, v) = normal.any_orthonormal_pair();
        PlanePatch { point, u, v, half }
    }

    /// In-plane coordinates of `p` (unclamped).
    #[inline]
    fn coords(&self, p: Vec3) -> (f32, f32) {
        let w = p - self.point;
        (w.dot(self.u), w.dot(self.v))
    }
}

impl Project for PlanePatch {
    #[inline]
    fn closest(&self, p: Vec3) -> Vec3 {
        let (a, b) = self.coords(p);
        let h = self.half;
        self.point + self.u * a.clamp(-h, h) + self.v * b.clamp(-h, h)
    }

    fn closest_jacobian(&self, p: Vec3) -> (Vec3, Mat3) {
        let (a, b) = self.coords(p);
        let h = self.half;
        let mut jac = Mat3::ZERO;
        if a.abs() < h {
            jac += outer(self.u, self.u);
        }
        if b.abs() < h {
            jac += outer(self.v, self.v);
        }
        (
            self.point + self.u * a.clamp(-h, h) + self.v * b.clamp(-h, h),
            jac,
        )
    }

    fn bounds(&self) -> Aabb {
        let (u, v) = (self.u * self.half, self.v * self.half);
        Aabb::from_points([
            self.point + u + v,
            self.point + u - v,
            self.point - u + v,
            self.point - u - v,
        ])
    }
}

//! The segment skeleton `[a, b]`.

use glam::{Mat3, Vec3};

use super::{Project, outer};
use crate::field::bounds::Aabb;

/// The segment from `a` to `b`; when `a = b` it is the point `a`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    a: Vec3,
    ab: Vec3,
    /// `1 / ‖b − a‖²`, 0 for a degenerate segment.
    inv_len2: f32,
}

impl Segment {
    /// The segment `[a, b]`.
    pub fn new(a: Vec3, b: Vec3) -> Self {
        let ab = b - a;
        let l2 = ab.length_squared();
        Segment {
            a,
            ab,
            inv_len2: if l2 > 0.0 { 1.0 / l2 } else { 0.0 },
        }
    }

    /// First end.
    pub fn a(&self) -> Vec3 {
        self.a
    }

    /// Second end.
    pub fn b(&self) -> Vec3 {
        self.a + self.ab
    }

    /// The unclamped parameter of the projection of `p` on the line.
    #[inline]
    fn param(&self, p: Vec3) -> f32 {
        (p - self.a).dot(self.ab) * self.inv_len2
    }

    /// Squared distance from `p`.
    #[inline]
    pub fn distance_squared(&self, p: Vec3) -> f32 {
        (p - self.closest(p)).length_squared()
    }
}

impl Project for Segment {
    #[inline]
    fn closest(&self, p: Vec3) -> Vec3 {
        self.a + self.ab * self.param(p).clamp(0.0, 1.0)
    }

    fn closest_jacobian(&self, p: Vec3) -> (Vec3, Mat3) {
        let t = self.param(p);
        let jac = if t > 0.0 && t < 1.0 {
            outer(self.ab, self.ab * self.inv_len2)
        } else {
            Mat3::ZERO
        };
        (self.a + self.ab * t.clamp(0.0, 1.0), jac)
    }

    fn bounds(&self) -> Aabb {
        Aabb::new(self.a, self.b())
    }
}

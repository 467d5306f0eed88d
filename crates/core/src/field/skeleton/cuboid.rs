//! The box skeleton: a solid box turned by a yaw angle about the vertical axis.

use glam::{Mat3, Vec3};

use super::{Project, outer};
use crate::field::bounds::Aabb;

/// The solid box of half-extents `half` centred on `center`, turned by `yaw` radians
/// about +z (counter-clockwise seen from above).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cuboid {
    center: Vec3,
    half: Vec3,
    /// Local axes in world coordinates: `(cos, sin, 0)`, `(−sin, cos, 0)`, `z`.
    axes: Mat3,
}

impl Cuboid {
    /// The box; `half` must be positive.
    pub fn new(center: Vec3, half: Vec3, yaw: f32) -> Self {
        let (s, c) = yaw.sin_cos();
        Cuboid {
            center,
            half,
            axes: Mat3::from_cols(Vec3::new(c, s, 0.0), Vec3::new(-s, c, 0.0), Vec3::Z),
        }
    }

    /// `p` in the box frame.
    #[inline]
    fn local(&self, p: Vec3) -> Vec3 {
        self.axes.transpose_mul_vec3(p - self.center)
    }
}

impl Project for Cuboid {
    #[inline]
    fn closest(&self, p: Vec3) -> Vec3 {
        self.center + self.axes * self.local(p).clamp(-self.half, self.half)
    }

    /// `Σ_{axes i not clamped} aᵢaᵢᵀ`.
    fn closest_jacobian(&self, p: Vec3) -> (Vec3, Mat3) {
        let l = self.local(p);
        let mut jac = Mat3::ZERO;
        for i in 0..3 {
            if l[i].abs() < self.half[i] {
                jac += outer(self.axes.col(i), self.axes.col(i));
            }
        }
        (
            self.center + self.axes * l.clamp(-self.half, self.half),
            jac,
        )
    }

    #[inline]
    fn distance(&self, p: Vec3) -> f32 {
        (self.local(p).abs() - self.half).max(Vec3::ZERO).length()
    }

    fn bounds(&self) -> Aabb {
        let ext = self.axes.abs() * self.half;
        Aabb::new(self.center - ext, self.center + ext)
    }
}

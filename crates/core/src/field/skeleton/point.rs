//! The point skeleton: `d(p) = ‖p − c‖`.

use glam::{Mat3, Vec3};

use super::Project;
use crate::field::bounds::Aabb;

/// A single point `center`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// The point.
    pub center: Vec3,
}

impl Project for Point {
    #[inline]
    fn closest(&self, _p: Vec3) -> Vec3 {
        self.center
    }

    #[inline]
    fn closest_jacobian(&self, _p: Vec3) -> (Vec3, Mat3) {
        (self.center, Mat3::ZERO)
    }

    #[inline]
    fn distance(&self, p: Vec3) -> f32 {
        (p - self.center).length()
    }

    fn bounds(&self) -> Aabb {
        Aabb::new(self.center, self.center)
    }
}

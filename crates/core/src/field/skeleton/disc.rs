//! The filled disc skeleton.

use glam::{Mat3, Vec3};

use super::{Project, outer};
use crate::field::bounds::Aabb;

/// The filled disc of `radius` centred on `center`, perpendicular to the unit `normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disc {
    center: Vec3,
    normal: Vec3,
    radius: f32,
}

impl Disc {
    /// The disc; `normal` must be a unit vector, `radius > 0`.
    pub fn new(center: Vec3, normal: Vec3, radius: f32) -> Self {
        Disc {
            center,
            normal,
            radius,
        }
    }

    /// In-plane offset of `p` from the centre.
    #[inline]
    fn in_plane(&self, p: Vec3) -> Vec3 {
        let w = p - self.center;
        w - self.normal * w.dot(self.normal)
    }
}

impl Project for Disc {
    #[inline]
    fn closest(&self, p: Vec3) -> Vec3 {
        let q = self.in_plane(p);
        let l2 = q.length_squared();
        if l2 <= self.radius * self.radius {
            self.center + q
        } else {
            self.center + q * (self.radius / l2.sqrt())
        }
    }

    /// `I − nnᵀ` over the disc, `(r/|q|)(I − nnᵀ − q̂q̂ᵀ)` beyond its rim.
    fn closest_jacobian(&self, p: Vec3) -> (Vec3, Mat3) {
        let q = self.in_plane(p);
        let l = q.length();
        let plane = Mat3::IDENTITY - outer(self.normal, self.normal);
        if l <= self.radius {
            (self.center + q, plane)
        } else {
            let u = q / l;
            let k = self.radius / l;
            (self.center + u * self.radius, (plane - outer(u, u)) * k)
        }
    }

    fn bounds(&self) -> Aabb {
        let n = self.normal;
        let ext = (Vec3::ONE - n * n).max(Vec3::ZERO).powf(0.5) * self.radius;
        Aabb::new(self.center - ext, self.center + ext)
    }
}

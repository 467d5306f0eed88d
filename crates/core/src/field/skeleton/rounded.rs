//! Solids made by rounding a convex skeleton: the sphere (a rounded point) and the
//! capsule (a rounded segment).

use glam::{Mat3, Vec3};

use super::{Point, Project, Segment, outer};
use crate::field::bounds::Aabb;

/// The set of points within `radius` of `inner`: distance `max(0, d_inner − radius)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rounded<C> {
    inner: C,
    radius: f32,
}

/// A solid ball: a rounded [`Point`].
pub type Sphere = Rounded<Point>;
/// A solid capsule: a rounded [`Segment`].
pub type Capsule = Rounded<Segment>;

impl<C: Project> Rounded<C> {
    /// `inner` grown by `radius > 0`.
    pub fn new(inner: C, radius: f32) -> Self {
        Rounded { inner, radius }
    }

    /// The rounded skeleton.
    pub fn inner(&self) -> &C {
        &self.inner
    }

    /// The rounding radius.
    pub fn radius(&self) -> f32 {
        self.radius
    }
}

impl<C: Project> Project for Rounded<C> {
    #[inline]
    fn closest(&self, p: Vec3) -> Vec3 {
        let s = self.inner.closest(p);
        let w = p - s;
        let rho = w.length();
        if rho <= self.radius {
            p
        } else {
            s + w * (self.radius / rho)
        }
    }

    /// `J = J_in + (r/ρ)(I − ûûᵀ)(I − J_in)` outside, `I` inside.
    fn closest_jacobian(&self, p: Vec3) -> (Vec3, Mat3) {
        let (s, j) = self.inner.closest_jacobian(p);
        let w = p - s;
        let rho = w.length();
        if rho <= self.radius {
            return (p, Mat3::IDENTITY);
        }
        let u = w / rho;
        let k = self.radius / rho;
        let proj = Mat3::IDENTITY - outer(u, u);
        (s + u * self.radius, j + proj * (Mat3::IDENTITY - j) * k)
    }

    #[inline]
    fn distance(&self, p: Vec3) -> f32 {
        (self.inner.distance(p) - self.radius).max(0.0)
    }

    #[inline]
    fn distance_grad(&self, p: Vec3) -> (f32, Vec3) {
        let (d, g) = self.inner.distance_grad(p);
        if d > self.radius {
            (d - self.radius, g)
        } else {
            (0.0, Vec3::Z)
        }
    }

    fn bounds(&self) -> Aabb {
        self.inner.bounds().dilate(self.radius)
    }
}

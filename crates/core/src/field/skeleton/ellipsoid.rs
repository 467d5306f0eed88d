//! The ellipsoid skeleton, with its exact Euclidean distance.
//!
//! For `y = p − c` outside the ellipsoid `Σ (xᵢ/eᵢ)² ≤ 1`, the closest point is
//! `xᵢ = eᵢ² yᵢ / (t + eᵢ²)` where `t > 0` is the root of
//! `F(t) = Σ (eᵢ yᵢ / (t + eᵢ²))² − 1` (Eberly, "Distance from a point to an ellipse, an
//! ellipsoid, or a hyperellipsoid"). `F` is decreasing and convex on `t ≥ 0`, and since
//! `t + eᵢ² ≤ t + e_max²`, `F(t) ≥ ‖e∘y‖²/(t + e_max²)² − 1`, so `t* ≥ ‖e∘y‖ − e_max²`:
//! Newton's method started at that bound climbs to the root monotonically, without
//! overshoot. Solved in f64.

use glam::{DVec3, Mat3, Vec3};

use super::{Project, outer};
use crate::field::bounds::Aabb;

/// The solid axis-aligned ellipsoid with semi-axes `radii` centred on `center`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ellipsoid {
    center: Vec3,
    radii: Vec3,
}

/// Newton iterations at most (convergence is quadratic near the root; from far away each
/// step at least multiplies `t + e²` by 1.5).
const MAX_NEWTON: usize = 64;

impl Ellipsoid {
    /// The ellipsoid; `radii` must be positive.
    pub fn new(center: Vec3, radii: Vec3) -> Self {
        Ellipsoid { center, radii }
    }

    /// Centre.
    pub fn center(&self) -> Vec3 {
        self.center
    }

    /// Semi-axes along x, y and z.
    pub fn radii(&self) -> Vec3 {
        self.radii
    }

    /// The root `t` of `F` for the local point `y`, or `None` when `y` is inside.
    fn root(&self, y: DVec3) -> Option<f64> {
        let e = self.radii.as_dvec3();
        if (y / e).length_squared() <= 1.0 {
            return None;
        }
        let e2 = e * e;
        let ey = e * y;
        let mut t = (ey.length() - e2.max_element()).max(0.0);
        for _ in 0..MAX_NEWTON {
            let inv = (DVec3::splat(t) + e2).recip();
            let q = ey * inv;
            let f = q.length_squared() - 1.0;
            if f <= 1e-12 {
                break;
            }
            let df = -2.0 * (q * q * inv).element_sum();
            let step = -f / df;
            t += step;
            if step <= 1e-10 * (t + e2.max_element()) {
                break;
            }
        }
        Some(t)
    }
}

impl Project for Ellipsoid {
    fn closest(&self, p: Vec3) -> Vec3 {
        let y = (p - self.center).as_dvec3();
        match self.root(y) {
            None => p,
            Some(t) => {
                let e2 = (self.radii * self.radii).as_dvec3();
                self.center + (e2 * y / (DVec3::splat(t) + e2)).as_vec3()
            }
        }
    }

    /// Implicit differentiation of `F(t, y) = 0`: `J = diag(D) − w wᵀ / k` with
    /// `Dᵢ = eᵢ²/(t + eᵢ²)`, `wᵢ = eᵢ² yᵢ/(t + eᵢ²)²`, `k = Σ eᵢ² yᵢ²/(t + eᵢ²)³`.
    fn closest_jacobian(&self, p: Vec3) -> (Vec3, Mat3) {
        let y = (p - self.center).as_dvec3();
        let Some(t) = self.root(y) else {
            return (p, Mat3::IDENTITY);
        };
        let e2 = (self.radii * self.radii).as_dvec3();
        let den = DVec3::splat(t) + e2;
        let d = e2 / den;
        let w = e2 * y / (den * den);
        let k = (w * y / den).element_sum();
        let mut jac = Mat3::from_diagonal(d.as_vec3());
        if k > 0.0 {
            jac -= outer(w.as_vec3(), (w / k).as_vec3());
        }
        (self.center + (d * y).as_vec3(), jac)
    }

    fn bounds(&self) -> Aabb {
        Aabb::new(self.center - self.radii, self.center + self.radii)
    }
}

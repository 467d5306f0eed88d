//! The capped cone skeleton: the solid of revolution of a right triangle.
//!
//! In the half-plane through the axis, `(ρ, z)` = (distance to the axis, height above
//! the base), the cone is the triangle `(0, 0), (r, 0), (0, h)`. The closest point of a
//! solid of revolution lies in the same half-plane, so the 3D distance is the 2D distance
//! to the triangle, whose closest point is on the base edge or on the slant edge.

use glam::{Mat3, Vec2, Vec3};

use super::{Project, outer};
use crate::field::bounds::Aabb;

/// The solid cone with a disc base of `radius` centred on `base` and its apex at `apex`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    base: Vec3,
    /// Unit axis from base to apex.
    axis: Vec3,
    height: f32,
    radius: f32,
}

/// The 2D projection onto the triangle: closest `(ρ, z)`, the 2×2 Jacobian as
/// `(J_ρρ, J_ρz, J_zz)`, and whether the point was inside.
struct Proj2 {
    at: Vec2,
    jac: [f32; 3],
    inside: bool,
}

impl Cone {
    /// The cone; `None` when `apex` lies on `base` (no axis).
    pub fn new(base: Vec3, apex: Vec3, radius: f32) -> Option<Self> {
        let a = apex - base;
        let height = a.length();
        (height > 1e-6 * radius.max(1.0)).then(|| Cone {
            base,
            axis: a / height,
            height,
            radius,
        })
    }

    /// Centre of the base disc.
    pub fn base(&self) -> Vec3 {
        self.base
    }

    /// Unit axis from the base towards the apex.
    pub fn axis(&self) -> Vec3 {
        self.axis
    }

    /// Distance from the base to the apex.
    pub fn height(&self) -> f32 {
        self.height
    }

    /// Radius of the base disc.
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// `(ρ, z, e_r)`: the half-plane coordinates of `p` and the unit radial direction
    /// (any perpendicular of the axis on the axis itself).
    #[inline]
    fn frame(&self, p: Vec3) -> (f32, f32, Vec3) {
        let w = p - self.base;
        let z = w.dot(self.axis);
        let q = w - self.axis * z;
        let rho = q.length();
        let er = if rho > 0.0 {
            q / rho
        } else {
            self.axis.any_orthonormal_vector()
        };
        (rho, z, er)
    }

    fn project2(&self, x: Vec2) -> Proj2 {
        let (r, h) = (self.radius, self.height);
        if x.y >= 0.0 && x.x * h + x.y * r <= r * h {
            return Proj2 {
                at: x,
                jac: [1.0, 0.0, 1.0],
                inside: true,
            };
        }
        // Base edge (0, 0)–(r, 0).
        let base_at = Vec2::new(x.x.clamp(0.0, r), 0.0);
        // Slant edge (r, 0)–(0, h).
        let a = Vec2::new(r, 0.0);
        let d = Vec2::new(-r, h);
        let tau = (x - a).dot(d) / d.length_squared();
        let slant_at = a + d * tau.clamp(0.0, 1.0);
        if (x - base_at).length_squared() <= (x - slant_at).length_squared() {
            let j = if x.x < r { 1.0 } else { 0.0 };
            Proj2 {
                at: base_at,
                jac: [j, 0.0, 0.0],
                inside: false,
            }
        } else if tau > 0.0 && tau < 1.0 {
            let t = d / d.length();
            Proj2 {
                at: slant_at,
                jac: [t.x * t.x, t.x * t.y, t.y * t.y],
                inside: false,
            }
        } else {
            Proj2 {
                at: slant_at,
                jac: [0.0; 3],
                inside: false,
            }
        }
    }
}

impl Project for Cone {
    fn closest(&self, p: Vec3) -> Vec3 {
        let (rho, z, er) = self.frame(p);
        let pr = self.project2(Vec2::new(rho, z));
        if pr.inside {
            p
        } else {
            self.base + self.axis * pr.at.y + er * pr.at.x
        }
    }

    /// `J = [e_r a] J₂ [e_r a]ᵀ + (ρ_s/ρ) e_θe_θᵀ` with `e_θe_θᵀ = I − aaᵀ − e_r e_rᵀ`.
    fn closest_jacobian(&self, p: Vec3) -> (Vec3, Mat3) {
        let (rho, z, er) = self.frame(p);
        let pr = self.project2(Vec2::new(rho, z));
        if pr.inside {
            return (p, Mat3::IDENTITY);
        }
        let a = self.axis;
        let [jrr, jrz, jzz] = pr.jac;
        let ratio = if rho > 0.0 { pr.at.x / rho } else { 0.0 };
        let theta = Mat3::IDENTITY - outer(a, a) - outer(er, er);
        let jac = outer(er, er) * jrr
            + (outer(er, a) + outer(a, er)) * jrz
            + outer(a, a) * jzz
            + theta * ratio;
        (self.base + a * pr.at.y + er * pr.at.x, jac)
    }

    fn bounds(&self) -> Aabb {
        let n = self.axis;
        let ext = (Vec3::ONE - n * n).max(Vec3::ZERO).powf(0.5) * self.radius;
        Aabb::new(self.base - ext, self.base + ext).include(self.base + self.axis * self.height)
    }
}

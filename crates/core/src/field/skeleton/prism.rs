//! The vertical prism skeleton: a simple polygon of the XY plane times a z range. Its
//! distance is `√(d_poly² + d_z²)` (distance to a Cartesian product). For the anisotropic
//! noise it is the union of the triangular prisms of an ear-clipping triangulation.

use glam::{Mat3, Vec2, Vec3};

use super::Project;
use super::polygon::{closest_on_boundary, contains, triangulate};
use crate::field::bounds::Aabb;

/// The solid `{(x, y, z) : (x, y) ∈ polygon, lo ≤ z ≤ hi}`.
#[derive(Clone, Debug, PartialEq)]
pub struct Prism {
    /// Counter-clockwise vertices of a simple polygon.
    polygon: Vec<Vec2>,
    lo: f32,
    hi: f32,
    pieces: Vec<TriPrism>,
    bounds: Aabb,
}

impl Prism {
    /// The prism over a validated polygon (see [`super::validate_polygon`]), `lo < hi`.
    pub fn new(polygon: Vec<Vec2>, lo: f32, hi: f32) -> Self {
        let pieces = triangulate(&polygon)
            .into_iter()
            .map(|t| TriPrism::new(t, lo, hi))
            .collect();
        let bounds = Aabb::from_points(polygon.iter().flat_map(|v| [v.extend(lo), v.extend(hi)]));
        Prism {
            polygon,
            lo,
            hi,
            pieces,
            bounds,
        }
    }

    /// The polygon, counter-clockwise.
    pub fn polygon(&self) -> &[Vec2] {
        &self.polygon
    }

    /// The closest point of the solid.
    pub fn closest(&self, p: Vec3) -> Vec3 {
        let xy = p.truncate();
        let c = if contains(&self.polygon, xy) {
            xy
        } else {
            closest_on_boundary(&self.polygon, xy)
        };
        c.extend(p.z.clamp(self.lo, self.hi))
    }

    /// Euclidean distance, 0 inside.
    pub fn distance(&self, p: Vec3) -> f32 {
        (p - self.closest(p)).length()
    }

    /// A box holding the prism.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// See [`super::Skeleton::visit_pieces`]: the pieces are triangular prisms.
    pub fn visit_pieces(
        &self,
        p: Vec3,
        mut reach: f32,
        f: &mut dyn FnMut(&dyn Project, f32) -> f32,
    ) {
        for t in &self.pieces {
            if t.bounds.distance(p) >= reach {
                continue;
            }
            let rho = t.distance(p);
            if rho < reach {
                reach = f(t, rho);
            }
        }
    }
}

/// A triangle of the XY plane times `[lo, hi]`: a convex piece of a [`Prism`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriPrism {
    tri: [Vec2; 3],
    lo: f32,
    hi: f32,
    bounds: Aabb,
}

impl TriPrism {
    /// The piece over the counter-clockwise triangle `tri`.
    pub fn new(tri: [Vec2; 3], lo: f32, hi: f32) -> Self {
        let bounds = Aabb::from_points(tri.iter().flat_map(|v| [v.extend(lo), v.extend(hi)]));
        TriPrism {
            tri,
            lo,
            hi,
            bounds,
        }
    }

    /// Closest point of the triangle to `p` and its 2×2 Jacobian as `(J_xx, J_xy, J_yy)`
    /// (Ericson, Real-Time Collision Detection §5.1.5, by Voronoi regions).
    fn project2(&self, p: Vec2) -> (Vec2, [f32; 3]) {
        let [a, b, c] = self.tri;
        let edge = |o: Vec2, d: Vec2, t: f32| {
            let u = d.normalize();
            (o + d * t, [u.x * u.x, u.x * u.y, u.y * u.y])
        };
        let (ab, ac, ap) = (b - a, c - a, p - a);
        let (d1, d2) = (ab.dot(ap), ac.dot(ap));
        if d1 <= 0.0 && d2 <= 0.0 {
            return (a, [0.0; 3]);
        }
        let bp = p - b;
        let (d3, d4) = (ab.dot(bp), ac.dot(bp));
        if d3 >= 0.0 && d4 <= d3 {
            return (b, [0.0; 3]);
        }
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            return edge(a, ab, d1 / (d1 - d3));
        }
        let cp = p - c;
        let (d5, d6) = (ab.dot(cp), ac.dot(cp));
        if d6 >= 0.0 && d5 <= d6 {
            return (c, [0.0; 3]);
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            return edge(a, ac, d2 / (d2 - d6));
        }
        let va = d3 * d6 - d5 * d4;
        if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
            return edge(b, c - b, (d4 - d3) / ((d4 - d3) + (d5 - d6)));
        }
        (p, [1.0, 0.0, 1.0])
    }
}

impl Project for TriPrism {
    fn closest(&self, p: Vec3) -> Vec3 {
        self.project2(p.truncate())
            .0
            .extend(p.z.clamp(self.lo, self.hi))
    }

    fn closest_jacobian(&self, p: Vec3) -> (Vec3, Mat3) {
        let (q, [xx, xy, yy]) = self.project2(p.truncate());
        let zz = if p.z > self.lo && p.z < self.hi {
            1.0
        } else {
            0.0
        };
        let jac = Mat3::from_cols(
            Vec3::new(xx, xy, 0.0),
            Vec3::new(xy, yy, 0.0),
            Vec3::new(0.0, 0.0, zz),
        );
        (q.extend(p.z.clamp(self.lo, self.hi)), jac)
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }
}

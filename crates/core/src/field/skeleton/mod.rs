//! Skeletons of the skeletal primitives (Paris et al. 2019 §5.2,
//! Génevaux et al. 2015 §4.1): the geometry a primitive's field falls off from, with its
//! exact Euclidean distance.
//!
//! * thin: [`Point`], [`Segment`], polyline and Catmull-Rom curve ([`Chain`]), [`Disc`],
//!   square plane patch ([`PlanePatch`]);
//! * volumetric (distance 0 inside, so the primitive is constant inside): [`Sphere`],
//!   box ([`Cuboid`]), [`Ellipsoid`], capped [`Cone`], [`Capsule`], vertical [`Prism`].
//!
//! Every distance is the exact Euclidean distance to the set (the curve's set is its
//! flattened polyline), so every distance is 1-Lipschitz. Each convex kind also gives the
//! Jacobian of its projection `s(p)`, which the anisotropic noise of
//! [`crate::field::primitive`] differentiates through. The non-convex kinds (polyline,
//! curve, prism) are unions of convex *pieces* (segments, triangular prisms) and expose
//! them through [`Skeleton::visit_pieces`].

mod chain;
mod cone;
mod cuboid;
mod curve;
mod disc;
mod ellipsoid;
mod plane;
mod point;
mod polygon;
mod prism;
mod rounded;
mod segment;
mod spec;

use glam::{Mat3, Vec3};

use super::bounds::Aabb;

pub use chain::Chain;
pub use cone::Cone;
pub use cuboid::Cuboid;
pub use curve::{SEGMENTS_PER_SPAN, catmull_rom};
pub use disc::Disc;
pub use ellipsoid::Ellipsoid;
pub use plane::PlanePatch;
pub use point::Point;
pub use polygon::validate_polygon;
pub use prism::{Prism, TriPrism};
pub use rounded::{Capsule, Rounded, Sphere};
pub use segment::Segment;
pub use spec::{Points, Polygon, Size3, SkeletonSpec, ZRange};

/// A closed convex set (or a thin one) and its Euclidean projection `s(p)`.
pub trait Project {
    /// The closest point of the set to `p` (`p` itself when `p` is inside a solid).
    fn closest(&self, p: Vec3) -> Vec3;

    /// `(s(p), ∂s/∂p)`. For a convex set the Jacobian is symmetric with `‖J‖ ≤ 1` and
    /// `‖I − J‖ ≤ 1`; on the measure-zero loci where `s` is not differentiable it is one
    /// of the one-sided limits.
    fn closest_jacobian(&self, p: Vec3) -> (Vec3, Mat3);

    /// Euclidean distance from `p` to the set, 0 inside.
    #[inline]
    fn distance(&self, p: Vec3) -> f32 {
        (p - self.closest(p)).length()
    }

    /// `(distance, unit gradient)`; the gradient is `+z` where the distance is 0.
    #[inline]
    fn distance_grad(&self, p: Vec3) -> (f32, Vec3) {
        let w = p - self.closest(p);
        let d = w.length();
        if d > 0.0 { (d, w / d) } else { (0.0, Vec3::Z) }
    }

    /// A box holding the set.
    fn bounds(&self) -> Aabb;
}

/// `a bᵀ`.
#[inline]
pub(crate) fn outer(a: Vec3, b: Vec3) -> Mat3 {
    Mat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// A compiled skeleton. Build it with [`Skeleton::from_spec`].
#[derive(Clone, Debug, PartialEq)]
pub enum Skeleton {
    /// A point.
    Point(Point),
    /// A segment (a zero-length one is a point).
    Segment(Segment),
    /// A polyline through its points.
    Polyline(Chain),
    /// A centripetal Catmull-Rom spline through its control points, flattened.
    Curve(Chain),
    /// A filled disc.
    Disc(Disc),
    /// A filled square patch of a plane.
    Plane(PlanePatch),
    /// A solid ball.
    Sphere(Sphere),
    /// A solid box, optionally turned about z.
    Box(Cuboid),
    /// A solid axis-aligned ellipsoid.
    Ellipsoid(Ellipsoid),
    /// A solid capped cone.
    Cone(Cone),
    /// A solid capsule.
    Capsule(Capsule),
    /// A solid vertical prism over a simple polygon.
    Prism(Prism),
}

/// Applies `$body` to the convex payload `$s` of every single-piece variant, and `$chain`
/// / `$prism` to the others.
macro_rules! dispatch {
    ($self:expr, $s:ident => $body:expr, $c:ident => $chain:expr, $pr:ident => $prism:expr) => {
        match $self {
            Skeleton::Point($s) => $body,
            Skeleton::Segment($s) => $body,
            Skeleton::Disc($s) => $body,
            Skeleton::Plane($s) => $body,
            Skeleton::Sphere($s) => $body,
            Skeleton::Box($s) => $body,
            Skeleton::Ellipsoid($s) => $body,
            Skeleton::Cone($s) => $body,
            Skeleton::Capsule($s) => $body,
            Skeleton::Polyline($c) | Skeleton::Curve($c) => $chain,
            Skeleton::Prism($pr) => $prism,
        }
    };
}

impl Skeleton {
    /// Compiles a validated spec. Total: a degenerate cone (apex on its base) becomes a
    /// disc, a zero-length segment a point ([`SkeletonSpec::check`] reports the first).
    pub fn from_spec(spec: &SkeletonSpec) -> Skeleton {
        match spec {
            SkeletonSpec::Point { center } => Skeleton::Point(Point { center: center.0 }),
            SkeletonSpec::Segment { a, b } => Skeleton::Segment(Segment::new(a.0, b.0)),
            SkeletonSpec::Polyline { points } => {
                Skeleton::Polyline(Chain::new(points.0.iter().map(|p| p.0)))
            }
            SkeletonSpec::Curve { points } => {
                let control: Vec<Vec3> = points.0.iter().map(|p| p.0).collect();
                Skeleton::Curve(Chain::new(catmull_rom(&control)))
            }
            SkeletonSpec::Disc {
                center,
                normal,
                radius,
            } => Skeleton::Disc(Disc::new(center.0, normal.unit(), radius.get())),
            SkeletonSpec::Plane {
                point,
                normal,
                half_size,
            } => Skeleton::Plane(PlanePatch::new(point.0, normal.unit(), half_size.get())),
            SkeletonSpec::Sphere { center, radius } => {
                Skeleton::Sphere(Sphere::new(Point { center: center.0 }, radius.get()))
            }
            SkeletonSpec::Box {
                center,
                half_size,
                yaw,
            } => Skeleton::Box(Cuboid::new(center.0, half_size.0, yaw.get().to_radians())),
            SkeletonSpec::Ellipsoid { center, radii } => {
                Skeleton::Ellipsoid(Ellipsoid::new(center.0, radii.0))
            }
            SkeletonSpec::Cone { base, apex, radius } => {
                match Cone::new(base.0, apex.0, radius.get()) {
                    Some(c) => Skeleton::Cone(c),
                    None => Skeleton::Disc(Disc::new(base.0, Vec3::Z, radius.get())),
                }
            }
            SkeletonSpec::Capsule { a, b, radius } => {
                Skeleton::Capsule(Capsule::new(Segment::new(a.0, b.0), radius.get()))
            }
            SkeletonSpec::Prism { polygon, z } => {
                Skeleton::Prism(Prism::new(polygon.vertices(), z.lo(), z.hi()))
            }
        }
    }

    /// The kind's name as written in tree files.
    pub fn kind(&self) -> &'static str {
        match self {
            Skeleton::Point(_) => "Point",
            Skeleton::Segment(_) => "Segment",
            Skeleton::Polyline(_) => "Polyline",
            Skeleton::Curve(_) => "Curve",
            Skeleton::Disc(_) => "Disc",
            Skeleton::Plane(_) => "Plane",
            Skeleton::Sphere(_) => "Sphere",
            Skeleton::Box(_) => "Box",
            Skeleton::Ellipsoid(_) => "Ellipsoid",
            Skeleton::Cone(_) => "Cone",
            Skeleton::Capsule(_) => "Capsule",
            Skeleton::Prism(_) => "Prism",
        }
    }

    /// True for the solid kinds (distance 0 inside).
    pub fn is_volumetric(&self) -> bool {
        matches!(
            self,
            Skeleton::Sphere(_)
                | Skeleton::Box(_)
                | Skeleton::Ellipsoid(_)
                | Skeleton::Cone(_)
                | Skeleton::Capsule(_)
                | Skeleton::Prism(_)
        )
    }

    /// Euclidean distance from `p` to the skeleton (0 inside a solid).
    #[inline]
    pub fn distance(&self, p: Vec3) -> f32 {
        dispatch!(self, s => s.distance(p), c => c.distance_capped(p, f32::INFINITY), pr => pr.distance(p))
    }

    /// `min(distance(p), cap)`, faster than [`Skeleton::distance`] for far points of the
    /// many-piece kinds (pieces farther than `cap` are skipped).
    #[inline]
    pub fn distance_capped(&self, p: Vec3, cap: f32) -> f32 {
        dispatch!(self, s => s.distance(p).min(cap), c => c.distance_capped(p, cap), pr => pr.distance(p).min(cap))
    }

    /// The projection `s(p)`: the closest point of the skeleton to `p`.
    #[inline]
    pub fn closest(&self, p: Vec3) -> Vec3 {
        dispatch!(self, s => s.closest(p), c => c.closest(p), pr => pr.closest(p))
    }

    /// `(d(p), ∇d(p))`: the gradient is the unit vector from `s(p)` to `p`; on the skeleton
    /// (or inside a solid), where `d` is not differentiable, it is `+z`.
    #[inline]
    pub fn distance_grad(&self, p: Vec3) -> (f32, Vec3) {
        let far = |w: Vec3| {
            let d = w.length();
            if d > 0.0 { (d, w / d) } else { (0.0, Vec3::Z) }
        };
        dispatch!(self, s => s.distance_grad(p), c => far(p - c.closest(p)), pr => far(p - pr.closest(p)))
    }

    /// A box holding the skeleton.
    pub fn bounds(&self) -> Aabb {
        dispatch!(self, s => s.bounds(), c => c.bounds(), pr => pr.bounds())
    }

    /// Lipschitz constant of [`Skeleton::distance`]: 1, every distance being exact.
    pub fn lipschitz(&self) -> f32 {
        1.0
    }

    /// The skeleton as one convex set, or `None` for the many-piece kinds (polyline,
    /// curve, prism).
    pub fn convex(&self) -> Option<&dyn Project> {
        dispatch!(self, s => Some(s as &dyn Project), _c => None, _pr => None)
    }

    /// Calls `f(piece, ρ)` for the convex pieces whose distance `ρ` to `p` is below
    /// `reach`; `f` returns the new reach (pieces beyond it are skipped). A convex kind is
    /// its own single piece; a chain's pieces are its segments, a prism's the triangular
    /// prisms of its polygon's triangulation. The skeleton is the union of its pieces.
    pub fn visit_pieces(&self, p: Vec3, reach: f32, f: &mut dyn FnMut(&dyn Project, f32) -> f32) {
        dispatch!(self, s => {
            let rho = s.distance(p);
            if rho < reach {
                f(s, rho);
            }
        }, c => c.visit_segments(p, reach, f), pr => pr.visit_pieces(p, reach, f))
    }
}

#[cfg(test)]
mod tests;

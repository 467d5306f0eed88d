//! Primitive shapes on the tape: the `PRIM` op's encoding of a [`Shape`] and a
//! [`Profile`], and its CPU twin, `project` (the closest point and signed distance, as
//! `project` in `crates/render/shaders/field.wgsl` computes them) and `primitive`.
//!
//! | shape | parameters (after [`prim::SHAPE`]) |
//! | --- | --- |
//! | sphere (a point: radius 0) | [`sphere`]: `centre, ρ` |
//! | capsule (a segment: radius 0) | [`capsule`]: `a, b, ρ` |
//! | axis-aligned box | [`cuboid`]: `centre, half` |
//! | heightfield prism | [`prism`]: `min, max` |
//! | capped cone | [`cone`]: `base, axis, height, radius` |
//! | axis-aligned ellipsoid | [`ellipsoid`]: `centre, radii` |

use glam::{Vec2, Vec3, Vec3A};

use super::format::{capsule, cone, cuboid, ellipsoid, flag, limit, prim, prism, shape, sphere};
use super::format::{get3, set3, tail};
use crate::field::falloff::{sigma, sigma_slope, wyvill, wyvill_slope};
use crate::field::{Aabb, Interval};

/// The skeleton of a primitive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A point.
    Point(Vec3),
    /// A ball of radius `radius` (its surface is the skeleton's zero distance).
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius, metres.
        radius: f32,
    },
    /// A segment `[a, b]`.
    Segment(Vec3, Vec3),
    /// A capsule around `[a, b]`.
    Capsule {
        /// First end.
        a: Vec3,
        /// Second end.
        b: Vec3,
        /// Radius, metres.
        radius: f32,
    },
    /// An axis-aligned box.
    Box {
        /// Centre.
        center: Vec3,
        /// Half the edge lengths.
        half: Vec3,
    },
    /// A solid capped cone ([`crate::field::skeleton::Cone`]): a disc of `radius` centred
    /// on `base`, normal to the unit `axis`, and the apex at `base + height·axis`.
    Cone {
        /// Centre of the base disc.
        base: Vec3,
        /// Unit axis from the base to the apex.
        axis: Vec3,
        /// Base-to-apex distance.
        height: f32,
        /// Radius of the base.
        radius: f32,
    },
    /// A solid axis-aligned ellipsoid ([`crate::field::skeleton::Ellipsoid`]).
    Ellipsoid {
        /// Centre.
        center: Vec3,
        /// Semi-axes along x, y, z (positive).
        radii: Vec3,
    },
    /// The prism of an implicit heightfield ([`crate::dem::HeightfieldField`],
    /// Paris et al. 2019 §5.1): its distance is `√(d_xy² + d_z²)` with `d_xy` the largest
    /// excess of `x, y` over `[min, max]` (the leaf's `R − clearance` of its rectangle, so
    /// `min, max` is the rectangle eroded by `R`) and `d_z` the distance from `z` to
    /// `[min.z, max.z]`. Not a Euclidean distance at the corners, but 1-Lipschitz like the
    /// others.
    Prism {
        /// Lower corner (`min > max` along x or y is allowed: a domain narrower than 2R).
        min: Vec3,
        /// Upper corner.
        max: Vec3,
    },
}

impl Shape {
    /// Appends the shape's parameters to `out`; returns its kind ([`shape`]).
    pub(super) fn encode(&self, out: &mut Vec<f32>) -> u32 {
        match *self {
            Shape::Point(c) => Shape::Sphere {
                center: c,
                radius: 0.0,
            }
            .encode(out),
            Shape::Segment(a, b) => Shape::Capsule { a, b, radius: 0.0 }.encode(out),
            Shape::Sphere { center, radius } => {
                let q = tail(out, sphere::LEN);
                set3(q, sphere::CENTER, center);
                q[sphere::RADIUS] = radius;
                shape::SPHERE
            }
            Shape::Capsule { a, b, radius } => {
                let q = tail(out, capsule::LEN);
                set3(q, capsule::A, a);
                set3(q, capsule::B, b);
                q[capsule::RADIUS] = radius;
                shape::CAPSULE
            }
            Shape::Box { center, half } => {
                let q = tail(out, cuboid::LEN);
                set3(q, cuboid::CENTER, center);
                set3(q, cuboid::HALF, half);
                shape::BOX
            }
            Shape::Prism { min, max } => {
                let q = tail(out, prism::LEN);
                set3(q, prism::MIN, min);
                set3(q, prism::MAX, max);
                shape::PRISM
            }
            Shape::Cone {
                base,
                axis,
                height,
                radius,
            } => {
                let q = tail(out, cone::LEN);
                set3(q, cone::BASE, base);
                set3(q, cone::AXIS, axis);
                q[cone::HEIGHT] = height;
                q[cone::RADIUS] = radius;
                shape::CONE
            }
            Shape::Ellipsoid { center, radii } => {
                let q = tail(out, ellipsoid::LEN);
                set3(q, ellipsoid::CENTER, center);
                set3(q, ellipsoid::RADII, radii);
                shape::ELLIPSOID
            }
        }
    }

    /// The box where the signed distance is `≤ reach`.
    pub(super) fn bounds(&self, reach: f32) -> Aabb {
        match *self {
            Shape::Point(c) => Aabb::around(c, reach),
            Shape::Sphere { center, radius } => Aabb::around(center, radius + reach),
            Shape::Segment(a, b) => Aabb::new(a, b).dilate(reach),
            Shape::Capsule { a, b, radius } => Aabb::new(a, b).dilate(radius + reach),
            Shape::Box { center, half } => Aabb::new(center - half, center + half).dilate(reach),
            Shape::Cone {
                base,
                axis,
                height,
                radius,
            } => {
                // The base disc's box (extent `radius·√(1 − aᵢ²)` along axis i) and the apex.
                let ext = (Vec3::ONE - axis * axis).max(Vec3::ZERO).powf(0.5) * radius;
                Aabb::new(base - ext, base + ext)
                    .include(base + axis * height)
                    .dilate(reach)
            }
            Shape::Ellipsoid { center, radii } => {
                Aabb::new(center - radii, center + radii).dilate(reach)
            }
            // Not `Aabb::new`: the corners are kept as given even when min > max.
            Shape::Prism { min, max } => Aabb {
                min: min - Vec3::splat(reach),
                max: max + Vec3::splat(reach),
            },
        }
    }
}

/// How a primitive turns its signed distance `sd` into a field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Profile {
    /// `energy · g(max(sd, 0) / radius)`, Wyvill's `g(x) = (1 − x²)³`.
    Wyvill {
        /// Radius of influence, metres.
        radius: f32,
        /// Energy (negative carves).
        energy: f32,
    },
    /// `σ(−sd, radius)`: `T` on the shape's surface, `2T` deep inside, 0 beyond `radius`.
    Sigma {
        /// Falloff distance, metres.
        radius: f32,
    },
}

/// `(closest point, signed distance)` of the shape `kind` with parameters `q` to `p`: the
/// twin of `project` in `crates/render/shaders/field.wgsl` (a prism has no closest point: `p`).
pub(super) fn project(kind: u32, q: &[f32], p: Vec3) -> (Vec3, f32) {
    match kind {
        shape::SPHERE => {
            let (c, rho) = (get3(q, sphere::CENTER), q[sphere::RADIUS]);
            let d = (p - c).length();
            let at = if d > rho { c + (p - c) * (rho / d) } else { p };
            (at, d - rho)
        }
        shape::CAPSULE => {
            let a = get3(q, capsule::A);
            let ab = get3(q, capsule::B) - a;
            let rho = q[capsule::RADIUS];
            let ap = p - a;
            let l2 = ab.length_squared();
            let h = if l2 > 0.0 {
                (ap.dot(ab) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let s = a + ab * h;
            let d = (ap - ab * h).length();
            let at = if d > rho { s + (p - s) * (rho / d) } else { p };
            (at, d - rho)
        }
        shape::BOX => {
            let (c, half) = (get3(q, cuboid::CENTER), get3(q, cuboid::HALF));
            let d = (p - c).abs() - half;
            let sd = Vec3A::from(d).max(Vec3A::ZERO).length() + d.max_element().min(0.0);
            (c + (p - c).clamp(-half, half), sd)
        }
        shape::CONE => cone_projection(q, p),
        shape::ELLIPSOID => ellipsoid_projection(q, p),
        _ => {
            // shape::PRISM
            let (lo, hi) = (get3(q, prism::MIN), get3(q, prism::MAX));
            let dxy = (lo.x - p.x)
                .max(p.x - hi.x)
                .max(lo.y - p.y)
                .max(p.y - hi.y)
                .max(0.0);
            let dz = (lo.z - p.z).max(p.z - hi.z).max(0.0);
            // Signed: inside, minus the depth below the nearest face, so a ball deep
            // inside gets a zero slope (an unsigned 0 would let it reach `r` outside).
            let inside = (lo - p).max(p - hi).max_element().min(0.0);
            (p, (dxy * dxy + dz * dz).sqrt() + inside)
        }
    }
}

/// `(closest point, distance)` of the cone `q` ([`cone`]) to `p`:
/// [`crate::field::skeleton::Cone`]'s projection onto the triangle `(0, 0), (r, 0), (0, h)`
/// of the half-plane `(ρ, z)` through the axis, in f32 as `crates/render/shaders/field.wgsl` computes it.
/// The distance is the 2D one (equal to the 3D one, without the cancellation of
/// `|p − s(p)|`).
fn cone_projection(q: &[f32], p: Vec3) -> (Vec3, f32) {
    let base = get3(q, cone::BASE);
    let axis = get3(q, cone::AXIS);
    let (h, r) = (q[cone::HEIGHT], q[cone::RADIUS]);
    let w = p - base;
    let z = w.dot(axis);
    let radial = w - axis * z;
    let rho = radial.length();
    if z >= 0.0 && rho * h + z * r <= r * h {
        return (p, 0.0);
    }
    let x = Vec2::new(rho, z);
    // Base edge (0, 0)–(r, 0), slant edge (r, 0)–(0, h).
    let base_at = Vec2::new(rho.clamp(0.0, r), 0.0);
    let d = Vec2::new(-r, h);
    let tau = (x - Vec2::new(r, 0.0)).dot(d) / d.length_squared();
    let slant_at = Vec2::new(r, 0.0) + d * tau.clamp(0.0, 1.0);
    let (db, ds) = (
        (x - base_at).length_squared(),
        (x - slant_at).length_squared(),
    );
    let (at, d2) = if db <= ds {
        (base_at, db)
    } else {
        (slant_at, ds)
    };
    // On the axis (ρ = 0) the closest point is on it too (at.x = 0), any e_r will do.
    let er = if rho > 0.0 { radial / rho } else { Vec3::ZERO };
    (base + axis * at.y + er * at.x, d2.sqrt())
}

/// `(closest point, distance)` of the ellipsoid `q` ([`ellipsoid`]) to `p`:
/// [`crate::field::skeleton::Ellipsoid`]'s Newton iteration on
/// `F(t) = Σ (eᵢyᵢ/(t + eᵢ²))² − 1` from the same lower bound of the root, in f32 (WGSL has
/// no f64), stopping at the root, after [`limit::ELLIPSOID_NEWTON`] steps (as the CPU's)
/// or after a step below `10⁻⁶·(t + e²_max)` (the iterates climb monotonically and
/// converge quadratically, so what is left is far smaller), as `crates/render/shaders/field.wgsl`
/// computes it. The distance is `|y·t/(t + e²)|`, the same `|y − s|` without the
/// cancellation near the surface.
fn ellipsoid_projection(q: &[f32], p: Vec3) -> (Vec3, f32) {
    let c = get3(q, ellipsoid::CENTER);
    let e = get3(q, ellipsoid::RADII);
    let y = p - c;
    if (y / e).length_squared() <= 1.0 {
        return (p, 0.0);
    }
    let e2 = e * e;
    let ey = e * y;
    let emax = e2.max_element();
    let mut t = (ey.length() - emax).max(0.0);
    for _ in 0..limit::ELLIPSOID_NEWTON {
        let inv = (Vec3::splat(t) + e2).recip();
        let qv = ey * inv;
        let f = qv.length_squared() - 1.0;
        if f <= 0.0 {
            break;
        }
        let df = -2.0 * (qv * qv * inv).element_sum();
        let step = -f / df;
        t += step;
        if step <= 1e-6 * (t + emax) {
            break;
        }
    }
    let den = Vec3::splat(t) + e2;
    (c + e2 * y / den, (y * t / den).length())
}

/// `(value at p, Lipschitz bound over B(c, r))` of the `PRIM` with flags `flags` and
/// parameters `q` ([`prim`]); `BOUND`: compute the bound (else the second component is
/// 0). Where `p = c` the distances are shared.
pub(super) fn primitive<const BOUND: bool>(
    flags: u32,
    q: &[f32],
    p: Vec3,
    c: Vec3,
    r: f32,
) -> (f32, f32) {
    let (rad, energy) = (q[prim::RADIUS], q[prim::ENERGY]);
    let kind = flags & flag::SHAPE_MASK;
    let shape = &q[prim::SHAPE..];
    let sd_p = project(kind, shape, p).1;
    if !BOUND {
        let v = if flags & flag::SIGMA != 0 {
            sigma(-sd_p, rad)
        } else {
            energy * wyvill(sd_p.max(0.0) / rad)
        };
        return (v, 0.0);
    }
    let sd_c = if p == c {
        sd_p
    } else {
        project(kind, shape, c).1
    };
    if flags & flag::SIGMA != 0 {
        let v = sigma(-sd_p, rad);
        (v, sigma_slope(Interval::new(-sd_c - r, -sd_c + r), rad))
    } else {
        let v = energy * wyvill(sd_p.max(0.0) / rad);
        let xs = Interval::new((sd_c - r).max(0.0) / rad, (sd_c + r).max(0.0) / rad);
        (v, energy.abs() / rad * wyvill_slope(xs))
    }
}

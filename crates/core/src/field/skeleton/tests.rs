//! Distances against brute force, projections against their Jacobians, and the specs.

use glam::{Mat3, Vec2, Vec3};

use super::*;
use crate::field::noise::mix32;
use crate::value::{Dir3, Finite, P2, P3, Positive};

struct Rng(u32);

impl Rng {
    fn f(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9e37_79b9);
        (mix32(self.0) >> 8) as f32 / (1u32 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f()
    }
    fn v(&mut self, s: f32) -> Vec3 {
        Vec3::new(self.range(-s, s), self.range(-s, s), self.range(-s, s))
    }
}

/// Every kind, with random parameters, and an independent sampler of the skeleton:
/// `samples(h)` returns points of the set no farther than `h` from any point of its
/// boundary (thin kinds: the whole set; solids: their boundary).
struct Case {
    spec: SkeletonSpec,
    samples: Box<dyn Fn(f32) -> Vec<Vec3>>,
    inside: Box<dyn Fn(Vec3) -> bool>,
}

fn grid2(n: usize) -> impl Iterator<Item = (f32, f32)> {
    (0..=n).flat_map(move |i| (0..=n).map(move |j| (i as f32 / n as f32, j as f32 / n as f32)))
}

/// Boundary cells of a solid given by `inside`, sampled on a grid of spacing `h` over `b`.
fn boundary_of(inside: &dyn Fn(Vec3) -> bool, b: Aabb, h: f32) -> Vec<Vec3> {
    let n = (b.size() / h).ceil().as_uvec3() + 1;
    let at = |i: u32, j: u32, k: u32| b.min + Vec3::new(i as f32, j as f32, k as f32) * h;
    let mut out = Vec::new();
    for i in 0..=n.x {
        for j in 0..=n.y {
            for k in 0..=n.z {
                let p = at(i, j, k);
                if !inside(p) {
                    continue;
                }
                let edge = [Vec3::X, Vec3::Y, Vec3::Z]
                    .iter()
                    .any(|&e| !inside(p + e * h) || !inside(p - e * h));
                if edge {
                    out.push(p);
                }
            }
        }
    }
    out
}

fn p3(v: Vec3) -> P3 {
    P3(v)
}

fn cases(rng: &mut Rng) -> Vec<Case> {
    let mut out = Vec::new();
    let never = || -> Box<dyn Fn(Vec3) -> bool> { Box::new(|_| false) };
    // Point.
    let c = rng.v(5.0);
    out.push(Case {
        spec: SkeletonSpec::Point { center: p3(c) },
        samples: Box::new(move |_| vec![c]),
        inside: never(),
    });
    // Segment.
    let (a, b) = (rng.v(5.0), rng.v(5.0));
    let seg = move |h: f32| {
        let n = ((b - a).length() / h).ceil() as usize + 1;
        (0..=n)
            .map(|i| a.lerp(b, i as f32 / n as f32))
            .collect::<Vec<_>>()
    };
    out.push(Case {
        spec: SkeletonSpec::Segment { a: p3(a), b: p3(b) },
        samples: Box::new(seg),
        inside: never(),
    });
    // Polyline.
    let pts: Vec<Vec3> = (0..5).map(|_| rng.v(6.0)).collect();
    let poly = pts.clone();
    out.push(Case {
        spec: SkeletonSpec::Polyline {
            points: Points(pts.iter().copied().map(p3).collect()),
        },
        samples: Box::new(move |h| {
            poly.windows(2)
                .flat_map(|w| {
                    let n = ((w[1] - w[0]).length() / h).ceil() as usize + 1;
                    (0..=n).map(move |i| w[0].lerp(w[1], i as f32 / n as f32))
                })
                .collect()
        }),
        inside: never(),
    });
    // Curve: sampled from the spline itself, densely (the flattening error is part of
    // the tolerance of the caller).
    let ctrl: Vec<Vec3> = (0..4)
        .map(|i| Vec3::new(i as f32 * 4.0, 0.0, 0.0) + rng.v(2.0))
        .collect();
    let dense = {
        let fine = catmull_rom(&ctrl);
        fine.windows(2)
            .flat_map(|w| (0..8).map(move |i| w[0].lerp(w[1], i as f32 / 8.0)))
            .collect::<Vec<_>>()
    };
    out.push(Case {
        spec: SkeletonSpec::Curve {
            points: Points(ctrl.iter().copied().map(p3).collect()),
        },
        samples: Box::new(move |_| dense.clone()),
        inside: never(),
    });
    // Disc.
    let (c, n, r) = (rng.v(4.0), rng.v(1.0).normalize(), rng.range(0.5, 4.0));
    let (u, v) = n.any_orthonormal_pair();
    out.push(Case {
        spec: SkeletonSpec::Disc {
            center: p3(c),
            normal: Dir3(n),
            radius: Positive(r),
        },
        samples: Box::new(move |h| {
            let m = (2.0 * r / h).ceil() as usize + 1;
            grid2(m)
                .map(|(x, y)| (2.0 * x - 1.0, 2.0 * y - 1.0))
                .filter(|(x, y)| x * x + y * y <= 1.0)
                .map(|(x, y)| c + (u * x + v * y) * r)
                .chain((0..2000).map(|i| {
                    let t = i as f32 / 2000.0 * std::f32::consts::TAU;
                    c + (u * t.cos() + v * t.sin()) * r
                }))
                .collect()
        }),
        inside: never(),
    });
    // Plane patch (independent axes: whatever orthonormal pair, the patch is the
    // square of side 2h in *its* axes; sample through the same pair).
    let (c, n, hs) = (rng.v(4.0), rng.v(1.0).normalize(), rng.range(0.5, 4.0));
    let (u, v) = n.any_orthonormal_pair();
    out.push(Case {
        spec: SkeletonSpec::Plane {
            point: p3(c),
            normal: Dir3(n),
            half_size: Positive(hs),
        },
        samples: Box::new(move |h| {
            let m = (2.0 * hs / h).ceil() as usize + 1;
            grid2(m)
                .map(|(x, y)| c + (u * (2.0 * x - 1.0) + v * (2.0 * y - 1.0)) * hs)
                .collect()
        }),
        inside: never(),
    });
    // Solids: sampled from an independent membership test.
    let solid = |spec: SkeletonSpec, inside: Box<dyn Fn(Vec3) -> bool>, b: Aabb| {
        let inside = std::rc::Rc::new(inside);
        let i2 = inside.clone();
        Case {
            spec,
            samples: Box::new(move |h| boundary_of(&*i2, b.dilate(h), h)),
            inside: Box::new(move |p| inside(p)),
        }
    };
    let (c, r) = (rng.v(3.0), rng.range(0.5, 3.0));
    out.push(solid(
        SkeletonSpec::Sphere {
            center: p3(c),
            radius: Positive(r),
        },
        Box::new(move |p| (p - c).length() <= r),
        Aabb::around(c, r),
    ));
    let (c, hs, yaw) = (
        rng.v(3.0),
        Vec3::new(
            rng.range(0.3, 3.0),
            rng.range(0.3, 3.0),
            rng.range(0.3, 3.0),
        ),
        rng.range(-180.0, 180.0),
    );
    let (s, co) = yaw.to_radians().sin_cos();
    out.push(solid(
        SkeletonSpec::Box {
            center: p3(c),
            half_size: Size3(hs),
            yaw: Finite(yaw),
        },
        Box::new(move |p| {
            let d = p - c;
            let l = Vec3::new(co * d.x + s * d.y, -s * d.x + co * d.y, d.z);
            l.abs().cmple(hs).all()
        }),
        Aabb::around(c, hs.length()),
    ));
    let (c, e) = (
        rng.v(3.0),
        Vec3::new(
            rng.range(0.4, 3.0),
            rng.range(0.4, 3.0),
            rng.range(0.4, 3.0),
        ),
    );
    out.push(solid(
        SkeletonSpec::Ellipsoid {
            center: p3(c),
            radii: Size3(e),
        },
        Box::new(move |p| ((p - c) / e).length_squared() <= 1.0),
        Aabb::around(c, e.max_element()),
    ));
    let (base, apex, r) = (rng.v(3.0), rng.v(3.0) + Vec3::Z * 2.0, rng.range(0.5, 3.0));
    out.push(solid(
        SkeletonSpec::Cone {
            base: p3(base),
            apex: p3(apex),
            radius: Positive(r),
        },
        Box::new(move |p| {
            let ax = apex - base;
            let h = ax.length();
            let z = (p - base).dot(ax) / h;
            let rho = ((p - base) - ax * (z / h)).length();
            (0.0..=h).contains(&z) && rho <= r * (1.0 - z / h)
        }),
        Aabb::around((base + apex) * 0.5, (apex - base).length() * 0.5 + r),
    ));
    let (a, b, r) = (rng.v(3.0), rng.v(3.0), rng.range(0.3, 2.0));
    out.push(solid(
        SkeletonSpec::Capsule {
            a: p3(a),
            b: p3(b),
            radius: Positive(r),
        },
        Box::new(move |p| {
            let t = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
            (p - a.lerp(b, t)).length() <= r
        }),
        Aabb::new(a, b).dilate(r),
    ));
    // An L-shaped (non-convex) prism, shifted and scaled.
    let (o, k, lo) = (
        rng.v(2.0).truncate(),
        rng.range(0.5, 1.5),
        rng.range(-2.0, 0.0),
    );
    let hi = lo + rng.range(0.5, 3.0);
    let l: Vec<Vec2> = [
        (0.0, 0.0),
        (3.0, 0.0),
        (3.0, 1.0),
        (1.0, 1.0),
        (1.0, 3.0),
        (0.0, 3.0),
    ]
    .iter()
    .map(|&(x, y)| o + Vec2::new(x, y) * k)
    .collect();
    let lp = l.clone();
    out.push(solid(
        SkeletonSpec::Prism {
            polygon: Polygon::new(l.iter().map(|&p| P2(p)).collect()).unwrap(),
            z: ZRange::new(lo, hi).unwrap(),
        },
        Box::new(move |p| {
            let q = (p.truncate() - o) / k;
            let in_l = (0.0..=3.0).contains(&q.x)
                && (0.0..=3.0).contains(&q.y)
                && (q.x <= 1.0 || q.y <= 1.0);
            in_l && (lo..=hi).contains(&p.z)
        }),
        Aabb::from_points(lp.iter().flat_map(|v| [v.extend(lo), v.extend(hi)])),
    ));
    out
}

#[test]
fn distances_match_brute_force() {
    let mut rng = Rng(10);
    for round in 0..3 {
        for case in cases(&mut rng) {
            let sk = Skeleton::from_spec(&case.spec);
            let h = 0.05;
            let samples = (case.samples)(h);
            assert!(!samples.is_empty());
            let bounds = sk.bounds();
            for _ in 0..150 {
                let p = rng.v(9.0);
                let brute = samples
                    .iter()
                    .map(|s| (p - *s).length())
                    .fold(f32::INFINITY, f32::min);
                let d = sk.distance(p);
                let inside = (case.inside)(p);
                let tol = if matches!(case.spec, SkeletonSpec::Curve { .. }) {
                    0.05
                } else {
                    h * 1.8
                };
                if inside {
                    assert!(
                        d <= tol,
                        "{} round {round}: inside {p} but d = {d}",
                        sk.kind()
                    );
                } else {
                    assert!(
                        (d - brute).abs() <= tol,
                        "{} round {round}: {p}: d = {d}, brute = {brute}",
                        sk.kind()
                    );
                }
                // The projection is on the skeleton, at the distance.
                let s = sk.closest(p);
                assert!(
                    sk.distance(s) < 1e-3,
                    "{}: s(p) off the skeleton",
                    sk.kind()
                );
                assert!(((p - s).length() - d).abs() < 1e-3 * (1.0 + d));
                assert!(
                    bounds.dilate(1e-4).contains(s),
                    "{}: s(p) outside bounds()",
                    sk.kind()
                );
                assert!((sk.distance_capped(p, 1.0) - d.min(1.0)).abs() < 1e-5);
                // 1-Lipschitz, and the gradient.
                let q = p + rng.v(0.5);
                assert!((sk.distance(q) - d).abs() <= (q - p).length() * sk.lipschitz() + 1e-4);
                let (d2, g) = sk.distance_grad(p);
                assert!((d2 - d).abs() < 1e-5);
                if d > 1e-2 {
                    let e = 1e-3;
                    let fd = Vec3::new(
                        sk.distance(p + Vec3::X * e) - sk.distance(p - Vec3::X * e),
                        sk.distance(p + Vec3::Y * e) - sk.distance(p - Vec3::Y * e),
                        sk.distance(p + Vec3::Z * e) - sk.distance(p - Vec3::Z * e),
                    ) / (2.0 * e);
                    assert!(
                        (fd - g).length() < 2e-2 || fd.length() < 0.98,
                        "{}: ∇d {g} vs FD {fd}",
                        sk.kind()
                    );
                }
            }
        }
    }
}

/// Spectral norm of a symmetric-ish 3×3 matrix (power iteration on `JᵀJ`).
fn norm(m: Mat3) -> f32 {
    let mtm = m.transpose() * m;
    let mut x = Vec3::new(0.6, 0.7, 0.4);
    for _ in 0..100 {
        let y = mtm * x;
        if y.length() < 1e-12 {
            return 0.0;
        }
        x = y.normalize();
    }
    (mtm * x).length().sqrt()
}

#[test]
fn projection_jacobians_match_finite_differences() {
    let mut rng = Rng(20);
    for _ in 0..4 {
        for case in cases(&mut rng) {
            let sk = Skeleton::from_spec(&case.spec);
            for _ in 0..200 {
                let p = rng.v(8.0);
                let mut visited = 0;
                sk.visit_pieces(p, f32::INFINITY, &mut |piece, rho| {
                    visited += 1;
                    assert!((piece.distance(p) - rho).abs() < 1e-6);
                    let (s, j) = piece.closest_jacobian(p);
                    assert!((s - piece.closest(p)).length() < 1e-4);
                    assert!(norm(j) <= 1.0 + 1e-4, "{}: ‖J‖ = {}", sk.kind(), norm(j));
                    assert!(norm(Mat3::IDENTITY - j) <= 1.0 + 1e-4);
                    let e = 1e-3;
                    for axis in Vec3::AXES {
                        let (fwd, bwd) = (piece.closest(p + axis * e), piece.closest(p - axis * e));
                        let jc = j * axis;
                        let ok = ((fwd - s) / e - jc).length() < 2e-2
                            || ((s - bwd) / e - jc).length() < 2e-2;
                        assert!(
                            ok,
                            "{}: J·{axis} = {jc}, FD {} / {}",
                            sk.kind(),
                            (fwd - s) / e,
                            (s - bwd) / e
                        );
                    }
                    f32::INFINITY
                });
                assert!(visited >= 1);
                // The skeleton is the union of its pieces.
                let mut nearest = f32::INFINITY;
                sk.visit_pieces(p, f32::INFINITY, &mut |_, rho| {
                    nearest = nearest.min(rho);
                    f32::INFINITY
                });
                assert!(
                    (nearest - sk.distance(p)).abs() < 1e-4,
                    "{}: pieces {nearest} vs {}",
                    sk.kind(),
                    sk.distance(p)
                );
            }
        }
    }
}

#[test]
fn specs_parse_with_positions() {
    let ok = [
        "Point(center: (0, 0, 1))",
        "Segment(a: (0, 0, 0), b: (1, 0, 0))",
        "Polyline(points: [(0, 0, 0), (1, 0, 0), (1, 1, 0)])",
        "Curve(points: [(0, 0, 0), (5, 0, 2)])",
        "Disc(center: (0, 0, 0), normal: (0, 0, 1), radius: 2)",
        "Plane(point: (0, 0, 0), normal: (0, 0, 1), half_size: 50)",
        "Sphere(center: (0, 0, 10), radius: 4)",
        "Box(center: (0, 0, 0), half_size: (1, 2, 3), yaw: 30)",
        "Box(center: (0, 0, 0), half_size: (1, 2, 3))",
        "Ellipsoid(center: (0, 0, 0), radii: (1, 2, 3))",
        "Cone(base: (0, 0, 0), apex: (0, 0, 5), radius: 2)",
        "Capsule(a: (0, 0, 0), b: (0, 0, 5), radius: 1)",
        "Prism(polygon: [(0, 0), (4, 0), (4, 4), (0, 4)], z: (-1, 3))",
    ];
    for s in ok {
        let spec: SkeletonSpec = ron::from_str(s).unwrap_or_else(|e| panic!("{s}: {e}"));
        spec.check().unwrap();
        let again: SkeletonSpec = ron::from_str(&ron::to_string(&spec).unwrap()).unwrap();
        assert_eq!(again, spec, "round trip of {s}");
        let sk = Skeleton::from_spec(&spec);
        assert_eq!(s.split('(').next().unwrap(), sk.kind());
    }
    let bad: [(&str, usize, &str); 8] = [
        (
            "Sphere(center: (0, 0, 0),\n radius: -4)",
            2,
            "expected a number > 0",
        ),
        ("Polyline(points: [\n(0, 0, 0)])", 2, "at least 2 points"),
        (
            "Prism(polygon: [(0, 0), (1, 1),\n (1, 0), (0, 1)], z: (0, 1))",
            2,
            "must be simple",
        ),
        (
            "Prism(polygon: [(0, 0), (1, 0), (1, 1)],\n z: (3, 1))",
            2,
            "lo < hi",
        ),
        (
            "Prism(polygon: [(0, 0), (1, 0)], z: (0, 1))",
            1,
            "at least 3 distinct",
        ),
        (
            "Sphere(center: (0, 0, 0), radius: 1,\n colour: 3)",
            2,
            "colour",
        ),
        ("Torus(center: (0, 0, 0))", 1, "Torus"),
        (
            "Box(center: (0, 0, 0),\n half_size: (1, 0, 1))",
            2,
            "expected a number > 0",
        ),
    ];
    for (s, line, msg) in bad {
        let e = ron::from_str::<SkeletonSpec>(s).unwrap_err();
        assert_eq!(e.span.start.line, line, "{s}: {e}");
        assert!(e.to_string().contains(msg), "{s}: {e}");
    }
    let flat: SkeletonSpec =
        ron::from_str("Cone(base: (1, 2, 3), apex: (1, 2, 3), radius: 2)").unwrap();
    assert!(flat.check().unwrap_err().contains("apex"));
    assert_eq!(Skeleton::from_spec(&flat).kind(), "Disc");
}

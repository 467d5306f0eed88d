//! Soundness of every bound the skeletal primitives report, for every skeleton kind, with
//! and without anisotropic noise, on random primitives (proptest) and random points.

use crate::common::Rng;

use glam::{Vec2, Vec3};
use karstic::field::noise::{NoiseSpec, Octaves};
use karstic::field::skeleton::{Points, Polygon, Size3, ZRange};
use karstic::field::{
    Aabb, Field, ISO, Interval, Primitive, PrimitiveSpec, Rect, SkeletonSpec, ZBands,
};
use karstic::value::{Dir3, Finite, NonNegative, P2, P3, Positive};
use proptest::collection::vec;
use proptest::prelude::*;

fn p3(r: f32) -> impl Strategy<Value = P3> {
    (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| P3(Vec3::new(x, y, z)))
}

fn size3(lo: f32, hi: f32) -> impl Strategy<Value = Size3> {
    (lo..hi, lo..hi, lo..hi).prop_map(|(x, y, z)| Size3(Vec3::new(x, y, z)))
}

fn pos(lo: f32, hi: f32) -> impl Strategy<Value = Positive> {
    (lo..hi).prop_map(Positive)
}

fn dir() -> impl Strategy<Value = Dir3> {
    (-1f32..1.0, -1f32..1.0, -1f32..1.0)
        .prop_filter("non-zero", |(x, y, z)| x * x + y * y + z * z > 0.05)
        .prop_map(|(x, y, z)| Dir3(Vec3::new(x, y, z)))
}

/// Star-shaped polygons (increasing angles about a centre): simple, often non-convex.
fn polygon() -> impl Strategy<Value = Polygon> {
    (p3(3.0), vec((0.05f32..1.0, 0.5f32..4.0), 3..9)).prop_filter_map("simple", |(c, pts)| {
        let mut angle = 0.0;
        let total: f32 = pts.iter().map(|p| p.0).sum();
        let v = pts
            .iter()
            .map(|&(step, r)| {
                angle += step / total * std::f32::consts::TAU;
                P2(c.0.truncate() + Vec2::from_angle(angle) * r)
            })
            .collect();
        Polygon::new(v).ok()
    })
}

fn skeleton() -> impl Strategy<Value = SkeletonSpec> {
    prop_oneof![
        p3(5.0).prop_map(|center| SkeletonSpec::Point { center }),
        (p3(5.0), p3(5.0)).prop_map(|(a, b)| SkeletonSpec::Segment { a, b }),
        vec(p3(6.0), 2..6).prop_map(|v| SkeletonSpec::Polyline { points: Points(v) }),
        vec(p3(6.0), 2..6).prop_map(|v| SkeletonSpec::Curve { points: Points(v) }),
        (p3(4.0), dir(), pos(0.5, 4.0)).prop_map(|(center, normal, radius)| SkeletonSpec::Disc {
            center,
            normal,
            radius
        }),
        (p3(4.0), dir(), pos(0.5, 4.0)).prop_map(|(point, normal, half_size)| {
            SkeletonSpec::Plane {
                point,
                normal,
                half_size,
            }
        }),
        (p3(4.0), pos(0.3, 3.0))
            .prop_map(|(center, radius)| SkeletonSpec::Sphere { center, radius }),
        (p3(4.0), size3(0.2, 3.0), -180f32..180.0).prop_map(|(center, half_size, yaw)| {
            SkeletonSpec::Box {
                center,
                half_size,
                yaw: Finite(yaw),
            }
        }),
        (p3(4.0), size3(0.3, 3.0))
            .prop_map(|(center, radii)| SkeletonSpec::Ellipsoid { center, radii }),
        (p3(4.0), p3(4.0), pos(0.3, 3.0))
            .prop_filter("axis", |(b, a, _)| (a.0 - b.0).length() > 0.3)
            .prop_map(|(base, apex, radius)| SkeletonSpec::Cone { base, apex, radius }),
        (p3(4.0), p3(4.0), pos(0.2, 2.0)).prop_map(|(a, b, radius)| SkeletonSpec::Capsule {
            a,
            b,
            radius
        }),
        (polygon(), -3f32..1.0, 0.3f32..4.0).prop_map(|(polygon, lo, h)| SkeletonSpec::Prism {
            polygon,
            z: ZRange::new(lo, lo + h).unwrap(),
        }),
    ]
}

/// A random primitive; `min_wavelength` keeps the noise smooth enough for finite
/// differences where that matters.
fn primitive(min_wavelength: f32) -> impl Strategy<Value = (Primitive, PrimitiveSpec, u64)> {
    let noise = prop::option::of((0f32..0.9, min_wavelength..6.0, 1u32..5, any::<u32>()));
    (
        skeleton(),
        0.3f32..4.0,
        -3f32..3.0,
        noise,
        any::<u32>(),
        any::<u64>(),
    )
        .prop_map(|(shape, falloff, energy, noise, seed, rng)| {
            let spec = PrimitiveSpec {
                name: None,
                shape,
                falloff: Positive(falloff),
                energy: Finite(if energy.abs() < 0.05 { 1.0 } else { energy }),
                noise: noise.map(|(frac, wavelength, octaves, seed_offset)| NoiseSpec {
                    amplitude: NonNegative(frac * falloff),
                    wavelength: Positive(wavelength),
                    octaves: Octaves::new(octaves).unwrap(),
                    seed_offset,
                }),
            };
            (Primitive::from_spec(&spec, seed), spec, rng)
        })
}

/// A random box near the support: anything from a sliver to the whole support.
fn random_box(rng: &mut Rng, prim: &Primitive) -> Aabb {
    let s = prim.support().dilate(1.0);
    let c = rng.in_box(&s);
    let size =
        Vec3::new(rng.f32(), rng.f32(), rng.f32()) * s.size().max_element() * rng.f32().powi(2);
    Aabb::new(c - size * 0.5, c + size * 0.5)
}

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 300,
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config())]

    /// (1) Intervals hold every sampled value, corners included.
    #[test]
    fn intervals_contain_samples((prim, spec, seed) in primitive(0.3)) {
        let mut rng = Rng(seed);
        for _ in 0..30 {
            let b = random_box(&mut rng, &prim);
            let iv = prim.interval(&b);
            let tol = 1e-5 * prim.energy().abs();
            let pts = b.corners().into_iter().chain((0..64).map(|_| rng.in_box(&b)));
            for p in pts {
                let v = prim.value(p);
                prop_assert!(iv.lo - tol <= v && v <= iv.hi + tol, "{spec:?}\nbox {b:?}: {v} not in {iv:?} at {p}");
            }
        }
    }

    /// (2) Global and per-box Lipschitz bounds on random pairs, close and far.
    #[test]
    fn lipschitz_bounds_hold((prim, spec, seed) in primitive(0.3)) {
        let mut rng = Rng(seed);
        let lambda = prim.lipschitz();
        let s = prim.support().dilate(1.0);
        for i in 0..400 {
            let p = rng.in_box(&s);
            // Half the pairs along the gradient, where the slope is steepest.
            let g = prim.value_grad(p).1;
            let d = if i % 2 == 0 && g.length() > 0.0 { g.normalize() } else { rng.dir() };
            let q = p + d * s.size().max_element() * [1e-3f32, 1e-2, 0.1, 1.0][i % 4] * rng.f32();
            let (vp, vq) = (prim.value(p), prim.value(q));
            let lhs = (vp - vq).abs();
            // Slack for the rounding of two values (up to |energy| = 3) a hair apart.
            let rounding = 4.0 * f32::EPSILON * (vp.abs() + vq.abs()) + 1e-6;
            prop_assert!(lhs <= lambda * (p - q).length() * 1.0001 + rounding, "{spec:?}\nglobal {lambda}: {lhs} over {}", (p - q).length());
        }
        for _ in 0..40 {
            let b = random_box(&mut rng, &prim);
            let lb = prim.lipschitz_box(&b);
            prop_assert!(lb <= lambda * 1.0001 + 1e-6, "box bound {lb} above the global {lambda}");
            for _ in 0..20 {
                let (p, q) = (rng.in_box(&b), rng.in_box(&b));
                let (vp, vq) = (prim.value(p), prim.value(q));
                let lhs = (vp - vq).abs();
                let rounding = 4.0 * f32::EPSILON * (vp.abs() + vq.abs()) + 1e-6;
                prop_assert!(lhs <= lb * (p - q).length() * 1.0001 + rounding, "{spec:?}\nbox {b:?} bound {lb}: {lhs} over {}", (p - q).length());
                let ls = prim.lipschitz_segment(p, q);
                prop_assert!(lhs <= ls * (p - q).length() * 1.0001 + rounding);
                // And every pair on the segment.
                let (u, v) = (p.lerp(q, rng.f32()), p.lerp(q, rng.f32()));
                let on = (prim.value(u) - prim.value(v)).abs();
                // (Absolute slack for the rounding of two nearly equal values.)
                prop_assert!(on <= ls * (u - v).length() * 1.0001 + 2e-5, "{spec:?}\nsegment bound {ls}: {on}");
            }
        }
    }

    /// (3) Analytic gradients against central differences, away from non-smooth loci
    /// (points whose one-sided differences disagree straddle a kink and are skipped; at
    /// most a few are).
    #[test]
    fn gradients_match_finite_differences((prim, spec, seed) in primitive(1.0)) {
        let mut rng = Rng(seed);
        let s = prim.support();
        let lambda = prim.lipschitz();
        let h = 1e-3;
        let tol = 2e-2 * lambda + 1e-3;
        let (mut tested, mut skipped) = (0, 0);
        for _ in 0..300 {
            let p = rng.in_box(&s);
            let (v, g) = prim.value_grad(p);
            prop_assert!((v - prim.value(p)).abs() <= 1e-5 * (1.0 + v.abs()));
            prop_assert!(g.length() <= lambda * 1.0001 + 1e-5, "{spec:?}\n|∇f| = {} above λ = {lambda}", g.length());
            let mut kink = false;
            let mut fd = Vec3::ZERO;
            for axis in 0..3 {
                let e = Vec3::AXES[axis] * h;
                let (fp, fm) = (prim.value(p + e), prim.value(p - e));
                let (fwd, bwd) = ((fp - v) / h, (v - fm) / h);
                kink |= (fwd - bwd).abs() > tol;
                fd[axis] = (fp - fm) / (2.0 * h);
            }
            if kink {
                skipped += 1;
                continue;
            }
            tested += 1;
            prop_assert!((fd - g).length() <= tol, "{spec:?}\nat {p}: ∇f = {g}, FD = {fd}");
        }
        prop_assert!(skipped * 10 <= tested, "{spec:?}\ntoo many kinks: {skipped} vs {tested}");
    }

    /// (4) Zero outside the support. (6) Volumetric skeletons: constant `E` inside.
    #[test]
    fn support_and_volumetric_interior((prim, spec, seed) in primitive(0.3)) {
        let mut rng = Rng(seed);
        let s = prim.support();
        let around = s.dilate(s.size().max_element());
        let mut outside = 0;
        while outside < 300 {
            let p = rng.in_box(&around);
            if !s.contains(p) {
                outside += 1;
                prop_assert_eq!(prim.value(p), 0.0, "{:?} at {}", spec, p);
                prop_assert_eq!(prim.value_grad(p), (0.0, Vec3::ZERO));
            }
        }
        let sk = prim.skeleton();
        if sk.is_volumetric() {
            let b = sk.bounds();
            let mut inside = 0;
            for _ in 0..2000 {
                let p = rng.in_box(&b);
                if sk.distance(p) == 0.0 {
                    inside += 1;
                    prop_assert_eq!(prim.value(p), prim.energy(), "{:?} at {}", spec, p);
                }
            }
            prop_assert!(inside > 0, "no interior sample for {:?}", spec);
        }
    }

    /// (5) The z-bands hold every crossing of `T` found on vertical lines of the footprint.
    #[test]
    fn z_bands_contain_crossings((prim, spec, seed) in primitive(0.3)) {
        let mut rng = Rng(seed);
        let s = prim.support().dilate(0.5);
        let z = s.z();
        for _ in 0..6 {
            let c = rng.in_box(&s).truncate();
            let half = Vec2::new(rng.f32(), rng.f32()) * 2.0 + 0.05;
            let fp = Rect::new(c - half, c + half);
            let mut bands = ZBands::new();
            prim.z_bands(&fp, z, &mut bands);
            for line in 0..25 {
                let xy = if line < 4 {
                    Vec2::new(if line & 1 == 0 { fp.min.x } else { fp.max.x }, if line & 2 == 0 { fp.min.y } else { fp.max.y })
                } else {
                    fp.min + Vec2::new(rng.f32(), rng.f32()) * (fp.max - fp.min)
                };
                let n = 400;
                let zs = |k: usize| z.lo + z.width() * k as f32 / n as f32;
                let mut last = prim.value(xy.extend(zs(0))) - ISO;
                for k in 1..=n {
                    let cur = prim.value(xy.extend(zs(k))) - ISO;
                    if (last > 0.0) != (cur > 0.0) {
                        let seg = Interval::new(zs(k - 1), zs(k));
                        prop_assert!(
                            bands.as_slice().iter().any(|b| b.overlaps(&seg)),
                            "{spec:?}\ncrossing in {seg:?} at {xy} outside the bands {:?}", bands.as_slice()
                        );
                    }
                    last = cur;
                }
            }
        }
    }

    /// Block evaluation equals point evaluation.
    #[test]
    fn eval_block_matches_points((prim, _spec, seed) in primitive(0.3)) {
        let mut rng = Rng(seed);
        let b = random_box(&mut rng, &prim);
        let dims = [5, 4, 3];
        let step = b.size() / 4.0;
        let mut out = vec![f32::NAN; 60];
        prim.eval_block(b.min, step, dims, &mut out);
        for k in 0..3 {
            for j in 0..4 {
                for i in 0..5 {
                    let p = b.min + Vec3::new(i as f32, j as f32, k as f32) * step;
                    prop_assert_eq!(out[i + 5 * (j + 4 * k)], prim.value(p));
                }
            }
        }
    }
}

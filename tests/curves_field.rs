//! The S field as a `Field`: sampled soundness of its bounds (with the noise
//! displacement on), gradients against finite differences, determinism, the cache, and
//! the memory of the sparse grid on a large domain.

use crate::common::Rng;
use crate::curves_util;

use std::path::Path;

use glam::Vec3;
use karstic::curves::{Features, Orientation};
use karstic::field::{Aabb, Field, ISO, Interval, Rect, ZBands};
use karstic::voxel::FeatureVolumeSpec;
use karstic::voxel::{Interpolation, SField, run};

fn load(name: &str) -> (FeatureVolumeSpec, Features) {
    let l = curves_util::load(name);
    (l.spec, l.features)
}

/// The ridge with noise that varies along the crest (amplitude 0 → 2.5 m, roughness
/// 0.05 → 0.2 /m): the displacement and its bounds are exercised.
fn noisy_ridge() -> SField {
    noisy_ridge_with(Interpolation::Trilinear)
}

fn noisy_ridge_with(interpolation: Interpolation) -> SField {
    let (mut spec, mut f) = load("ridge");
    spec.interpolation = interpolation;
    for c in &mut f.curves {
        for (k, cp) in c.constraints.iter_mut().enumerate() {
            cp.amplitude = 2.5 * k as f32;
            cp.roughness = 0.05 + 0.15 * k as f32;
        }
        if c.constraints.len() == 1 {
            c.constraints[0].amplitude = 0.5;
            c.constraints[0].roughness = 0.1;
        }
    }
    spec.build_features(&f, 3, 1 << 32).unwrap()
}

/// `loose`: the largest accepted median ratio of the box Lipschitz bound to the gradient
/// near the surface (worst-case noise bounds are far above typical noise slopes).
fn check_soundness(f: &SField, seed: u64, loose: f32) {
    let mut rng = Rng(seed);
    let support = f.support();
    let around = support.dilate(4.0);
    let lip = f.lipschitz();
    assert!(lip.is_finite() && lip > 0.0);
    let mut max_ratio = 0.0f32;
    for _ in 0..3000 {
        // Lipschitz on random pairs, some close, some far, some outside the support.
        let a = rng.in_box(&around);
        let b = if rng.f32() < 0.5 {
            a + (Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5) * 3.0
        } else {
            rng.in_box(&around)
        };
        let (fa, fb) = (f.value(a), f.value(b));
        let d = a.distance(b).max(1e-6);
        max_ratio = max_ratio.max((fa - fb).abs() / d);
        assert!(
            (fa - fb).abs() <= lip * d + 1e-5,
            "global Lipschitz {lip} broken: {fa} {fb} over {d}"
        );
        let seg = f.lipschitz_segment(a, b);
        assert!(
            (fa - fb).abs() <= seg * d + 1e-5,
            "segment Lipschitz {seg} broken"
        );
    }
    let _ = max_ratio;
    // Near the surface, the box bound is within a sane factor of the true slope.
    let mut ratios = Vec::new();
    for _ in 0..4000 {
        let p = rng.in_box(&support);
        let (v, g) = f.value_grad(p);
        if (v - ISO).abs() < 0.05 && g.length() > 1e-3 {
            ratios.push(f.lipschitz_box(&Aabb::around(p, 0.5)) / g.length());
        }
    }
    ratios.sort_by(f32::total_cmp);
    assert!(
        ratios.len() > 10 && ratios[0] >= 1.0 - 1e-3,
        "box bound below the gradient: {:?}",
        ratios.first()
    );
    let median = ratios[ratios.len() / 2];
    eprintln!(
        "Lipschitz box bound / gradient near the surface: median {median:.2}, global bound {lip:.2}"
    );
    assert!(
        median < loose,
        "box Lipschitz bound too loose (median ratio {median})"
    );
    for _ in 0..300 {
        // Intervals and box Lipschitz bounds over random boxes of all sizes.
        let c = rng.in_box(&around);
        let r = 0.3 + 20.0 * rng.f32() * rng.f32();
        let b = Aabb::around(c, r);
        let iv = f.interval(&b);
        let lb = f.lipschitz_box(&b);
        let mut prev: Option<(Vec3, f32)> = None;
        for _ in 0..60 {
            let p = rng.in_box(&b);
            let v = f.value(p);
            assert!(iv.contains(v), "interval {iv:?} misses {v} at {p} in {b:?}");
            if let Some((q, w)) = prev {
                assert!(
                    (v - w).abs() <= lb * p.distance(q) + 1e-5,
                    "box Lipschitz {lb} broken in {b:?}"
                );
            }
            prev = Some((p, v));
        }
    }
    for _ in 0..400 {
        // Gradient against central differences, away from the min() switch and cell faces
        // (both are kinks of a piecewise-smooth field): compare on smooth samples only.
        let p = rng.in_box(&support.dilate(-2.0));
        let (v, g) = f.value_grad(p);
        assert!((v - f.value(p)).abs() < 1e-5);
        let e = 1e-3;
        let fd = Vec3::new(
            f.value(p + Vec3::X * e) - f.value(p - Vec3::X * e),
            f.value(p + Vec3::Y * e) - f.value(p - Vec3::Y * e),
            f.value(p + Vec3::Z * e) - f.value(p - Vec3::Z * e),
        ) / (2.0 * e);
        let fd2 = Vec3::new(
            f.value(p + Vec3::X * 2.0 * e) - f.value(p - Vec3::X * 2.0 * e),
            f.value(p + Vec3::Y * 2.0 * e) - f.value(p - Vec3::Y * 2.0 * e),
            f.value(p + Vec3::Z * 2.0 * e) - f.value(p - Vec3::Z * 2.0 * e),
        ) / (4.0 * e);
        if (fd - fd2).length() < 1e-3 * (1.0 + fd.length()) {
            assert!(
                (fd - g).length() < 2e-2 * (1.0 + g.length()),
                "gradient {g} vs differences {fd} at {p}"
            );
        }
    }
}

/// `S'` obeys [`SField::s_lipschitz`] on close and far pairs inside the domain; returns
/// the largest slope seen.
fn check_s_slope(f: &SField, seed: u64) -> f32 {
    let (mut rng, dom, ls) = (Rng(seed), f.support().dilate(-0.5), f.s_lipschitz());
    let mut seen = 0.0f32;
    for i in 0..20_000 {
        let a = rng.in_box(&dom);
        let off = Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5;
        let b = if i % 2 == 0 {
            a + off * 0.2
        } else {
            rng.in_box(&dom)
        };
        let d = a.distance(b).max(1e-6);
        let q = (f.s_value(a) - f.s_value(b)).abs() / d;
        seen = seen.max(q);
        assert!(
            q <= ls * (1.0 + 1e-4) + 1e-4,
            "S' slope {q} above its bound {ls}"
        );
    }
    eprintln!("S' slope seen {seen:.2}, bound {ls:.2}");
    seen
}

/// `S'` over random small boxes anywhere in the domain (also where σ saturates and
/// `check_soundness` cannot see S): the values lie in [`SField::s_interval`] and pairs obey
/// [`SField::s_lipschitz_box`].
fn check_s_boxes(f: &SField, seed: u64) {
    let mut rng = Rng(seed);
    let h = f.params().voxel;
    let dom = f.support();
    for _ in 0..3000 {
        let b = Aabb::around(rng.in_box(&dom), h * (0.3 + 2.0 * rng.f32()));
        let (iv, lb) = (f.s_interval(&b), f.s_lipschitz_box(&b));
        let b = b.intersection(dom);
        let mut prev: Option<(Vec3, f32)> = None;
        for _ in 0..40 {
            let p = rng.in_box(&b);
            let v = f.s_value(p);
            // The value-only path (the march's) is the gradient path's value, bit for bit.
            assert_eq!(v.to_bits(), f.s_grad(p).0.to_bits(), "S' at {p}");
            assert!(
                iv.contains(v),
                "S interval {iv:?} misses {v} at {p} in {b:?}"
            );
            if let Some((q, w)) = prev {
                let d = p.distance(q).max(1e-6);
                assert!(
                    (v - w).abs() <= lb * d * (1.0 + 1e-4) + 1e-5,
                    "S box Lipschitz {lb} broken in {b:?}: {}",
                    (v - w).abs() / d
                );
            }
            prev = Some((p, v));
        }
    }
}

#[test]
fn bounds_are_sound_with_noise() {
    let f = noisy_ridge();
    assert!(f.stats().levels.len() >= 3);
    check_soundness(&f, 1, 100.0);
    // The displaced S' itself (not only σ(S'), which saturates away from the surface)
    // obeys the widened bound on close and far pairs inside the domain.
    let seen = check_s_slope(&f, 5);
    assert!(
        seen > 1.0,
        "the noise steepens S' beyond its unit distance slope"
    );
    // The noise moves the surface: a crest sample with α = 2.5 is displaced.
    let plain = {
        let (spec, f) = load("ridge");
        spec.build_features(&f, 3, 1 << 32).unwrap()
    };
    let p = Vec3::new(100.0, 66.0, 42.0);
    assert!((f.s_value(p) - plain.s_value(p)).abs() > 1e-3);
}

#[test]
fn bounds_are_sound_on_a_carving_tunnel() {
    let (mut spec, feats) = load("tunnel");
    spec.orientation = Orientation::Air;
    let f = spec.build_features(&feats, 0, 1 << 32).unwrap();
    check_soundness(&f, 2, 5.0);
    // Air orientation: the tunnel's inside is the solid of the carving field.
    assert!(f.value(feats.tunnels[0].path.eval(0.5)) > ISO);
}

/// A scene of `trees/curves/` with tricubic interpolation, and with trilinear.
fn tricubic(name: &str) -> (SField, SField) {
    let (mut spec, f) = load(name);
    let lin = spec.build_features(&f, 0, 1 << 32).unwrap();
    spec.interpolation = Interpolation::Tricubic;
    (spec.build_features(&f, 0, 1 << 32).unwrap(), lin)
}

#[test]
fn tricubic_bounds_are_sound() {
    let (f, lin) = tricubic("overhang");
    check_soundness(&f, 11, 5.0);
    check_s_slope(&f, 12);
    check_s_boxes(&f, 16);
    check_s_boxes(&lin, 17);
    eprintln!(
        "S Lipschitz bound: tricubic {:.2}, trilinear {:.2}",
        f.s_lipschitz(),
        lin.s_lipschitz()
    );
    // Intervals of S' over small boxes where the blend is on contain the sampled values
    // (the σ of `check_soundness` saturates away from the surface).
    let mut rng = Rng(13);
    let dom = f.support().dilate(-3.0);
    for _ in 0..400 {
        let b = Aabb::around(rng.in_box(&dom), 0.5 + 3.0 * rng.f32());
        let iv = f.interval(&b);
        for _ in 0..40 {
            let p = rng.in_box(&b);
            assert!(iv.contains(f.value(p)));
        }
    }
    // With the noise displacement, on the ridge.
    let g = noisy_ridge_with(Interpolation::Tricubic);
    check_soundness(&g, 14, 100.0);
    check_s_slope(&g, 15);
    check_s_boxes(&g, 18);
}

#[test]
fn tricubic_interpolates_the_nodes_and_is_smooth() {
    let (f, lin) = tricubic("overhang");
    let fine = f.levels().last().unwrap().geom;
    let mut rng = Rng(21);
    let (mut differ, mut n) = (0, 0);
    for _ in 0..4000 {
        // At the nodes both interpolants take the node values.
        let g = (Vec3::new(rng.f32(), rng.f32(), rng.f32()) * (fine.dims - 1).as_vec3()).floor();
        let p = fine.origin + g * fine.h;
        let (a, b) = (f.s_value(p), lin.s_value(p));
        assert!(
            (a - b).abs() < 1e-4 * (1.0 + b.abs()),
            "{a} vs {b} at node {p}"
        );
        // Between them they differ near the surface, where S bends.
        let q = p + Vec3::new(0.5, 0.3, 0.6) * fine.h;
        if lin.s_value(q).abs() < 2.0 * fine.h {
            n += 1;
            differ += ((f.s_value(q) - lin.s_value(q)).abs() > 1e-4) as usize;
        }
    }
    assert!(
        n > 50 && differ * 2 > n,
        "tricubic differs at {differ} of {n}"
    );
    // C¹: the gradient does not jump across cell faces near the surface (trilinear's does).
    let jumps = |f: &SField| {
        let mut rng = Rng(22);
        let mut j = Vec::new();
        while j.len() < 300 {
            let g =
                (Vec3::new(rng.f32(), rng.f32(), rng.f32()) * (fine.dims - 1).as_vec3()).floor();
            let p = fine.origin + (g + Vec3::new(0.0, rng.f32(), rng.f32())) * fine.h;
            if f.s_value(p).abs() > 2.0 * fine.h || !f.support().dilate(-8.0).contains(p) {
                continue;
            }
            let e = 1e-3 * fine.h;
            let (a, b) = (f.s_grad(p - Vec3::X * e).1, f.s_grad(p + Vec3::X * e).1);
            j.push((a - b).length());
        }
        j.sort_by(f32::total_cmp);
        j[j.len() * 9 / 10]
    };
    let (jc, jl) = (jumps(&f), jumps(&lin));
    eprintln!(
        "90th percentile of the gradient jumps across x faces: tricubic {jc:.2e}, trilinear {jl:.2e}"
    );
    assert!(jc * 20.0 < jl, "tricubic {jc} vs trilinear {jl}");
}

#[test]
fn z_bands_contain_the_surface() {
    let f = noisy_ridge();
    let mut rng = Rng(9);
    let d = f.support();
    for _ in 0..40 {
        let c = rng.in_box(&d);
        let fp = Rect::new(c.truncate() - 2.0, c.truncate() + 2.0);
        let mut bands = ZBands::new();
        f.z_bands(&fp, Interval::new(d.min.z - 1.0, d.max.z + 1.0), &mut bands);
        for _ in 0..10 {
            let xy = fp.min + (fp.max - fp.min) * glam::Vec2::new(rng.f32(), rng.f32());
            let mut last = f.value(xy.extend(d.max.z + 1.0)) > ISO;
            for k in 0..400 {
                let z = d.max.z + 1.0 - k as f32 * (d.size().z + 2.0) / 400.0;
                let now = f.value(xy.extend(z)) > ISO;
                if now != last {
                    let zc = z + 0.5 * (d.size().z + 2.0) / 400.0;
                    assert!(
                        bands.as_slice().iter().any(|b| b.dilate(0.2).contains(zc)),
                        "crossing at z = {zc} outside {bands:?}"
                    );
                }
                last = now;
            }
        }
    }
}

#[test]
fn deterministic_whatever_the_thread_count() {
    let (spec, f) = load("ridges");
    let (p, _) = spec.params(0, 1 << 32);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| run(&f, &p).unwrap());
    let three = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap()
        .install(|| run(&f, &p).unwrap());
    assert_eq!(one.levels.len(), three.levels.len());
    for l in 0..one.levels.len() {
        assert_eq!(one.levels[l].coords(), three.levels[l].coords());
        let (a, b): (Vec<u32>, Vec<u32>) = (
            one.s[l].iter().map(|x| x.to_bits()).collect(),
            three.s[l].iter().map(|x| x.to_bits()).collect(),
        );
        assert!(a == b, "level {l} differs");
    }
}

#[test]
fn builds_are_cached_by_content() {
    let (spec, f) = load("cliff");
    let a = spec.build_features(&f, 0, 1 << 32).unwrap();
    let t = std::time::Instant::now();
    let b = spec.build_features(&f, 0, 1 << 32).unwrap();
    assert!(
        t.elapsed().as_millis() < 50,
        "second build took {:?}",
        t.elapsed()
    );
    assert!(
        std::ptr::eq(a.levels().as_ptr(), b.levels().as_ptr()),
        "the same volume is shared"
    );
    let mut g = f.clone();
    g.curves[0].constraints[0].left = -g.curves[0].constraints[0].left;
    let c = spec.build_features(&g, 0, 1 << 32).unwrap();
    assert!(
        !std::ptr::eq(a.levels().as_ptr(), c.levels().as_ptr()),
        "changed curves rebuild"
    );
}

#[test]
fn tunnel_in_a_1024_cube_stays_under_a_gigabyte() {
    // A 24 m wide tunnel winding through a 1024 m cube at 1 m voxels (1024³ nodes dense
    // would be 4 GiB for S alone, ~40 GiB with the pipeline's fields).
    let text = r#"FeatureVolume(
        curves: Inline(tunnels: [(
            path: [Abs(-20, 300, 500), Abs(300, 200, 480), Abs(700, 800, 540), Abs(1044, 600, 520)],
            width: Const(24), height: Const(18),
        )]),
        domain: ((0, 0, 0), (1023, 1023, 1023)),
        voxel: 1.0,
    )"#;
    let spec: FeatureVolumeSpec =
        karstic::voxel::spec::parse_ron(text, Path::new("<test>")).unwrap();
    let f = spec.build(Path::new("."), 0).unwrap();
    let st = f.stats();
    let fine = st.levels.last().unwrap();
    assert_eq!(fine.dims, glam::IVec3::splat(1024));
    assert!(st.peak_bytes < 1 << 30, "peak {} bytes", st.peak_bytes);
    eprintln!(
        "peak {} MiB, field {} MiB, fine bricks {}",
        st.peak_bytes >> 20,
        st.field_bytes >> 20,
        fine.bricks
    );
    let path = &spec
        .feature_set(Path::new("."))
        .unwrap()
        .resolve(&|_| None)
        .unwrap()
        .tunnels[0]
        .path;
    assert!(f.value(path.eval(0.5)) < ISO, "the tunnel is open");
    assert!(
        f.value(path.eval(0.5) + Vec3::Z * 30.0) > ISO,
        "rock above it"
    );
}

//! The S field as a `Field`: sampled soundness of its bounds (with the noise
//! displacement on), gradients against finite differences, determinism, the cache, and
//! the memory of the sparse grid on a large domain.

mod curves_util;

use std::path::Path;

use glam::Vec3;
use karstic::curves::{FeatureVolumeSpec, Features, Orientation};
use karstic::field::{Aabb, Field, Interval, Rect, T, ZBands};
use karstic::voxel::{SField, run};

fn load(name: &str) -> (FeatureVolumeSpec, Features) {
    let l = curves_util::load(name);
    (l.spec, l.features)
}

/// The ridge with noise that varies along the crest (amplitude 0 → 2.5 m, roughness
/// 0.05 → 0.2 /m): the displacement and its bounds are exercised.
fn noisy_ridge() -> SField {
    let (spec, mut f) = load("ridge");
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

struct Rng(u64);
impl Rng {
    fn f(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn point(&mut self, b: &Aabb) -> Vec3 {
        b.min + Vec3::new(self.f(), self.f(), self.f()) * b.size()
    }
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
        let a = rng.point(&around);
        let b = if rng.f() < 0.5 {
            a + (Vec3::new(rng.f(), rng.f(), rng.f()) - 0.5) * 3.0
        } else {
            rng.point(&around)
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
        let p = rng.point(&support);
        let (v, g) = f.value_grad(p);
        if (v - T).abs() < 0.05 && g.length() > 1e-3 {
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
        let c = rng.point(&around);
        let r = 0.3 + 20.0 * rng.f() * rng.f();
        let b = Aabb::around(c, r);
        let iv = f.interval(&b);
        let lb = f.lipschitz_box(&b);
        let mut prev: Option<(Vec3, f32)> = None;
        for _ in 0..60 {
            let p = rng.point(&b);
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
        let p = rng.point(&support.dilate(-2.0));
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

#[test]
fn bounds_are_sound_with_noise() {
    let f = noisy_ridge();
    assert!(f.stats().levels.len() >= 3);
    check_soundness(&f, 1, 100.0);
    // The displaced S' itself (not only σ(S'), which saturates away from the surface)
    // obeys the widened bound on close and far pairs inside the domain.
    let (mut rng, dom, ls) = (Rng(5), f.support().dilate(-0.5), f.s_lipschitz());
    let mut seen = 0.0f32;
    for i in 0..20_000 {
        let a = rng.point(&dom);
        let off = Vec3::new(rng.f(), rng.f(), rng.f()) - 0.5;
        let b = if i % 2 == 0 {
            a + off * 0.2
        } else {
            rng.point(&dom)
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
    assert!(f.value(feats.tunnels[0].path.eval(0.5)) > T);
}

#[test]
fn z_bands_contain_the_surface() {
    let f = noisy_ridge();
    let mut rng = Rng(9);
    let d = f.support();
    for _ in 0..40 {
        let c = rng.point(&d);
        let fp = Rect::new(c.truncate() - 2.0, c.truncate() + 2.0);
        let mut bands = ZBands::new();
        f.z_bands(&fp, Interval::new(d.min.z - 1.0, d.max.z + 1.0), &mut bands);
        for _ in 0..10 {
            let xy = fp.min + (fp.max - fp.min) * glam::Vec2::new(rng.f(), rng.f());
            let mut last = f.value(xy.extend(d.max.z + 1.0)) > T;
            for k in 0..400 {
                let z = d.max.z + 1.0 - k as f32 * (d.size().z + 2.0) / 400.0;
                let now = f.value(xy.extend(z)) > T;
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
        karstic::curves::spec::parse_ron(text, Path::new("<test>")).unwrap();
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
    assert!(f.value(path.eval(0.5)) < T, "the tunnel is open");
    assert!(
        f.value(path.eval(0.5) + Vec3::Z * 30.0) > T,
        "rock above it"
    );
}

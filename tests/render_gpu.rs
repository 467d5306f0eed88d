//! The GPU path: naga validates every shader; the tape evaluator against independent
//! formulas; and, when an adapter exists, the GPU against the CPU on the same tapes.

use crate::common;

use common::{
    Blobs, Rng, SigmaSphere, TUNNEL_VIEW, Terrain, assert_frames_match, assert_probes_match,
    check_segment_lipschitz, dem, gpu, tapes,
};
use glam::{Affine3A, Quat, Vec3};
use indicatif::ProgressBar;
use karstic::field::falloff::{sigma, wyvill};
use karstic::field::{Aabb, Fbm, Field, ISO};
use karstic::render::gpu::{GpuContext, SHADER_MODULES, shader_source};
use karstic::render::{Camera, Materials, Method, RenderSettings, render};
use karstic::tape::{Combine, FEATURES, Profile, Shape, Tape, TapeBuilder};

#[test]
fn every_shader_parses_and_validates_with_naga() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(karstic::render::gpu::header::SHADER_DIR);
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".wgsl"))
        .collect();
    files.sort();
    for f in &files {
        assert!(
            SHADER_MODULES
                .iter()
                .any(|(_, parts)| parts.contains(&f.as_str())),
            "crates/render/shaders/{f} belongs to no module, so nothing validates it"
        );
    }
    for (name, parts) in SHADER_MODULES {
        let src: String = parts
            .iter()
            .map(|p| std::fs::read_to_string(dir.join(p)).unwrap())
            .collect();
        if *name == "trace" {
            assert_eq!(
                src,
                shader_source(),
                "the embedded source is the files on disk"
            );
        }
        let module = naga::front::wgsl::parse_str(&src)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&src)));
        let info = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::default(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&src)));
        // The pipelines a tape compiles (Tape::features): every feature alone, none, all.
        let n = FEATURES.len() as u32;
        for bits in (0..n).map(|k| 1 << k).chain([0, (1 << n) - 1]) {
            let mut constants = naga::back::PipelineConstants::default();
            for (k, v) in Tape::feature_constants(bits) {
                constants.insert(k.to_string(), v);
            }
            naga::back::pipeline_constants::process_overrides(&module, &info, None, &constants)
                .unwrap_or_else(|e| panic!("{name} with features {bits:b}: {e}"));
        }
        for entry in ["render", "probe", "fbm_probe"] {
            assert!(
                module.entry_points.iter().any(|e| e.name == entry),
                "{name} lacks {entry}"
            );
        }
    }
}

/// A tape using every op: a blend of a capsule and a warped σ-box, minus a sphere, in
/// union with a constant-shifted segment, all under guards; and its direct formula.
fn mixed() -> (Tape, impl Fn(Vec3) -> f32) {
    let warp = Affine3A::from_scale_rotation_translation(
        Vec3::new(1.5, 0.8, 1.0),
        Quat::from_rotation_z(0.6),
        Vec3::new(2.0, 1.0, 0.5),
    );
    let (ca, cb) = (Vec3::new(-3.0, 0.0, 0.0), Vec3::new(3.0, 1.0, 1.0));
    let ball = Vec3::new(1.0, 0.5, 1.2);
    let (sa, sb) = (Vec3::new(-2.0, -4.0, 0.0), Vec3::new(2.0, -4.0, 2.0));
    let mut t = TapeBuilder::new();
    let g = t.guard_begin(Aabb::new(Vec3::splat(-20.0), Vec3::splat(20.0)));
    t.primitive(
        Shape::Capsule {
            a: ca,
            b: cb,
            radius: 0.5,
        },
        Profile::Wyvill {
            radius: 2.0,
            energy: 1.2,
        },
    );
    t.warp_begin(warp).unwrap();
    t.primitive(
        Shape::Box {
            center: Vec3::ZERO,
            half: Vec3::new(1.0, 2.0, 0.7),
        },
        Profile::Sigma { radius: 0.8 },
    );
    t.warp_end().unwrap();
    t.combine(Combine::Blend).unwrap();
    t.primitive(
        Shape::Sphere {
            center: ball,
            radius: 1.0,
        },
        Profile::Wyvill {
            radius: 2.5,
            energy: 2.0,
        },
    );
    t.combine(Combine::Difference).unwrap();
    t.guard_end(g).unwrap();
    t.primitive(
        Shape::Segment(sa, sb),
        Profile::Wyvill {
            radius: 1.5,
            energy: 0.9,
        },
    );
    t.constant(0.1);
    t.primitive(
        Shape::Point(sb),
        Profile::Wyvill {
            radius: 3.0,
            energy: 1.0,
        },
    );
    t.combine(Combine::Intersection).unwrap();
    t.combine(Combine::Blend).unwrap();
    t.combine(Combine::Union).unwrap();
    let tape = t.finish().unwrap();
    let inv = warp.inverse();
    let f = move |p: Vec3| {
        let seg = |a: Vec3, b: Vec3| {
            let ab = b - a;
            let h = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
            (p - a - ab * h).length()
        };
        let capsule = 1.2 * wyvill((seg(ca, cb) - 0.5).max(0.0) / 2.0);
        let q = inv.transform_point3(p);
        let d = q.abs() - Vec3::new(1.0, 2.0, 0.7);
        let sd = d.max(Vec3::ZERO).length() + d.max_element().min(0.0);
        let boxed = sigma(-sd, 0.8);
        let sphere = 2.0 * wyvill((p.distance(ball) - 1.0).max(0.0) / 2.5);
        let a = (capsule + boxed).min(2.0 * ISO - sphere);
        let b = 0.9 * wyvill(seg(sa, sb) / 1.5) + 0.1f32.min(wyvill(p.distance(sb) / 3.0));
        a.max(b)
    };
    (tape, f)
}

#[test]
fn tapes_evaluate_the_fields_they_encode() {
    let mut rng = Rng(11);
    let (tape, f) = mixed();
    for _ in 0..5000 {
        let p = Vec3::new(
            rng.range(-8.0, 8.0),
            rng.range(-8.0, 8.0),
            rng.range(-4.0, 5.0),
        );
        assert!(
            (tape.value(p) - f(p)).abs() < 1e-5,
            "mixed tape at {p}: {} vs {}",
            tape.value(p),
            f(p)
        );
    }
    let blobs = Blobs::in_ball(300, 8.0, 1.5, 1.0, 5);
    let bt = tapes::blobs(&blobs);
    let s = SigmaSphere {
        center: Vec3::new(1.0, 2.0, 3.0),
        radius: 2.0,
        falloff: 0.7,
    };
    let st = tapes::sigma_sphere(&s);
    for _ in 0..5000 {
        let p = rng.in_ball(11.0);
        assert!((bt.value(p) - blobs.value_brute(p)).abs() < 1e-4);
        assert!((st.value(p) - s.value(p)).abs() < 1e-6);
    }
    assert!(
        bt.support().contains_box(&blobs.support()) && blobs.support().contains_box(&bt.support())
    );
}

#[test]
fn tape_bounds_are_sound() {
    let (tape, _) = mixed();
    check_segment_lipschitz(
        &tape,
        &Aabb::new(Vec3::splat(-9.0), Vec3::splat(9.0)),
        30_000,
        21,
    );
    let bt = tapes::blobs(&Blobs::in_ball(200, 8.0, 1.5, 1.0, 6));
    check_segment_lipschitz(&bt, &bt.support().dilate(1.0), 20_000, 22);
    let tt = tapes::terrain(&Terrain::new(60.0, 8.0, 3.0), 64);
    check_segment_lipschitz(&tt, &tt.support().dilate(2.0), 20_000, 23);
    let dt = tapes::dem_with_cave(&dem::jacksboro());
    check_segment_lipschitz(&dt, &dt.support(), 20_000, 25);
    // Outside the support every tape is 0.
    let mut rng = Rng(24);
    for t in [&tape, &bt, &tt] {
        let b = t.support();
        for _ in 0..2000 {
            let p = b.center()
                + (rng.in_ball(1.0).normalize_or_zero()) * b.radius() * rng.range(1.01, 2.0);
            assert_eq!(t.value(p), 0.0, "non-zero outside the support at {p}");
        }
    }
}

#[test]
fn malformed_tapes_are_errors() {
    let mut t = TapeBuilder::new();
    assert!(t.combine(Combine::Blend).is_err());
    t.constant(1.0);
    t.constant(2.0);
    assert!(t.finish().is_err(), "two values left");
    let mut t = TapeBuilder::new();
    let g = t.guard_begin(Aabb::around(Vec3::ZERO, 1.0));
    t.primitive(
        Shape::Point(Vec3::ZERO),
        Profile::Wyvill {
            radius: 5.0,
            energy: 1.0,
        },
    );
    assert!(t.guard_end(g).is_err(), "guard smaller than the support");
    let mut t = TapeBuilder::new();
    assert!(
        t.warp_begin(Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0)))
            .is_err()
    );
    let mut t = TapeBuilder::new();
    for _ in 0..40 {
        t.constant(1.0);
    }
    for _ in 0..39 {
        t.combine(Combine::Blend).unwrap();
    }
    assert!(t.finish().is_err(), "deeper than the GPU stack");
}

#[test]
fn gpu_probes_match_the_cpu_tape() {
    let Some(ctx) = gpu() else { return };
    let (tape, _) = mixed();
    let tt = tapes::terrain(&Terrain::new(60.0, 8.0, 3.0), 64);
    let mut rng = Rng(31);
    for (t, scale) in [(&tape, 9.0), (&tt, 70.0)] {
        let pts: Vec<(Vec3, f32)> = (0..4000)
            .map(|_| {
                (
                    rng.in_ball(scale),
                    if rng.f32() < 0.3 {
                        0.0
                    } else {
                        rng.range(0.0, 0.3 * scale)
                    },
                )
            })
            .collect();
        assert_probes_match(ctx, t, &pts);
    }
}

fn compare(
    name: &str,
    tape: &Tape,
    ctx: &GpuContext,
    (w, h): (u32, u32),
    method: Method,
    min_hits: usize,
) {
    let cam = Camera::frame(&tape.support(), 40.0, w, h).unwrap();
    let settings = RenderSettings::for_scene(&tape.support(), &cam, method);
    let start = std::time::Instant::now();
    let cpu = render(tape, &cam, &settings, &ProgressBar::hidden());
    let cpu_s = start.elapsed().as_secs_f64();
    let gpu = ctx.render(tape, &cam, &settings).unwrap();
    eprintln!(
        "{name}: CPU {cpu_s:.3} s, GPU {:.3} s; hits CPU {} GPU {}",
        start.elapsed().as_secs_f64() - cpu_s,
        cpu.hits(),
        gpu.hits()
    );
    assert!(cpu.hits() >= min_hits, "{name}: the scene is in view");
    assert_frames_match(name, &cpu, &gpu);
}

/// Rendering in passes of a few evaluations per pixel (each pixel saving its state and
/// resuming in the next dispatch, as on lavapipe when its loop budget runs out) gives the
/// image of one pass, bit for bit, with and without shadows.
#[test]
fn renders_in_passes_equal_one_pass() {
    let Some(ctx) = gpu() else { return };
    let tape = mixed().0;
    for shadows in [false, true] {
        let cam = Camera::frame(&tape.support(), 40.0, 40, 28).unwrap();
        let mut settings = RenderSettings::for_scene(&tape.support(), &cam, Method::Segment);
        settings.shading.shadows = shadows;
        let one = ctx.render(&tape, &cam, &settings).unwrap();
        assert!(one.hits() > 40, "{} hits", one.hits());
        for per_pass in [1, 3, 17] {
            let split = ctx
                .render_in_passes(&tape, &cam, &settings, per_pass)
                .unwrap();
            assert_eq!(one.rgba, split.rgba, "{per_pass} evaluations per pass");
            assert_eq!(one.steps, split.steps, "{per_pass} evaluations per pass");
            assert!(
                one.depth
                    .iter()
                    .zip(&split.depth)
                    .all(|(a, b)| a == b || (a.is_infinite() && b.is_infinite())),
                "{per_pass} evaluations per pass"
            );
        }
    }
}

#[test]
fn gpu_renders_match_the_cpu() {
    let Some(ctx) = gpu() else { return };
    compare(
        "blobs",
        &tapes::blobs(&Blobs::in_ball(200, 8.0, 1.5, 1.0, 8)),
        ctx,
        (96, 72),
        Method::Segment,
        600,
    );
    compare(
        "terrain",
        &tapes::terrain(&Terrain::new(60.0, 8.0, 3.0), 96),
        ctx,
        (96, 72),
        Method::Segment,
        1400,
    );
    compare("mixed", &mixed().0, ctx, (80, 60), Method::Segment, 180);
    compare(
        "jacksboro DEM with a tunnel",
        &tapes::dem_with_cave(&dem::jacksboro()),
        ctx,
        (96, 54),
        Method::Segment,
        2000,
    );
    compare(
        "sphere tracing",
        &tapes::sigma_sphere(&SigmaSphere {
            center: Vec3::ZERO,
            radius: 3.0,
            falloff: 1.0,
        }),
        ctx,
        (64, 48),
        Method::Sphere,
        250,
    );
}

/// The WGSL port of the seeded simplex fBm against `Fbm::value` (same hash, gradients and
/// corner order in f32): equal within 2e-5 (the range is [−1, 1]) at points near the
/// origin, around the first octave's lattice, and far out (DEM coordinates), for seeds
/// with high bits set, 1 to 12 octaves and several wavelengths.
#[test]
fn gpu_noise_matches_the_cpu_noise() {
    let Some(ctx) = gpu() else { return };
    let mut rng = Rng(77);
    for (seed, wavelength, octaves) in [
        (0u32, 1.0f32, 1u32),
        (7, 3.0, 4),
        (0xdead_beef, 9.0, 6),
        (u32::MAX, 0.37, 12),
        (123_456, 40.0, 3),
    ] {
        let f = Fbm::with(seed, wavelength, octaves);
        let pts: Vec<Vec3> = (0..20_000)
            .map(|i| match i % 3 {
                0 => rng.in_ball(4.0 * wavelength),
                1 => rng.in_ball(100.0 * wavelength),
                _ => Vec3::new(4000.0, 5000.0, 700.0) + rng.in_ball(500.0),
            })
            .collect();
        let got = ctx.probe_fbm(&f, &pts).unwrap();
        let (mut worst, mut spread) = (0.0f32, 0.0f32);
        for (&p, &g) in pts.iter().zip(&got) {
            let c = f.value(p);
            worst = worst.max((g - c).abs());
            spread = spread.max(c.abs());
            assert!(
                (g - c).abs() <= 2e-5,
                "seed {seed:#x}, λ {wavelength}, {octaves} octaves at {p}: GPU {g}, CPU {c}"
            );
        }
        eprintln!("fbm seed {seed:#x} λ {wavelength} o {octaves}: max |GPU − CPU| = {worst:e}");
        assert!(spread > 0.3, "the noise is not trivial ({spread})");
    }
}

/// The main job's tree on the GPU with its materials: the terrain travels with the tape
/// (`Tape::with_ground`), so rock on the features, soil, grass and the dry-grass patches,
/// the occlusion and the sun's disk come out as on the CPU.
#[test]
fn gpu_materials_match_the_cpu_on_the_main_job() {
    let Some(ctx) = gpu() else { return };
    let file = karstic::scene::load(std::path::Path::new("trees/jacksboro_caves.ron")).unwrap();
    let compiled = file.compile().unwrap();
    let tape = Tape::from_tree(&compiled.tree).unwrap();
    // The shader has no raster of talus and streams (`gpu::unsupported`): without it.
    let materials = Materials {
        top: None,
        ..karstic::picture::materials(&file.scene, &compiled.tree, compiled.ground)
    };
    let region = karstic::picture::scene_box(&file.scene, &compiled.tree);
    // Close to the arch: feature rock, ground and sky in one frame.
    let cam = Camera::look_at(
        Vec3::new(4900.0, 4380.0, 780.0),
        Vec3::new(4620.0, 4950.0, 640.0),
        30.0,
        64,
        36,
    )
    .unwrap();
    let settings = RenderSettings {
        materials,
        ..RenderSettings::for_scene(&region, &cam, Method::Segment)
    };
    let cpu = render(&tape, &cam, &settings, &ProgressBar::hidden());
    let gpu = ctx.render(&tape, &cam, &settings).unwrap();
    assert!(cpu.hits() > 1000, "{} hits", cpu.hits());
    assert_frames_match("main job with materials", &cpu, &gpu);
    // Into the tunnel's mouth: the sky occlusion at cave scale.
    let (eye, target) = TUNNEL_VIEW;
    let cam = Camera::look_at(eye, target, 40.0, 64, 36).unwrap();
    let settings = RenderSettings {
        trace: settings.trace.with_pixel_angle(cam.pixel_angle()),
        ..settings
    };
    let cpu = render(&tape, &cam, &settings, &ProgressBar::hidden());
    let gpu = ctx.render(&tape, &cam, &settings).unwrap();
    assert_frames_match("main job into the tunnel", &cpu, &gpu);
}

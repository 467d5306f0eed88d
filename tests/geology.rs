//! The geology (Paris et al. 2019 §4) and the erosion node (§6): strata follow their
//! plane, faults jump only on their domain's boundary, bounds are sound, tree-file errors
//! carry positions, the section PNG shows the strata, and everything is deterministic.

use std::path::Path;
use std::process::Command;

use glam::{Vec2, Vec3};
use karstic::field::Resistance;
use karstic::field::{Aabb, Bound, Field};
use karstic::geology::section::{AIR, HARD, OUTLINE, SOFT, Section};
use karstic::geology::{Geology, GeologySpec};
use karstic::value::ron_options;

use crate::common::{Rng, check_segment_lipschitz, check_z_bands};

const CLIFF: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/trees/strata_cliff.ron");

fn geology(text: &str) -> Geology {
    let spec: GeologySpec = ron_options().from_str(text).expect("a valid geology");
    Geology::from_spec(&spec, 7)
}

/// Layers 4 m hard (0.9) and 2 m soft (0.1), ramps 0.5 m wide, on a plane through
/// (0, 0, 3) tilted towards +x.
const TILTED: &str = r#"(root: Strata(point: (0, 0, 3), normal: (0.3, 0, 1),
    profile: Layers(layers: [(thickness: 4, resistance: 0.9), (thickness: 2, resistance: 0.1)],
                    transition: 0.5)))"#;

#[test]
fn strata_resistance_follows_the_plane() {
    let g = geology(TILTED);
    let n = Vec3::new(0.3, 0.0, 1.0).normalize();
    let (u, v) = (Vec3::Y, n.cross(Vec3::Y));
    let origin = Vec3::new(0.0, 0.0, 3.0);
    let mut rng = Rng(3);
    for _ in 0..500 {
        // Along the plane the resistance does not change.
        let d = rng.range(-30.0, 30.0);
        let p = origin + n * d;
        let q = p + u * rng.range(-200.0, 200.0) + v * rng.range(-200.0, 200.0);
        assert!(
            (g.resistance(p) - g.resistance(q)).abs() < 1e-4,
            "ρ changed along the plane at d = {d}: {} vs {}",
            g.resistance(p),
            g.resistance(q)
        );
        // Across it, the layer's value away from the ramps (period 6 m).
        let k = d.rem_euclid(6.0);
        let expect = if (0.3..3.7).contains(&k) {
            Some(0.9)
        } else if (4.3..5.7).contains(&k) {
            Some(0.1)
        } else {
            None
        };
        if let Some(e) = expect {
            assert!(
                (g.resistance(p) - e).abs() < 1e-4,
                "ρ at d = {d}: {}",
                g.resistance(p)
            );
        }
    }
}

/// Sound ranges and Lipschitz bounds of a geology over random boxes in `region`.
fn check_geology_bounds(g: &Geology, region: &Aabb, seed: u64) {
    let mut rng = Rng(seed);
    for _ in 0..300 {
        let c = rng.in_box(region);
        let half = Vec3::new(
            rng.range(0.1, 8.0),
            rng.range(0.1, 8.0),
            rng.range(0.1, 8.0),
        );
        let b = Aabb::new(c - half, c + half);
        let Bound {
            range: iv,
            lipschitz: l,
        } = g.bound(&b);
        let ps: Vec<Vec3> = (0..40).map(|_| rng.in_box(&b)).collect();
        for w in ps.windows(2) {
            let (p, q) = (w[0], w[1]);
            let v = g.value(p);
            assert!(iv.contains(v), "ρ = {v} at {p} outside {iv:?} over {b:?}");
            let dv = (v - g.value(q)).abs();
            assert!(
                dv <= l * p.distance(q) * 1.001 + 1e-5,
                "|Δρ| = {dv} > {l}·{}",
                p.distance(q)
            );
        }
    }
}

/// Hard folded layers, a softened sphere, a taper and a fault dipping 60°.
const FAULTED: &str = r#"(root: Fault(
    point: (0, 0, 0), normal: (0.866, 0, 0.5), slip: (0, 0, -3.1),
    region: (min: (-50, -20, -40), max: (50, 20, 40)),
    child: Blend([
        Taper(axis: (0, 1, 0), from: -20, to: 20, factor: (0.8, 1.4), child:
            Fold(turbulence: (amplitude: 1.5, wavelength: 12, octaves: 2),
                 child: Strata(profile: Layers(layers: [(thickness: 5, resistance: 0.95),
                                                       (thickness: 3, resistance: 0.15)])))),
        Turbulence(base: 0, noise: (amplitude: 0.05, wavelength: 2)),
        Local(shape: Curve(points: [(-10, -5, 0), (0, 0, 4), (10, 5, 0)]), falloff: 4, energy: -0.4),
    ]),
))"#;

#[test]
fn geology_bounds_are_sound() {
    let region = Aabb::new(Vec3::splat(-60.0), Vec3::splat(60.0));
    check_geology_bounds(&geology(FAULTED), &region, 11);
    check_geology_bounds(&geology(TILTED), &region, 12);
}

#[test]
fn faults_jump_only_on_their_domain_boundary() {
    let g = geology(FAULTED);
    let n = Vec3::new(0.866, 0.0, 0.5).normalize();
    let mut rng = Rng(5);
    let (mut jumps, mut crossings) = (0, 0);
    for _ in 0..2000 {
        let p = Vec3::new(
            rng.range(-45.0, 45.0),
            rng.range(-15.0, 15.0),
            rng.range(-35.0, 35.0),
        );
        let step = 0.01;
        // Straddling the fault plane (inside the region): the layers are offset by a slip
        // that is not a whole period, so the resistance jumps at many places.
        let on = p - n * n.dot(p);
        let (a, b) = (on - n * step, on + n * step);
        if Aabb::new(Vec3::new(-50.0, -20.0, -40.0), Vec3::new(50.0, 20.0, 40.0)).contains(b) {
            crossings += 1;
            if (g.value(a) - g.value(b)).abs() > 0.2 {
                jumps += 1;
            }
            assert_eq!(
                g.bound(&Aabb::new(a, b)).lipschitz,
                f32::INFINITY,
                "a box across the fault has no finite Lipschitz bound"
            );
        }
        // Away from the boundary the field is continuous: the local bound holds.
        if n.dot(p).abs() > 0.5 {
            let q = p + Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ) * 0.2;
            if n.dot(q).signum() == n.dot(p).signum() {
                let l = g.bound(&Aabb::new(p, q)).lipschitz;
                assert!(l.is_finite(), "finite away from the fault at {p}");
                assert!((g.value(p) - g.value(q)).abs() <= l * p.distance(q) + 1e-5);
            }
        }
    }
    assert!(crossings > 1000, "{crossings} crossings sampled");
    assert!(
        jumps * 4 > crossings,
        "only {jumps} of {crossings} crossings jump"
    );
    // Outside the region the fault moves nothing: no jump across the plane.
    for z in [-70.0f32, 70.0] {
        let on = Vec3::new(-z * 0.5 / 0.866, 0.0, z);
        let (a, b) = (on - n * 0.01, on + n * 0.01);
        assert!(
            (g.value(a) - g.value(b)).abs() < 0.05,
            "jump outside the region at z = {z}"
        );
    }
}

#[test]
fn erosion_node_bounds_are_sound() {
    let file = karstic::scene::load(CLIFF).unwrap();
    let tree = file.compile().unwrap().tree;
    let region = Aabb::new(Vec3::new(-100.0, -90.0, -10.0), Vec3::new(90.0, 90.0, 90.0));
    // Intervals over random boxes, every node.
    let mut rng = Rng(21);
    for _ in 0..200 {
        let c = rng.in_box(&region);
        let half = Vec3::new(
            rng.range(0.2, 12.0),
            rng.range(0.2, 12.0),
            rng.range(0.2, 12.0),
        );
        let b = Aabb::new(c - half, c + half);
        let iv = tree.interval(&b);
        let lb = tree.lipschitz_box(&b);
        let ps: Vec<Vec3> = (0..24).map(|_| rng.in_box(&b)).collect();
        for w in ps.windows(2) {
            let v = tree.value(w[0]);
            assert!(iv.lo - 1e-4 <= v && v <= iv.hi + 1e-4, "{v} outside {iv:?}");
            let dv = (v - tree.value(w[1])).abs();
            assert!(
                dv <= lb * w[0].distance(w[1]) * 1.001 + 1e-5,
                "box Lipschitz {lb}: {dv}"
            );
        }
    }
    check_segment_lipschitz(&tree, &region, 3000, 22);
    let (crossings, _) = check_z_bands("strata_cliff", &tree, 12, 6, 23);
    assert!(crossings > 0);
    // Where the rock is soft the surface recedes: the field drops by up to the strength.
    let g = file.compile().unwrap().geology;
    let soft = Vec3::new(10.0, 0.0, 11.0);
    assert!(
        g.value(soft) < 0.3,
        "the lowest soft stratum at {soft}: ρ = {}",
        g.value(soft)
    );
}

#[test]
fn erosion_has_no_gpu_encoding_and_says_so() {
    let tree = karstic::scene::load(CLIFF).unwrap().compile().unwrap().tree;
    let e = karstic::tape::tape_from_tree(&tree).unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(e, karstic::tape::TapeError::NoEncoding { .. }),
        "{msg}"
    );
    assert!(msg.contains("the erosion node \"erosion\""), "{msg}");
}

#[test]
fn geology_errors_carry_positions() {
    let scene = |geology: &str| {
        format!(
            "(\n    version: 1,\n    geology: (\n        root: {geology},\n    ),\n    root: Primitive(shape: Sphere(center: (0, 0, 0), radius: 1), falloff: 1),\n)\n"
        )
    };
    for (geology, expect) in [
        (
            "Strata(profile: Band(half_width: -2, resistance: 1))",
            "expected a number > 0",
        ),
        (
            "Strata(profile: Layers(layers: [(thickness: 2, resistance: 0.5)]))",
            "at least two layers",
        ),
        (
            "Strata(profile: Layers(layers: [(thickness: 2, resistance: 0.5), (thickness: 1, resistance: 0.1)], transition: 1.5))",
            "wider than the thinnest layer",
        ),
        (
            "Stratum(profile: Band(half_width: 2, resistance: 1))",
            "variant named `Stratum`",
        ),
        ("Constant(1.5)", "expected a number in [0, 1]"),
        (
            "Taper(axis: (0, 0, 1), from: 0, to: 10, factor: (1, 2), child: Constant(0.5))",
            "horizontal",
        ),
    ] {
        let text = scene(geology);
        let e = karstic::scene::parse_scene(&text, Path::new("bad.ron")).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.starts_with("bad.ron:4:"),
            "{geology}: no position of line 4 in {msg}"
        );
        assert!(msg.contains(expect), "{geology}: {msg}");
    }
    let text = "(version: 1, root: Erode(strength: 0.3, region: (min: (0, 0, 0), max: (1, 1, 1)),\n    child: Primitive(shape: Sphere(center: (0, 0, 0), radius: 1), falloff: 1), extra: 1))";
    let e = karstic::scene::parse_scene(text, Path::new("bad.ron")).unwrap_err();
    assert!(e.to_string().starts_with("bad.ron:2:"), "{e}");
}

/// Horizontal layers: soft (0.1) from z = 0 to 10, hard (0.9) from 10 to 20, repeating;
/// a slab whose top is at z ≈ 25.
const LAYERED: &str = r#"(
    version: 1,
    seed: 4,
    geology: (root: Strata(profile: Layers(layers: [(thickness: 10, resistance: 0.1),
                                                    (thickness: 10, resistance: 0.9)],
                                           transition: 1))),
    root: Primitive(shape: Box(center: (0, 0, 0), half_size: (200, 200, 25)), falloff: 2),
)"#;

fn karstic() -> Command {
    Command::new(env!("CARGO_BIN_EXE_karstic"))
}

fn pixel(img: &image::RgbaImage, x: u32, y: u32) -> [u8; 3] {
    let p = img.get_pixel(x, y).0;
    [p[0], p[1], p[2]]
}

#[test]
fn section_png_shows_strata_and_outline() {
    let dir = tempfile::tempdir().unwrap();
    let tree = dir.path().join("layered.ron");
    std::fs::write(&tree, LAYERED).unwrap();
    let out = dir.path().join("cut.png");
    // 100 m wide, z from −5 to 35: 200 × 80 pixels, 0.5 m each.
    let run = |threads: &str, out: &Path| {
        let o = karstic()
            .env("RAYON_NUM_THREADS", threads)
            .args(["geology", "section"])
            .arg(&tree)
            .args([
                "--plane",
                "-50",
                "0",
                "50",
                "0",
                "--z",
                "-5",
                "35",
                "--width",
                "200",
                "--outline",
                "-o",
            ])
            .arg(out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    run("1", &out);
    let img = image::open(&out).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (200, 80));
    // Row j is at z = 35 − 0.5·(j + ½).
    let row = |z: f32| ((35.0 - z) / 0.5 - 0.5).round() as u32;
    assert_eq!(
        pixel(&img, 100, row(5.0)),
        Section::rock_colour(0.1),
        "soft layer"
    );
    assert_eq!(
        pixel(&img, 100, row(15.0)),
        Section::rock_colour(0.9),
        "hard layer"
    );
    assert_eq!(pixel(&img, 100, row(30.0)), AIR, "air above the slab");
    // The slab's top (g(d/2) = ½ at d ≈ 0.9 m above z = 25) is outlined in every column.
    for x in [0, 57, 100, 199] {
        let outlined = (row(27.0)..=row(25.0)).any(|j| pixel(&img, x, j) == OUTLINE);
        assert!(outlined, "no outline in column {x}");
    }
    // Pale is resistant.
    let lum = |c: [u8; 3]| c.iter().map(|&v| v as u32).sum::<u32>();
    assert!(lum(Section::rock_colour(0.9)) > lum(Section::rock_colour(0.1)));
    assert_eq!(Section::rock_colour(0.0), SOFT);
    assert_eq!(Section::rock_colour(1.0), HARD);
    // Same bytes on any number of threads; no temporary file left beside the output.
    let again = dir.path().join("again.png");
    run("2", &again);
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&again).unwrap());
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 3, "{names:?}");
}

#[test]
fn section_refuses_bad_cuts() {
    let b = 1 << 30;
    assert!(Section::new(Vec2::ZERO, Vec2::ZERO, (0.0, 1.0), (10, 10), b).is_err());
    assert!(Section::new(Vec2::ZERO, Vec2::X, (1.0, 1.0), (10, 10), b).is_err());
    assert!(Section::new(Vec2::ZERO, Vec2::X, (0.0, 1.0), (0, 10), b).is_err());
    assert!(Section::new(Vec2::ZERO, Vec2::X, (0.0, 1.0), (100_000, 100_000), 1 << 20).is_err());
}

#[test]
fn geology_and_erosion_are_deterministic() {
    let a = karstic::scene::load(CLIFF).unwrap().compile().unwrap();
    let b = karstic::scene::load(CLIFF).unwrap().compile().unwrap();
    let mut rng = Rng(8);
    let region = Aabb::new(Vec3::new(-100.0, -90.0, -10.0), Vec3::new(90.0, 90.0, 90.0));
    for _ in 0..500 {
        let p = rng.in_box(&region);
        assert_eq!(a.geology.value(p).to_bits(), b.geology.value(p).to_bits());
        assert_eq!(a.tree.value(p).to_bits(), b.tree.value(p).to_bits());
    }
    // A different scene seed moves the noise.
    let mut file = karstic::scene::load(CLIFF).unwrap();
    file.scene.seed += 1;
    let c = file.compile().unwrap();
    let differ = (0..200)
        .map(|_| rng.in_box(&region))
        .filter(|&p| a.geology.value(p) != c.geology.value(p))
        .count();
    assert!(
        differ > 100,
        "only {differ} of 200 points changed with the seed"
    );
}

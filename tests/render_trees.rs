//! The scenes of `trees/` through the renderer: their GPU tapes against the compiled trees
//! (values, CPU images and, with an adapter, GPU images), and the traced depth of the trees
//! against ray casting their Marching Cubes meshes.

use crate::common;

use std::path::{Path, PathBuf};

use common::{Rng, assert_frames_match, assert_probes_match, depth_agreement, gpu};
use glam::Vec3;
use indicatif::ProgressBar;
use karstic::dem::{Heightfield, HeightfieldField, ImplicitParams, Interpolation};
use karstic::field::{Aabb, Field, T, Tree, TreeBuilder};
use karstic::mesh::{GridSpec, MeshOptions, polygonize};
use karstic::render::raycast::MeshRaycaster;
use karstic::render::trace::TraceParams;
use karstic::render::{Camera, Method, RenderSettings, cpu, render};
use karstic::tape::{Tape, TapeError, tape_from_tree};

/// The scenes `trees/*.ron` and `trees/curves/*.ron`, sorted.
fn tree_files() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees");
    let mut files: Vec<PathBuf> = [root.clone(), root.join("curves")]
        .iter()
        .flat_map(|dir| std::fs::read_dir(dir).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    files.sort();
    assert!(files.len() >= 18, "{files:?}");
    files
}

fn compile(path: &Path) -> Tree {
    karstic::scene::load(path)
        .and_then(|s| s.compile())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .tree
}

/// The scene's path under `trees/`, without the extension (`curves/arch`).
fn name(path: &Path) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees");
    let rel = path.strip_prefix(&root).unwrap_or(path).with_extension("");
    rel.to_string_lossy().into_owned()
}

/// `(name, tree, tape)` of every scene: each must encode (compiled once per test binary,
/// the Feature Curve scenes run the voxel pipeline).
fn scenes() -> &'static [(String, Tree, Tape)] {
    static SCENES: std::sync::OnceLock<Vec<(String, Tree, Tape)>> = std::sync::OnceLock::new();
    SCENES.get_or_init(|| {
        let encoded: Vec<_> = tree_files()
            .into_iter()
            .map(|path| {
                let tree = compile(&path);
                let tape = tape_from_tree(&tree)
                    .unwrap_or_else(|e| panic!("{}: no GPU tape: {e}", name(&path)));
                (name(&path), tree, tape)
            })
            .collect();
        encoded
    })
}

/// The scenes with a surface (all but an empty Feature Curve volume).
fn solid_scenes() -> impl Iterator<Item = &'static (String, Tree, Tape)> {
    scenes().iter().filter(|s| !s.1.support().is_empty())
}

/// The box of the solid `f > T`, from the grid points of a 64³ lattice over the support
/// that are inside, grown by one lattice step (clamped to the support): what the views
/// frame, so a scene whose support is much larger than its solid (the floating island,
/// the intersection of two heightfields) fills the image.
fn solid_box(tree: &Tree) -> Aabb {
    let s = tree.support();
    let step = s.size() / 63.0;
    let mut b = Aabb::EMPTY;
    for k in 0..64 {
        for j in 0..64 {
            for i in 0..64 {
                let p = s.min + Vec3::new(i as f32, j as f32, k as f32) * step;
                if tree.value(p) > T {
                    b = b.include(p);
                }
            }
        }
    }
    assert!(!b.is_empty(), "no solid on the lattice");
    Aabb {
        min: (b.min - step).max(s.min),
        max: (b.max + step).min(s.max),
    }
}

/// A 96 × 64 view framing the solid, and the render settings for the tree.
fn view(tree: &Tree) -> (Camera, RenderSettings) {
    let cam = Camera::frame(&solid_box(tree), 40.0, 96, 64).unwrap();
    let settings = RenderSettings::for_scene(&tree.support(), &cam, Method::Segment);
    (cam, settings)
}

fn point_in(rng: &mut Rng, b: &Aabb) -> Vec3 {
    b.min + Vec3::new(rng.f32(), rng.f32(), rng.f32()) * b.size()
}

/// Points spread over the tree: uniform in the root's support and in the supports of
/// random nodes, plus points on the surface `f = T` found by bisecting between samples
/// on either side of it.
fn sample_points(tree: &Tree, n: usize, seed: u64) -> (Vec<Vec3>, usize) {
    let mut rng = Rng(seed);
    // (A constant's "everywhere" is ±f32::MAX: finite corners, infinite size.)
    let finite = |b: &Aabb| !b.is_empty() && b.size().is_finite();
    let boxes: Vec<Aabb> = (0..tree.nodes().len() as u32)
        .map(|id| tree.info(id).support)
        .filter(finite)
        .collect();
    let root = tree.support();
    assert!(finite(&root), "support {root:?}");
    let mut pts = Vec::with_capacity(n);
    let mut surface = 0;
    while pts.len() < n {
        let b = if rng.f32() < 0.5 {
            root.dilate(0.05 * root.radius())
        } else {
            boxes[(rng.next_u64() % boxes.len() as u64) as usize]
        };
        let (p, q) = (point_in(&mut rng, &b), point_in(&mut rng, &b));
        pts.push(p);
        let (fp, fq) = (tree.value(p) - T, tree.value(q) - T);
        if fp * fq < 0.0 {
            let (mut a, mut z) = (p, q);
            for _ in 0..30 {
                let m = 0.5 * (a + z);
                if (tree.value(m) - T) * fp > 0.0 {
                    a = m;
                } else {
                    z = m;
                }
            }
            pts.push(a);
            surface += 1;
        }
    }
    (pts, surface)
}

/// Every scene of `trees/` and `trees/curves/` encodes; its tape equals its tree at
/// points spread over it and on its surface, and the tape's ball bounds are sound.
#[test]
fn tapes_of_the_scenes_equal_their_trees() {
    for (name, tree, tape) in scenes() {
        if tree.support().is_empty() {
            // A Feature Curve volume without a surface (guidance curves alone): 0.
            assert!(
                tape.instrs.len() == 1 && tape.value(Vec3::ZERO) == 0.0,
                "{name}: an empty field is the constant 0"
            );
            continue;
        }
        let (pts, surface) = sample_points(tree, 20_000, 7);
        assert!(surface >= 500, "{name}: only {surface} surface points");
        let mut between = 0;
        for &p in &pts {
            let (v, t) = (tree.value(p), tape.value(p));
            between += usize::from(v > 1e-3 && (v - 2.0 * T).abs() > 1e-3 && v < 0.999);
            assert!(
                (v - t).abs() <= 1e-4 * v.abs().max(1.0),
                "{name} at {p}: tree {v}, tape {t}"
            );
        }
        assert!(
            between * 20 >= pts.len(),
            "{name}: only {between} points where the value is not saturated"
        );
        // Its ball bounds are sound on random segments (the S-field leaves' bound from the
        // value at the centre included).
        common::check_segment_lipschitz(tape, &tree.support(), 4000, 17);
        // The tape's support is the tree's (the encoder passes the cached supports on).
        let (a, b) = (tape.support(), tree.support());
        assert!(b.contains_box(&a), "{name}: tape support {a:?} ⊄ {b:?}");
        assert!(
            (a.size() - b.size()).abs().max_element() <= 1e-4 * b.size().max_element(),
            "{name}: tape support {a:?} vs tree {b:?}"
        );
        eprintln!(
            "{name}: {} instructions, {} params, {} heights",
            tape.instrs.len(),
            tape.params.len(),
            tape.heights.len()
        );
    }
}

/// The CPU images of a tree and of its tape: the tape's finite-difference normals and
/// rounding make the only differences.
#[test]
fn tape_images_match_tree_images_on_the_cpu() {
    for (name, tree, tape) in solid_scenes() {
        let (cam, settings) = view(tree);
        let a = render(tree, &cam, &settings, &ProgressBar::hidden());
        let b = render(tape, &cam, &settings, &ProgressBar::hidden());
        assert!(a.hits() >= 600, "{name}: {} hits", a.hits());
        assert_frames_match(name, &a, &b);
        // The tape's ball bounds are local like the tree's, so its segment tracing takes
        // about the tree's steps; a bound blind to where the ball is (as the prism's
        // unsigned distance once was: 0 inside, so every ball reached `r` outside) takes
        // sphere tracing's, 3.5 times as many on the main job.
        let (sa, sb) = (a.mean_steps(), b.mean_steps());
        eprintln!("{name}: {sa:.1} steps per ray on the tree, {sb:.1} on its tape");
        assert!(
            sb <= 1.6 * sa,
            "{name}: tape {sb:.1} steps per ray, tree {sa:.1}"
        );
    }
}

/// With an adapter: the GPU evaluates every scene's tape (values and ball bounds, with
/// and without a ball) as the CPU does, at points spread over the scene and on its
/// surface.
#[test]
fn gpu_probes_of_the_scenes_match_the_cpu() {
    let Some(ctx) = gpu() else { return };
    for (name, tree, tape) in solid_scenes() {
        let (pts, _) = sample_points(tree, 3000, 21);
        let mut rng = Rng(4);
        let scale = tree.support().radius() * 0.05;
        let probes: Vec<(Vec3, f32)> = pts
            .into_iter()
            .enumerate()
            .map(|(i, p)| {
                (
                    p,
                    if i % 3 == 0 {
                        0.0
                    } else {
                        rng.range(0.0, scale)
                    },
                )
            })
            .collect();
        eprintln!("{name}");
        assert_probes_match(ctx, tape, &probes);
    }
}

/// With an adapter (lavapipe in CI): the GPU render of every scene's tape against
/// the CPU render of the tree itself.
#[test]
fn gpu_renders_of_the_scenes_match_the_cpu() {
    let Some(ctx) = gpu() else { return };
    for (name, tree, tape) in solid_scenes() {
        let (cam, settings) = view(tree);
        let start = std::time::Instant::now();
        let a = render(tree, &cam, &settings, &ProgressBar::hidden());
        let cpu_s = start.elapsed().as_secs_f64();
        let b = ctx.render(tape, &cam, &settings).unwrap();
        eprintln!(
            "{name}: CPU {cpu_s:.3} s, GPU {:.3} s; hits CPU {} GPU {}",
            start.elapsed().as_secs_f64() - cpu_s,
            a.hits(),
            b.hits()
        );
        assert!(a.hits() >= 600, "{name}: {} hits", a.hits());
        assert_frames_match(name, &a, &b);
    }
}

/// The ground truth on real trees: the traced depth agrees with ray casting the
/// Marching Cubes mesh of the same tree on ≥ 99 % of hit pixels, within one cell size.
#[test]
fn traced_depth_matches_the_marching_cubes_mesh_of_the_scenes() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees");
    for (file, cells, (w, h)) in [
        ("arch.ron", 200.0, (128, 96)),
        ("rock_spire.ron", 160.0, (128, 96)),
        ("floating_island.ron", 1024.0, (192, 144)),
    ] {
        let tree = compile(&dir.join(file));
        let support = tree.support();
        let solid = solid_box(&tree);
        let cell = solid.size().max_element() / cells;
        let n = ((solid.size() / cell).ceil() + 2.0).as_uvec3();
        let grid = GridSpec::new(
            solid.min - Vec3::splat(cell),
            Vec3::splat(cell),
            [n.x as usize, n.y as usize, n.z as usize],
        )
        .unwrap();
        let (mesh, _) = polygonize(&tree, &grid, &MeshOptions::default()).unwrap();
        let positions: Vec<Vec3> = mesh.positions.iter().map(|&p| Vec3::from(p)).collect();
        let caster = MeshRaycaster::new(&positions, &mesh.triangles);
        let cam = Camera::frame(&solid, 40.0, w, h).unwrap();
        let truth = caster.depth(&cam);
        let params = TraceParams::for_scene(Method::Segment, 2.0 * support.radius())
            .with_pixel_angle(cam.pixel_angle());
        let (depth, _) = cpu::depth(&tree, &cam, &params);
        let (frac, hits) = depth_agreement(&truth, &depth, cell);
        eprintln!(
            "{file}: {} triangles, cell {cell:.2} m, {hits} hit pixels, {:.2}% agree",
            mesh.triangles.len(),
            frac * 100.0
        );
        assert!(hits >= 2000, "{file}: {hits} hit pixels");
        assert!(
            frac >= 0.99,
            "{file}: {:.2}% of hit pixels agree within {cell} m",
            frac * 100.0
        );
    }
}

fn prim(spec: &str) -> std::sync::Arc<dyn Field> {
    let spec: karstic::field::PrimitiveSpec =
        ron::from_str(spec).unwrap_or_else(|e| panic!("{spec}: {e}"));
    std::sync::Arc::new(karstic::field::Primitive::from_spec(&spec, 1))
}

fn heightfield(cell: glam::Vec2, interp: Interpolation) -> std::sync::Arc<dyn Field> {
    let (nx, ny) = (24, 17);
    let z = (0..nx * ny)
        .map(|k| {
            let (i, j) = ((k % nx) as f32, (k / nx) as f32);
            3.0 * (0.5 * i).sin() + 2.0 * (0.3 * j).cos() + 0.1 * i
        })
        .collect();
    let hf = Heightfield::new(nx, ny, glam::Vec2::new(-5.0, 3.0), cell, z).unwrap();
    let mut params = ImplicitParams::with_falloff(2.5);
    params.vertical_scale = 1.5;
    params.vertical_offset = 4.0;
    params.placement = glam::Vec2::new(2.0, -1.0);
    params.interpolation = interp;
    std::sync::Arc::new(HeightfieldField::new(&hf, &params).unwrap())
}

/// A tree using every encoded node and skeleton kind — big BVH blend, union, intersection,
/// difference with a negative curve, rotated and scaled transforms, constants, a box
/// turned by 90°, cones (one upside down) and ellipsoids, a zero-length segment and a
/// placed, scaled heightfield, bilinear and bicubic — equals its tape, and with an adapter
/// the GPU evaluates the tape as the CPU does.
#[test]
fn every_encoding_equals_its_node() {
    let mut b = TreeBuilder::new();
    let mut blobs: Vec<_> = (0..40)
        .map(|i| {
            let a = i as f32 * 0.7;
            let s = format!(
                "(shape: Point(center: ({}, {}, {})), falloff: 2.5, energy: 0.8)",
                8.0 * a.cos(),
                8.0 * a.sin(),
                0.2 * i as f32
            );
            b.leaf(prim(&s), None)
        })
        .collect();
    for s in [
        "(shape: Segment(a: (-3, 0, 1), b: (4, 2, 3)), falloff: 2)",
        "(shape: Segment(a: (1, 1, 1), b: (1, 1, 1)), falloff: 2)",
        "(shape: Sphere(center: (0, 4, 2), radius: 1.5), falloff: 2, energy: 1.3)",
        "(shape: Capsule(a: (-5, -5, 0), b: (-2, -6, 4), radius: 1), falloff: 1.5)",
        "(shape: Box(center: (3, -4, 0), half_size: (2, 1, 0.5), yaw: 90), falloff: 1.2)",
        "(shape: Polyline(points: [(-6, 2, 0), (-3, 5, 2), (0, 6, 1)]), falloff: 1.8)",
        "(shape: Cone(base: (6, 6, -1), apex: (7, 5, 6), radius: 2.5), falloff: 2, energy: 1.1)",
        "(shape: Cone(base: (-7, -1, 5), apex: (-6, 1, 0), radius: 1.5), falloff: 1.5)",
        "(shape: Ellipsoid(center: (2, -7, 1), radii: (3, 1.2, 2)), falloff: 1.8, energy: 1.2)",
        "(shape: Ellipsoid(center: (-2, 7, 3), radii: (0.6, 2.5, 1)), falloff: 1.2)",
    ] {
        blobs.push(b.leaf(prim(s), None));
    }
    let blend = b.blend(blobs, None);
    let curve = b.leaf(
        prim(
            "(shape: Curve(points: [(-8, 0, 2), (0, 1, 3), (8, 0, 2)]), falloff: 2, energy: -0.7)",
        ),
        None,
    );
    let carve = b.leaf(
        prim("(shape: Sphere(center: (2, 2, 2), radius: 2), falloff: 1.5, energy: 1.4)"),
        None,
    );
    let carved = b.difference(blend, vec![carve], None);
    let with_curve = b.blend(vec![carved, curve], None);
    let boxed = b.leaf(
        prim("(shape: Box(center: (0, 0, 1), half_size: (4, 3, 2)), falloff: 2)"),
        None,
    );
    let moved = b.transform(
        boxed,
        glam::Affine3A::from_scale_rotation_translation(
            Vec3::new(1.2, 0.7, 1.0),
            glam::Quat::from_rotation_z(0.5) * glam::Quat::from_rotation_x(0.3),
            Vec3::new(-9.0, 9.0, 2.0),
        ),
        None,
    );
    let third = b.constant(0.3, None);
    let ball = b.leaf(prim("(shape: Point(center: (-9, 9, 2)), falloff: 6)"), None);
    let capped = b.intersection(vec![moved, ball], None);
    let lifted = b.union(vec![capped, third], None);
    let capped_lift = b.intersection(vec![lifted, ball], None);
    let terrain = b.leaf(
        heightfield(glam::Vec2::splat(1.5), Interpolation::Bilinear),
        None,
    );
    let flipped = b.transform(
        terrain,
        glam::Affine3A::from_scale_rotation_translation(
            Vec3::new(1.0, 1.0, -1.0),
            glam::Quat::IDENTITY,
            Vec3::new(0.0, 0.0, 12.0),
        ),
        None,
    );
    let island = b.intersection(vec![terrain, flipped], None);
    let smooth = b.leaf(
        heightfield(glam::Vec2::splat(1.5), Interpolation::Bicubic),
        None,
    );
    let smooth = b.transform(
        smooth,
        glam::Affine3A::from_translation(Vec3::new(20.0, -6.0, 0.0)),
        None,
    );
    let root = b.union(
        vec![with_curve, capped_lift, island, smooth],
        Some("root".into()),
    );
    let tree = b.build(root);
    let tape = tape_equals_tree(&tree, 30_000);
    common::check_segment_lipschitz(&tape, &tree.support(), 20_000, 4);
    if let Some(ctx) = gpu() {
        let mut rng = Rng(5);
        let (pts, _) = sample_points(&tree, 6000, 9);
        let pts: Vec<(Vec3, f32)> = pts
            .into_iter()
            .enumerate()
            .map(|(i, p)| (p, if i % 3 == 0 { 0.0 } else { rng.range(0.0, 3.0) }))
            .collect();
        assert_probes_match(ctx, &tape, &pts);
    }
    // Each heightfield alone, where the prism's corners get their share of the points.
    for interp in [Interpolation::Bilinear, Interpolation::Bicubic] {
        let mut b = TreeBuilder::new();
        let leaf = b.leaf(heightfield(glam::Vec2::splat(1.5), interp), None);
        tape_equals_tree(&b.build(leaf), 20_000);
    }
}

/// Compares the tree and its tape at [`sample_points`]; returns the tape.
fn tape_equals_tree(tree: &Tree, n: usize) -> Tape {
    let tape = tape_from_tree(tree).unwrap();
    let (pts, surface) = sample_points(tree, n, 3);
    assert!(surface >= n / 50, "{surface} surface points");
    for p in pts {
        let (v, t) = (tree.value(p), tape.value(p));
        assert!(
            (v - t).abs() <= 1e-4 * v.abs().max(1.0),
            "at {p}: tree {v}, tape {t}"
        );
    }
    tape
}

#[test]
fn nodes_without_an_encoding_are_named_errors() {
    let refused = |leaf: std::sync::Arc<dyn Field>, expect: &str| {
        let mut b = TreeBuilder::new();
        let a = b.leaf(leaf, Some("it".into()));
        let other = b.leaf(prim("(shape: Point(center: (0, 0, 0)), falloff: 1)"), None);
        let root = b.blend(vec![other, a], None);
        let e = tape_from_tree(&b.build(root)).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, TapeError::NoEncoding { .. }), "{msg}");
        assert!(msg.contains(expect), "{msg} lacks {expect:?}");
    };
    refused(
        prim("(shape: Box(center: (0, 0, 0), half_size: (1, 2, 1), yaw: 30), falloff: 1)"),
        "the Box primitive \"it\" has no GPU encoding: only boxes with a yaw",
    );
    refused(
        prim("(shape: Disc(center: (0, 0, 0), normal: (0, 0, 1), radius: 2), falloff: 1)"),
        "not Disc",
    );
    refused(
        heightfield(glam::Vec2::new(1.5, 2.0), Interpolation::Bilinear),
        "square cells",
    );
}

/// Noisy primitives on every convex shape the tape knows (cone and ellipsoid included) (and a noisy polyline, carving
/// with E < 0) and turbulence warps, localized and not, nested in an affine transform: the
/// tape equals the tree, its ball bounds are sound, and with an adapter the GPU evaluates
/// the same values and bounds and renders the same image as the CPU renders the tree.
#[test]
fn noisy_primitives_and_turbulence_warps_equal_their_nodes() {
    use karstic::field::{Fbm, Warp};
    let mut b = TreeBuilder::new();
    let noise = |a: f32, w: f32, o: u32, s: u32| {
        format!("noise: Some((amplitude: {a}, wavelength: {w}, octaves: {o}, seed_offset: {s}))")
    };
    let mut kids = Vec::new();
    for (i, s) in [
        "Point(center: (0, 0, 2))",
        "Segment(a: (-6, 3, 1), b: (-1, 6, 3))",
        "Sphere(center: (5, 4, 2), radius: 2)",
        "Capsule(a: (-7, -5, 0), b: (-3, -6, 3), radius: 1.2)",
        "Box(center: (4, -4, 0), half_size: (2.5, 1.5, 1))",
        "Cone(base: (8, 0, -1), apex: (9, 1, 6), radius: 2.5)",
        "Ellipsoid(center: (-9, 3, 2), radii: (2.5, 1.5, 2))",
    ]
    .iter()
    .enumerate()
    {
        let spec = format!(
            "(shape: {s}, falloff: 3, energy: 1.2, {})",
            noise(
                (1.0 + 0.3 * i as f32).min(2.2),
                2.5 + i as f32,
                2 + i as u32 % 5,
                i as u32
            )
        );
        kids.push(b.leaf(prim(&spec), None));
    }
    let blend = b.blend(kids, None);
    let carve = b.leaf(
        prim(&format!(
            "(shape: Polyline(points: [(-8, 0, 3), (0, 1, 4), (8, -1, 3)]), falloff: 2, energy: -0.8, {})",
            noise(0.9, 3.0, 3, 9)
        )),
        None,
    );
    let carved = b.blend(vec![blend, carve], None);
    let region = Aabb::new(Vec3::new(-6.0, -6.0, -2.0), Vec3::new(2.0, 6.0, 6.0));
    let local = b.warp(
        carved,
        Warp::new(Fbm::with(5, 4.0, 3), 11, 0.8, Some((region, 2.5))),
        Some("local".into()),
    );
    let rock = b.leaf(
        prim(&format!(
            "(shape: Sphere(center: (0, 0, 0), radius: 2), falloff: 2.5, {})",
            noise(0.6, 2.0, 3, 2)
        )),
        None,
    );
    let everywhere = b.warp(rock, Warp::new(Fbm::with(9, 3.0, 2), 3, 0.7, None), None);
    let moved = b.transform(
        everywhere,
        glam::Affine3A::from_scale_rotation_translation(
            Vec3::splat(1.3),
            glam::Quat::from_rotation_z(0.7),
            Vec3::new(0.0, 12.0, 2.0),
        ),
        None,
    );
    let root = b.union(vec![local, moved], Some("root".into()));
    let tree = b.build(root);
    let tape = tape_equals_tree(&tree, 30_000);
    common::check_segment_lipschitz(&tape, &tree.support(), 20_000, 5);
    let Some(ctx) = gpu() else { return };
    let mut rng = Rng(12);
    let s = tree.support();
    let pts: Vec<(Vec3, f32)> = (0..6000)
        .map(|i| {
            let r = if i % 3 == 0 { 0.0 } else { rng.range(0.0, 4.0) };
            (point_in(&mut rng, &s), r)
        })
        .collect();
    assert_probes_match(ctx, &tape, &pts);
    let (cam, settings) = view(&tree);
    let a = render(&tree, &cam, &settings, &ProgressBar::hidden());
    let g = ctx.render(&tape, &cam, &settings).unwrap();
    assert!(a.hits() >= 600, "{} hits", a.hits());
    assert_frames_match("noisy", &a, &g);
}

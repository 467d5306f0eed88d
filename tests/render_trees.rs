//! The scenes of `trees/` through the renderer: their GPU tapes against the compiled trees
//! (the conformance suite's checks, CPU images and, with an adapter, GPU images), the
//! traced depth of the trees against ray casting their Marching Cubes meshes, and the
//! nodes without an encoding.

use crate::common;

use std::path::{Path, PathBuf};

use crate::tape_conformance::conform;
use common::{TUNNEL_VIEW, assert_frames_match_within, depth_agreement, gpu};
use glam::Vec3;
use indicatif::ProgressBar;
use karstic::compile::Compiled;
use karstic::dem::{Heightfield, HeightfieldField, ImplicitParams, Interpolation};
use karstic::field::{Aabb, Field, ISO, Tree, TreeBuilder};
use karstic::mesh::{GridSpec, MeshOptions, polygonize};
use karstic::render::guide::Guide;
use karstic::render::raycast::MeshRaycaster;
use karstic::render::trace::TraceParams;
use karstic::render::{Camera, Method, RenderSettings, cpu, render};
use karstic::tape::{Tape, TapeError, tape_from_tree};

/// The scenes `trees/*.ron`, `trees/curves/*.ron` and `trees/paper/*.ron`, sorted.
fn tree_files() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees");
    let mut files: Vec<PathBuf> = [root.clone(), root.join("curves"), root.join("paper")]
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

/// Scenes whose nodes have no GPU encoding (elevation trees, erosion by a geology, as the
/// fin arch's weathering):
/// `tests/elevation_trees.rs` and `tests/geology.rs` check that the tape names the reason.
/// And the canyon: its 181k carving spheres make a tape of as many instructions, which
/// the GPU walks in full at every point; lavapipe ends a shader's loop after its
/// iteration budget, so the software adapter's values lose the carving there (a tape
/// that skips far children, as the CPU's BVH does, is not built yet). And the bluff: its
/// terrain's eroded amplification has no encoding, and its geology colours its rock,
/// which the shader cannot; the hoodoo field's badland slope is amplified too.
const CPU_ONLY: &[&str] = &[
    "elevation_valley",
    "fin_arch",
    "hoodoo_field",
    "jacksboro_bluff",
    "jacksboro_canyon",
    "paper/fig4_fault",
    "paper/fig4_fold",
    "paper/fig4_local",
    "strata_cliff",
    "strata_islands",
];

/// `(name, tree, tape)` of every scene but [`CPU_ONLY`]: each must encode (compiled once per test binary,
/// the Feature Curve scenes run the voxel pipeline).
fn scenes() -> &'static [(String, Tree, Tape)] {
    static SCENES: std::sync::OnceLock<Vec<(String, Tree, Tape)>> = std::sync::OnceLock::new();
    SCENES.get_or_init(|| {
        let encoded: Vec<_> = tree_files()
            .into_iter()
            .filter(|path| !CPU_ONLY.contains(&name(path).as_str()))
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
                if tree.value(p) > ISO {
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
/// The share of pixels whose colours must agree between two renders of `tape`'s scene
/// from `cam`: 99%, or 97% when the scene has noise finer than a pixel at the solid's
/// distance (the main job's detailed DEM, 5 m relief under 100 m pixels): one sample a
/// pixel of sub-pixel relief is aliasing, and hits a hair apart shade apart.
/// Scenes whose features are narrower than a pixel of the 96 × 64 view that frames their
/// whole solid ([`view`]), with the share of pixels whose colours must agree: the hoodoo
/// field's columns are 1–4 m wide where a pixel spans 4 m, so the CPU and the GPU shade
/// their silhouettes differently on 3 % of the pixels (their hit masks still agree on 99 %,
/// and the field values in [`scenes_conform_on_the_tree_the_cpu_tape_and_the_gpu`]).
const SUB_PIXEL: &[(&str, f64)] = &[("hoodoo_field", 0.96)];

fn colour_share(tree: &Tree, tape: &Tape, cam: &Camera) -> f64 {
    let footprint = cam.pixel_angle() * cam.eye.distance(solid_box(tree).center());
    let finest = tape
        .noises
        .iter()
        .map(|f| f.wavelength() / (1u32 << (f.octaves() - 1)) as f32)
        .fold(f32::INFINITY, f32::min);
    if finest < footprint { 0.97 } else { 0.99 }
}

fn view(tree: &Tree) -> (Camera, RenderSettings) {
    let cam = Camera::frame(&solid_box(tree), 40.0, 96, 64).unwrap();
    let settings = RenderSettings::for_scene(&tree.support(), &cam, Method::Segment);
    (cam, settings)
}

/// Every scene of `trees/` and `trees/curves/` encodes, and its tree, CPU tape and GPU
/// agree as the conformance suite's checks say ([`conform`]).
#[test]
fn scenes_conform_on_the_tree_the_cpu_tape_and_the_gpu() {
    for (name, tree, tape) in scenes() {
        if tree.support().is_empty() {
            // A Feature Curve volume without a surface (guidance curves alone): 0.
            assert!(
                tape.instrs.len() == 1 && tape.value(Vec3::ZERO) == 0.0,
                "{name}: an empty field is the constant 0"
            );
            continue;
        }
        eprintln!(
            "{name}: {} instructions, {} params, {} heights",
            tape.instrs.len(),
            tape.params.len(),
            tape.heights.len()
        );
        conform(name, tree, tape, &[]);
        // The tape's support is the tree's (the encoder passes the cached supports on).
        let (a, b) = (tape.support(), tree.support());
        assert!(
            (a.size() - b.size()).abs().max_element() <= 1e-4 * b.size().max_element(),
            "{name}: tape support {a:?} vs tree {b:?}"
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
        assert_frames_match_within(name, &a, &b, colour_share(tree, tape, &cam));
        // The tape's ball bounds are local like the tree's, so its segment tracing takes
        // about the tree's steps; a bound blind to where the ball is (as the prism's
        // unsigned distance once was: 0 inside, so every ball reached `r` outside) takes
        // sphere tracing's, 3.5 times as many on the main job. (The S-field leaf's ball
        // bound uses its global slope of S where the tree's uses the bricks': on the
        // thesis arch, a slab since issue 13, that costs 1.66 times the tree's steps. The
        // tree's heightfield leaf bounds a segment by the slope along its direction, the
        // tape's by the slope in every direction: 1.9 times the tree's steps on the sea
        // cliffs.)
        let (sa, sb) = (a.mean_steps(), b.mean_steps());
        eprintln!("{name}: {sa:.1} steps per ray on the tree, {sb:.1} on its tape");
        assert!(
            sb <= 2.1 * sa,
            "{name}: tape {sb:.1} steps per ray, tree {sa:.1}"
        );
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
        let share = SUB_PIXEL
            .iter()
            .find(|(n, _)| *n == name)
            .map_or_else(|| colour_share(tree, tape, &cam), |&(_, share)| share);
        assert_frames_match_within(name, &a, &b, share);
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

/// The tree file at `path` compiled, its preview's camera at `width × height` and the
/// render settings `karstic render` gives it.
fn job_view(path: &Path, width: u32, height: u32) -> (Compiled, Camera, RenderSettings) {
    let loaded = karstic::scene::load(path).unwrap();
    let compiled = loaded.compile().unwrap();
    let tree = &compiled.tree;
    let cam = karstic::picture::camera(&loaded.scene, tree, None, None, width, height).unwrap();
    let settings = karstic::picture::settings(
        &loaded.scene,
        tree,
        compiled.ground.clone(),
        &cam,
        Method::Segment,
    );
    (compiled, cam, settings)
}

#[test]
fn a_job_sun_lights_every_picture_from_where_it_stands() {
    // trees/jacksboro_bluff.ron sets its sun at bearing 160° (south-south-east), 20° up:
    // the pictures' sun points there (east is +x, north +y), and its low light reaches the
    // cliff's east face; a tree without one keeps the default sun, in the south-west.
    let trees = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees");
    let (_, _, bluff) = job_view(&trees.join("jacksboro_bluff.ron"), 64, 36);
    let (az, el) = (160f32.to_radians(), 20f32.to_radians());
    let want = Vec3::new(az.sin() * el.cos(), az.cos() * el.cos(), el.sin());
    assert!(
        bluff.shading.sun.distance(want) < 1e-5,
        "{} for {want}",
        bluff.shading.sun
    );
    assert!(bluff.shading.sun.dot(Vec3::X) > 0.3, "the east face is lit");
    let (_, _, caves) = job_view(&trees.join("jacksboro_caves.ron"), 64, 36);
    assert!(
        caves.shading.sun.x < 0.0 && caves.shading.sun.y < 0.0,
        "the default sun stands in the south-west: {}",
        caves.shading.sun
    );
}

/// The length along `ray` of the solid (`f > T`) that a crossing at `t` enters, sampled
/// every `tol / 64` and followed up to `2·tol`; 0 when no sample within `tol / 8` of `t` is
/// solid.
fn solid_run(f: &dyn Field, ray: &karstic::render::camera::Ray, t: f32, tol: f32) -> f32 {
    let step = tol / 64.0;
    let inside = |u: f32| f.value(ray.at(u)) > ISO;
    let Some(start) = (-8..=8).map(|k| t + k as f32 * step).find(|&u| inside(u)) else {
        return 0.0;
    };
    let mut u = start;
    while u - start < 2.0 * tol && inside(u) {
        u += step;
    }
    u - start
}

/// A render prunes its tree per tile ([`Field::prune`]) and starts each tile's rays where
/// its beam leaves the air; the pruned tree must hit the surfaces the whole tree hits. The
/// job views of the tunnel and main-job scenes, traced with the render's own parameters
/// through the whole tree (`cpu::depth`), agree with the render's depths: the same pixels
/// hit, at the same distance within the tolerance — except where the nearer hit is a
/// sliver of solid thinner along the ray than the march's tolerance `ε + cone·t` (the
/// march's steps never fall below it, so such slivers are hit or stepped over depending on
/// where the steps fall: a grazed edge of the arch on the main job). A sliver thicker than
/// that, missed by one trace, means a bound that is not sound.
#[test]
fn pruned_tiles_hit_where_the_whole_tree_does() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees");
    for file in ["ridge_tunnel.ron", "jacksboro_caves.ron"] {
        let path = dir.join(file);
        let (compiled, cam, mut settings) = job_view(&path, 128, 72);
        // The field's surfaces alone: the plants are not the tree's.
        settings.vegetation = None;
        let tree = &compiled.tree;
        let p = &settings.trace;
        let frame = cpu::render(tree, &cam, &settings, &ProgressBar::hidden());
        let (depth, _) = cpu::depth(tree, &cam, p);
        let mut worst = (0.0f32, 0u32);
        let (mut off, mut slivers) = (0, 0);
        for (k, (&a, &b)) in frame.depth.iter().zip(&depth).enumerate() {
            let near = a.min(b);
            let tol = p.epsilon + p.cone * near;
            let d = if a.is_finite() && b.is_finite() {
                (a - b).abs()
            } else if a.is_finite() || b.is_finite() {
                f32::INFINITY
            } else {
                0.0
            };
            if d <= 4.0 * tol {
                continue;
            }
            let ray = cam.pixel_ray(k as u32 % cam.width, k as u32 / cam.width);
            if solid_run(tree, &ray, near, tol) < tol {
                slivers += 1;
                continue;
            }
            off += 1;
            if d > worst.0 {
                worst = (d, k as u32);
            }
        }
        let k = worst.1 as usize;
        assert!(
            off == 0,
            "{file}: {off} pixels off; worst at pixel {k}: render {} m, whole tree {} m",
            frame.depth[k],
            depth[k]
        );
        assert!(slivers <= 8, "{file}: {slivers} pixels on slivers");
        assert!(frame.depth.iter().filter(|t| t.is_finite()).count() > depth.len() / 2);
    }
}

/// The sea cliffs' job sets a water level and its geology colours the rock: in its
/// preview, pixels whose rays cross more than 12 m of water (three times its clarity) show water (blue over red), and
/// the cliff's rock above it shows sandstone (red over blue); the soft bed at sea level is
/// darker rock than the hard sandstone above it.
#[test]
fn sea_level_shows_water_and_the_geology_colours_the_rock() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/sea_cliffs.ron");
    let (compiled, cam, settings) = job_view(&path, 96, 54);
    let tree = &compiled.tree;
    assert_eq!(settings.shading.water.map(|w| w.level), Some(0.0));
    let m = &settings.materials;
    let (soft, hard) = (Vec3::new(60.0, 92.0, 0.0), Vec3::new(60.0, 92.0, 20.0));
    assert!(
        m.rock_at(soft).length() < 0.6 * m.rock_at(hard).length(),
        "soft bed {} against sandstone {}",
        m.rock_at(soft),
        m.rock_at(hard)
    );
    let frame = cpu::render(tree, &cam, &settings, &ProgressBar::hidden());
    let (mut water, mut rock) = (0, 0);
    for (k, &t) in frame.depth.iter().enumerate() {
        let (i, j) = (k as u32 % cam.width, k as u32 / cam.width);
        let [r, _, b, _] = [0, 1, 2, 3].map(|c| frame.rgba[4 * k + c]);
        let ray = cam.pixel_ray(i, j);
        let z = ray.at(t).z;
        // Metres of water the ray crosses before the floor (shallows show their floor).
        let path = (t - ray.origin.z / -ray.dir.z).max(0.0);
        if !t.is_finite() || z < 0.0 {
            if ray.dir.z < 0.0 && path > 12.0 {
                assert!(b > r, "pixel ({i}, {j}) under the water: {r} red, {b} blue");
                water += 1;
            }
        } else if z > 5.0 && m.cover(cam.pixel_ray(i, j).at(t), Vec3::Y).rock > 0.0 {
            rock += usize::from(r > b);
        }
    }
    let n = frame.depth.len();
    assert!(water > n / 10, "{water} of {n} pixels show water");
    assert!(rock > n / 10, "{rock} of {n} pixels show sandstone");
}

/// Boxes where the main job's render asks its tree for intervals: the beams of the job
/// view's tiles (the box of the tile's rays' segments `[t, t + δ]`, `δ` from a sixteenth of
/// the span down to a sixteen-thousandth) and slabs around the surface the view sees
/// (thin or wide along each axis, 0.5 m to 500 m).
fn job_view_boxes(tree: &Tree, cam: &Camera, p: &TraceParams, rng: &mut common::Rng) -> Vec<Aabb> {
    let support = tree.support();
    let (tx, ty) = (
        cam.width.div_ceil(cpu::TILE),
        cam.height.div_ceil(cpu::TILE),
    );
    let mut boxes = Vec::new();
    for k in 0..tx * ty {
        let (x0, y0) = ((k % tx) * cpu::TILE, (k / tx) * cpu::TILE);
        let spans: Vec<_> = (y0..(y0 + cpu::TILE).min(cam.height))
            .flat_map(|j| (x0..(x0 + cpu::TILE).min(cam.width)).map(move |i| (i, j)))
            .filter_map(|(i, j)| {
                let r = cam.pixel_ray(i, j);
                r.clip(&support).map(|sp| (r, sp))
            })
            .collect();
        let Some((t0, t1)) = spans
            .iter()
            .map(|s| s.1)
            .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
        else {
            continue;
        };
        for _ in 0..12 {
            let delta = (t1 - t0) / 16.0 * 0.5f32.powf(rng.range(0.0, 10.0));
            let t = rng.range(t0, t1);
            let b = spans.iter().fold(Aabb::EMPTY, |b, (r, sp)| {
                let (a, c) = (t.max(sp.0), (t + delta).min(sp.1));
                if a <= c {
                    b.union(Aabb::from_points([r.at(a), r.at(c)]))
                } else {
                    b
                }
            });
            if !b.is_empty() {
                boxes.push(b);
            }
        }
    }
    let hits: Vec<Vec3> = (0..200)
        .filter_map(|_| {
            let r = cam.pixel_ray(
                (rng.next_u64() % cam.width as u64) as u32,
                (rng.next_u64() % cam.height as u64) as u32,
            );
            let tr = karstic::render::trace::trace(tree, &r, r.clip(&support)?, p);
            tr.hit().then(|| r.at(tr.t))
        })
        .collect();
    for h in &hits {
        let size = Vec3::new(rng.f32(), rng.f32(), rng.f32()).map(|u| 0.5 * 1000f32.powf(u));
        let c = *h + (Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5) * size;
        boxes.push(Aabb::new(c - 0.5 * size, c + 0.5 * size));
    }
    boxes
}

/// The main job's tree, node by node (heightfield with detail, the Feature Volumes' S
/// fields, the Replace transitions, the carves), and the tree pruned to each box's
/// neighbourhood as the render prunes it: values sampled in the boxes of
/// [`job_view_boxes`] (uniformly, and densely on each box's diagonal) lie in the intervals
/// over the boxes. The render's beam skips every box whose interval is below `T`: an
/// unsound interval there starts rays past the ground.
#[test]
fn main_job_intervals_are_sound_where_the_render_asks() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/jacksboro_caves.ron");
    let (compiled, cam, settings) = job_view(&path, 128, 72);
    let tree = &compiled.tree;
    let mut rng = common::Rng(23);
    let boxes = job_view_boxes(tree, &cam, &settings.trace, &mut rng);
    let (mut air, mut ground) = (0, 0);
    for b in &boxes {
        let mut points: Vec<Vec3> = (0..96).map(|_| rng.in_box(b)).collect();
        points.extend((0..=64).map(|k| b.min + b.size() * k as f32 / 64.0));
        let pruned = tree.prune(&b.dilate(2.0 * settings.shading.ao_radius));
        let nodes = (0..tree.nodes().len() as u32).map(|id| {
            let name = tree
                .info(id)
                .name
                .clone()
                .unwrap_or_else(|| format!("node {id}"));
            (name, Box::new(tree.subtree(id)) as Box<dyn Field>)
        });
        for (name, f) in nodes.chain(pruned.map(|f| ("the pruned tree".to_string(), f))) {
            let iv = f.interval(b);
            for &p in &points {
                let v = f.value(p);
                assert!(
                    iv.lo - 1e-5 <= v && v <= iv.hi + 1e-5,
                    "{name}: f({p}) = {v} outside its interval {iv:?} over {b:?}"
                );
            }
        }
        let iv = tree.interval(b);
        air += (iv.hi < ISO) as usize;
        ground += points.iter().any(|&p| tree.value(p) > ISO) as usize;
    }
    let n = boxes.len();
    assert!(n > 500, "{n} boxes");
    assert!(
        air > n / 10 && ground > n / 5,
        "{air} boxes of air, {ground} with ground of {n}"
    );
}

/// The job's pictures follow its mesh inside the region ([`Guide`]): on the main job's
/// view and on a close-up of its arch, the guided traces find the surface the whole
/// field's march finds (same pixels hit, at the same distance within the tolerance) on all
/// but the grazed slivers, with far fewer evaluations; guided renders match unguided ones,
/// shadows included. A guide from the same mesh lifted by 12 m (faces off the surface)
/// disagrees on the arch, so the agreement is the mesh's doing.
#[test]
fn guided_traces_find_the_surface_the_field_march_finds() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/jacksboro_caves.ron");
    let (compiled, main_cam, settings) = job_view(&path, 128, 72);
    let tree = &compiled.tree;
    let job = karstic::scene::load(&path).unwrap().scene.job.unwrap();
    let region = job.region.unwrap();
    // The job's own cell: its guides are meshed at it.
    let cell = job.cell.0;
    let grid = GridSpec::with_cell(&Aabb::new(region.min.0, region.max.0), cell).unwrap();
    let (mesh, _) = polygonize(tree, &grid, &MeshOptions::default()).unwrap();
    let guide = |lift: f32| {
        let mut m = mesh.clone();
        m.positions.iter_mut().for_each(|p| p[2] += lift);
        let g = Guide::from_mesh(&m, &grid.bounds(), cell, 1 << 30).unwrap();
        vec![std::sync::Arc::new(g)]
    };
    let (right, lifted) = (guide(0.0), guide(12.0));
    let materials = settings.materials.clone();
    let arch = tree
        .info(karstic::landform::feature_node(tree, "arch").unwrap())
        .support
        .intersection(grid.bounds());
    let arch_cam =
        karstic::render::views::feature_view(tree, &[], &arch, &materials, 40.0, (96, 54))
            .unwrap()
            .unwrap();
    for (name, cam) in [("main view", main_cam), ("arch", arch_cam)] {
        let p = settings.trace.with_pixel_angle(cam.pixel_angle());
        let (field, steps) = cpu::depth(tree, &cam, &p);
        let agreement = |guides| {
            let (depth, guided_steps) = cpu::depth_guided(tree, guides, &cam, &p);
            let (mut same, mut hits) = (0, 0);
            for (k, (&a, &b)) in field.iter().zip(&depth).enumerate() {
                if !(a.is_finite() || b.is_finite()) {
                    continue;
                }
                hits += 1;
                let tol = p.epsilon + p.cone * a.min(b);
                let ray = cam.pixel_ray(k as u32 % cam.width, k as u32 / cam.width);
                let close = a.is_finite() && b.is_finite() && (a - b).abs() <= 4.0 * tol;
                same += usize::from(close || solid_run(tree, &ray, a.min(b), tol) < tol);
            }
            let mean = |s: &[u32]| s.iter().sum::<u32>() as f64 / s.len() as f64;
            (
                same as f64 / hits as f64,
                mean(&guided_steps) / mean(&steps),
            )
        };
        let (share, cost) = agreement(&right);
        assert!(share >= 0.99, "{name}: guided traces agree on {share:.4}");
        if name == "arch" {
            let (wrong, _) = agreement(&lifted);
            assert!(wrong < 0.9, "{name}: a lifted guide agrees on {wrong:.4}");
            assert!(
                cost < 0.3,
                "{name}: guided evaluations {cost:.2} of the march's"
            );
            // One sample a pixel: supersampling picks its edge pixels by each picture's
            // own contrast, so a few pixels that differ change which others are refined.
            let settings = RenderSettings {
                antialias: false,
                ..settings.clone()
            };
            let plain = render(tree, &cam, &settings, &ProgressBar::hidden());
            let s = RenderSettings {
                guides: right.clone(),
                ..settings.clone()
            };
            let guided = render(tree, &cam, &s, &ProgressBar::hidden());
            assert_frames_match_within(name, &plain, &guided, 0.97);
        }
    }
}

/// A guided trace that locates its hit by bracketing the surface around a face must leave
/// the tracer able to take the hit's gradient: on the hoodoo field (a blend whose tracer
/// keeps per-ray lists of the children it crosses), the gradient the tracer gives at each
/// guided hit is the field's there. (Stale lists from an earlier part of the ray gave the
/// hoodoos' flanks wrong normals.)
#[test]
fn guided_hits_keep_the_fields_gradient() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/hoodoo_field.ron");
    let (compiled, cam, settings) = job_view(&path, 96, 54);
    let tree = &compiled.tree;
    assert!(tree.keeps_line_lists());
    let job = karstic::scene::load(&path).unwrap().scene.job.unwrap();
    let region = job.region.unwrap();
    let grid = GridSpec::with_cell(&Aabb::new(region.min.0, region.max.0), 2.0).unwrap();
    let (mesh, _) = polygonize(tree, &grid, &MeshOptions::default()).unwrap();
    let guides = vec![std::sync::Arc::new(
        Guide::from_mesh(&mesh, &grid.bounds(), 2.0, 1 << 30).unwrap(),
    )];
    let mut tracer = karstic::render::Tracer::new(tree).with_guides(&guides);
    let (mut hits, mut off) = (0, Vec::new());
    for k in 0..cam.width * cam.height {
        let ray = cam.pixel_ray(k % cam.width, k / cam.width);
        let Some(span) = ray.clip(&tree.support()) else {
            continue;
        };
        let tr = tracer.trace(&ray, span, &settings.trace);
        if !tr.hit() {
            continue;
        }
        hits += 1;
        let g = tracer.gradient(&ray, tr.t);
        let want = tree.value_grad(ray.at(tr.t)).1;
        if (g - want).length() > 1e-3 * want.length().max(1e-3) {
            off.push((k, g, want));
        }
    }
    assert!(hits > 2000, "{hits} hits");
    assert!(
        off.is_empty(),
        "{} of {hits} gradients off: {:?}",
        off.len(),
        &off[..off.len().min(3)]
    );
}

/// Sky occlusion at cave scale: looking into the main job's tunnel, the surfaces deep in
/// the rock (a feature's, far below the DEM's ground) lie in shade against the same view
/// without it, while the open ground around the mouth is lit exactly as before.
#[test]
fn cave_interiors_lie_in_shade() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/jacksboro_caves.ron");
    let (compiled, _, mut settings) = job_view(&path, 96, 54);
    let (eye, target) = TUNNEL_VIEW;
    let cam = Camera::look_at(eye, target, 40.0, 96, 54).unwrap();
    settings.trace = settings.trace.with_pixel_angle(cam.pixel_angle());
    assert!(
        settings.shading.cave_reach > 10.0,
        "{}",
        settings.shading.cave_reach
    );
    let with = render(&compiled.tree, &cam, &settings, &ProgressBar::hidden());
    settings.shading.cave_reach = 0.0;
    let without = render(&compiled.tree, &cam, &settings, &ProgressBar::hidden());
    let luma = |f: &karstic::render::Frame, k: usize| {
        f.rgba[4 * k..4 * k + 3]
            .iter()
            .map(|&c| c as f32)
            .sum::<f32>()
    };
    let (mut deep, mut open) = ((0.0, 0.0, 0), 0);
    for (k, &t) in with.depth.iter().enumerate() {
        assert_eq!(t, without.depth[k], "the hits do not move");
        if !t.is_finite() {
            continue;
        }
        let k32 = k as u32;
        let p = cam.pixel_ray(k32 % 96, k32 / 96).at(t);
        let feature = settings.materials.feature(p);
        if feature >= 1.0 && settings.materials.off_ground(p) < -15.0 {
            deep = (
                deep.0 + luma(&with, k),
                deep.1 + luma(&without, k),
                deep.2 + 1,
            );
        } else if feature <= 0.0 {
            assert_eq!(with.rgba[4 * k..4 * k + 4], without.rgba[4 * k..4 * k + 4]);
            open += 1;
        }
    }
    assert!(
        deep.2 > 200 && open > 50,
        "{} deep, {open} open pixels",
        deep.2
    );
    let ratio = deep.0 / deep.1;
    assert!(
        ratio < 0.75,
        "deep in the tunnel: {ratio} of the light without"
    );
}

/// `karstic render` meshes the part of the job's region its camera sees to guide the
/// tracer (`picture::view_guides`), in levels: the job's cell near the eye, then twice as
/// coarse each where those cells still span at most 8 pixels. The main view's region
/// guides span most of the region; a narrow view from the same eye a part of it, holding
/// every point of the region a fine grid of its pixel rays crosses. A close-up whose cells
/// would span many pixels (the tunnel view, from inside the region), a camera looking away
/// from the region, or a tree without a job, gets none.
#[test]
fn view_guides_cover_what_the_camera_sees_of_the_region() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/jacksboro_caves.ron");
    let loaded = karstic::scene::load(&path).unwrap();
    let (compiled, main_cam, _) = job_view(&path, 640, 360);
    let tree = &compiled.tree;
    let job = loaded.scene.job.as_ref();
    let r = job.unwrap().region.unwrap();
    let cell = job.unwrap().cell.0;
    let region = Aabb::new(r.min.0, r.max.0);
    // The region's guides: the backdrop's cells are the job's `full_cell`, 6 of its cells.
    let guides = |cam: &Camera| {
        karstic::picture::view_guides(tree, job, cam, None, 1 << 32, true)
            .unwrap()
            .into_iter()
            .filter(|g| g.cell() < 5.0 * cell)
            .collect::<Vec<_>>()
    };
    let volume = |b: &Aabb| b.size().x * b.size().y * b.size().z;
    let hull =
        |gs: &[std::sync::Arc<Guide>]| gs.iter().map(|g| g.bounds()).fold(Aabb::EMPTY, Aabb::union);

    let main = guides(&main_cam);
    assert!(main.len() >= 2 && main[0].cell() >= cell, "{main:?}");
    for pair in main.windows(2) {
        assert!(
            (pair[1].cell() / pair[0].cell() - 2.0).abs() < 1e-3,
            "{main:?}"
        );
    }
    let b = hull(&main);
    assert!(
        volume(&b) > 0.5 * volume(&region),
        "main view's guide {b:?}"
    );
    assert!(
        region.dilate(3.0).contains_box(&b),
        "{b:?} beyond {region:?}"
    );
    // Where the view meets the region, the finest guide holding the point guides there:
    // its cells span at most 8 pixels.
    let mut levels_used = std::collections::BTreeSet::new();
    for k in 0..64 * 36 {
        let ray = main_cam.pixel_ray(k % 64 * 10, k / 64 * 10);
        let Some((t0, t1)) = ray.clip(&region) else {
            continue;
        };
        for s in 0..=16 {
            let p = ray.at(t0 + (t1 - t0) * s as f32 / 16.0);
            let Some(g) = main.iter().position(|g| g.bounds().contains(p)) else {
                continue;
            };
            levels_used.insert(g);
            let pixels = main[g].cell() / (p.distance(main_cam.eye) * main_cam.pixel_angle());
            assert!(
                pixels <= 8.0,
                "level {g}: a cell spans {pixels} pixels at {p}"
            );
        }
    }
    assert_eq!(levels_used.len(), main.len(), "{main:?}");

    let outside = Vec3::new(4900.0, 4380.0, 780.0);
    let arch = Vec3::new(4480.0, 4990.0, 690.0);
    let narrow = Camera::look_at(outside, arch, 10.0, 96, 54).unwrap();
    let b = hull(&guides(&narrow));
    assert!(
        volume(&b) < 0.3 * volume(&region),
        "narrow view's guide {b:?}"
    );
    let (mut inside, mut all) = (0, 0);
    for k in 0..96 * 54 {
        let ray = narrow.pixel_ray(k % 96, k / 96);
        let Some((t0, t1)) = ray.clip(&region) else {
            continue;
        };
        for s in 0..=16 {
            all += 1;
            inside += usize::from(b.contains(ray.at(t0 + (t1 - t0) * s as f32 / 16.0)));
        }
    }
    assert!(
        all > 1000 && inside as f64 >= 0.99 * all as f64,
        "{inside} of {all} points in the guide"
    );

    let all =
        |cam: &Camera| karstic::picture::view_guides(tree, job, cam, None, 1 << 32, true).unwrap();
    let (eye, target) = TUNNEL_VIEW;
    assert!(all(&Camera::look_at(eye, target, 40.0, 96, 54).unwrap()).is_empty());
    let outside = Vec3::new(4900.0, 4380.0, 780.0);
    let away = Camera::look_at(outside, outside + Vec3::new(1.0, -1.0, 0.2), 40.0, 96, 54).unwrap();
    assert!(all(&away).is_empty());
    assert!(
        karstic::picture::view_guides(tree, None, &main_cam, None, 1 << 32, true)
            .unwrap()
            .is_empty()
    );
}

/// Beyond the job's region, `picture::view_guides` meshes the terrain the camera sees in
/// backdrop levels twice as coarse each, swept towards the sun: on the main view the
/// points of every primary ray's span in the support and of every shadow ray from its
/// hit up to the support's top lie in a guide (there the ray follows a mesh instead of
/// marching the field). Without the sun, the shadow rays leave the guides.
#[test]
fn backdrop_guides_cover_the_view_and_its_shadow_rays() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/jacksboro_caves.ron");
    let loaded = karstic::scene::load(&path).unwrap();
    let (compiled, cam, settings) = job_view(&path, 128, 72);
    let tree = &compiled.tree;
    let job = loaded.scene.job.as_ref();
    let sun = settings.shading.sun;
    let support = tree.support();
    let guides = |sun| karstic::picture::view_guides(tree, job, &cam, sun, 1 << 32, true).unwrap();
    let lit = guides(Some(sun));
    // The backdrop's cells start at the job's `full_cell`, 6 of the region's.
    let cell = job.unwrap().cell.0;
    let backdrop: Vec<_> = lit.iter().filter(|g| g.cell() > 5.0 * cell).collect();
    assert!(
        backdrop.len() >= 2 && backdrop.len() < lit.len(),
        "the region and two backdrop levels: {lit:?}"
    );
    for pair in backdrop.windows(2) {
        let ratio = pair[1].cell() / pair[0].cell();
        assert!((1.9..2.1).contains(&ratio), "{lit:?}");
    }
    let (depth, _) = cpu::depth_guided(tree, &lit, &cam, &settings.trace);
    let covered = |guides: &[std::sync::Arc<Guide>], shadow: bool| {
        let (mut inside, mut all) = (0, 0);
        for (k, &t) in depth.iter().enumerate() {
            let ray = cam.pixel_ray(k as u32 % cam.width, k as u32 / cam.width);
            let ray = match shadow {
                false => ray,
                true if t.is_finite() => karstic::render::Ray {
                    origin: ray.at(t),
                    dir: sun,
                },
                true => continue,
            };
            let Some((t0, t1)) = ray.clip(&support) else {
                continue;
            };
            for s in 0..=16 {
                let p = ray.at(t0 + (t1 - t0) * s as f32 / 16.0);
                all += 1;
                inside += usize::from(guides.iter().any(|g| g.bounds().contains(p)));
            }
        }
        assert!(all > 50_000, "{all} points");
        inside as f64 / all as f64
    };
    let primary = covered(&lit, false);
    let shadows = covered(&lit, true);
    assert!(
        primary > 0.99,
        "{primary} of the primary rays' points in a guide"
    );
    assert!(
        shadows > 0.995,
        "{shadows} of the shadow rays' points in a guide"
    );
    let unlit = covered(&guides(None), true);
    assert!(
        unlit < 0.95,
        "{unlit} of the shadow rays' points without the sun's sweep"
    );
}

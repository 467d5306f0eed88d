//! `karstic edit`: the editor driven headless through its accessibility tree
//! (egui_kittest): edits are `tree set`'s, undo restores the file byte for byte, invalid
//! values are refused with the loader's message, clicks place anchors where the tracer
//! hit, and the viewport shows the tracer's image.

use std::path::{Path, PathBuf};
use std::time::Duration;

use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use karstic::compile::edit;
use karstic::editor::brush::Brush;
use karstic::editor::preview::{
    COARSEST_DIVISOR, DRAG_BUDGET, FAST_DIVISOR, FIRST_DIVISOR, Quality, fast_size,
};
use karstic::editor::{Backend, Editor, Headless, Tool, settle};
use karstic::scene::NodeSpec;

use crate::common::{REQUIRE_GPU, assert_frames_match, unavailable};

/// A Jacksboro crop with a carved grotto, a small job view.
const TREE: &str = r#"(
    version: 1,
    name: "editor_test",
    terrain: "dem",
    job: (
        region: (min: (3000, 4500, 300), max: (5000, 6000, 1100)),
        cell: 10,
        image: (320, 180),
        camera: (eye: (5200, 3900, 1300), target: (4000, 5200, 600)),
        fov: 40, vegetation: 0, // bare: egui's texture sampling blurs pixel-sized crowns
    ),
    root: Difference(
        name: "root",
        base: Heightfield(name: "dem", source: "jacksboro_crop.asc", falloff: 30.0),
        carves: [
            Anchor(
                name: "grotto",
                at: (3690, 5220),
                offset: -12,
                child: Primitive(
                    name: "blob",
                    shape: Sphere(center: (0, 0, 0), radius: 30),
                    falloff: 8.0,
                ),
            ),
        ],
    ),
)
"#;

/// A folder with the tree (as `name`) and its DEM.
fn scene_dir(names: &[&str]) -> (tempfile::TempDir, Vec<PathBuf>) {
    let dir = tempfile::tempdir().unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/data");
    for f in ["jacksboro_crop.asc", "jacksboro_crop.prj"] {
        std::fs::copy(data.join(f), dir.path().join(f)).unwrap();
    }
    let paths = names
        .iter()
        .map(|n| {
            let p = dir.path().join(n);
            std::fs::write(&p, TREE).unwrap();
            p
        })
        .collect();
    (dir, paths)
}

/// The editor on `path` without a renderer (the viewport's image is in its state).
fn harness(path: &Path) -> Harness<'static, Editor> {
    let mut h = Harness::builder()
        .with_size(egui::vec2(1000.0, 600.0))
        .build_ui_state(|ui, e: &mut Editor| e.ui(ui), Editor::open(path));
    h.run_steps(2);
    h
}

fn select(h: &mut Harness<'_, Editor>, name: &str) {
    h.get_by_label(name).click();
    h.run_steps(2);
    assert_eq!(h.state().selected(), Some(name));
}

#[test]
fn editor_set_writes_what_tree_set_writes_and_undo_restores() {
    let (_dir, paths) = scene_dir(&["a.ron", "b.ron"]);
    let (a, b) = (&paths[0], &paths[1]);
    let original = std::fs::read(a).unwrap();
    let mut h = harness(a);
    select(&mut h, "blob");
    h.get_by_role_and_label(Role::SpinButton, "radius")
        .set_value_accesskit(45.0);
    h.run_steps(2);
    edit::set_param(b, "blob.shape.radius", "45").unwrap();
    let written = std::fs::read(a).unwrap();
    assert_eq!(
        String::from_utf8_lossy(&written),
        String::from_utf8_lossy(&std::fs::read(b).unwrap())
    );
    assert_ne!(written, original);
    assert!(h.state().text().contains("radius: 45"));
    // The previous version is kept beside the file.
    let mut bak = a.as_os_str().to_owned();
    bak.push(".bak");
    assert_eq!(std::fs::read(&bak).unwrap(), original);

    h.get_by_label("Undo").click();
    h.run_steps(2);
    assert_eq!(
        std::fs::read(a).unwrap(),
        original,
        "undo restores the bytes"
    );
    h.get_by_label("Redo").click();
    h.run_steps(2);
    assert_eq!(
        std::fs::read(a).unwrap(),
        written,
        "redo applies the edit again"
    );
}

/// A count is edited as a whole number: its widget steps and writes whole numbers (shown
/// as `8.00`, a count took `9.5` and answered "Expected comma").
#[test]
fn editor_edits_counts_as_whole_numbers() {
    let (_dir, paths) = scene_dir(&["a.ron"]);
    let a = &paths[0];
    let noisy = TREE.replace(
        "falloff: 8.0,\n",
        "falloff: 8.0,\n                    noise: (amplitude: 2, wavelength: 10, octaves: 3),\n",
    );
    std::fs::write(a, &noisy).unwrap();
    let mut h = harness(a);
    select(&mut h, "blob");
    h.get_by_role_and_label(Role::SpinButton, "octaves")
        .set_value_accesskit(5.5);
    h.run_steps(2);
    let text = std::fs::read_to_string(a).unwrap();
    assert!(
        text.contains("octaves: 5)") || text.contains("octaves: 6)"),
        "{text}\n{}",
        h.state().status()
    );
}

#[test]
fn editor_refuses_an_invalid_value_with_the_loaders_message() {
    let (_dir, paths) = scene_dir(&["a.ron"]);
    let a = &paths[0];
    let original = std::fs::read(a).unwrap();
    let mut h = harness(a);
    select(&mut h, "blob");
    h.get_by_role_and_label(Role::SpinButton, "radius")
        .set_value_accesskit(-5.0);
    h.run_steps(2);
    assert_eq!(std::fs::read(a).unwrap(), original, "nothing written");
    let message = karstic::io::chain(&edit::set_param(a, "blob.shape.radius", "-5").unwrap_err());
    assert!(message.contains("radius"), "{message}");
    assert!(
        h.query_all_by_label(&message).count() > 0,
        "{message} not shown"
    );
    // The message is about the node left: selecting another one clears it.
    select(&mut h, "grotto");
    assert_eq!(
        h.query_all_by_label(&message).count(),
        0,
        "{message} still shown"
    );
    assert!(h.state().status().is_empty(), "{}", h.state().status());
}

#[test]
fn editor_reloads_the_file_and_shows_its_errors_with_positions() {
    let (_dir, paths) = scene_dir(&["a.ron"]);
    let a = &paths[0];
    let mut h = harness(a);
    std::thread::sleep(Duration::from_millis(20));
    std::fs::write(a, TREE.replace("radius: 30", "radius: 31, colour: 2")).unwrap();
    h.run_steps(2);
    let e = h
        .state()
        .load_error()
        .expect("the broken file is reported")
        .to_string();
    let located = karstic::io::chain(&karstic::scene::load(a).unwrap_err());
    assert_eq!(e, located);
    assert!(e.contains("a.ron:22:66:"), "{e}");
    std::fs::write(a, TREE.replace("radius: 30", "radius: 31")).unwrap();
    h.run_steps(2);
    assert!(h.state().load_error().is_none());
    assert!(h.state().text().contains("radius: 31"));
}

/// The pixel of `frame` nearest its centre whose ray hit the surface.
fn a_hit_pixel(frame: &karstic::render::Frame) -> (u32, u32) {
    let (w, h) = (frame.width, frame.height);
    (0..w * h)
        .filter(|&k| frame.depth[k as usize].is_finite())
        .map(|k| (k % w, k / w))
        .min_by_key(|&(i, j)| (i as i64 - w as i64 / 2).pow(2) + (j as i64 - h as i64 / 2).pow(2))
        .expect("the view sees the terrain")
}

#[test]
fn editor_click_places_an_anchor_where_the_tracer_hit() {
    let (_dir, paths) = scene_dir(&["a.ron"]);
    let a = &paths[0];
    let mut h = harness(a);
    settle(&mut h, Duration::from_secs(120)).unwrap();
    h.state_mut().tool = Tool::Anchor;
    let shown = h.state().shown().unwrap().clone();
    let rect = h.state().viewport().unwrap();
    let (i, j) = a_hit_pixel(&shown.frame);
    let pos = rect.min
        + egui::vec2(
            (i as f32 + 0.5) * rect.width() / shown.frame.width as f32,
            (j as f32 + 0.5) * rect.height() / shown.frame.height as f32,
        );
    for pressed in [true, false] {
        h.event(egui::Event::PointerMoved(pos));
        h.event(egui::Event::PointerButton {
            pos,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: egui::Modifiers::NONE,
        });
        h.step();
    }
    h.run_steps(2);
    // The tracer's answer for that pixel: the depth of the image shown.
    let file = karstic::scene::load(a).unwrap();
    let cam = shown.camera;
    let t = shown.frame.depth[(j * cam.width + i) as usize];
    assert!(t.is_finite());
    let p = cam.pixel_ray(i, j).at(t);
    let named = file.scene.named();
    let Some(NodeSpec::Anchor(anchor)) = named.get("anchor_1") else {
        panic!("no anchor placed: {}", h.state().status());
    };
    let at = anchor.at.0;
    assert!(
        (at - p.truncate()).length() <= 1e-3,
        "anchor at {at:?}, the tracer hit {p:?}"
    );
    // The toolbar's offset (0 m by default) is the anchor's.
    assert_eq!(anchor.offset.0, 0.0);
    assert_eq!(h.state().selected(), Some("anchor_1"));
}

#[test]
fn editor_viewport_shows_the_tracers_image() {
    if karstic::render::gpu::GpuContext::new().is_err() {
        unavailable(REQUIRE_GPU, "the editor's snapshot needs a wgpu adapter");
        return;
    }
    let (_dir, paths) = scene_dir(&["a.ron"]);
    let a = &paths[0];
    let how = Headless {
        size: (900, 500),
        select: None,
        graph: false,
        backend: Backend::Cpu,
        timeout: Duration::from_secs(120),
        budget: karstic::io::DEFAULT_MEMORY_BUDGET,
    };
    let mut h = karstic::editor::headless(a, &how).unwrap();
    let image = h.render().unwrap();
    let shown = h.state().shown().unwrap().clone();
    assert_eq!(shown.tracer, "CPU");
    let rect = h.state().viewport().unwrap();
    let f = &shown.frame;
    assert_eq!(
        (f.width, f.height),
        (rect.width().round() as u32, rect.height().round() as u32)
    );
    // The tracer's image through the same camera, independently.
    let file = karstic::scene::load(a).unwrap();
    let compiled = file.compile().unwrap();
    let reference = karstic::editor::preview::draw(
        &file.scene,
        &compiled,
        &shown.camera,
        karstic::editor::preview::Quality::Full,
    );
    let (x0, y0) = (rect.min.x.round() as u32, rect.min.y.round() as u32);
    let (mut total, mut far) = (0u64, 0usize);
    for j in 0..f.height {
        for i in 0..f.width {
            let got = image.get_pixel(x0 + i, y0 + j).0;
            let k = 4 * (j * f.width + i) as usize;
            let d = (0..3)
                .map(|c| (got[c] as i32 - reference.rgba[k + c] as i32).unsigned_abs())
                .max()
                .unwrap();
            total += d as u64;
            far += usize::from(d > 12);
        }
    }
    let n = (f.width * f.height) as f64;
    let mean = total as f64 / n;
    assert!(mean < 2.0, "mean difference {mean:.2} levels");
    assert!(
        (far as f64) < 0.01 * n,
        "{far} pixels differ by more than 12 levels"
    );
}

/// With `--gpu` the viewport's refined image is the wgpu tracer's (here on whatever
/// adapter there is, lavapipe included), equal to the CPU's image of the same view within
/// the renderers' parity tolerance, and the status line says which tracer drew it.
#[test]
fn editor_refines_the_viewport_on_the_gpu_when_asked() {
    if karstic::render::gpu::GpuContext::new().is_err() {
        unavailable(
            REQUIRE_GPU,
            "the editor's GPU viewport needs a wgpu adapter",
        );
        return;
    }
    let (_dir, paths) = scene_dir(&["a.ron"]);
    let how = Headless {
        size: (700, 260),
        select: None,
        graph: false,
        backend: Backend::Gpu,
        timeout: Duration::from_secs(300),
        budget: karstic::io::DEFAULT_MEMORY_BUDGET,
    };
    let h = karstic::editor::headless(&paths[0], &how).unwrap();
    let shown = h.state().shown().unwrap().clone();
    assert!(
        shown.tracer.starts_with("GPU ("),
        "drawn by {}",
        shown.tracer
    );
    assert_eq!(shown.quality, Quality::Full);
    let f = &shown.frame;
    assert!(
        f.width >= 100 && f.height >= 100,
        "{} × {}",
        f.width,
        f.height
    );
    let file = karstic::scene::load(&paths[0]).unwrap();
    let compiled = file.compile().unwrap();
    // The GPU's viewport draws the ground bare (the shader has no plants, no talus).
    let bare = karstic::editor::preview::gpu_settings(&file.scene, &compiled, &shown.camera);
    let cpu = karstic::render::render(
        &compiled.tree,
        &shown.camera,
        &bare,
        &indicatif::ProgressBar::hidden(),
    );
    assert!(cpu.hits() > f.depth.len() / 4, "{} hits", cpu.hits());
    assert_frames_match("the editor's GPU viewport", &cpu, f);
    h.get_by_label_contains("viewport: GPU (");
}

/// A dragged value recompiles the tree for each preview, its Feature Volumes taken from
/// the process's memo when nothing they are built from changed: the memo's volume is
/// the direct build's, and a value of the volume's rebuilds it.
#[test]
fn editor_memo_volumes_are_the_direct_builds() {
    let (dir, _) = scene_dir(&[]);
    let path = dir.path().join("tunnel.ron");
    std::fs::write(&path, tunnel_tree()).unwrap();
    let file = karstic::scene::load(&path).unwrap();
    let volume = |scene: &karstic::scene::Scene| {
        let f = karstic::scene::SceneFile {
            scene: scene.clone(),
            path: path.clone(),
            base_dir: dir.path().to_path_buf(),
        };
        let spec = f.feature_volumes()[0].clone();
        f.build_feature_volume(&spec, scene.seed, 1 << 30).unwrap()
    };
    // The whole field, its voxels included (a small volume).
    let text = |f: karstic::voxel::SField| format!("{f:?}");
    let before = text(volume(&file.scene));
    // The anchor's offset is not the volume's: the same field.
    let mut other = file.scene.clone();
    edit::set_in_scene(&mut other, &path, "grotto.offset", "-20").unwrap();
    assert!(
        text(volume(&other)) == before,
        "the anchor changed the volume"
    );
    // Built directly (no memo) on each scene's terrain: the reference.
    let direct = |scene: &karstic::scene::Scene| {
        let f = karstic::scene::SceneFile {
            scene: scene.clone(),
            path: path.clone(),
            base_dir: dir.path().to_path_buf(),
        };
        let g = f.compile().unwrap().ground.unwrap();
        let ground = |xy: glam::Vec2| Some(g.height(xy));
        let opts = karstic::voxel::spec::BuildOptions {
            seed: scene.seed,
            ground: Some(&ground),
            max_memory: 1 << 30,
        };
        text(
            f.feature_volumes()[0]
                .build_with(dir.path(), &opts)
                .unwrap(),
        )
    };
    assert!(
        direct(&file.scene) == before,
        "the memo's volume is not the direct build's"
    );
    // A value of the volume's: built again.
    let mut finer = file.scene.clone();
    edit::set_in_scene(&mut finer, &path, "cave.voxel", "10").unwrap();
    let f = text(volume(&finer));
    assert!(
        f != before,
        "the memo kept the volume of the old voxel size"
    );
    assert!(f == direct(&finer));
    // The terrain's values: the memo answers what a direct build does.
    let mut raised = file.scene.clone();
    edit::set_in_scene(&mut raised, &path, "dem.vertical_offset", "50").unwrap();
    assert!(text(volume(&raised)) == direct(&raised));
    assert!(text(volume(&file.scene)) == before);
}

/// The fast pass: a sixteenth of the side before any cost is known, then the size that
/// fits the drag budget, between an eighth and a thirty-second of the side.
#[test]
fn editor_fast_passes_fit_the_drag_budget() {
    let view = (960, 540);
    let side = |d: u32| (960 / d, 540 / d);
    assert_eq!(fast_size(view, None, DRAG_BUDGET), side(FIRST_DIVISOR));
    // 1 µs a pixel: 518,400 pixels take 0.52 s, 80 ms is 6.5× fewer: 1/2.5 of the
    // side, held at an eighth.
    assert_eq!(fast_size(view, Some(1e-6), DRAG_BUDGET), side(FAST_DIVISOR));
    // 31 µs a pixel (a 120 × 67 pass in 0.25 s): 200× too many, a fifteenth of the side.
    assert_eq!(fast_size(view, Some(3.1e-5), DRAG_BUDGET), side(15));
    // Far too slow: held at a thirty-second; a tiny view: at least one pixel.
    assert_eq!(
        fast_size(view, Some(1.0), DRAG_BUDGET),
        side(COARSEST_DIVISOR)
    );
    assert_eq!(fast_size((10, 5), Some(1.0), DRAG_BUDGET), (1, 1));
}

/// The editor's tree with a Feature Volume carving a tunnel whose ends are on the
/// ground: two `Ground` control points.
fn tunnel_tree() -> String {
    TREE.replace(
        "        carves: [\n",
        r#"        carves: [
            FeatureVolume(
                name: "cave",
                curves: Inline(tunnels: [(
                    path: [Ground(3600, 5100, -5), Ground(3800, 5150, -5)],
                    width: Const(30),
                    height: Const(20),
                )]),
                domain: ((3450, 4950, 300), (3950, 5300, 1100)),
                voxel: 20,
            ),
"#,
    )
}

/// The primary button pressed (or released) at `pos`.
fn primary(pos: egui::Pos2, pressed: bool) -> egui::Event {
    egui::Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: egui::Modifiers::NONE,
    }
}

/// Presses the primary button at `from` and moves to `to` in steps, still pressed.
fn press_and_move(h: &mut Harness<'_, Editor>, from: egui::Pos2, to: egui::Pos2) {
    h.event(egui::Event::PointerMoved(from));
    h.step();
    h.event(primary(from, true));
    h.step();
    for k in 1..=8 {
        h.event(egui::Event::PointerMoved(
            from + (to - from) * (k as f32 / 8.0),
        ));
        h.step();
    }
}

/// Releases the primary button at `to`.
fn release(h: &mut Harness<'_, Editor>, to: egui::Pos2) {
    h.step();
    h.event(primary(to, false));
    h.step();
    h.run_steps(2);
}

/// Presses the primary button at `from`, moves to `to` in steps and releases there.
fn drag(h: &mut Harness<'_, Editor>, from: egui::Pos2, to: egui::Pos2) {
    press_and_move(h, from, to);
    release(h, to);
}

#[test]
fn editor_drags_a_feature_curve_point_along_the_surface_as_one_edit() {
    let (dir, _) = scene_dir(&[]);
    let a = dir.path().join("a.ron");
    std::fs::write(&a, tunnel_tree()).unwrap();
    let original = std::fs::read(&a).unwrap();
    let mut h = harness(&a);
    settle(&mut h, Duration::from_secs(300)).unwrap();
    let shown = h.state().shown().unwrap().clone();
    let rect = h.state().viewport().unwrap();
    let f = &shown.frame;
    let cam = shown.camera;
    let to_screen = |(x, y): (f32, f32)| {
        rect.min
            + egui::vec2(
                x * rect.width() / f.width as f32,
                y * rect.height() / f.height as f32,
            )
    };
    // The tunnel's first point, where the viewport shows it.
    let handle = shown
        .handles
        .iter()
        .find(|h| h.volume == "cave" && h.slot == karstic::editor::points::Slot::Tunnel(0, 0))
        .expect("the tunnel's first point is a handle")
        .clone();
    let from = to_screen(karstic::editor::points::project(&cam, handle.world).unwrap());
    assert!(rect.contains(from), "the point is in view");
    // Dragged to the surface at a pixel well away from it.
    let (i, j) = a_hit_pixel(f);
    let to = to_screen((i as f32 + 0.5, j as f32 + 0.5));
    assert!(from.distance(to) > 30.0, "{from:?} → {to:?}");
    drag(&mut h, from, to);
    let p = cam.pixel_ray(i, j).at(f.depth[(j * f.width + i) as usize]);
    let file = karstic::scene::load(&a).unwrap();
    let named = file.scene.named();
    let Some(NodeSpec::FeatureVolume(v)) = named.get("cave") else {
        panic!("no cave: {}", h.state().status());
    };
    let karstic::voxel::spec::CurveSource::Inline(set) = &v.curves else {
        panic!("the curves stay inline");
    };
    let karstic::voxel::spec::Point::Ground(x, y, off) = set.tunnels[0].path[0] else {
        panic!(
            "the point stays on the ground: {:?}",
            set.tunnels[0].path[0]
        );
    };
    assert!(
        (glam::Vec2::new(x.0, y.0) - p.truncate()).length() < 1e-2,
        "moved to ({}, {}), the surface under the pointer is {p:?} ({})",
        x.0,
        y.0,
        h.state().status()
    );
    assert_eq!(off.0, -5.0, "the offset is kept");
    assert_eq!(
        set.tunnels[0].path[1],
        karstic::voxel::spec::Point::Ground(
            karstic::value::Finite(3800.0),
            karstic::value::Finite(5150.0),
            karstic::value::Finite(-5.0)
        ),
        "the other point stays"
    );
    assert_eq!(h.state().selected(), Some("cave"));
    // One edit: one undo puts the file back byte for byte.
    h.get_by_label("Undo").click();
    h.run_steps(2);
    assert_eq!(std::fs::read(&a).unwrap(), original);
}

#[test]
fn editor_drops_absolute_points_in_the_plane_parallel_to_the_image() {
    use karstic::editor::points::{Handle, Slot, drop_at, project};
    let cam = karstic::render::Camera::look_at(
        glam::Vec3::new(0.0, -100.0, 50.0),
        glam::Vec3::ZERO,
        40.0,
        200,
        100,
    )
    .unwrap();
    let world = glam::Vec3::new(10.0, 5.0, 3.0);
    let handle = Handle {
        volume: "v".into(),
        slot: Slot::Curve(0, 1),
        point: karstic::voxel::spec::Point::Abs(
            karstic::value::Finite(10.0),
            karstic::value::Finite(5.0),
            karstic::value::Finite(3.0),
        ),
        world,
    };
    let frame = karstic::render::Frame::new(1, 1, vec![0; 4], vec![f32::INFINITY], vec![0]);
    let (x, y) = project(&cam, world).unwrap();
    let forward = (cam.target - cam.eye).normalize();
    for (dx, dy) in [(0.0, 0.0), (25.0, -10.0), (-40.0, 30.0)] {
        let q = drop_at(&handle, &frame, &cam, x + dx, y + dy).unwrap();
        // In the plane through the point, parallel to the image…
        assert!(((q - world).dot(forward)).abs() < 1e-3, "{q:?}");
        // …and under the pointer.
        let (qx, qy) = project(&cam, q).unwrap();
        assert!(
            (qx - x - dx).abs() < 1e-2 && (qy - y - dy).abs() < 1e-2,
            "{qx}, {qy}"
        );
    }
}

#[test]
fn editor_duplicates_a_node_with_named_children_under_fresh_names() {
    let (_dir, paths) = scene_dir(&["a.ron"]);
    let a = &paths[0];
    let mut h = harness(a);
    select(&mut h, "grotto");
    h.get_by_label("Duplicate").click();
    h.run_steps(2);
    let file = karstic::scene::load(a).unwrap_or_else(|e| panic!("{e}"));
    let named = file.scene.named();
    let Some(NodeSpec::Anchor(copy)) = named.get("grotto_1") else {
        panic!("no copy: {}", h.state().status());
    };
    assert_eq!(copy.child.name(), Some("blob_1"), "the child renamed too");
    assert!(named.contains_key("grotto") && named.contains_key("blob"));
    assert_eq!(h.state().selected(), Some("grotto_1"));
    // Again: the next free suffix.
    h.get_by_label("Duplicate").click();
    h.run_steps(2);
    let file = karstic::scene::load(a).unwrap();
    let named = file.scene.named();
    let mut names: Vec<&str> = named.keys().copied().collect();
    names.sort();
    assert_eq!(
        names,
        [
            "blob",
            "blob_1",
            "blob_1_1",
            "dem",
            "grotto",
            "grotto_1",
            "grotto_1_1",
            "root"
        ]
    );
}

#[test]
fn editor_shows_the_normals_and_the_cost_of_its_image() {
    let (_dir, paths) = scene_dir(&["a.ron"]);
    let a = &paths[0];
    let mut h = harness(a);
    h.get_by_label("normals").click();
    h.run_steps(2);
    settle(&mut h, Duration::from_secs(120)).unwrap();
    let shown = h.state().shown().unwrap().clone();
    let f = &shown.frame;
    let normals = shown.normals.as_ref().expect("the normals were asked for");
    assert_eq!(h.state().shown_colours().as_ref(), Some(normals));
    let file = karstic::scene::load(a).unwrap();
    let compiled = file.compile().unwrap();
    let (mut hits, mut misses) = (0, 0);
    for k in (0..f.width * f.height).step_by(97) {
        let (i, j) = (k % f.width, k / f.width);
        let t = f.depth[k as usize];
        let got = &normals[4 * k as usize..4 * k as usize + 3];
        if t.is_finite() {
            let n =
                karstic::render::trace::normal(&compiled.tree, shown.camera.pixel_ray(i, j).at(t));
            for c in 0..3 {
                let want = (n[c] + 1.0) * 127.5;
                assert!(
                    (got[c] as f32 - want).abs() <= 1.0,
                    "pixel {i},{j}: {got:?} for {n:?}"
                );
            }
            hits += 1;
        } else {
            assert_eq!(got, [0, 0, 0], "the sky is black");
            misses += 1;
        }
    }
    assert!(hits > 20, "{hits} hits, {misses} misses");
    h.get_by_label("cost").click();
    h.run_steps(2);
    assert_eq!(h.state().shown_colours(), Some(f.cost_rgba()));
    assert_ne!(f.cost_rgba(), f.rgba);
}

#[test]
fn editor_graph_selects_like_the_outline_and_follows_the_file() {
    let (_dir, paths) = scene_dir(&["a.ron"]);
    // Wide enough for the graph's four columns between the outline and the inspector.
    let mut h = Harness::builder()
        .with_size(egui::vec2(1500.0, 800.0))
        .build_ui_state(|ui, e: &mut Editor| e.ui(ui), Editor::open(&paths[0]));
    h.run_steps(2);
    h.get_by_label("graph").click();
    h.run_steps(2);
    // Every named node is in the outline and, lowest in the window, in the graph.
    let graph_node = |h: &Harness<'_, Editor>, name: &str| {
        let nodes: Vec<_> = h.get_all_by_label_contains(name).collect();
        assert!(nodes.len() >= 2, "{name}: in the outline and the graph");
        nodes
            .into_iter()
            .max_by(|a, b| a.rect().min.y.total_cmp(&b.rect().min.y))
            .unwrap()
            .rect()
    };
    for name in ["root", "dem", "grotto", "blob"] {
        let at = graph_node(&h, name).center();
        h.get_all_by_label_contains(name)
            .find(|n| n.rect().center() == at)
            .unwrap()
            .click();
        h.run_steps(2);
        assert_eq!(h.state().selected(), Some(name));
    }
    // Parents to the right of their children, wired from the file's tree.
    assert!(graph_node(&h, "root").min.x > graph_node(&h, "grotto").min.x);
    assert!(graph_node(&h, "grotto").min.x > graph_node(&h, "blob").min.x);
    // An edit of the file shows in both at once.
    edit::set_param(&paths[0], "blob.name", "\"bubble\"").unwrap();
    h.run_steps(2);
    graph_node(&h, "bubble");
}

/// Ctrl+S answers in the status line (it gave no sign of anything): every edit is already
/// in the file.
#[test]
fn editor_ctrl_s_says_the_file_is_saved() {
    let (_dir, paths) = scene_dir(&["a.ron"]);
    let mut h = harness(&paths[0]);
    h.event(egui::Event::Key {
        key: egui::Key::S,
        physical_key: None,
        pressed: true,
        repeat: false,
        modifiers: egui::Modifiers::COMMAND,
    });
    h.run_steps(2);
    let status = h.state().status().to_string();
    assert!(
        status.starts_with("saved: every edit is written to"),
        "{status}"
    );
    assert!(status.contains("a.ron"), "{status}");
}

/// Selecting a node leaves the viewport's size as it was, so its picture does not restart:
/// the inspector's content scrolls rather than widening its panel (a node with wider
/// fields narrowed the viewport, 963 → 983 → 956 px, and the image fell back to coarse
/// blocks at each selection).
#[test]
fn editor_viewport_keeps_its_size_when_the_selection_changes() {
    let (dir, _) = scene_dir(&[]);
    let wide = TREE.replace(
        "source: \"jacksboro_crop.asc\"",
        "source: \"jacksboro_crop.asc\", detail: (noise: (amplitude: 4.0, wavelength: 60.0, octaves: 3, seed_offset: 12345678), steep: 0.5)",
    );
    let path = dir.path().join("a.ron");
    std::fs::write(&path, wide).unwrap();
    let mut h = harness(&path);
    let before = h.state().viewport().expect("the viewport is drawn");
    for name in ["dem", "blob", "grotto", "root", "dem"] {
        select(&mut h, name);
        let now = h.state().viewport().expect("the viewport is drawn");
        assert_eq!(now, before, "selecting {name} moved the viewport");
    }
}

/// A headland of bedded rock standing 50 m out of a sea, a blind cave (a Feature Volume
/// tunnel of the air, `Abs` points) inside it: the scene the sea-cave scenario authors in.
const CLIFF_TREE: &str = r#"(
    version: 1,
    name: "sea_cave_editor",
    job: (
        region: (min: (-100, -250, -80), max: (700, 250, 120)),
        cell: 4,
        image: (320, 180),
        camera: (eye: (800, -400, 90), target: (380, 20, 0)),
        fov: 40,
        vegetation: 0,
        water_level: 0,
    ),
    root: Difference(
        name: "root",
        base: Blend(name: "land", children: [
            // The headland: its sea face at x = 400.
            Primitive(name: "headland", shape: Box(center: (150, 0, 0), half_size: (250, 200, 50)), falloff: 6),
            Primitive(name: "seabed", shape: Box(center: (300, 0, -50), half_size: (400, 250, 20)), falloff: 6),
        ]),
        carves: [
            FeatureVolume(
                name: "cave",
                curves: Inline(tunnels: [(
                    path: [Abs(250, 0, 5), Abs(330, 20, 5)],
                    width: Const(24),
                    height: Const(16),
                )]),
                domain: ((150, -120, -40), (480, 140, 60)),
                voxel: 4,
                orientation: Air,
            ),
        ],
    ),
)
"#;

/// The cliff tree in a folder of its own, and the editor on it, settled.
fn cliff_editor() -> (tempfile::TempDir, PathBuf, Harness<'static, Editor>) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cliff.ron");
    std::fs::write(&path, CLIFF_TREE).unwrap();
    // Frames of 50 ms, so that two clicks a frame apart are a double click (egui's
    // limit is 0.3 s; the harness's default frame is 0.25 s).
    let mut h = Harness::builder()
        .with_size(egui::vec2(1000.0, 600.0))
        .with_step_dt(0.05)
        .build_ui_state(|ui, e: &mut Editor| e.ui(ui), Editor::open(&path));
    settle(&mut h, Duration::from_secs(300)).unwrap();
    (dir, path, h)
}

/// Where the world point `p` is in the editor's viewport, in points.
fn on_screen(h: &Harness<'_, Editor>, p: glam::Vec3) -> egui::Pos2 {
    let shown = h.state().shown().unwrap();
    let rect = h.state().viewport().unwrap();
    let (x, y) = karstic::editor::points::project(&shown.camera, p).unwrap();
    rect.min
        + egui::vec2(
            x * rect.width() / shown.frame.width as f32,
            y * rect.height() / shown.frame.height as f32,
        )
}

/// The world point a drag of a handle at `world` must aim at to land `by` further, in the
/// plane through it parallel to the image (where an `Abs` point moves).
fn in_image_plane(h: &Harness<'_, Editor>, world: glam::Vec3, by: glam::Vec3) -> glam::Vec3 {
    let cam = h.state().shown().unwrap().camera;
    let forward = cam.basis().2;
    world + by - forward * by.dot(forward)
}

/// `clicks` clicks of `button` at `pos`, one frame an event (two: a double click).
fn click_at(
    h: &mut Harness<'_, Editor>,
    pos: egui::Pos2,
    button: egui::PointerButton,
    clicks: usize,
) {
    let press = |pressed| egui::Event::PointerButton {
        pos,
        button,
        pressed,
        modifiers: egui::Modifiers::NONE,
    };
    h.event(egui::Event::PointerMoved(pos));
    for _ in 0..clicks {
        h.event(press(true));
        h.event(press(false));
    }
    h.step();
    h.run_steps(2);
}

/// The handle of the `cave` volume at `slot` in the editor's latest image.
fn cave_handle(
    h: &Harness<'_, Editor>,
    slot: karstic::editor::points::Slot,
) -> karstic::editor::points::Handle {
    let shown = h.state().shown().unwrap();
    (shown.handles.iter())
        .find(|x| x.volume == "cave" && x.slot == slot)
        .unwrap_or_else(|| panic!("no handle {slot:?}"))
        .clone()
}

/// The points of the cave's tunnel in the file.
fn cave_path(path: &Path) -> Vec<karstic::voxel::spec::Point> {
    let file = karstic::scene::load(path).unwrap();
    let named = file.scene.named();
    let Some(NodeSpec::FeatureVolume(v)) = named.get("cave") else {
        panic!("no cave");
    };
    let karstic::voxel::spec::CurveSource::Inline(set) = &v.curves else {
        panic!("the curves stay inline");
    };
    set.tunnels[0].path.clone()
}

#[test]
fn editor_inserts_and_removes_curve_points_and_previews_a_drag() {
    use karstic::editor::points::Slot;
    use karstic::value::Finite;
    use karstic::voxel::spec::Point;
    let (_dir, path, mut h) = cliff_editor();
    let original = cave_path(&path);
    // A double click on the first point inserts one halfway to the second.
    let first = cave_handle(&h, Slot::Tunnel(0, 0));
    let at = on_screen(&h, first.world);
    click_at(&mut h, at, egui::PointerButton::Primary, 2);
    let three = cave_path(&path);
    assert_eq!(three.len(), 3, "{}", h.state().status());
    let f = Finite;
    assert_eq!(three[1], Point::Abs(f(290.0), f(10.0), f(5.0)));
    assert_eq!((three[0], three[2]), (original[0], original[1]));
    assert_eq!(h.state().selected(), Some("cave"));
    settle(&mut h, Duration::from_secs(300)).unwrap();
    // A right click on it removes it.
    let mid = cave_handle(&h, Slot::Tunnel(0, 1));
    assert_eq!(mid.point, three[1]);
    let at = on_screen(&h, mid.world);
    click_at(&mut h, at, egui::PointerButton::Secondary, 1);
    assert_eq!(cave_path(&path), original, "{}", h.state().status());
    settle(&mut h, Duration::from_secs(300)).unwrap();
    // A path keeps two points: the right click is refused, in words.
    let before = std::fs::read(&path).unwrap();
    let end = cave_handle(&h, Slot::Tunnel(0, 1));
    let at = on_screen(&h, end.world);
    click_at(&mut h, at, egui::PointerButton::Secondary, 1);
    assert_eq!(std::fs::read(&path).unwrap(), before);
    assert!(
        h.state().status().contains("at least 2 points"),
        "{}",
        h.state().status()
    );
    // While a point is dragged the viewport previews the volume rebuilt with the point
    // where it is, on a coarser grid, and the file is not written until the release.
    let from = on_screen(&h, end.world);
    let goal = in_image_plane(&h, end.world, glam::Vec3::new(60.0, 60.0, 0.0));
    let to = on_screen(&h, goal);
    press_and_move(&mut h, from, to);
    let (preview, version) = h.state().previewing().expect("a preview while dragging");
    let preview = preview.clone();
    let named = preview.named();
    let Some(NodeSpec::FeatureVolume(v)) = named.get("cave") else {
        panic!("no cave in the preview");
    };
    // 330 × 260 × 100 m in at most 32³ voxels: 6.4 m, not the file's 4 m.
    assert!((v.voxel.get() - 6.4).abs() < 0.05, "{}", v.voxel.get());
    let karstic::voxel::spec::CurveSource::Inline(set) = &v.curves else {
        panic!()
    };
    let Point::Abs(x, y, _) = set.tunnels[0].path[1] else {
        panic!()
    };
    assert!(
        glam::Vec2::new(x.0, y.0).distance(goal.truncate()) < 3.0,
        "the preview's point ({}, {}) is under the pointer, at {goal}",
        x.0,
        y.0
    );
    assert_eq!(
        std::fs::read(&path).unwrap(),
        before,
        "nothing written mid-drag"
    );
    // The preview is drawn.
    let start = std::time::Instant::now();
    while h.state().shown().unwrap().version != version {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the preview was not drawn"
        );
        h.step();
        std::thread::sleep(Duration::from_millis(10));
    }
    release(&mut h, to);
    let Point::Abs(x, ..) = cave_path(&path)[1] else {
        panic!()
    };
    assert!((x.0 - goal.x).abs() < 3.0, "written on release: {x:?}");
}

#[test]
fn editor_authors_a_sea_cave_with_brushes_and_a_dragged_tunnel() {
    use karstic::editor::points::Slot;
    let (_dir, path, mut h) = cliff_editor();
    let mut actions = 0;
    // 1. Drag the blind cave's inner end out through the sea face (x = 400).
    let end = cave_handle(&h, Slot::Tunnel(0, 1));
    let goal = in_image_plane(&h, end.world, glam::Vec3::new(110.0, 110.0, 0.0));
    assert!(goal.x > 420.0, "{goal}");
    let (from, to) = (on_screen(&h, end.world), on_screen(&h, goal));
    drag(&mut h, from, to);
    actions += 1;
    settle(&mut h, Duration::from_secs(300)).unwrap();
    // 2. The carve brush, made smaller with the wheel.
    h.get_by_label("carve").click();
    h.run_steps(2);
    actions += 1;
    let face = |y: f32| glam::Vec3::new(403.0, y, 6.0);
    let over = on_screen(&h, face(-100.0));
    h.event(egui::Event::PointerMoved(over));
    h.event(egui::Event::MouseWheel {
        unit: egui::MouseWheelUnit::Point,
        delta: egui::vec2(0.0, -350.0),
        phase: egui::TouchPhase::Move,
        source: egui::MouseWheelSource::Unknown,
        modifiers: egui::Modifiers::NONE,
    });
    h.run_steps(30);
    actions += 1;
    let radius = h.state().place_radius;
    assert!(
        (5.0..15.0).contains(&radius),
        "the wheel sized the brush: {radius}"
    );
    // 3. A stroke along the sea face at the waterline: the wave-cut notch the cave opens
    // from.
    let (from, to) = (on_screen(&h, face(-150.0)), on_screen(&h, face(40.0)));
    press_and_move(&mut h, from, to);
    // While it is drawn, the viewport previews the stroke's node, nothing written yet.
    let (preview, _) = h.state().previewing().expect("a stroke is previewed");
    let Some(NodeSpec::Difference(root)) = preview.named().get("root").copied().cloned() else {
        panic!()
    };
    assert!(root.carves.iter().any(|c| c.name() == Some("carve_1")));
    assert!(!std::fs::read_to_string(&path).unwrap().contains("carve_1"));
    release(&mut h, to);
    actions += 1;
    settle(&mut h, Duration::from_secs(300)).unwrap();
    // 4. A raise stroke on the headland's top (the Blend "land" selected): a ridge.
    h.get_by_label("land").click();
    h.run_steps(2);
    h.get_by_label("raise").click();
    h.run_steps(2);
    actions += 2;
    assert_eq!(h.state().tool, Tool::Brush(Brush::Raise));
    let top = |x: f32| glam::Vec3::new(x, -100.0, 53.0);
    let (from, to) = (on_screen(&h, top(250.0)), on_screen(&h, top(370.0)));
    let rect = h.state().viewport().unwrap();
    assert!(
        rect.contains(from) && rect.contains(to),
        "{from:?} → {to:?} in {rect:?}"
    );
    drag(&mut h, from, to);
    actions += 1;
    assert_eq!(
        h.state().selected(),
        Some("raise_1"),
        "{}",
        h.state().status()
    );
    settle(&mut h, Duration::from_secs(300)).unwrap();
    // 5. Save.
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    h.run_steps(2);
    actions += 1;
    assert!(
        h.state().status().starts_with("saved"),
        "{}",
        h.state().status()
    );
    let picture = h.state().shown().unwrap().frame.clone();
    let text = std::fs::read_to_string(&path).unwrap();
    drop(h);

    // The file holds what was authored.
    let scene = karstic::scene::load(&path).unwrap().scene;
    let named = scene.named();
    let Some(NodeSpec::Difference(root)) = named.get("root") else {
        panic!()
    };
    let carve = root
        .carves
        .iter()
        .find(|c| c.name() == Some("carve_1"))
        .expect("the carve stroke is a carve of the root");
    let NodeSpec::Primitive(carve) = carve else {
        panic!("{carve:?}")
    };
    let karstic::field::skeleton::SkeletonSpec::Polyline { points } = &carve.shape else {
        panic!("a stroke is a polyline: {:?}", carve.shape)
    };
    assert!(points.0.len() >= 5, "{} points", points.0.len());
    let Some(NodeSpec::Blend(land)) = named.get("land") else {
        panic!()
    };
    assert!(land.children.iter().any(|c| c.name() == Some("raise_1")));
    let Some(karstic::voxel::spec::Point::Abs(x, ..)) = cave_path(&path).get(1).copied() else {
        panic!()
    };
    assert!(x.0 > 410.0, "the cave opens through the face: {x:?}");
    // The field: the notch and the cave mouth are air, the ridge rock.
    use karstic::field::Field;
    let dir = path.parent().unwrap();
    let c = karstic::compile::compile_scene(&scene, &path, dir).unwrap();
    let iso = karstic::field::ISO;
    let notch = points.0[points.0.len() / 2].0;
    assert!(
        c.tree.value(notch - glam::Vec3::X * 2.0) < iso,
        "the notch at {notch} is carved"
    );
    assert!(
        c.tree.value(glam::Vec3::new(398.0, 0.0, 30.0)) > iso,
        "the face stands above it"
    );
    let karstic::voxel::spec::Point::Abs(_, y, z) = cave_path(&path)[1] else {
        panic!()
    };
    // Where the tunnel's axis crosses the face, from (250, 0, 5) to its dragged end.
    let t = (400.0 - 250.0) / (x.0 - 250.0);
    let mouth = glam::Vec3::new(400.0, t * y.0, 5.0 + t * (z.0 - 5.0));
    assert!(
        c.tree.value(mouth) < iso,
        "the cave's mouth at {mouth} is open"
    );
    let ridge = glam::Vec3::new(310.0, -100.0, 52.0 + radius * 0.5);
    assert!(c.tree.value(ridge) > iso, "the ridge at {ridge} is rock");

    // Reopened, the editor shows the same tree and the same picture.
    let mut again = harness(&path);
    settle(&mut again, Duration::from_secs(300)).unwrap();
    assert_eq!(again.state().text(), text);
    assert_eq!(again.state().scene(), Some(&scene));
    assert_frames_match(
        "the reopened editor's picture",
        &again.state().shown().unwrap().frame,
        &picture,
    );
    // The scenario's count, quoted in docs/editor.md.
    assert_eq!(actions, 8);
}

/// Lists show as rows (a polyline's points): moved, removed and added, each one edit of
/// the list; an invalid row is refused with the loader's message.
#[test]
fn editor_edits_lists_as_rows() {
    let (_dir, paths) = scene_dir(&["a.ron"]);
    let a = &paths[0];
    let line = TREE.replace(
        "shape: Sphere(center: (0, 0, 0), radius: 30),",
        "shape: Polyline(points: [(0, 0, 0), (10, 0, 0), (20, 5, 0)]),",
    );
    std::fs::write(a, &line).unwrap();
    let mut h = harness(a);
    select(&mut h, "blob");
    let points = |a: &Path| {
        let scene = karstic::scene::load(a).unwrap().scene;
        let named = scene.named();
        let Some(NodeSpec::Primitive(p)) = named.get("blob") else {
            panic!()
        };
        let karstic::field::skeleton::SkeletonSpec::Polyline { points } = &p.shape else {
            panic!()
        };
        (points.0.iter())
            .map(|p| p.0.to_array())
            .collect::<Vec<_>>()
    };
    // The first row down: the first two points trade places.
    h.get_all_by_label("down").next().unwrap().click();
    h.run_steps(2);
    let p = points(a);
    assert_eq!(
        p,
        [[10.0, 0.0, 0.0], [0.0, 0.0, 0.0], [20.0, 5.0, 0.0]],
        "{}",
        h.state().status()
    );
    // The last row removed, then a copy of the (new) last added.
    h.get_all_by_label("remove").nth(2).unwrap().click();
    h.run_steps(2);
    assert_eq!(points(a), [[10.0, 0.0, 0.0], [0.0, 0.0, 0.0]]);
    h.get_by_label("add").click();
    h.run_steps(2);
    assert_eq!(
        points(a),
        [[10.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    );
    // A row the loader refuses (a point needs three numbers) writes nothing; its message
    // shows under the list.
    let before = std::fs::read(a).unwrap();
    let row = h
        .get_all_by_role_and_label(Role::TextInput, "points")
        .next()
        .unwrap();
    row.focus();
    row.type_text(", 9");
    h.run_steps(2);
    h.key_press(egui::Key::Enter);
    h.run_steps(2);
    assert_eq!(std::fs::read(a).unwrap(), before, "{}", h.state().status());
    let message = h.state().status().to_string();
    assert!(message.contains("points"), "{message}");
    assert!(
        h.query_all_by_label(&message).count() > 0,
        "{message} not shown"
    );
    // Every edit is one undo: three undos give the file back byte for byte.
    for _ in 0..3 {
        h.get_by_label("Undo").click();
        h.run_steps(2);
    }
    assert_eq!(std::fs::read_to_string(a).unwrap(), line);
}

/// After an edit the editor refines the rows of the edited node first (`refine`'s
/// `first`): the bands that meet them come before the others, and the picture is the same.
#[test]
fn editor_refines_the_edited_region_first() {
    use karstic::editor::preview::{draw, refine};
    let (_dir, paths) = scene_dir(&["a.ron"]);
    let file = karstic::scene::load(&paths[0]).unwrap();
    let compiled = file.compile().unwrap();
    let look = |w, h| {
        karstic::render::Camera::look_at(
            glam::Vec3::new(5200.0, 3900.0, 1300.0),
            glam::Vec3::new(4000.0, 5200.0, 600.0),
            40.0,
            w,
            h,
        )
        .unwrap()
    };
    let (full, small) = (look(160, 90), look(10, 6));
    let fast = draw(&file.scene, &compiled, &small, Quality::Fast);
    let mut order = Vec::new();
    let first = 60..70;
    let focused = refine(
        &file.scene,
        &compiled,
        &full,
        &fast,
        Some(first.clone()),
        &|| false,
        &mut |_, rows| order.push(rows),
    )
    .unwrap();
    assert!(
        order[0].start > 0 && order[0].start < first.end && first.start < order[0].end,
        "{order:?}"
    );
    let covered: u32 = order.iter().map(|r| r.len() as u32).sum();
    assert_eq!(covered, 90, "every row once: {order:?}");
    let plain = refine(
        &file.scene,
        &compiled,
        &full,
        &fast,
        None,
        &|| false,
        &mut |_, _| {},
    )
    .unwrap();
    assert_eq!(focused.rgba, plain.rgba, "the same picture");
    // The node an edit changes.
    use karstic::editor::Edit;
    let set = Edit::Set {
        target: "grotto.offset".into(),
        value: "-10".into(),
    };
    assert_eq!(set.node().as_deref(), Some("grotto"));
    let add = Edit::Add {
        parent: "root".into(),
        node: "Primitive(name: \"carve_1\", shape: Point(center: (0, 0, 0)), falloff: 2)".into(),
    };
    assert_eq!(add.node().as_deref(), Some("carve_1"));
}

/// An option is a toggle: switched on it takes the first value the loader accepts there,
/// switched off it is `None`; each one edit, undone byte for byte.
#[test]
fn editor_toggles_options() {
    let (dir, _) = scene_dir(&[]);
    let a = dir.path().join("a.ron");
    std::fs::write(&a, tunnel_tree()).unwrap();
    let original = std::fs::read(&a).unwrap();
    let mut h = harness(&a);
    select(&mut h, "cave");
    let falloff = |a: &Path| {
        let scene = karstic::scene::load(a).unwrap().scene;
        let named = scene.named();
        let Some(NodeSpec::FeatureVolume(v)) = named.get("cave") else {
            panic!()
        };
        v.falloff.map(|f| f.get())
    };
    assert_eq!(falloff(&a), None);
    h.get_by_role_and_label(Role::CheckBox, "falloff").click();
    h.run_steps(2);
    assert_eq!(falloff(&a), Some(1.0), "{}", h.state().status());
    h.get_by_role_and_label(Role::CheckBox, "falloff").click();
    h.run_steps(2);
    assert_eq!(falloff(&a), None, "{}", h.state().status());
    for _ in 0..2 {
        h.get_by_label("Undo").click();
        h.run_steps(2);
    }
    assert_eq!(std::fs::read(&a).unwrap(), original);
}

//! The editor's preview (BENCHMARKS.md "## The editor (issue 17)"), on the main job's
//! tree `trees/jacksboro_caves.ron` through its job camera, for a 960 × 540 viewport:
//!
//! * `open`: load, compile and the fast pass (120 × 67, an eighth of the side, without
//!   shadow rays or occlusion) — what the editor does before its first image;
//! * `drag view`: one fast pass of the compiled scene at 120 × 67 and 240 × 135 (the
//!   view dragged: the editor picks the size that fits 80 ms);
//! * `drag value`: a parameter changed in memory (`set_in_scene` of the grotto's
//!   offset), the scene compiled again and a 120 × 67 fast pass (a value dragged);
//! * `refined 960x540`: the full image, shaded as `karstic render` shades it.

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use karstic::editor::preview::{Quality, draw};
use karstic::render::cpu::scene_camera;
use karstic::scene::{compile_scene, edit, load};

fn editor(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/jacksboro_caves.ron");
    let file = load(&path).unwrap();
    let compiled = file.compile().unwrap();
    let camera = |w, h| scene_camera(&file.scene, &compiled.tree, None, None, w, h).unwrap();
    let mut g = c.benchmark_group("editor jacksboro_caves");
    g.sample_size(10);
    g.bench_function("open", |b| {
        b.iter(|| {
            let f = load(&path).unwrap();
            let comp = f.compile().unwrap();
            let cam = scene_camera(&f.scene, &comp.tree, None, None, 120, 67).unwrap();
            draw(&f.scene, &comp, &cam, Quality::Fast)
        })
    });
    let fast = camera(120, 67);
    g.bench_function("drag view 120x67", |b| {
        b.iter(|| draw(&file.scene, &compiled, &fast, Quality::Fast))
    });
    let quarter = camera(240, 135);
    g.bench_function("drag view 240x135", |b| {
        b.iter(|| draw(&file.scene, &compiled, &quarter, Quality::Fast))
    });
    let mut k = 0;
    g.bench_function("drag value 120x67", |b| {
        b.iter(|| {
            k += 1;
            let mut s = file.scene.clone();
            let v = format!("{}", -12 - k % 5);
            edit::set_in_scene(&mut s, &path, "grotto.offset", &v).unwrap();
            let comp = compile_scene(&s, &path, &file.base_dir).unwrap();
            draw(&s, &comp, &fast, Quality::Fast)
        })
    });
    let full = camera(960, 540);
    g.bench_function("refined 960x540", |b| {
        b.iter(|| draw(&file.scene, &compiled, &full, Quality::Full))
    });
    g.finish();
}

criterion_group!(benches, editor);
criterion_main!(benches);

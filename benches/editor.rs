//! The editor's three performance targets (issue 17; BENCHMARKS.md "## The editor"), on
//! the main job's tree `trees/jacksboro_caves.ron` through its job camera, for a
//! 960 × 540 viewport:
//!
//! * `open`: load, compile and the first fast pass (a sixteenth of the side, 60 × 33,
//!   without shadow rays or occlusion) — what the editor does before its first image
//!   (in-process: the voxel pipeline's memo is warm, as the disk cache is on a second
//!   opening);
//! * `drag view 60x33` and `drag view 120x67`: one fast pass of the compiled scene at a
//!   sixteenth and an eighth of the side (the view dragged: the editor picks the size
//!   that fits 80 ms, between an eighth and a thirty-second of the side);
//! * `drag value 60x33`: a parameter changed in memory (`set_in_scene` of the grotto's
//!   offset), the scene compiled again and a fast pass (a value dragged);
//! * `refined 960x540`: the editor's refinement on the CPU (the fast pass, then the full
//!   image band by band over it), against `render 960x540`, the full image as
//!   `karstic render` draws it.

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use karstic::editor::preview::{DRAG_BUDGET, Quality, draw, fast_size, refine};
use karstic::render::cpu::scene_camera;
use karstic::scene::{compile_scene, edit, load};

fn editor(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/jacksboro_caves.ron");
    let file = load(&path).unwrap();
    let compiled = file.compile().unwrap();
    let camera = |(w, h)| scene_camera(&file.scene, &compiled.tree, None, None, w, h).unwrap();
    let view = (960, 540);
    let first = fast_size(view, None, DRAG_BUDGET);
    let mut g = c.benchmark_group("editor jacksboro_caves");
    g.sample_size(10);
    g.bench_function("open", |b| {
        b.iter(|| {
            let f = load(&path).unwrap();
            let comp = f.compile().unwrap();
            let cam = scene_camera(&f.scene, &comp.tree, None, None, first.0, first.1).unwrap();
            draw(&f.scene, &comp, &cam, Quality::Fast)
        })
    });
    let small = camera(first);
    g.bench_function("drag view 60x33", |b| {
        b.iter(|| draw(&file.scene, &compiled, &small, Quality::Fast))
    });
    let eighth = camera((view.0 / 8, view.1 / 8));
    g.bench_function("drag view 120x67", |b| {
        b.iter(|| draw(&file.scene, &compiled, &eighth, Quality::Fast))
    });
    let mut k = 0;
    g.bench_function("drag value 60x33", |b| {
        b.iter(|| {
            k += 1;
            let mut s = file.scene.clone();
            let v = format!("{}", -12 - k % 5);
            edit::set_in_scene(&mut s, &path, "grotto.offset", &v).unwrap();
            let comp = compile_scene(&s, &path, &file.base_dir).unwrap();
            draw(&s, &comp, &small, Quality::Fast)
        })
    });
    let full = camera(view);
    g.bench_function("refined 960x540", |b| {
        b.iter(|| {
            let fast = draw(&file.scene, &compiled, &small, Quality::Fast);
            refine(
                &file.scene,
                &compiled,
                &full,
                &fast,
                &|| false,
                &mut |_, _| {},
            )
        })
    });
    g.bench_function("render 960x540", |b| {
        b.iter(|| draw(&file.scene, &compiled, &full, Quality::Full))
    });
    g.finish();
}

criterion_group!(benches, editor);
criterion_main!(benches);

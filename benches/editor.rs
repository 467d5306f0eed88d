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
//!
//! The figures are the **CPU time** of the process (all its threads, from
//! `/proc/self/task/*/schedstat`, in ms), not wall time: on a machine shared with other
//! work the wall time says more about the load than about the editor. With
//! `RAYON_NUM_THREADS=1` the CPU time is the wall time of an unloaded core.

use std::path::Path;

use criterion::measurement::{Measurement, ValueFormatter};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use karstic::compile::{compile_scene, edit};
use karstic::editor::preview::{DRAG_BUDGET, Quality, draw, fast_size, refine};
use karstic::scene::load;

/// Nanoseconds on a CPU of every thread of this process so far (Linux).
fn cpu_ns() -> u64 {
    let tasks = std::fs::read_dir("/proc/self/task").expect("/proc/self/task (Linux)");
    tasks
        .filter_map(|t| std::fs::read_to_string(t.ok()?.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .sum()
}

/// Criterion's measurement as the process's CPU time.
struct CpuTime;

impl Measurement for CpuTime {
    type Intermediate = u64;
    type Value = u64;
    fn start(&self) -> u64 {
        cpu_ns()
    }
    fn end(&self, start: u64) -> u64 {
        cpu_ns().saturating_sub(start)
    }
    fn add(&self, a: &u64, b: &u64) -> u64 {
        a + b
    }
    fn zero(&self) -> u64 {
        0
    }
    fn to_f64(&self, v: &u64) -> f64 {
        *v as f64
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        self
    }
}

impl ValueFormatter for CpuTime {
    fn scale_values(&self, _typical: f64, values: &mut [f64]) -> &'static str {
        values.iter_mut().for_each(|v| *v *= 1e-6);
        "ms (CPU)"
    }
    fn scale_throughputs(&self, _: f64, _: &Throughput, values: &mut [f64]) -> &'static str {
        values.iter_mut().for_each(|v| *v *= 1e-6);
        "ms (CPU)"
    }
    fn scale_for_machines(&self, _values: &mut [f64]) -> &'static str {
        "ns"
    }
}

fn editor(c: &mut Criterion<CpuTime>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/jacksboro_caves.ron");
    let file = load(&path).unwrap();
    let compiled = file.compile().unwrap();
    let camera =
        |(w, h)| karstic::picture::camera(&file.scene, &compiled.tree, None, None, w, h).unwrap();
    let view = (960, 540);
    let first = fast_size(view, None, DRAG_BUDGET);
    let mut g = c.benchmark_group("editor jacksboro_caves");
    g.sample_size(10);
    g.bench_function("open", |b| {
        b.iter(|| {
            let f = load(&path).unwrap();
            let comp = f.compile().unwrap();
            let cam = karstic::picture::camera(&f.scene, &comp.tree, None, None, first.0, first.1)
                .unwrap();
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
                None,
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

criterion_group! {
    name = benches;
    config = Criterion::default().with_measurement(CpuTime);
    targets = editor
}
criterion_main!(benches);

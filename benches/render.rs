//! Rendering benchmarks (BENCHMARKS.md "## Rendering (issue 6)").
//!
//! * The 1,000-point blob scene of the segment-tracing paper: points scattered in a ball
//!   of radius 10, Wyvill blobs of radius 2 (about 8 overlap at a point), 500 × 500, the
//!   default framing. The blob field (tests/common) answers local Lipschitz bounds from a
//!   uniform grid; the same scene as a GPU tape (BVH of guards) is measured too.
//! * The same scene as a real tree file, `trees/blobs.ron` (1,000 points in a ball of
//!   radius 30, falloff 6: the test scene scaled by 3), compiled by the scene loader —
//!   the field `karstic render` traces — and its tape from `tape_from_tree`.
//! * Plain sphere tracing with the global bound, on smaller images.
//! * The main job's tree, `trees/jacksboro_caves.ron` (DEM heightfield, bicubic, with an
//!   S-field tunnel carved, an S-field arch and a noisy grotto), compiled by the scene
//!   loader, at 1280 × 720 and 1920 × 1080 with shadows; segment vs sphere steps reported
//!   at 320 × 180; its GPU tape's ms per frame at 320 × 180 and 1920 × 1080 (on a
//!   software adapter the latter only with `KARSTIC_BENCH_SOFTWARE_GPU=1`).
//! * The Jacksboro DEM (90 m cells) with a tunnel carved through it, as a tape, at
//!   1280 × 720, and a synthetic terrain chunk at 500 × 500.
//!
//! Besides criterion's wall-clock medians, each scene prints its steps per ray and the
//! CPU seconds one frame takes (user + system): on a machine shared with other jobs the
//! latter tracks the work better.

#[path = "../tests/common/mod.rs"]
#[allow(dead_code, unused_imports)] // the helpers this bench does not use
mod common;

use common::{Blobs, Terrain, dem, tapes};
use criterion::{Criterion, criterion_group, criterion_main};
use indicatif::ProgressBar;
use karstic::field::Field;
use karstic::field::Tree;
use karstic::render::gpu::GpuContext;
use karstic::render::{Camera, Method, RenderSettings, render};
use karstic::tape::{Tape, tape_from_tree};

fn scene(
    f: &dyn Field,
    (w, h): (u32, u32),
    method: Method,
    shadows: bool,
) -> (Camera, RenderSettings) {
    let cam = Camera::frame(&f.support(), 40.0, w, h).unwrap();
    let mut s = RenderSettings::for_scene(&f.support(), &cam, method);
    s.shading.shadows = shadows;
    (cam, s)
}

/// CPU seconds used by this process so far (user + system), from /proc.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit(')')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (ticks(11) + ticks(12)) / 100.0
}

fn report(name: &str, f: &dyn Field, size: (u32, u32), method: Method, shadows: bool, cone: bool) {
    let (cam, mut s) = scene(f, size, method, shadows);
    if !cone {
        s.trace.cone = 0.0;
    }
    let (cpu0, wall0) = (cpu_seconds(), std::time::Instant::now());
    let mut frame = render(f, &cam, &s, &ProgressBar::hidden());
    let mut runs = 1;
    while cpu_seconds() - cpu0 < 2.0 && runs < 50 {
        frame = render(f, &cam, &s, &ProgressBar::hidden());
        runs += 1;
    }
    let cpu = (cpu_seconds() - cpu0) / runs as f64;
    let wall = wall0.elapsed().as_secs_f64() / runs as f64;
    let hit_steps: Vec<f64> = (0..frame.steps.len())
        .filter(|&k| frame.depth[k].is_finite())
        .map(|k| frame.steps[k] as f64)
        .collect();
    eprintln!(
        "{name}: {}x{} {method:?}{}{}: {:.1} steps per ray, {:.1} per hit ray, {} hits; {cpu:.3} CPU-s per frame ({wall:.3} s wall)",
        size.0,
        size.1,
        if shadows { " shadows" } else { "" },
        if cone { "" } else { " (no pixel cone)" },
        frame.mean_steps(),
        hit_steps.iter().sum::<f64>() / hit_steps.len().max(1) as f64,
        frame.hits()
    );
}

/// Milliseconds per frame on the GPU adapter, if there is one: one frame, after a small
/// one that compiles the pipeline. On a software adapter (lavapipe) frames larger than
/// 500 × 500 take minutes and run only with `KARSTIC_BENCH_SOFTWARE_GPU=1`.
fn report_gpu(name: &str, tape: &Tape, size: (u32, u32)) {
    let ctx = match GpuContext::new() {
        Ok(c) => c,
        Err(e) => {
            eprintln!("{name}: no GPU timing ({e})");
            return;
        }
    };
    if ctx.software
        && size.0 * size.1 > 500 * 500
        && std::env::var_os("KARSTIC_BENCH_SOFTWARE_GPU").is_none()
    {
        eprintln!(
            "{name}: {}x{} on {} skipped (software adapter; KARSTIC_BENCH_SOFTWARE_GPU=1 runs it)",
            size.0, size.1, ctx.adapter
        );
        return;
    }
    let (cam, s) = scene(tape, (32, 18), Method::Segment, true);
    ctx.render(tape, &cam, &s).unwrap();
    let (cam, s) = scene(tape, size, Method::Segment, true);
    let start = std::time::Instant::now();
    let frame = ctx.render(tape, &cam, &s).unwrap();
    eprintln!(
        "{name}: {}x{} on {}: {:.0} ms per frame, {:.1} steps per ray, {} hits",
        size.0,
        size.1,
        ctx.adapter,
        start.elapsed().as_secs_f64() * 1e3,
        frame.mean_steps(),
        frame.hits()
    );
}

/// A tree file of `trees/`, compiled.
fn tree_file(name: &str) -> Tree {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("trees")
        .join(name);
    karstic::scene::load(&path)
        .and_then(|s| s.compile())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .tree
}

fn bench(c: &mut Criterion) {
    let blobs = Blobs::in_ball(1000, 10.0, 2.0, 1.0, 2020);
    let blob_tape = tapes::blobs(&blobs);
    let blob_tree = tree_file("blobs.ron");
    let blob_tree_tape = tape_from_tree(&blob_tree).unwrap();
    let caves = tree_file("jacksboro_caves.ron");
    let terrain = Terrain::new(1000.0, 120.0, 30.0);
    let dem_tape = tapes::dem_with_cave(&dem::jacksboro());
    report("blobs", &blobs, (32, 32), Method::Sphere, false, false);
    report("blobs", &blobs, (100, 100), Method::Segment, false, false);
    report(
        "blobs.ron",
        &blob_tree,
        (32, 32),
        Method::Sphere,
        false,
        false,
    );
    // The main job's tree: segment vs plain sphere tracing at the same (small) size.
    for method in [Method::Segment, Method::Sphere] {
        report(
            "jacksboro_caves.ron",
            &caves,
            (320, 180),
            method,
            true,
            true,
        );
    }
    report_gpu("dem with cave", &dem_tape, (480, 270));
    // The main job's tree on the GPU (every node encodes): the CLI's framing and size of
    // `karstic render trees/jacksboro_caves.ron --gpu --size 1920 1080`.
    let caves_tape = tape_from_tree(&caves).unwrap();
    report_gpu("jacksboro_caves.ron", &caves_tape, (320, 180));
    report_gpu("jacksboro_caves.ron", &caves_tape, (1920, 1080));
    for (name, f, size, method, shadows) in [
        (
            "blobs",
            &blobs as &dyn Field,
            (500, 500),
            Method::Segment,
            true,
        ),
        ("blobs", &blobs, (500, 500), Method::Segment, false),
        ("blobs", &blobs, (100, 100), Method::Segment, false),
        ("blobs", &blobs, (100, 100), Method::Sphere, false),
        ("blobs", &blobs, (500, 500), Method::Sphere, false),
        ("blob tape", &blob_tape, (500, 500), Method::Segment, false),
        ("blobs.ron", &blob_tree, (500, 500), Method::Segment, true),
        ("blobs.ron", &blob_tree, (500, 500), Method::Segment, false),
        ("blobs.ron", &blob_tree, (100, 100), Method::Sphere, false),
        (
            "blobs.ron tape",
            &blob_tree_tape,
            (500, 500),
            Method::Segment,
            false,
        ),
        (
            "dem with cave",
            &dem_tape,
            (1280, 720),
            Method::Segment,
            true,
        ),
        (
            "jacksboro_caves.ron",
            &caves,
            (1280, 720),
            Method::Segment,
            true,
        ),
        (
            "jacksboro_caves.ron",
            &caves,
            (1920, 1080),
            Method::Segment,
            true,
        ),
        ("terrain", &terrain, (500, 500), Method::Segment, true),
    ] {
        report(name, f, size, method, shadows, true);
        let (cam, s) = scene(f, size, method, shadows);
        let id = format!(
            "{name} {}x{} {method:?}{}",
            size.0,
            size.1,
            if shadows { " shadows" } else { "" }
        )
        .to_lowercase();
        let mut g = c.benchmark_group("render");
        g.sample_size(10);
        g.bench_function(id, |b| {
            b.iter(|| render(f, &cam, &s, &ProgressBar::hidden()))
        });
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);

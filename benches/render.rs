//! Rendering benchmarks (BENCHMARKS.md "## Rendering (issue 6)").
//!
//! The 1,000-point blob scene of the segment-tracing paper: points scattered in a ball of
//! radius 10, Wyvill blobs of radius 2 (about 8 overlap at a point), rendered at
//! 500 × 500 with the default framing. The blob field answers local Lipschitz bounds from
//! a uniform grid (tests/common). Plain sphere tracing with the global bound is measured
//! on a 100 × 100 image: at 500 × 500 it takes too long for criterion.

#[path = "../tests/common/mod.rs"]
mod common;

use common::{Blobs, Terrain, tapes};
use criterion::{Criterion, criterion_group, criterion_main};
use indicatif::ProgressBar;
use karstic::field::Field;
use karstic::render::{Camera, Method, RenderSettings, render};

fn scene(f: &dyn Field, size: u32, method: Method, shadows: bool) -> (Camera, RenderSettings) {
    let cam = Camera::frame(&f.support(), 40.0, size, size).unwrap();
    let mut s = RenderSettings::for_scene(&f.support(), &cam, method);
    s.shading.shadows = shadows;
    (cam, s)
}

/// CPU seconds used by this process so far (user + system), from /proc: on a machine
/// shared with other jobs this tracks the work done better than the wall clock.
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

fn report(name: &str, f: &dyn Field, size: u32, method: Method, shadows: bool) {
    let (cam, s) = scene(f, size, method, shadows);
    let (cpu0, wall0) = (cpu_seconds(), std::time::Instant::now());
    let mut frame = render(f, &cam, &s, &ProgressBar::hidden());
    let mut runs = 1;
    while cpu_seconds() - cpu0 < 2.0 && runs < 50 {
        frame = render(f, &cam, &s, &ProgressBar::hidden());
        runs += 1;
    }
    let cpu = (cpu_seconds() - cpu0) / runs as f64;
    let wall = wall0.elapsed().as_secs_f64() / runs as f64;
    let hit_steps: Vec<u32> = (0..frame.steps.len())
        .filter(|&k| frame.depth[k].is_finite())
        .map(|k| frame.steps[k])
        .collect();
    eprintln!(
        "{name}: {size}² {method:?}{}: {:.1} steps per ray, {:.1} per hit ray, {} hits; {cpu:.3} CPU-s per frame ({wall:.3} s wall)",
        if shadows { " shadows" } else { "" },
        frame.mean_steps(),
        hit_steps.iter().map(|&s| s as f64).sum::<f64>() / hit_steps.len().max(1) as f64,
        frame.hits()
    );
}

fn bench(c: &mut Criterion) {
    let blobs = Blobs::in_ball(1000, 10.0, 2.0, 1.0, 2020);
    let blob_tape = tapes::blobs(&blobs);
    let terrain = Terrain::new(1000.0, 120.0, 30.0);
    for (name, f, size, method, shadows) in [
        ("blobs", &blobs as &dyn Field, 500, Method::Segment, true),
        ("blobs", &blobs, 500, Method::Segment, false),
        ("blobs", &blobs, 100, Method::Segment, false),
        ("blobs", &blobs, 100, Method::Sphere, false),
        ("blob tape", &blob_tape, 500, Method::Segment, false),
        ("terrain", &terrain, 500, Method::Segment, true),
    ] {
        report(name, f, size, method, shadows);
        let (cam, s) = scene(f, size, method, shadows);
        let id = format!(
            "{name} {size}x{size} {method:?}{}",
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

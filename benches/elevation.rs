//! Issue 16 target: elevation-tree queries ≥ 20 M/s on 2 cores for a 1,000-primitive tree.
//!
//! The tree: a blend (over a base of 100 m) of 1,000 disc primitives over a 6 km square,
//! radii 150 to 400 m (about 28 per km², Génevaux et al. 2015 §8: "ten to a few hundred
//! primitives per square kilometre"): 900 constant elevations (plateaus, hills of the
//! blend) and 100 fBm hills of 3 octaves. 1,000,000 random points per iteration through
//! `ElevationTree::heights` (rayon chunks); the grid index over the supports makes a
//! query visit only the discs over its cell.

#[path = "../tests/common/rng.rs"]
#[allow(dead_code)] // the draws this bench does not use
mod rng;

use rng::Rng;
use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec2;
use karstic::elevation::multifractal::{ElevationFn, Kind, Multifractal};
use karstic::elevation::primitive::{Disc, Primitive};
use karstic::elevation::{ElevationTree, Lod, Node};

/// The 1,000-disc tree.
fn tree() -> ElevationTree {
    let mut rng = Rng(16);
    let children = (0..1000)
        .map(|k| {
            let centre = Vec2::new(rng.f32() * 6000.0, rng.f32() * 6000.0);
            let radius = 150.0 + 250.0 * rng.f32();
            let elevation = if k % 10 == 0 {
                ElevationFn::Fractal(Multifractal::new(Kind::Fbm, 100.0, 150.0, 300.0, 3, k))
            } else {
                ElevationFn::Constant(100.0 + 200.0 * rng.f32())
            };
            Node::primitive(Primitive::Disc(Disc {
                centre,
                radius,
                elevation,
            }))
        })
        .collect();
    ElevationTree::new(Node::blend(100.0, children))
}

fn bench(c: &mut Criterion) {
    let t = tree();
    let mut rng = Rng(1);
    let n = 1_000_000;
    let points: Vec<Vec2> = (0..n)
        .map(|_| Vec2::new(rng.f32() * 6000.0, rng.f32() * 6000.0))
        .collect();
    let mut out = vec![0.0f32; n];
    let mut g = c.benchmark_group("elevation_tree");
    g.throughput(Throughput::Elements(n as u64));
    g.sample_size(20);
    g.bench_function("heights_1000_discs", |b| {
        b.iter(|| {
            t.heights(black_box(&points), &Lod::FULL, &mut out);
            black_box(&out);
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

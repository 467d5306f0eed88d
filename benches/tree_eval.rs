//! Issue 2 targets: point queries and grid evaluation of large trees.
//!
//! * a blend of 100,000 small spheres scattered over a 5 km square: point queries
//!   (≥ 10 M/s on 2 cores) and a 256³ grid (≥ 40 M values/s);
//! * the 1,000-point blob scene of `trees/blobs.ron` over a 256³ grid;
//!   with the naive, unpruned per-point evaluation as the baseline in the same run;
//! * point queries one by one (`Field::value` over rayon chunks) and batched
//!   (`Tree::values`, parallel chunks).

#[path = "../tests/common/rng.rs"]
#[allow(dead_code)] // the draws this bench does not use
mod rng;

use rng::Rng;
use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use karstic::field::{Field, Grid, Tree, eval_grid, eval_grid_naive};
use rayon::prelude::*;

/// 100,000 spheres of radius 2 m and falloff 3 m over [0, 5000]² with centres at z ∈ [0, 20].
pub fn spheres_scene() -> Tree {
    let mut rng = Rng(42);
    let mut text = String::from("(version: 1, root: Blend(children: [\n");
    for _ in 0..100_000 {
        let (x, y, z) = (rng.f32() * 5000.0, rng.f32() * 5000.0, rng.f32() * 20.0);
        text +=
            &format!("Primitive(shape: Sphere(center: ({x}, {y}, {z}), radius: 2), falloff: 3),\n");
    }
    text += "]))";
    let scene = karstic::scene::parse_scene(&text, "spheres".as_ref()).unwrap();
    karstic::scene::compile_scene(&scene, "spheres".as_ref(), ".".as_ref())
        .unwrap()
        .tree
}

fn blobs_scene() -> Tree {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/trees/blobs.ron");
    karstic::scene::load(path).unwrap().compile().unwrap().tree
}

fn grid_over(tree: &Tree, n: usize) -> Grid {
    let s = tree.support();
    Grid {
        origin: s.min,
        step: s.size() / (n - 1) as f32,
        dims: [n, n, n],
    }
}

fn bench(c: &mut Criterion) {
    let spheres = spheres_scene();
    let blobs = blobs_scene();

    let mut rng = Rng(7);
    let n = 1 << 20;
    let uniform: Vec<Vec3> = (0..n)
        .map(|_| {
            Vec3::new(
                rng.f32() * 5000.0,
                rng.f32() * 5000.0,
                rng.f32() * 25.0 - 2.5,
            )
        })
        .collect();
    let mut g = c.benchmark_group("point_queries_100k_spheres");
    g.throughput(Throughput::Elements(n as u64));
    g.sample_size(20);
    g.bench_function("uniform_in_box", |b| {
        b.iter(|| {
            uniform
                .par_chunks(4096)
                .map(|ch| ch.iter().map(|&p| spheres.value(p)).sum::<f32>())
                .sum::<f32>()
        })
    });
    let mut out = vec![0.0; n];
    g.bench_function("uniform_in_box_batched", |b| {
        b.iter(|| {
            spheres.values(&uniform, &mut out);
            black_box(&out);
        })
    });
    g.finish();

    for (name, tree) in [("spheres_100k", &spheres), ("blobs_1000", &blobs)] {
        let grid = grid_over(tree, 256);
        let mut g = c.benchmark_group(format!("grid_256_{name}"));
        g.throughput(Throughput::Elements(grid.len() as u64));
        g.sample_size(10);
        g.bench_function("pruned", |b| {
            b.iter(|| black_box(eval_grid(tree, &grid, None)))
        });
        g.bench_function("naive", |b| {
            b.iter(|| black_box(eval_grid_naive(tree, &grid)))
        });
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);

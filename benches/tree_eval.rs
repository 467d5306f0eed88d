//! Issue 2 targets: point queries and grid evaluation of large trees.
//!
//! * a blend of 100,000 small spheres scattered over a 5 km square: point queries
//!   (≥ 10 M/s on 2 cores) and a 256³ grid (≥ 40 M values/s);
//! * the 1,000-point blob scene of `trees/blobs.ron` over a 256³ grid;
//!   with the naive, unpruned per-point evaluation as the baseline in the same run;
//! * point queries one by one (`Field::value` over rayon chunks) and batched
//!   (`Tree::values`, parallel chunks).
//!
//! Issue 15's per-sample cost, on one thread: the karst scene of Paris et al. 2019's public
//! C++ code (its 6,541 carving spheres and its terrain, exported into `benches/data`), on
//! the C++ program's own Marching Cubes lattice (198 × 199 × 59 samples):
//!
//! * `karst/values_stage`: the values stage of [`polygonize`] (default options), in
//!   samples evaluated by that stage per second;
//! * `karst/polygonize`: the whole mesher;
//! * `karst/grid_every_sample`: [`eval_grid`] over every sample of the lattice, as the
//!   C++ evaluates it (no z-band pruning).

#[path = "../tests/common/rng.rs"]
#[allow(dead_code)] // the draws this bench does not use
mod rng;

use rng::Rng;
use std::hint::black_box;

use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use karstic::field::{Field, Grid, Tree, eval_grid, eval_grid_naive};
use karstic::mesh::{GridSpec, MeshOptions, MeshStats, polygonize};
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
    karstic::compile::compile_scene(&scene, "spheres".as_ref(), ".".as_ref())
        .unwrap()
        .tree
}

/// Tree file text for the karst scene of `benches/data`: the C++ terrain as a heightfield
/// leaf (falloff 15 m, its terrain node's radius) blended with the carving spheres (radius
/// 5.1 m, energy −6.8 on the C++ scale whose surface is at 7.5, so −6.8/15 on ours).
fn karst_scene() -> Tree {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/benches/data");
    let centres = std::fs::read_to_string(format!("{dir}/karst_spheres.txt")).unwrap();
    let mut text = String::from(
        "(version: 1, root: Blend(children: [\n\
         Heightfield(source: \"karst_terrain.asc\", falloff: 15),\n\
         Blend(name: \"karst\", children: [\n",
    );
    let energy = -6.8 / 15.0;
    for c in centres.lines().filter(|l| !l.starts_with('#')) {
        let c: Vec<&str> = c.split_whitespace().collect();
        text += &format!(
            "Primitive(shape: Point(center: ({}, {}, {})), falloff: 5.1, energy: {energy}),\n",
            c[0], c[1], c[2]
        );
    }
    text += "])]))";
    let scene = karstic::scene::parse_scene(&text, "karst".as_ref()).unwrap();
    karstic::compile::compile_scene(&scene, "karst".as_ref(), dir.as_ref())
        .unwrap()
        .tree
}

/// The lattice of the C++ program's Marching Cubes on its karst scene (its `res` 200),
/// in our frame (z up).
fn karst_grid() -> GridSpec {
    GridSpec::new(
        Vec3::new(-199.359, -198.993, -34.405),
        Vec3::new(2.02395, 2.0239, 2.04845),
        [197, 198, 58],
    )
    .unwrap()
}

fn values_stage(stats: &MeshStats) -> Duration {
    stats.stages.iter().find(|s| s.0 == "values").unwrap().1
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

fn karst(c: &mut Criterion) {
    let tree = karst_scene();
    let grid = karst_grid();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let opts = MeshOptions::default();
    let mesh = || one.install(|| polygonize(&tree, &grid, &opts).unwrap());
    let (_, stats) = mesh();
    eprintln!("karst, one thread:\n{stats}");
    let mut g = c.benchmark_group("karst");
    g.sample_size(10);
    g.throughput(Throughput::Elements(stats.field_evaluations));
    g.bench_function("values_stage", |b| {
        b.iter_custom(|iters| (0..iters).map(|_| values_stage(&mesh().1)).sum())
    });
    g.bench_function("polygonize", |b| b.iter(mesh));
    let every = Grid {
        origin: grid.origin,
        step: grid.spacing,
        dims: grid.cells.map(|c| c + 1),
    };
    g.throughput(Throughput::Elements(every.len() as u64));
    g.bench_function("grid_every_sample", |b| {
        b.iter(|| one.install(|| black_box(eval_grid(&tree, &every, None))))
    });
    g.finish();
}

criterion_group!(benches, bench, karst);
criterion_main!(benches);

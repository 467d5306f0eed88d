//! Marching Cubes benches.
//!
//! * `mc_dense/*`: the dense path on the three 256³ grids of `benches/skimage_compare.py`
//!   (same formulas), in M voxels/s (compare with scikit-image through that script).
//! * `polygonize/*`: a 400 m terrain with 40 caves at 2 m cells, bound-pruned with direct
//!   elevation extraction, pruned without it, and plain MC (every sample evaluated);
//!   #C0/#C is printed once per variant.

#[path = "../tests/mesh_fields/mod.rs"]
mod mesh_fields;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use karstic::field::Field;
use karstic::mesh::{DenseGrid, GridSpec, MeshOptions, mc_dense, polygonize};

const N: usize = 256;

/// `f(x, y, z)` on N³ samples spanning [-1, 1]³, C order.
fn grid(f: impl Fn(f32, f32, f32) -> f32 + Sync) -> Vec<f32> {
    use rayon::prelude::*;
    let t = |i: usize| -1.0 + 2.0 * i as f32 / (N - 1) as f32;
    let mut v = vec![0f32; N * N * N];
    v.par_chunks_mut(N * N).enumerate().for_each(|(k, layer)| {
        for j in 0..N {
            for i in 0..N {
                layer[i + N * j] = f(t(i), t(j), t(k));
            }
        }
    });
    v
}

fn blob(x: f32, y: f32, z: f32) -> f32 {
    [
        (-0.3, -0.1, 0.0, 0.45),
        (0.35, 0.1, 0.1, 0.4),
        (0.0, 0.3, -0.3, 0.35),
    ]
    .iter()
    .map(|&(cx, cy, cz, r): &(f32, f32, f32, f32)| {
        (-((x - cx).powi(2) + (y - cy).powi(2) + (z - cz).powi(2)) / (r * r)).exp()
    })
    .sum()
}

fn terrain(x: f32, y: f32, z: f32) -> f32 {
    let xw = x + 0.12 * (7.0 * z + 2.0 * y).sin();
    let h = 0.25 * (3.0 * xw).sin() * (2.0 * y).cos() + 0.08 * (9.0 * xw + 5.0 * y).sin();
    let mut f = 0.5 + 2.0 * (h - z);
    for (cx, cy, cz, r) in [(-0.4f32, 0.2f32, -0.2f32, 0.25f32), (0.3, -0.3, -0.1, 0.2)] {
        let d2 = ((x - cx).powi(2) + (y - cy).powi(2) + (z - cz).powi(2)) / (r * r);
        f -= 1.5 * (1.0 - d2).max(0.0).powi(3);
    }
    f
}

fn gyroid(x: f32, y: f32, z: f32) -> f32 {
    let w = 8.0 * std::f32::consts::PI;
    0.5 + (w * x).sin() * (w * y).cos()
        + (w * y).sin() * (w * z).cos()
        + (w * z).sin() * (w * x).cos()
}

fn dense(c: &mut Criterion) {
    let mut g = c.benchmark_group("mc_dense");
    g.sample_size(10);
    g.throughput(Throughput::Elements((N * N * N) as u64));
    let spacing = Vec3::splat(2.0 / (N - 1) as f32);
    for (name, f) in [
        ("blob", blob as fn(f32, f32, f32) -> f32),
        ("terrain", terrain),
        ("gyroid", gyroid),
    ] {
        let values = grid(f);
        let dg = DenseGrid::new(&values, [N; 3], Vec3::splat(-1.0), spacing).unwrap();
        g.bench_function(name, |b| b.iter(|| mc_dense(&dg, 0.5)));
    }
    g.finish();
}

fn pruned(c: &mut Criterion) {
    let t = mesh_fields::caved_terrain(40);
    let grid = GridSpec::with_cell(&t.support(), 2.0).unwrap();
    let mut g = c.benchmark_group("polygonize");
    g.sample_size(10);
    let variants = [
        ("pruned_elevation", true, true),
        ("pruned_field", true, false),
        ("plain_mc", false, false),
    ];
    for (name, prune, elevation) in variants {
        let opts = MeshOptions {
            prune,
            elevation,
            ..MeshOptions::default()
        };
        let (_, stats) = polygonize(&t, &grid, &opts).unwrap();
        eprintln!("polygonize/{name}:\n{stats}");
        g.bench_function(name, |b| {
            b.iter(|| polygonize(&t as &dyn Field, &grid, &opts).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, dense, pruned);
criterion_main!(benches);

//! Issue 15: the erosion node's cost over its child and the geology it reads.
//!
//! On `trees/strata_cliff.ron` (Paris et al. 2019 Fig. 10), 4,096 uniform points of the
//! erosion region: the whole tree (the `Erode` root), its child alone (the terrain), and
//! the geology's `ρ` alone. The node's own cost is `tree − child − ρ` per point.

#[path = "../tests/common/rng.rs"]
#[allow(dead_code)] // the draws this bench does not use
mod rng;

use rng::Rng;
use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use karstic::field::{Aabb, Field};

fn bench(c: &mut Criterion) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/trees/strata_cliff.ron");
    let compiled = karstic::scene::load(path).unwrap().compile().unwrap();
    let tree = &compiled.tree;
    let terrain = tree.subtree(tree.find("terrain").expect("the cliff's terrain node"));
    let geology = &compiled.geology;
    let region = Aabb::new(Vec3::new(-90.0, -100.0, 0.0), Vec3::new(80.0, 100.0, 80.0));
    let mut rng = Rng(15);
    let points: Vec<Vec3> = (0..4096).map(|_| rng.in_box(&region)).collect();

    let mut g = c.benchmark_group("erode");
    g.throughput(Throughput::Elements(points.len() as u64));
    g.bench_function("tree (Erode root)", |b| {
        b.iter(|| {
            points
                .iter()
                .map(|&p| tree.value(black_box(p)))
                .sum::<f32>()
        })
    });
    g.bench_function("child alone", |b| {
        b.iter(|| {
            points
                .iter()
                .map(|&p| terrain.value(black_box(p)))
                .sum::<f32>()
        })
    });
    g.bench_function("geology rho alone", |b| {
        b.iter(|| {
            points
                .iter()
                .map(|&p| geology.value(black_box(p)))
                .sum::<f32>()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

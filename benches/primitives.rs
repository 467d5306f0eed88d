//! Point evaluation cost of the skeletal primitives, per kind, with and without noise.
//! Baseline: `value/sphere` (the leaf of the lead's 100,000-sphere blend).

#[path = "../tests/common/rng.rs"]
#[allow(dead_code)] // the draws this bench does not use
mod rng;

use rng::Rng;
use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use karstic::field::{Aabb, Field, Primitive, PrimitiveSpec};

const N: usize = 4096;

fn points(b: &Aabb) -> Vec<Vec3> {
    let mut rng = Rng(0x1234_5678_9abc_def0);
    (0..N).map(|_| rng.in_box(b)).collect()
}

fn prim(s: &str) -> Primitive {
    let spec: PrimitiveSpec = ron::from_str(s).expect("bench spec");
    Primitive::from_spec(&spec, 1)
}

fn bench(c: &mut Criterion) {
    let cases = [
        (
            "sphere",
            "(shape: Sphere(center: (0, 0, 0), radius: 3), falloff: 2)",
        ),
        ("point", "(shape: Point(center: (0, 0, 0)), falloff: 4)"),
        (
            "capsule",
            "(shape: Capsule(a: (0, 0, 0), b: (4, 1, 2), radius: 1), falloff: 2)",
        ),
        (
            "box",
            "(shape: Box(center: (0, 0, 0), half_size: (2, 3, 1), yaw: 30), falloff: 2)",
        ),
        (
            "ellipsoid",
            "(shape: Ellipsoid(center: (0, 0, 0), radii: (3, 2, 1)), falloff: 2)",
        ),
        (
            "cone",
            "(shape: Cone(base: (0, 0, 0), apex: (0, 1, 5), radius: 2), falloff: 2)",
        ),
        (
            "curve8",
            "(shape: Curve(points: [(0, 0, 0), (5, 0, 1), (8, 4, 2), (6, 9, 1), (1, 11, 0), (-3, 8, 2), (-4, 3, 1), (-1, 1, 0)]), falloff: 2)",
        ),
        (
            "prism",
            "(shape: Prism(polygon: [(0, 0), (6, 0), (6, 2), (2, 2), (2, 6), (0, 6)], z: (0, 4)), falloff: 2)",
        ),
        (
            "sphere+noise4",
            "(shape: Sphere(center: (0, 0, 0), radius: 3), falloff: 2, noise: Some((amplitude: 0.8, wavelength: 3, octaves: 4)))",
        ),
        (
            "curve8+noise4",
            "(shape: Curve(points: [(0, 0, 0), (5, 0, 1), (8, 4, 2), (6, 9, 1), (1, 11, 0), (-3, 8, 2), (-4, 3, 1), (-1, 1, 0)]), falloff: 2, noise: Some((amplitude: 0.8, wavelength: 3, octaves: 4)))",
        ),
    ];
    let mut g = c.benchmark_group("value");
    g.throughput(Throughput::Elements(N as u64));
    for (name, s) in cases {
        let p = prim(s);
        let pts = points(&p.support());
        g.bench_function(name, |b| {
            b.iter(|| pts.iter().map(|&q| p.value(black_box(q))).sum::<f32>())
        });
    }
    g.finish();
    let mut g = c.benchmark_group("value_grad");
    g.throughput(Throughput::Elements(N as u64));
    for (name, s) in [cases[0], cases[8]] {
        let p = prim(s);
        let pts = points(&p.support());
        g.bench_function(name, |b| {
            b.iter(|| {
                pts.iter()
                    .map(|&q| p.value_grad(black_box(q)).0)
                    .sum::<f32>()
            })
        });
    }
    g.finish();
    let mut g = c.benchmark_group("interval");
    g.throughput(Throughput::Elements(N as u64));
    for (name, s) in [cases[0], cases[8]] {
        let p = prim(s);
        let boxes: Vec<Aabb> = points(&p.support())
            .iter()
            .map(|&q| Aabb::around(q, 0.25))
            .collect();
        g.bench_function(name, |b| {
            b.iter(|| {
                boxes
                    .iter()
                    .map(|q| p.interval(black_box(q)).hi)
                    .sum::<f32>()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

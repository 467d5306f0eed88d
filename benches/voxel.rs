//! The Feature Curve pipeline on the thesis's benchmark scene (Becher 2016, Table 7.1): a
//! ridge from three curves, full pipeline with distance propagation, at 64×32×64,
//! 128×64×128 and 256×128×256 voxels (z up here: x × y × z = 128 × 128 × 64 and so on),
//! with and without varying noise parameters (the noise diffusion stage); and the S-field
//! leaf's evaluation with trilinear and tricubic interpolation.

#[path = "../tests/common/rng.rs"]
#[allow(dead_code)] // the draws this bench does not use
mod rng;

use rng::Rng;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use karstic::field::Field;
use karstic::value::{P3, Positive};
use karstic::voxel::FeatureVolumeSpec;
use karstic::voxel::spec::BuildOptions;
use karstic::voxel::{Interpolation, run};

fn ridge(c: &mut Criterion) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/curves");
    let file = karstic::scene::load(dir.join("ridge.ron")).unwrap();
    let spec = file.feature_volumes()[0].clone();
    let plain = spec.feature_set(&dir).unwrap().resolve(&|_| None).unwrap();
    let mut noisy = plain.clone();
    for curve in &mut noisy.curves {
        for (k, cp) in curve.constraints.iter_mut().enumerate() {
            cp.amplitude = 0.5 + 2.0 * k as f32;
            cp.roughness = 0.05 + 0.1 * k as f32;
        }
    }
    let mut g = c.benchmark_group("feature_curves_ridge");
    g.sample_size(10);
    for (label, voxel) in [("64x32x64", 2.0), ("128x64x128", 1.0), ("256x128x256", 0.5)] {
        let spec = FeatureVolumeSpec {
            voxel: Positive(voxel),
            ..spec.clone()
        };
        let (p, _) = spec.params(0, 8 << 30);
        g.bench_function(label, |b| b.iter(|| run(&plain, &p).unwrap()));
        g.bench_function(format!("{label}_noise"), |b| {
            b.iter(|| run(&noisy, &p).unwrap())
        });
    }
    g.finish();
}

/// The pipeline with terrain boundary conditions (issue 13): the default scene's arch on
/// the Jacksboro DEM, its domain resized to 128 × 128 × 64 nodes (4 m voxels): sampling
/// the terrain, making room for the arch, and the run.
fn on_terrain(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/jacksboro_caves.ron");
    let file = karstic::scene::load(&path).unwrap();
    let arch = file
        .feature_volumes()
        .into_iter()
        .find(|f| f.name.as_deref() == Some("arch"))
        .unwrap()
        .clone();
    let spec = FeatureVolumeSpec {
        domain: (
            P3(glam::Vec3::new(4380.0, 4700.0, 520.0)),
            P3(glam::Vec3::new(4888.0, 5208.0, 772.0)),
        ),
        voxel: Positive(4.0),
        ..arch
    };
    let tree = file.compile().unwrap().tree;
    let dem = tree.nodes()[tree.find("dem").unwrap() as usize]
        .leaf()
        .and_then(|f| f.as_any())
        .and_then(|a| a.downcast_ref::<karstic::dem::HeightfieldField>())
        .unwrap();
    let ground = |xy: glam::Vec2| Some(dem.height(xy)).filter(|h| h.is_finite());
    let opts = BuildOptions {
        ground: Some(&ground),
        ..Default::default()
    };
    let base = path.parent().unwrap();
    let (p, _) = spec.params(0, 8 << 30);
    let mut g = c.benchmark_group("feature_curves_on_terrain");
    g.sample_size(10);
    g.bench_function("arch_128x128x64", |b| {
        b.iter(|| run(&spec.resolve(base, &opts).unwrap(), &p).unwrap())
    });
    g.finish();
}

/// `value_grad` of the ridge's leaf (128×64×128) at 100k points near its surface.
fn interpolation(c: &mut Criterion) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/curves");
    let file = karstic::scene::load(dir.join("ridge.ron")).unwrap();
    let mut spec = file.feature_volumes()[0].clone();
    let features = spec.feature_set(&dir).unwrap().resolve(&|_| None).unwrap();
    let lin = spec.build_features(&features, 0, 8 << 30).unwrap();
    spec.interpolation = Interpolation::Tricubic;
    let cubic = spec.build_features(&features, 0, 8 << 30).unwrap();
    // Points near the surface: a deterministic scatter, kept where |S| < 3 m.
    let d = lin.params().domain;
    let mut rng = Rng(1);
    let mut points = Vec::new();
    while points.len() < 100_000 {
        let p = rng.in_box(&d);
        if lin.s_value(p).abs() < 3.0 {
            points.push(p);
        }
    }
    let mut g = c.benchmark_group("feature_volume_eval_100k");
    g.sample_size(10);
    for (label, f) in [("trilinear", &lin), ("tricubic", &cubic)] {
        g.bench_function(label, |b| {
            b.iter(|| points.iter().map(|&p| f.value_grad(p).0).sum::<f32>())
        });
    }
    g.finish();
}

criterion_group!(benches, ridge, on_terrain, interpolation);
criterion_main!(benches);

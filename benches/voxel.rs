//! The Feature Curve pipeline on the thesis's benchmark scene (seed 000 Table 7.1): a
//! ridge from three curves, full pipeline with distance propagation, at 64×32×64,
//! 128×64×128 and 256×128×256 voxels (z up here: x × y × z = 128 × 128 × 64 and so on),
//! with and without varying noise parameters (the noise diffusion stage).

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use karstic::curves::FeatureVolumeSpec;
use karstic::scene::Positive;
use karstic::voxel::run;

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

criterion_group!(benches, ridge);
criterion_main!(benches);

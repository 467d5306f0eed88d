//! The heightfield leaf's hot paths on the Jacksboro UTM DEM resampled to 30 m (1030 × 1087
//! samples): point evaluation, per-column z-bands and elevation queries, block evaluation,
//! and the generic interval-subdivision z-bands as the baseline the pyramid replaces; and
//! the eroded amplification of the bundled crop over the main job's region and over the
//! issue's 1,560 × 490 m region at 2.5 m (issue 38: ≤ 2 s on 2 cores).

#[path = "../tests/common/rng.rs"]
#[allow(dead_code)] // the draws this bench does not use
mod rng;

use rng::Rng;
use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{Vec2, Vec3};
use karstic::dem::HeightfieldField;
use karstic::field::contract::z_bands_by_interval;
use karstic::field::{Field, Interval, Rect, ZBands};
use karstic::scene::HeightfieldSpec;

fn leaf() -> HeightfieldField {
    let mut spec = HeightfieldSpec::new("../shared/data/dem/jacksboro_utm16n_90m.tif", 60.0);
    spec.cell_size = Some(karstic::value::Positive::new(30.0));
    spec.load(Path::new(env!("CARGO_MANIFEST_DIR")))
        .expect("the shared DEM loads")
}

fn points(f: &HeightfieldField, n: usize) -> Vec<Vec3> {
    let s = f.support();
    let mut rng = Rng(9);
    (0..n).map(|_| rng.in_box(&s)).collect()
}

/// Footprints of 100 × 100 MC columns of 30 m in raster order (as a mesher walks them),
/// across the DEM's south-west corner so that walls, nodata and interior all occur.
fn columns(f: &HeightfieldField) -> Vec<Rect> {
    let o = f.heightfield().origin() + Vec2::new(-600.0, 2000.0);
    (0..100 * 100)
        .map(|k| {
            let a = o + Vec2::new((k % 100) as f32, (k / 100) as f32) * 30.0;
            Rect::new(a, a + Vec2::splat(30.0))
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let f = leaf();
    let pts = points(&f, 10_000);
    let fps = columns(&f);
    let z = f.support().z();
    let z = Interval::new(z.lo, z.hi);

    c.bench_function("dem/value x10k", |b| {
        b.iter(|| pts.iter().map(|p| f.value(black_box(*p))).sum::<f32>())
    });
    c.bench_function("dem/value_grad x10k", |b| {
        b.iter(|| {
            pts.iter()
                .map(|p| f.value_grad(black_box(*p)).0)
                .sum::<f32>()
        })
    });
    let mut bands = ZBands::new();
    c.bench_function("dem/z_bands x10k (pyramid)", |b| {
        b.iter(|| {
            let mut n = 0;
            for fp in &fps {
                bands.clear();
                f.z_bands(black_box(fp), z, &mut bands);
                n += bands.as_slice().len();
            }
            n
        })
    });
    c.bench_function(
        "dem/z_bands x10k (generic interval subdivision baseline)",
        |b| {
            b.iter(|| {
                let mut n = 0;
                for fp in &fps {
                    bands.clear();
                    z_bands_by_interval(&f, black_box(fp), z, &mut bands);
                    n += bands.as_slice().len();
                }
                n
            })
        },
    );
    c.bench_function("dem/elevation x10k", |b| {
        b.iter(|| {
            fps.iter()
                .filter(|fp| f.elevation(black_box(fp)).is_some())
                .count()
        })
    });
    let mut out = vec![0.0f32; 32 * 32 * 32];
    let origin = f.support().center() - Vec3::splat(16.0 * 30.0);
    c.bench_function("dem/eval_block 32³", |b| {
        b.iter(|| f.eval_block(black_box(origin), Vec3::splat(30.0), [32, 32, 32], &mut out))
    });
    c.bench_function("dem/value 32³ (per-point baseline)", |b| {
        b.iter(|| {
            for k in 0..32 {
                for j in 0..32 {
                    for i in 0..32 {
                        let p = origin + Vec3::new(i as f32, j as f32, k as f32) * 30.0;
                        out[i + 32 * (j + 32 * k)] = f.value(black_box(p));
                    }
                }
            }
        })
    });
}

/// The eroded amplification (a tree's `amplify: ()`) of the main job's DEM over `region`
/// at 2.5 m.
fn amplification(c: &mut Criterion) {
    use karstic::dem::Interpolation;
    use karstic::erosion::amplify::amplify;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/data/jacksboro_crop.asc");
    let dem = karstic::dem::read(&path, &Default::default())
        .expect("the bundled DEM")
        .heightfield;
    let spec: karstic::scene::AmplifySpec = ron::from_str("()").expect("defaults");
    let mut g = c.benchmark_group("amplify");
    g.sample_size(10);
    for (name, min, max) in [
        (
            "main job region 660x490 m",
            (3300.0, 4840.0),
            (3960.0, 5330.0),
        ),
        ("1560x490 m", (3000.0, 4840.0), (4560.0, 5330.0)),
    ] {
        let region = Rect::new(Vec2::from(min), Vec2::from(max));
        let p = spec.params(11, Some((region, 2.5))).expect("params");
        g.bench_function(name, |b| {
            b.iter(|| amplify(&dem, Interpolation::Bicubic, black_box(&p), 8 << 30).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, bench, amplification);
criterion_main!(benches);

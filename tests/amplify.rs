//! Issue 38, eroded amplification of a DEM: the amplified terrain keeps the DEM cell by
//! cell, its channels are incised and have the concavity of rivers, it is the same at any
//! thread count, and tree files reach it through the job's region.

use std::path::Path;

use glam::Vec2;
use karstic::dem::{self, Heightfield, Inset, Interpolation, Trace};
use karstic::erosion::amplify::{AmplifyParams, amplify};
use karstic::field::{Aabb, Field, Rect};
use karstic::procedural::GenerateSpec;
use karstic::scene::{AmplifySpec, HeightfieldSpec};

const BUDGET: u64 = 1 << 30;

/// The main job's DEM (the bundled 128 × 128 crop at 90 m).
fn crop() -> Heightfield {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/data/jacksboro_crop.asc");
    dem::read(&path, &Default::default()).unwrap().heightfield
}

/// A ridged range of 120 m relief on 30 m cells, not eroded: another terrain, and one
/// whose valleys no river shaped.
fn ridged() -> Heightfield {
    let g: GenerateSpec = ron::from_str(
        "(kind: Ridged((wavelength: 900)), size: (49, 49), cell: 30, relief: 120, seed: 5)",
    )
    .unwrap();
    g.build(BUDGET).unwrap()
}

/// The defaults of a tree's `amplify: ()` over `region` at `cell`.
fn params(region: Rect, cell: f32) -> AmplifyParams {
    let spec: AmplifySpec = ron::from_str("()").unwrap();
    spec.params(11, Some((region, cell))).unwrap()
}

/// The main job's region (`trees/jacksboro_bluff.ron`).
fn bluff_region() -> Rect {
    Rect::new(Vec2::new(3300.0, 4840.0), Vec2::new(3960.0, 5330.0))
}

/// The amplified surface `h + δ` on the inset's lattice, and the DEM's `h` there.
fn surfaces(dem: &Heightfield, inset: &Inset) -> (Vec<f32>, Vec<f32>) {
    let d = inset.delta();
    let base: Vec<f32> = (0..d.samples().len())
        .map(|k| {
            let q = d.origin() + Vec2::new((k % d.nx()) as f32, (k / d.nx()) as f32) * d.cell();
            dem.sample(q, Interpolation::Bicubic)
        })
        .collect();
    let amplified = base.iter().zip(d.samples()).map(|(b, d)| b + d).collect();
    (amplified, base)
}

/// Per DEM cell inside `region`: the mean of `δ` over the cell (36 points).
fn cell_means(dem: &Heightfield, inset: &Inset, region: Rect) -> Vec<f32> {
    let c = dem.cell();
    let mut out = Vec::new();
    for j in 0..dem.ny() - 1 {
        for i in 0..dem.nx() - 1 {
            let lo = dem.origin() + Vec2::new(i as f32, j as f32) * c;
            let cell = Rect::new(lo, lo + c);
            if !region.contains_rect(&cell) {
                continue;
            }
            let mut sum = 0.0;
            for b in 0..6 {
                for a in 0..6 {
                    let q = lo + Vec2::new(a as f32 + 0.5, b as f32 + 0.5) / 6.0 * c;
                    sum += inset.delta().sample(q, Interpolation::Bicubic);
                }
            }
            out.push(sum / 36.0);
        }
    }
    out
}

/// Averaged back over each DEM cell, the amplified terrain is the DEM: within 0.25 m RMS
/// and 1 m at worst (the issue allows 1 m and 3 m), on the bundled DEM over the main
/// job's region and on a ridged range. The amplification is not a no-op: it moves the
/// ground by metres between.
#[test]
fn amplified_terrain_averages_back_to_the_dem() {
    let ridged_region = Rect::new(Vec2::new(300.0, 300.0), Vec2::new(1140.0, 1140.0));
    for (name, dem, region, cell) in [
        ("bluff", crop(), bluff_region(), 2.5),
        ("ridged", ridged(), ridged_region, 3.0),
    ] {
        let inset = amplify(&dem, Interpolation::Bicubic, &params(region, cell), BUDGET).unwrap();
        let means = cell_means(&dem, &inset, region);
        assert!(means.len() >= 16, "{name}: {} cells", means.len());
        let rms = (means.iter().map(|m| m * m).sum::<f32>() / means.len() as f32).sqrt();
        let worst = means.iter().fold(0.0f32, |w, m| w.max(m.abs()));
        assert!(
            rms <= 0.25 && worst <= 1.0,
            "{name}: rms {rms} m, worst {worst} m"
        );
        let d = inset.delta().samples();
        let moved = (d.iter().map(|v| v * v).sum::<f32>() / d.len() as f32).sqrt();
        assert!(
            moved > 1.0,
            "{name}: the ground moved by {moved} m RMS only"
        );
    }
}

/// How far sample `k` lies below the ground `r` samples to either side, across the axis
/// (of the four through it) where it lies deepest: across a channel.
fn valley_depth(z: &[f32], nx: usize, k: usize, r: usize) -> f32 {
    [1, nx + 1, nx, nx - 1]
        .into_iter()
        .map(|s| 0.5 * (z[k - r * s] + z[k + r * s]) - z[k])
        .fold(f32::NEG_INFINITY, f32::max)
}

/// Channels are incised: where the drainage area passes 10⁴ m², the amplified ground lies
/// on average more than 2 m below the ground 10 m to either side across the channel,
/// where the DEM itself lies within 0.5 m of it.
#[test]
fn channels_are_incised_along_the_drainage() {
    let dem = crop();
    let region = bluff_region();
    let inset = amplify(&dem, Interpolation::Bicubic, &params(region, 2.5), BUDGET).unwrap();
    let (z, base) = surfaces(&dem, &inset);
    let d = inset.delta();
    let (nx, r) = (d.nx(), 4);
    let area = inset.trace(Trace::Area);
    let channel: Vec<usize> = (0..z.len())
        .filter(|&k| {
            let (i, j) = (k % nx, k / nx);
            let q = d.origin() + Vec2::new(i as f32, j as f32) * d.cell();
            area[k] >= 1e4
                && i >= r
                && j >= r
                && i + r < nx
                && j + r < d.ny()
                && region.contains_rect(&Rect::new(q, q))
        })
        .collect();
    assert!(channel.len() > 200, "{} channel samples", channel.len());
    let mean = |z: &[f32]| {
        channel
            .iter()
            .map(|&k| valley_depth(z, nx, k, r))
            .sum::<f32>()
            / channel.len() as f32
    };
    let (cut, before) = (mean(&z), mean(&base));
    assert!(cut > 2.0, "channels {cut} m below their banks");
    assert!(
        before.abs() < 0.5,
        "the DEM's own valleys {before} m deep at 10 m"
    );
}

/// The slope–area relation's exponent over samples of drainage area ≥ `amin`: the
/// steepest descent to a neighbour against the area, median slopes in bins of 0.2 decades
/// of area (bins of 10 samples or more), least squares on the bins. Returns `θ` in
/// `S ∝ A^−θ`.
fn concavity(z: &[f32], area: &[f32], nx: usize, ny: usize, cell: f32, amin: f32) -> f32 {
    let mut bins: std::collections::BTreeMap<i32, Vec<f32>> = Default::default();
    for j in 1..ny - 1 {
        for i in 1..nx - 1 {
            let k = i + nx * j;
            if area[k] < amin {
                continue;
            }
            let mut s = 0.0f32;
            for (di, dj) in karstic::analysis::flow::NEIGHBOURS {
                let n = (i as isize + di) as usize + nx * (j as isize + dj) as usize;
                let l = cell * ((di * di + dj * dj) as f32).sqrt();
                s = s.max((z[k] - z[n]) / l);
            }
            if s > 1e-4 {
                bins.entry((area[k].log10() / 0.2).floor() as i32)
                    .or_default()
                    .push(s.ln());
            }
        }
    }
    let points: Vec<(f32, f32)> = bins
        .into_iter()
        .filter(|(_, v)| v.len() >= 10)
        .map(|(b, mut v)| {
            v.sort_by(f32::total_cmp);
            (
                (b as f32 + 0.5) * 0.2 * std::f32::consts::LN_10,
                v[v.len() / 2],
            )
        })
        .collect();
    assert!(points.len() >= 6, "{} bins", points.len());
    let n = points.len() as f32;
    let mx = points.iter().map(|p| p.0).sum::<f32>() / n;
    let my = points.iter().map(|p| p.1).sum::<f32>() / n;
    let sxy: f32 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f32 = points.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    -sxy / sxx
}

/// The amplified channels' river profiles are natural: on the whole bundled DEM amplified
/// at 20 m, the slope–area exponent of the channels of 0.1 km² and more lies between 0.35
/// and 0.65, the range of real rivers (Whipple 2004). On a ridged range no river shaped,
/// amplified at 5 m, the upsampled range has no concavity and the amplified one has some
/// (channels of 2,000 m² and more: more than 0.35; it overshoots the range there, about
/// 0.7, the channel heads sitting on its steep slopes: an open limit, docs/amplify.md).
#[test]
fn amplified_channels_have_the_concavity_of_rivers() {
    for (name, dem, margin, cell, amin, amplified, raw) in [
        ("bluff", crop(), 360.0, 20.0, 1e5, 0.35..=0.65, 0.35..=0.65),
        ("ridged", ridged(), 120.0, 5.0, 2e3, 0.35..=1.0, -1.0..=0.2),
    ] {
        let x = dem.extent();
        let region = Rect::new(x.min + margin, x.max - margin);
        let inset = amplify(&dem, Interpolation::Bicubic, &params(region, cell), BUDGET).unwrap();
        let d = inset.delta();
        let (z, base) = surfaces(&dem, &inset);
        let theta = concavity(&z, inset.trace(Trace::Area), d.nx(), d.ny(), cell, amin);
        assert!(amplified.contains(&theta), "{name}: θ = {theta}");
        let mut filled = base.clone();
        karstic::analysis::flow::fill_in_place(&mut filled, d.nx(), d.ny());
        let mut area = Vec::new();
        karstic::analysis::flow::mfd_area(&filled, d.nx(), d.ny(), d.cell(), 1.0, &mut area);
        let before = concavity(&filled, &area, d.nx(), d.ny(), cell, amin);
        assert!(
            raw.contains(&before),
            "{name}: θ = {before} before amplifying"
        );
    }
}

/// The same amplification whatever the thread count, to the bit.
#[test]
fn amplification_is_the_same_at_every_thread_count() {
    let dem = crop();
    let p = params(bluff_region(), 5.0);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| amplify(&dem, Interpolation::Bicubic, &p, BUDGET).unwrap())
    };
    let (a, b) = (run(1), run(3));
    let bits = |i: &Inset| {
        let mut v: Vec<u32> = i.delta().samples().iter().map(|x| x.to_bits()).collect();
        for t in Trace::ALL {
            v.extend(i.trace(t).iter().map(|x| x.to_bits()));
        }
        v
    };
    assert!(bits(&a) == bits(&b), "one thread and three differ");
}

/// A tree's `amplify: ()` takes the job's region and cell; without a job it asks for a
/// region, naming the field; the amplified leaf joins the DEM at the inset's edge.
#[test]
fn tree_files_amplify_over_the_job_region() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees");
    let spec: HeightfieldSpec = ron::from_str(
        "(source: \"data/jacksboro_crop.asc\", falloff: 30, interpolation: Bicubic, amplify: Some(()))",
    )
    .unwrap();
    let err = spec.load(&dir).unwrap_err().to_string();
    assert!(err.contains("amplify.region"), "{err}");
    let mut cache = karstic::scene::DemCache::new(BUDGET);
    let region = bluff_region();
    let leaf = spec
        .load_with(&dir, &mut cache, 11, Some((region, 5.0)))
        .unwrap();
    let inset = leaf.inset().expect("an inset");
    let e = inset.delta().extent();
    assert!(e.contains_rect(&region), "{e:?}");
    assert_eq!(inset.delta().cell(), Vec2::splat(5.0));
    // Continuous across the inset's edge: just inside and just outside agree.
    let plain = HeightfieldSpec {
        amplify: None,
        ..spec.clone()
    }
    .load(&dir)
    .unwrap();
    for t in 0..50 {
        let x = e.min.x + (e.max.x - e.min.x) * (t as f32 + 0.5) / 50.0;
        for y in [e.min.y, e.max.y] {
            let (a, b) = (
                leaf.base_height(Vec2::new(x, y)),
                plain.base_height(Vec2::new(x, y)),
            );
            assert!((a - b).abs() < 1e-3, "({x}, {y}): {a} against {b}");
        }
    }
    // Inside, the two differ.
    let c = (region.min + region.max) * 0.5;
    let moved = (0..100)
        .map(|k| c + Vec2::new((k % 10) as f32, (k / 10) as f32) * 7.0)
        .filter(|&q| (leaf.base_height(q) - plain.base_height(q)).abs() > 0.1)
        .count();
    assert!(moved > 30, "{moved} of 100 points moved");
}

/// The amplified leaf's bounds hold where the inset changes it: intervals of small boxes
/// around the surface contain the sampled values, box Lipschitz bounds hold on sampled
/// pairs, and segment bounds along random segments (the tracer's). They prune three
/// quarters as often as the plain leaf's at least (the amplified ground is rougher).
#[test]
fn amplified_leaf_bounds_are_sound_over_the_inset() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees");
    let spec: HeightfieldSpec = ron::from_str(
        "(source: \"data/jacksboro_crop.asc\", falloff: 10, interpolation: Bicubic, amplify: Some(()))",
    )
    .unwrap();
    let mut cache = karstic::scene::DemCache::new(BUDGET);
    let region = bluff_region();
    let f = spec
        .load_with(&dir, &mut cache, 11, Some((region, 2.5)))
        .unwrap();
    let plain = HeightfieldSpec {
        amplify: None,
        ..spec.clone()
    }
    .load(&dir)
    .unwrap();
    let e = f.inset().unwrap().delta().extent();
    let informative = |f: &dyn Field| {
        let mut rng = crate::common::Rng(38);
        let mut count = 0;
        for _ in 0..3000 {
            let xy = Vec2::new(rng.range(e.min.x, e.max.x), rng.range(e.min.y, e.max.y));
            let z = plain.base_height(xy) + rng.range(-15.0, 15.0);
            let c = xy.extend(z);
            let half = glam::Vec3::splat(rng.range(0.2, 20.0));
            let b = Aabb::new(c - half, c + half);
            let iv = f.interval(&b);
            let lb = f.lipschitz_box(&b);
            count += (iv.width() < 2.0 * karstic::field::ISO) as usize;
            for _ in 0..12 {
                let (p, q) = (rng.in_box(&b), rng.in_box(&b));
                let v = f.value(p);
                assert!(
                    iv.lo - 1e-5 <= v && v <= iv.hi + 1e-5,
                    "f({p}) = {v} not in {iv:?}"
                );
                let d = p.distance(q);
                if d > 1e-2 {
                    let slope = (v - f.value(q)).abs() / d;
                    assert!(slope <= lb * 1.001 + 1e-6, "slope {slope} > {lb} in {b:?}");
                }
            }
        }
        count
    };
    let (amplified, before) = (informative(&f), informative(&plain));
    assert!(
        amplified * 4 >= before * 3,
        "{amplified} informative intervals amplified, {before} plain"
    );
    let near = Aabb::new(e.min.extend(800.0), e.max.extend(1000.0));
    crate::common::check_segment_lipschitz(&f, &near, 20000, 38);
}

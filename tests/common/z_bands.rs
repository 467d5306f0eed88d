//! Sampled soundness of a field's z-bands: every sign change of `f − ISO` along a column
//! lies in a band the field gave for a footprint holding that column.

use glam::Vec2;
use karstic::field::{Field, ISO, Interval, Rect, ZBands};

use super::Rng;

/// Over `footprints` random footprints (half-sizes 1–60 m) in the field's support dilated
/// by 10 m, scans `columns` random columns each in 2,000 steps over the support's z range
/// and asserts that every crossing lies in a band of its footprint (`name` labels the
/// message). Returns the crossings found and the mean fraction of z the bands pruned.
pub fn check_z_bands(
    name: &str,
    f: &dyn Field,
    footprints: usize,
    columns: usize,
    seed: u64,
) -> (usize, f32) {
    let mut rng = Rng(seed);
    let s = f.support().dilate(10.0);
    let zr = Interval::new(s.min.z, s.max.z);
    let mut bands = ZBands::new();
    let (mut crossings, mut pruned) = (0, 0.0);
    for _ in 0..footprints {
        let c = rng.in_box(&s).truncate();
        let half = Vec2::new(rng.range(1.0, 60.0), rng.range(1.0, 60.0));
        let fp = Rect::new(c - half, c + half);
        bands.clear();
        f.z_bands(&fp, zr, &mut bands);
        pruned += 1.0 - bands.as_slice().iter().map(|b| b.width()).sum::<f32>() / zr.width();
        for _ in 0..columns {
            let xy = Vec2::new(rng.range(fp.min.x, fp.max.x), rng.range(fp.min.y, fp.max.y));
            crossings += column_crossings_in_bands(name, f, xy, zr, 2000, &bands);
        }
    }
    (crossings, pruned / footprints as f32)
}

/// Scans the column at `xy` over `zr` in `n` steps and asserts that every sign change of
/// `f − ISO` lies in one of `bands` (`name` labels the message); returns how many it found.
pub fn column_crossings_in_bands(
    name: &str,
    f: &dyn Field,
    xy: Vec2,
    zr: Interval,
    n: usize,
    bands: &ZBands,
) -> usize {
    let dz = zr.width() / n as f32;
    let mut crossings = 0;
    let mut prev = f.value(xy.extend(zr.lo)) > ISO;
    for k in 1..=n {
        let z = zr.lo + k as f32 * dz;
        let cur = f.value(xy.extend(z)) > ISO;
        if cur != prev {
            crossings += 1;
            let seg = Interval::new(z - dz, z);
            assert!(
                bands.as_slice().iter().any(|b| b.overlaps(&seg)),
                "{name}: crossing in {seg:?} at {xy} outside {:?}",
                bands.as_slice()
            );
        }
        prev = cur;
    }
    crossings
}

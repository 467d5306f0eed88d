//! What the landform generators read off a heightfield besides drainage ([`super::flow`]):
//! slope, stream power `σ = A^½·s` (Paris et al. 2019 §6.1, after Cordonnier et al. 2016),
//! sinks (the pits of Barnes et al. 2014 that are deep enough to matter) and coastal
//! accessibility (how open a sample is to the sea, the `α` of Paris et al. 2019 §6.1).
//!
//! Grids are [`Heightfield`]s, NaN for nodata; every function returns one value per
//! sample, in the grid's order.

use glam::Vec2;
use rayon::prelude::*;

use super::flow::{drainage_area, fill_depressions, is_pit};
use crate::dem::Heightfield;

/// The slope `‖∇h‖` (rise over run, so 1 is 45°) of every sample, by central differences
/// (one-sided on the edges and next to nodata); 0 on nodata and where no neighbour is
/// valid along an axis.
pub fn slope(hf: &Heightfield) -> Vec<f32> {
    let (nx, ny) = (hf.nx(), hf.ny());
    let c = hf.cell();
    let z = hf.samples();
    // The derivative along one axis at `k`, from the valid neighbours `k ± step`.
    let diff = |k: usize, lo: Option<usize>, hi: Option<usize>, h: f32| -> f32 {
        let valid = |n: Option<usize>| n.filter(|&n| !z[n].is_nan());
        match (valid(lo), valid(hi)) {
            (Some(a), Some(b)) => (z[b] - z[a]) / (2.0 * h),
            (Some(a), None) => (z[k] - z[a]) / h,
            (None, Some(b)) => (z[b] - z[k]) / h,
            (None, None) => 0.0,
        }
    };
    (0..z.len())
        .into_par_iter()
        .map(|k| {
            if z[k].is_nan() {
                return 0.0;
            }
            let (i, j) = (k % nx, k / nx);
            let gx = diff(
                k,
                (i > 0).then(|| k - 1),
                (i + 1 < nx).then_some(k + 1),
                c.x,
            );
            let gy = diff(
                k,
                (j > 0).then(|| k - nx),
                (j + 1 < ny).then_some(k + nx),
                c.y,
            );
            gx.hypot(gy)
        })
        .collect()
}

/// Stream power `σ = A^½·s` of every sample (Paris et al. 2019 §6.1): `A` the drainage
/// area by multiple flow directions (Freeman 1991) over the depression-filled grid
/// (Barnes et al. 2014), `s` the slope of the raw grid. 0 on nodata.
pub fn stream_power(hf: &Heightfield) -> Vec<f32> {
    let area = drainage_area(&fill_depressions(hf));
    slope(hf)
        .iter()
        .zip(&area)
        .map(|(s, a)| a.sqrt() * s)
        .collect()
}

/// The sinks of `hf`: pits (no lower 8-neighbour, [`is_pit`]) whose depression is at
/// least `min_depth` metres deep (the depression-filled grid stands that much above them),
/// as sample indices in increasing order. Shallow pits (noise, flat cells) are not sinks.
pub fn sinks(hf: &Heightfield, min_depth: f32) -> Vec<usize> {
    let filled = fill_depressions(hf);
    let (z, f) = (hf.samples(), filled.samples());
    (0..z.len())
        .filter(|&k| is_pit(hf, k) && f[k] - z[k] >= min_depth)
        .collect()
}

/// Number of horizontal directions [`coastal_accessibility`] looks along.
pub const ACCESS_DIRECTIONS: usize = 16;

/// How open each sample is to the sea, in `[0, 1]`: the fraction of
/// [`ACCESS_DIRECTIONS`] horizontal directions along which a march from the sample, once
/// past its own shore (ground higher than `sea_level + clearance`), meets sea (samples
/// below `sea_level`) and stays on it for the rest of `reach` metres (or leaves the map
/// over it). A headland is open on most sides, a straight coast on about half, the back
/// of a bay on few (land across the water closes a direction), an inland sample out of
/// reach on none; the sea itself is 1, nodata 0. This stands in for the accessibility of
/// Miller 1994 that Paris et al. 2019 §6.1 multiply with the wave stress.
pub fn coastal_accessibility(
    hf: &Heightfield,
    sea_level: f32,
    clearance: f32,
    reach: f32,
) -> Vec<f32> {
    let (nx, ny) = (hf.nx(), hf.ny());
    let c = hf.cell();
    let step = c.x.min(c.y);
    let steps = (reach / step).ceil().max(1.0) as usize;
    let dirs: Vec<Vec2> = (0..ACCESS_DIRECTIONS)
        .map(|d| Vec2::from_angle(std::f32::consts::TAU * d as f32 / ACCESS_DIRECTIONS as f32))
        .collect();
    let z = hf.samples();
    let at = |p: Vec2| -> Option<f32> {
        let (i, j) = ((p.x / c.x).round(), (p.y / c.y).round());
        (i >= 0.0 && j >= 0.0 && (i as usize) < nx && (j as usize) < ny)
            .then(|| z[i as usize + nx * j as usize])
    };
    (0..z.len())
        .into_par_iter()
        .map(|k| {
            if z[k].is_nan() {
                return 0.0;
            }
            let p = Vec2::new((k % nx) as f32 * c.x, (k / nx) as f32 * c.y);
            let open = dirs
                .iter()
                .filter(|d| {
                    let mut at_sea = false;
                    for s in 1..=steps {
                        match at(p + **d * (s as f32 * step)) {
                            None => return at_sea,
                            Some(h) if h.is_nan() => return at_sea,
                            Some(h) if h < sea_level => at_sea = true,
                            Some(h) if h > sea_level + clearance && at_sea => return false,
                            Some(_) => {}
                        }
                    }
                    at_sea
                })
                .count();
            if z[k] < sea_level {
                1.0
            } else {
                open as f32 / ACCESS_DIRECTIONS as f32
            }
        })
        .collect()
}

//! Thermal erosion (Musgrave, Kolb and Mace 1989, §3): material on a slope steeper than
//! the talus angle slides to its lower neighbours until no slope exceeds it.
//!
//! Each pass is a Jacobi step: every sample computes, from the same elevations, the
//! excess drop `e = (h − h_n) − tan θ · L` to each 8-neighbour at distance `L`, moves
//! [`TRANSFER`] of its largest excess and splits it among the neighbours in proportion to
//! their excess. Samples gather what their neighbours send, so the rows are independent
//! and the result is the same whatever the thread count. Mass is conserved; nodata is
//! left out.

use rayon::prelude::*;

use crate::analysis::flow::NEIGHBOURS;

/// The fraction of its largest excess drop a sample sheds per pass (½ would level a lone
/// pair in one pass; less keeps a sample fed by many neighbours from overshooting).
pub const TRANSFER: f32 = 0.25;

/// What [`erode`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThermalReport {
    /// Passes run.
    pub iterations: u32,
    /// The largest excess drop left, metres (≤ the tolerance when it converged).
    pub max_excess: f32,
}

/// Thermal erosion of the samples `z` of an `nx × ny` grid of `dx × dy` cells with talus
/// angle `talus` (radians, in `(0, π/2)`), passes until no drop between 8-neighbours
/// exceeds `tan(talus) · distance` by more than `tolerance` metres, or `max_iterations`.
#[allow(clippy::too_many_arguments)]
pub fn erode(
    z: &mut [f32],
    nx: usize,
    ny: usize,
    dx: f32,
    dy: f32,
    talus: f32,
    tolerance: f32,
    max_iterations: u32,
) -> ThermalReport {
    let tan = talus.tan();
    let allowed: [f32; 8] = NEIGHBOURS.map(|(di, dj)| tan * (di as f32 * dx).hypot(dj as f32 * dy));
    // Per sample: what it sheds and, per unit of excess, what each neighbour receives.
    let mut shed = vec![0.0f32; z.len()];
    let mut ratio = vec![0.0f32; z.len()];
    let mut next = z.to_vec();
    let mut report = ThermalReport {
        iterations: 0,
        max_excess: max_excess(z, nx, ny, &allowed),
    };
    while report.max_excess > tolerance && report.iterations < max_iterations {
        let zr: &[f32] = z;
        shed.par_chunks_mut(nx)
            .zip(ratio.par_chunks_mut(nx))
            .enumerate()
            .for_each(|(j, (shed, ratio))| {
                for i in 0..nx {
                    let (mut most, mut total) = (0.0f32, 0.0f32);
                    for_excess(zr, nx, ny, i, j, &allowed, |e| {
                        most = most.max(e);
                        total += e;
                    });
                    shed[i] = TRANSFER * most;
                    ratio[i] = if total > 0.0 { shed[i] / total } else { 0.0 };
                }
            });
        let ratio_r: &[f32] = &ratio;
        next.par_chunks_mut(nx).enumerate().for_each(|(j, row)| {
            for (i, out) in row.iter_mut().enumerate() {
                let k = i + nx * j;
                if zr[k].is_nan() {
                    *out = zr[k];
                    continue;
                }
                let mut h = zr[k] - shed[k];
                // Neighbour n sends ratio[n] · e(n → k); the distance, hence the
                // allowed drop, is the same both ways.
                for (d, &(di, dj)) in NEIGHBOURS.iter().enumerate() {
                    let (a, b) = (i as isize + di, j as isize + dj);
                    if a < 0 || b < 0 || a as usize >= nx || b as usize >= ny {
                        continue;
                    }
                    let n = a as usize + nx * b as usize;
                    let e = zr[n] - zr[k] - allowed[d];
                    if e > 0.0 {
                        h += ratio_r[n] * e;
                    }
                }
                *out = h;
            }
        });
        z.copy_from_slice(&next);
        report.iterations += 1;
        report.max_excess = max_excess(z, nx, ny, &allowed);
    }
    report
}

/// Calls `f` with every positive excess drop from sample `(i, j)` to a valid neighbour.
#[inline]
fn for_excess(
    z: &[f32],
    nx: usize,
    ny: usize,
    i: usize,
    j: usize,
    allowed: &[f32; 8],
    mut f: impl FnMut(f32),
) {
    let h = z[i + nx * j];
    if h.is_nan() {
        return;
    }
    for (d, &(di, dj)) in NEIGHBOURS.iter().enumerate() {
        let (a, b) = (i as isize + di, j as isize + dj);
        if a < 0 || b < 0 || a as usize >= nx || b as usize >= ny {
            continue;
        }
        // NaN neighbours give NaN, which is not > 0.
        let e = h - z[a as usize + nx * b as usize] - allowed[d];
        if e > 0.0 {
            f(e);
        }
    }
}

/// The largest excess drop between 8-neighbours (0 when no slope exceeds the talus).
fn max_excess(z: &[f32], nx: usize, ny: usize, allowed: &[f32; 8]) -> f32 {
    (0..ny)
        .into_par_iter()
        .map(|j| {
            let mut most = 0.0f32;
            for i in 0..nx {
                for_excess(z, nx, ny, i, j, allowed, |e| most = most.max(e));
            }
            most
        })
        .reduce(|| 0.0, f32::max)
}

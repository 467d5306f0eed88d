//! Fluvial erosion by the stream-power law `∂h/∂t = U − K A^m S^n`, solved implicitly in
//! O(n) along the flow graph's stack (Braun and Willett 2013, §2.3 and eq. 24–26): each
//! sample's new elevation depends only on its receiver's, already updated, so one pass
//! downstream to upstream solves the whole grid, stably for any time step.

use crate::analysis::flow::{FlowGraph, fill_in_place};

/// The stream-power law's constants: `K` (erodibility, in `m^{1−2m} / yr` for `n = 1`),
/// the area exponent `m` and the slope exponent `n`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreamPower {
    /// Erodibility `K`.
    pub k: f32,
    /// Drainage-area exponent `m`.
    pub m: f32,
    /// Slope exponent `n` (> 0).
    pub n: f32,
}

/// One step of uplift and stream-power erosion on the samples `z` of an `nx × ny` grid of
/// `dx × dy` cells, reusing `graph` and `area` between steps.
///
/// Interior samples rise by `uplift · dt` (base level, the edge and the rim of nodata, stays
/// put). Depressions are filled first when the receivers find pits (Priority-Flood + ε,
/// Barnes et al. 2014: a closed basin fills with sediment up to its spill point), then
/// every sample is eroded in stack order: with `F = K dt A^m / L^n`, the new elevation
/// solves `h − h₀ + F (h − h_r)^n = 0` — in closed form for `n = 1`, by Newton's method
/// otherwise (Braun and Willett 2013 §2.3). A sample not above its receiver is left alone.
#[allow(clippy::too_many_arguments)]
pub fn step(
    z: &mut [f32],
    nx: usize,
    ny: usize,
    dx: f32,
    dy: f32,
    law: StreamPower,
    uplift: f32,
    dt: f32,
    graph: &mut FlowGraph,
    area: &mut Vec<f32>,
) {
    let rise = uplift * dt;
    if rise != 0.0 {
        for j in 1..ny.saturating_sub(1) {
            for k in j * nx + 1..(j + 1) * nx - 1 {
                if !FlowGraph::is_base_level(z, nx, ny, k) && !z[k].is_nan() {
                    z[k] += rise;
                }
            }
        }
    }
    if graph.update(z, nx, ny, dx, dy) > 0 {
        fill_in_place(z, nx, ny);
        graph.update(z, nx, ny, dx, dy);
    }
    graph.accumulate(dx * dy, area);
    let (rec, len) = (graph.receivers(), graph.lengths());
    let (kdt, m, n) = (f64::from(law.k) * f64::from(dt), f64::from(law.m), law.n);
    for &k in graph.stack() {
        let k = k as usize;
        let r = rec[k] as usize;
        if r == k {
            continue;
        }
        let (h0, hr) = (f64::from(z[k]), f64::from(z[r]));
        if h0 <= hr {
            continue;
        }
        let l = f64::from(len[k]);
        let a = f64::from(area[k]);
        let h = if n == 1.0 {
            let f = kdt * a.powf(m) / l;
            (h0 + f * hr) / (1.0 + f)
        } else {
            newton(h0, hr, kdt * a.powf(m) / l.powf(f64::from(n)), f64::from(n))
        };
        z[k] = h as f32;
    }
}

/// Solves `h − h₀ + F (h − h_r)^n = 0` for `h ∈ (h_r, h₀]` by Newton's method from `h₀`
/// (Braun and Willett 2013, eq. 26): the residual is increasing and convex for `n ≥ 1`,
/// so the iterates decrease monotonically; for `n < 1` they are kept above `h_r`.
fn newton(h0: f64, hr: f64, f: f64, n: f64) -> f64 {
    let mut h = h0;
    for _ in 0..50 {
        let d = h - hr;
        let g = h - h0 + f * d.powf(n);
        let dg = 1.0 + f * n * d.powf(n - 1.0);
        let next = (h - g / dg).max(hr + 1e-9 * d);
        if (next - h).abs() <= 1e-9 * (1.0 + h.abs()) {
            return next;
        }
        h = next;
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn newton_solves_the_implicit_equation() {
        for n in [0.7, 1.0, 1.5, 2.0] {
            let (h0, hr, f) = (120.0, 100.0, 0.05);
            let h = newton(h0, hr, f, n);
            let g = h - h0 + f * (h - hr).powf(n);
            assert!(g.abs() < 1e-6, "n = {n}: residual {g}");
            assert!(h > hr && h < h0);
        }
    }
}

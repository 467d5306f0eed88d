//! Fluvial erosion by the stream-power law `∂h/∂t = U − K A^m S^n`, solved implicitly in
//! O(n) along the flow graph's stack (Braun and Willett 2013, §2.3 and eq. 24–26): each
//! sample's new elevation depends only on its receiver's, already updated, so one pass
//! downstream to upstream solves the whole grid, stably for any time step.

use crate::analysis::flow::{FlowGraph, NEIGHBOURS, fill_in_place};

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

/// The first half of a step of uplift and stream-power erosion on the samples `z` of an
/// `nx × ny` grid of `dx × dy` cells: interior samples rise by `rise` (base level, the
/// edge and the rim of nodata, stays put), then `graph` gets the receivers and the stack.
/// Depressions are filled first when the receivers find pits (Priority-Flood + ε, Barnes
/// et al. 2014: a closed basin fills with sediment up to its spill point).
pub fn route(
    z: &mut [f32],
    nx: usize,
    ny: usize,
    dx: f32,
    dy: f32,
    rise: f32,
    graph: &mut FlowGraph,
) {
    let has_nodata = FlowGraph::has_nodata(z);
    if rise != 0.0 {
        for j in 1..ny.saturating_sub(1) {
            for k in j * nx + 1..(j + 1) * nx - 1 {
                if !FlowGraph::base_level(z, nx, ny, k, has_nodata) && !z[k].is_nan() {
                    z[k] += rise;
                }
            }
        }
    }
    if graph.update(z, nx, ny, dx, dy) > 0 {
        // Most pits are single samples that rounding or diffusion left on a filled flat:
        // raising each to just above its lowest neighbour is what the flood would do to
        // them, at a fraction of its cost. Where that does not drain them all, the flood
        // fills what remains (and the receivers are found once more, not twice).
        if !raise_pits(z, nx, ny, graph, has_nodata) {
            fill_in_place(z, nx, ny);
        }
        graph.update(z, nx, ny, dx, dy);
    }
}

/// The second half of a step ([`route`] first): every sample eroded towards its receiver
/// in `graph`'s stack order, with drainage areas `area` (m²). With `F = K dt A^m / L^n`,
/// the new elevation solves `h − h₀ + F (h − h_r)^n = 0` — in closed form for `n = 1`, by
/// Newton's method otherwise (Braun and Willett 2013 §2.3). A sample not above its
/// receiver is left alone.
pub fn incise(z: &mut [f32], graph: &FlowGraph, area: &[f32], law: StreamPower, dt: f32) {
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

/// Raises pits to the next float above their lowest neighbour, starting from the pits of
/// `graph` (valid, non-base samples that are their own receivers) and following the
/// neighbours a raise turns into pits, for at most [`LOCAL_RAISES`] raises per initial
/// pit (a deep basin would take one per float step: the flood's work). In a fixed order.
/// Returns whether no pit is left.
fn raise_pits(z: &mut [f32], nx: usize, ny: usize, graph: &FlowGraph, has_nodata: bool) -> bool {
    let rec = graph.receivers();
    let mut todo: Vec<usize> = (0..z.len())
        .filter(|&k| rec[k] as usize == k && is_pit(z, nx, ny, k, has_nodata))
        .collect();
    todo.reverse();
    let mut budget = todo.len() * LOCAL_RAISES;
    while let Some(k) = todo.pop() {
        if !is_pit(z, nx, ny, k, has_nodata) {
            continue;
        }
        if budget == 0 {
            return false;
        }
        budget -= 1;
        let lowest = neighbours(nx, k)
            .map(|n| z[n])
            .fold(f32::INFINITY, f32::min);
        z[k] = lowest.next_up();
        todo.extend(neighbours(nx, k).filter(|&n| is_pit(z, nx, ny, n, has_nodata)));
    }
    true
}

/// Raises per initial pit that [`raise_pits`] may make.
const LOCAL_RAISES: usize = 16;

/// The 8 neighbours of an interior sample `k`.
fn neighbours(nx: usize, k: usize) -> impl Iterator<Item = usize> {
    let (i, j) = ((k % nx) as isize, (k / nx) as isize);
    NEIGHBOURS
        .iter()
        .map(move |&(di, dj)| (i + di) as usize + nx * (j + dj) as usize)
}

/// A valid sample, not base level, with no lower neighbour.
fn is_pit(z: &[f32], nx: usize, ny: usize, k: usize, has_nodata: bool) -> bool {
    !z[k].is_nan()
        && !FlowGraph::base_level(z, nx, ny, k, has_nodata)
        && neighbours(nx, k).all(|n| z[n] >= z[k])
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

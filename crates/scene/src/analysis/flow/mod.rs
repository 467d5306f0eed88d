//! Drainage on a heightfield grid: depression filling by Priority-Flood (Barnes, Lehman
//! and Mulla 2014, "Priority-Flood: An optimal depression-filling and watershed-labeling
//! algorithm", Algorithm 3, "Priority-Flood + ε") and drainage area by multiple flow
//! directions (Freeman 1991, "Calculating catchment area with divergent flow based on a
//! regular grid").
//!
//! Grids are [`Heightfield`]s: 8-connected samples, NaN for nodata. Water leaves the
//! domain at the grid's edges and at nodata: those cells are the seeds of the flood.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, VecDeque};

use crate::dem::Heightfield;

mod graph;

pub use graph::FlowGraph;

/// Freeman's (1991) exponent on the slope in the flow partition.
pub const FREEMAN_EXPONENT: f32 = 1.1;

/// The eight neighbours `(di, dj)`, in a fixed order (determinism).
pub const NEIGHBOURS: [(isize, isize); 8] = [
    (1, 0),
    (1, 1),
    (0, 1),
    (-1, 1),
    (-1, 0),
    (-1, -1),
    (0, -1),
    (1, -1),
];

/// A cell in the flood's queue: lowest elevation first, then lowest index (so equal
/// elevations pop in a fixed order). The elevation is kept as an integer with the order of
/// the floats (finite values only: nodata never enters the queue) in the high half of one
/// word, the index in the low half (grids hold fewer than 2³² samples), so comparing is
/// one integer comparison.
type Low = Reverse<u64>;

/// `z`'s bits as a `u32` that sorts as `z` does.
fn ordered(z: f32) -> u32 {
    let b = z.to_bits();
    if b >> 31 == 1 { !b } else { b | 1 << 31 }
}

fn low(z: f32, k: usize) -> Low {
    Reverse(u64::from(ordered(z)) << 32 | k as u64)
}

/// The valid neighbours of sample `k` of an `nx × ny` grid, as indices.
fn neighbours(k: usize, nx: usize, ny: usize) -> impl Iterator<Item = (usize, usize)> {
    let (i, j) = ((k % nx) as isize, (k / nx) as isize);
    NEIGHBOURS
        .iter()
        .enumerate()
        .filter_map(move |(d, &(di, dj))| {
            let (a, b) = (i + di, j + dj);
            (a >= 0 && b >= 0 && (a as usize) < nx && (b as usize) < ny)
                .then(|| (d, a as usize + nx * b as usize))
        })
}

/// The grid with every depression filled so that each valid sample has a strictly
/// descending 8-connected path to the edge or to nodata (Priority-Flood + ε: a sample
/// surrounded by higher ground is raised to the next float above its spill point, so
/// filled flats still drain). Nodata stays nodata.
pub fn fill_depressions(hf: &Heightfield) -> Heightfield {
    let mut z = hf.samples().to_vec();
    fill_in_place(&mut z, hf.nx(), hf.ny());
    Heightfield::new(hf.nx(), hf.ny(), hf.origin(), hf.cell(), z)
        .expect("same sizes as a valid heightfield, finite values")
}

/// [`fill_depressions`] on the samples `z` of an `nx × ny` grid, in place (the erosion
/// loop's form: no copy of the grid).
pub fn fill_in_place(z: &mut [f32], nx: usize, ny: usize) {
    let mut done = vec![false; z.len()];
    let mut open = BinaryHeap::new();
    // Samples raised inside a depression: each is just above the sample that reached it,
    // so they go first and in order of arrival, without the heap (Barnes et al. 2014,
    // Algorithm 3's "pit" queue).
    let mut pit = VecDeque::new();
    // Seeds: valid samples on the edge or next to nodata.
    for k in 0..z.len() {
        if z[k].is_nan() {
            done[k] = true;
            continue;
        }
        let (i, j) = (k % nx, k / nx);
        let rim = i == 0 || j == 0 || i + 1 == nx || j + 1 == ny;
        if rim || neighbours(k, nx, ny).any(|(_, n)| z[n].is_nan()) {
            done[k] = true;
            open.push(low(z[k], k));
        }
    }
    loop {
        let k = match pit.pop_front() {
            Some(k) => k,
            None => match open.pop() {
                Some(Reverse(key)) => (key & 0xffff_ffff) as usize,
                None => break,
            },
        };
        let zc = z[k];
        let mut visit = |n: usize| {
            if done[n] {
                return;
            }
            done[n] = true;
            // Raise a pit to just above its spill point.
            if z[n] <= zc {
                z[n] = zc.next_up();
                pit.push_back(n);
            } else {
                open.push(low(z[n], n));
            }
        };
        let (i, j) = (k % nx, k / nx);
        if i > 0 && j > 0 && i + 1 < nx && j + 1 < ny {
            // inside: the neighbours by offset, in the fixed order
            for (di, dj) in NEIGHBOURS {
                visit((k as isize + di + nx as isize * dj) as usize);
            }
        } else {
            for (_, n) in neighbours(k, nx, ny) {
                visit(n);
            }
        }
    }
}

/// Drainage area (m²) of every sample of `filled` (a grid without depressions, from
/// [`fill_depressions`]): its own cell plus everything that flows into it, each sample
/// passing its area to its lower neighbours in proportion to `tan β^p` with Freeman's
/// `p` ([`FREEMAN_EXPONENT`]; β the slope towards the neighbour, diagonals at `√2`
/// cells). Water that reaches a sample with no lower neighbour (the edge, next to
/// nodata) leaves there. Nodata has area 0.
pub fn drainage_area(filled: &Heightfield) -> Vec<f32> {
    let mut area = Vec::new();
    mfd_area(
        filled.samples(),
        filled.nx(),
        filled.ny(),
        filled.cell(),
        FREEMAN_EXPONENT,
        &mut area,
    );
    area
}

/// [`drainage_area`] of the samples `z` of an `nx × ny` grid of `cell`s, into `area`, with
/// `exponent` on the slopes (Freeman's 1.1; 1 is Quinn et al. 1991's partition by slope,
/// without the power's cost).
pub fn mfd_area(
    z: &[f32],
    nx: usize,
    ny: usize,
    cell: glam::Vec2,
    exponent: f32,
    area: &mut Vec<f32>,
) {
    let c = cell;
    let cell_area = c.x * c.y;
    let dist: [f32; 8] = NEIGHBOURS.map(|(di, dj)| (di as f32 * c.x).hypot(dj as f32 * c.y));
    // Highest first; ties by index, so the order is fixed: keys of the elevation's ordered
    // bits, complemented, then the index.
    let mut order: Vec<u64> = (0..z.len())
        .filter(|&k| !z[k].is_nan())
        .map(|k| u64::from(!ordered(z[k])) << 32 | k as u64)
        .collect();
    order.sort_unstable();
    let order = order.into_iter().map(|key| (key & 0xffff_ffff) as usize);
    let mut acc: Vec<f64> = z
        .iter()
        .map(|v| {
            if v.is_nan() {
                0.0
            } else {
                f64::from(cell_area)
            }
        })
        .collect();
    let mut weights = [(0usize, 0f64); 8];
    for k in order {
        let mut count = 0;
        let mut total = 0.0;
        for (d, n) in neighbours(k, nx, ny) {
            let drop = z[k] - z[n];
            if drop > 0.0 {
                let s = f64::from(drop / dist[d]);
                let w = if exponent == 1.0 {
                    s
                } else {
                    s.powf(f64::from(exponent))
                };
                weights[count] = (n, w);
                total += w;
                count += 1;
            }
        }
        if total > 0.0 {
            let a = acc[k];
            for &(n, w) in &weights[..count] {
                acc[n] += a * w / total;
            }
        }
    }
    area.clear();
    area.extend(acc.into_iter().map(|a| a as f32));
}

/// Whether sample `k` of `hf` has no lower 8-neighbour while not being on the grid's edge
/// or next to nodata: a pit, where water would pond.
pub fn is_pit(hf: &Heightfield, k: usize) -> bool {
    let (nx, ny) = (hf.nx(), hf.ny());
    let z = hf.samples();
    let (i, j) = (k % nx, k / nx);
    if z[k].is_nan() || i == 0 || j == 0 || i + 1 == nx || j + 1 == ny {
        return false;
    }
    neighbours(k, nx, ny).all(|(_, n)| !z[n].is_nan() && z[n] >= z[k])
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    fn grid(nx: usize, ny: usize, f: impl Fn(usize, usize) -> f32) -> Heightfield {
        let z = (0..nx * ny).map(|k| f(k % nx, k / nx)).collect();
        Heightfield::new(nx, ny, Vec2::ZERO, Vec2::splat(10.0), z).unwrap()
    }

    /// A bumpy surface with many closed basins (and a nodata hole).
    fn bumpy() -> Heightfield {
        grid(40, 30, |i, j| {
            if (12..15).contains(&i) && (8..10).contains(&j) {
                return f32::NAN;
            }
            let (x, y) = (i as f32, j as f32);
            100.0
                + 5.0 * (x * 0.7).sin() * (y * 0.5).cos()
                + 0.3 * x
                + ((i * 7 + j * 13) % 5) as f32
        })
    }

    #[test]
    fn filling_leaves_no_pit_and_never_lowers() {
        let hf = bumpy();
        let pits = (0..hf.samples().len()).filter(|&k| is_pit(&hf, k)).count();
        assert!(pits > 5, "the test surface should have pits, has {pits}");
        let filled = fill_depressions(&hf);
        for k in 0..hf.samples().len() {
            assert!(!is_pit(&filled, k), "sample {k} is still a pit");
            let (a, b) = (hf.samples()[k], filled.samples()[k]);
            assert!(a.is_nan() && b.is_nan() || b >= a, "sample {k}: {a} → {b}");
        }
        // Filling twice changes nothing: the filled grid has no depression left (bit
        // for bit, nodata included).
        let bits = |h: &Heightfield| h.samples().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&fill_depressions(&filled)), bits(&filled));
    }

    #[test]
    fn a_surface_without_pits_is_left_as_it_is() {
        let hf = grid(20, 10, |i, j| (i + 2 * j) as f32);
        assert_eq!(fill_depressions(&hf), hf);
    }

    #[test]
    fn drainage_on_a_tilted_plane_grows_linearly_and_sums_at_the_outlet() {
        // Sloping down to the east: every sample drains east; rows far from the north
        // and south edges carry (i + 1) cells of area at column i.
        let (nx, ny) = (30, 61);
        let hf = grid(nx, ny, |i, _| 50.0 - 2.0 * i as f32);
        let area = drainage_area(&fill_depressions(&hf));
        let cell = 100.0;
        let j = ny / 2;
        for i in 0..nx {
            let a = area[i + nx * j];
            let want = (i + 1) as f32 * cell;
            assert!((a - want).abs() < 1e-3 * want, "column {i}: {a} ≠ {want}");
        }
        // The outlet (the east column) receives the whole domain.
        let outlet: f64 = (0..ny).map(|j| f64::from(area[nx - 1 + nx * j])).sum();
        let domain = (nx * ny) as f64 * f64::from(cell);
        assert!(
            (outlet - domain).abs() < 1e-6 * domain,
            "{outlet} ≠ {domain}"
        );
    }

    #[test]
    fn drainage_conserves_area_on_a_filled_bumpy_surface() {
        let filled = fill_depressions(&bumpy());
        let area = drainage_area(&filled);
        let (nx, ny) = (filled.nx(), filled.ny());
        let z = filled.samples();
        // Water leaves only where a sample has no lower neighbour: the edge and nodata's rim.
        let mut out = 0.0f64;
        for k in 0..z.len() {
            if z[k].is_nan() {
                assert_eq!(area[k], 0.0);
                continue;
            }
            let lower = neighbours(k, nx, ny).any(|(_, n)| z[n] < z[k]);
            if !lower {
                out += f64::from(area[k]);
            }
        }
        let valid = z.iter().filter(|v| !v.is_nan()).count() as f64 * 100.0;
        assert!((out - valid).abs() < 1e-4 * valid, "{out} ≠ {valid}");
    }
}

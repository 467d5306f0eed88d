//! Error-bounded triangulated irregular networks (TINs) of heightfields by greedy
//! insertion on a Delaunay triangulation (Garland & Heckbert 1995, Algorithm III).
//!
//! The triangulation starts as the grid's rectangle cut in two triangles. Each triangle
//! keeps its worst grid point — the one farthest, vertically, from the triangle's plane
//! ([`raster`]) — and a priority queue holds the triangles by that error. The largest is
//! inserted as a vertex into the very triangle it lies in ([`delaunay`]: no point
//! location, edge flips keep the triangulation Delaunay), and only the triangles the
//! insertion changed are scanned again: every triangle an incremental Delaunay insertion
//! creates or flips has the new vertex as a corner, so they are the new vertex's star.
//! The queue is indexed by triangle: a triangle scanned again has its entry moved (or
//! removed, when now within the bound) in place, so every pop is a live triangle. The loop
//! stops when the largest error left is at most the bound, so the TIN is within the bound
//! at every grid point.
//!
//! A grid with nodata (a DEM's rotated edges, voids) is triangulated over its valid area:
//! the voids are filled far below the lowest valid sample ([`VOID_DROP`]), so any triangle
//! reaching from valid ground into a void is far off at the valid points it covers and is
//! refined until the triangles over valid points have valid corners only; the triangles
//! with a corner in a void are then dropped. The TIN is within the bound at every valid
//! grid point, and covers every valid point that has a valid neighbour across a cell.

mod delaunay;
mod queue;
mod raster;

use glam::{Vec2, Vec3};

use super::Mesh;
use crate::dem::Heightfield;
use delaunay::{Tri, Triangulation, Vertex};
use queue::Queue;
use raster::Scanner;

/// Errors of [`greedy`].
#[derive(Debug, thiserror::Error)]
pub enum TinError {
    /// The bound is negative or not a number.
    #[error("the maximum error must be a finite number ≥ 0 metres, got {0}")]
    Bound(f64),
    /// Every sample is nodata.
    #[error("the heightfield has no valid sample: nothing to triangulate")]
    NoData,
    /// The triangulation would exceed the memory budget.
    #[error(transparent)]
    Budget(#[from] crate::io::IoError),
    /// The grid has more points than the triangulation can number.
    #[error("a {0}×{1} grid has more points than a TIN can index (2²⁹)")]
    TooLarge(usize, usize),
}

/// Bytes the triangulation may take per grid point when every point becomes a vertex:
/// the vertex (12), two triangles' records (64) and errors (16), queue entries (8 each, a
/// few per triangle), and room for the vectors' growth.
const BYTES_PER_VERTEX: u64 = 256;

/// How far below the lowest valid sample nodata samples are set while triangulating: far
/// enough that a triangle with a corner in a void is off by more than any bound at the
/// valid points strictly inside it, near enough for f32 heights to stay exact to a
/// centimetre.
pub const VOID_DROP: f32 = 1.0e5;

/// A triangulated irregular network over a heightfield's grid points.
#[derive(Clone, Debug, PartialEq)]
pub struct Tin {
    /// Vertices in the heightfield's frame (metres, Z up): grid points with their heights.
    pub positions: Vec<[f32; 3]>,
    /// Triangles as vertex indices, counter-clockwise seen from above.
    pub triangles: Vec<[u32; 3]>,
    /// The largest vertical distance between the TIN and a grid point, metres.
    pub max_error: f64,
}

impl Tin {
    /// The TIN without its triangles that have a corner in a void (a vertex set
    /// [`VOID_DROP`] below the valid ground), vertices renumbered.
    fn without_voids(self) -> Tin {
        let lo = self
            .positions
            .iter()
            .map(|p| p[2])
            .fold(f32::INFINITY, f32::min);
        // Valid heights lie above the fill by about VOID_DROP; voids at the fill.
        let void = |v: u32| self.positions[v as usize][2] < lo + 0.5 * VOID_DROP;
        let mut index = vec![u32::MAX; self.positions.len()];
        let mut positions = Vec::new();
        let triangles = self
            .triangles
            .iter()
            .filter(|t| !t.iter().any(|&v| void(v)))
            .map(|t| {
                t.map(|v| {
                    if index[v as usize] == u32::MAX {
                        index[v as usize] = positions.len() as u32;
                        positions.push(self.positions[v as usize]);
                    }
                    index[v as usize]
                })
            })
            .collect();
        Tin {
            positions,
            triangles,
            max_error: self.max_error,
        }
    }

    /// The TIN as a mesh with area-weighted vertex normals (pointing up).
    pub fn to_mesh(&self) -> Mesh {
        let pos = |v: u32| Vec3::from(self.positions[v as usize]);
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        for &[a, b, c] in &self.triangles {
            let n = (pos(b) - pos(a)).cross(pos(c) - pos(a));
            for v in [a, b, c] {
                acc[v as usize] += n;
            }
        }
        Mesh {
            positions: self.positions.clone(),
            normals: acc
                .iter()
                .map(|n| n.try_normalize().unwrap_or(Vec3::Z).to_array())
                .collect(),
            triangles: self.triangles.clone(),
            attributes: Vec::new(),
        }
    }
}

/// The TIN of `hf` within `max_error` metres (vertically) of every grid point, by greedy
/// insertion; refuses grids whose worst case (every point a vertex) would take more than
/// `budget` bytes.
pub fn greedy(hf: &Heightfield, max_error: f64, budget: u64) -> Result<Tin, TinError> {
    if !(max_error >= 0.0 && max_error.is_finite()) {
        return Err(TinError::Bound(max_error));
    }
    let (lo, _) = hf.z_range().ok_or(TinError::NoData)?;
    let filled: Option<Vec<f32>> = (hf.nodata_count() > 0).then(|| {
        hf.samples()
            .iter()
            .map(|&z| if z.is_nan() { lo - VOID_DROP } else { z })
            .collect()
    });
    let h = filled.as_deref().unwrap_or(hf.samples());
    let (nx, ny) = (hf.nx(), hf.ny());
    let points = nx as u64 * ny as u64;
    crate::io::check_budget(
        format!("the triangulation of {nx}×{ny} grid points"),
        points.saturating_mul(BYTES_PER_VERTEX),
        budget,
    )?;
    // Half-edges and queue entries are numbered with u32: six per point at most.
    if points > 1 << 29 {
        return Err(TinError::TooLarge(nx, ny));
    }
    let mut g = Greedy {
        dt: Triangulation::rectangle(
            nx as i32 - 1,
            ny as i32 - 1,
            [(0, 0), (nx - 1, 0), (nx - 1, ny - 1), (0, ny - 1)].map(|(i, j)| h[i + nx * j]),
        ),
        h,
        nx,
        max_error,
        worst: Vec::new(),
        queue: Queue::default(),
        scanner: Scanner::default(),
    };
    g.run();
    let tin = g.into_tin(hf);
    Ok(match filled {
        Some(_) => tin.without_voids(),
        None => tin,
    })
}

/// A queue entry: the triangle's error (as f32 bits, which order like the numbers for
/// errors ≥ 0) above its index, which breaks ties.
fn key(error: f64, t: usize) -> u64 {
    (u64::from((error as f32).to_bits()) << 32) | t as u64
}

/// The state of a greedy insertion.
struct Greedy<'h> {
    dt: Triangulation,
    /// The samples, row-major.
    h: &'h [f32],
    nx: usize,
    max_error: f64,
    /// Each triangle's largest error, by triangle index (its worst grid point and that
    /// point's height are in the triangle's record, `Tri::a` and `Tri::b`).
    worst: Vec<f64>,
    /// The triangles worse than the bound, by error: [`key`]s, one per triangle.
    queue: Queue,
    /// The scans' rows.
    scanner: Scanner,
}

impl Greedy<'_> {
    /// Scans the rectangle's two triangles, then inserts worst points until every
    /// triangle is within the bound.
    fn run(&mut self) {
        let mut changed = vec![0, 1];
        loop {
            for t in changed.drain(..) {
                self.scan(t as usize);
            }
            let Some(t) = self.queue.pop() else { break };
            // The next pop is most often the next largest now: its record is asked for
            // while this insertion and its scans run.
            if let Some(next) = self.queue.peek() {
                crate::cache::prefetch(&self.dt.tris[next]);
            }
            let Tri { a: at, b: z, .. } = self.dt.tris[t];
            // Grids have fewer than 2³² points.
            let nx = self.nx as u32;
            let p = Vertex {
                i: (at % nx) as i32,
                j: (at / nx) as i32,
                z: f32::from_bits(z),
            };
            // The new triangles cover this one (and parts of its neighbours): its rows are
            // asked for while the insertion runs.
            raster::prefetch_rows(self.dt.corners(t).map(Vertex::ij), self.h, self.nx);
            self.dt.insert(t as u32, p, &mut changed);
        }
    }

    /// Finds the worst grid point of triangle `t` and queues it if over the bound.
    fn scan(&mut self, t: usize) {
        let corners = self.dt.corners(t);
        let w = self.scanner.worst_point(
            corners.map(Vertex::ij),
            corners.map(|v| f64::from(v.z)),
            self.h,
            self.nx,
        );
        if self.worst.len() <= t {
            self.worst.resize(t + 1, 0.0);
        }
        self.worst[t] = w.error;
        self.dt.tris[t].a = w.at;
        self.dt.tris[t].b = self.h[w.at as usize].to_bits();
        if w.error > self.max_error {
            self.queue.set(key(w.error, t));
        } else {
            self.queue.remove(t);
        }
    }

    /// The finished TIN in `hf`'s frame.
    fn into_tin(self, hf: &Heightfield) -> Tin {
        let (origin, cell) = (hf.origin(), hf.cell());
        let positions = self
            .dt
            .vertices
            .iter()
            .map(|v| {
                let xy = origin + Vec2::new(v.i as f32, v.j as f32) * cell;
                [xy.x, xy.y, v.z]
            })
            .collect();
        let triangles = (0..self.dt.len()).map(|t| self.dt.triangle(t)).collect();
        let max_error = self.worst.iter().copied().fold(0.0, f64::max);
        Tin {
            positions,
            triangles,
            max_error,
        }
    }
}

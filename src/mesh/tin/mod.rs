//! Error-bounded triangulated irregular networks (TINs) of heightfields by greedy
//! insertion on a Delaunay triangulation (Garland & Heckbert 1995, Algorithm III).
//!
//! The triangulation starts as the grid's four corners. Each triangle keeps its worst
//! grid point — the one farthest, vertically, from the triangle's plane ([`raster`]) —
//! and a priority queue holds the triangles by that error. The largest is inserted as a
//! vertex ([`spade`] keeps the triangulation Delaunay), and only the triangles the
//! insertion changed are scanned again: every triangle an incremental Delaunay insertion
//! creates or flips has the new vertex as a corner, so they are the new vertex's star.
//! Queue entries of triangles changed since are recognised as stale when popped (their
//! error is no longer the triangle's) and dropped. The loop stops when the largest error
//! left is at most the bound, so the TIN is within the bound at every grid point.

mod raster;

use std::collections::BinaryHeap;

use glam::{Vec2, Vec3};
use spade::handles::{FixedFaceHandle, FixedVertexHandle, InnerTag};
use spade::{DelaunayTriangulation, Point2, Triangulation};

use super::Mesh;
use crate::dem::Heightfield;
use raster::{Worst, worst_point};

/// Errors of [`greedy`].
#[derive(Debug, thiserror::Error)]
pub enum TinError {
    /// The bound is negative or not a number.
    #[error("the maximum error must be a finite number ≥ 0 metres, got {0}")]
    Bound(f64),
    /// The heightfield has nodata samples.
    #[error(
        "the heightfield has {0} nodata samples: a TIN needs every grid point (fill the voids first)"
    )]
    NoData(usize),
    /// The triangulation would exceed the memory budget.
    #[error(transparent)]
    Budget(#[from] crate::io::IoError),
    /// The grid has more points than the triangulation can number.
    #[error("a {0}×{1} grid has more points than a TIN can index (2³¹)")]
    TooLarge(usize, usize),
    /// The triangulation refused a point (cannot happen with grid points).
    #[error("triangulation: {0}")]
    Triangulation(String),
}

/// Bytes the triangulation may take per grid point when every point becomes a vertex
/// (spade's vertex, three undirected edges and two faces, plus our per-face candidate).
const BYTES_PER_VERTEX: u64 = 200;

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

/// The triangulation, in grid coordinates (vertices at integer `(i, j)`).
type Delaunay = DelaunayTriangulation<Point2<f64>>;

/// A face of the triangulation (never the outer one).
type InnerFace = FixedFaceHandle<InnerTag>;

/// The TIN of `hf` within `max_error` metres (vertically) of every grid point, by greedy
/// insertion; refuses grids whose worst case (every point a vertex) would take more than
/// `budget` bytes.
pub fn greedy(hf: &Heightfield, max_error: f64, budget: u64) -> Result<Tin, TinError> {
    if !(max_error >= 0.0 && max_error.is_finite()) {
        return Err(TinError::Bound(max_error));
    }
    let nodata = hf.nodata_count();
    if nodata > 0 {
        return Err(TinError::NoData(nodata));
    }
    let (nx, ny) = (hf.nx(), hf.ny());
    let points = nx as u64 * ny as u64;
    crate::io::check_budget(
        format!("the triangulation of {nx}×{ny} grid points"),
        points.saturating_mul(BYTES_PER_VERTEX),
        budget,
    )?;
    // spade and the queue number faces with u32: at most twice the points.
    if points > 1 << 31 {
        return Err(TinError::TooLarge(nx, ny));
    }
    let mut g = Greedy {
        dt: Delaunay::new(),
        h: hf.samples(),
        nx,
        max_error,
        worst: Vec::new(),
        faces: Vec::new(),
        queue: BinaryHeap::new(),
    };
    g.run(ny)?;
    Ok(g.into_tin(hf))
}

/// The grid indices of a vertex position (integers, exactly).
fn grid(p: Point2<f64>) -> [i64; 2] {
    [p.x as i64, p.y as i64]
}

/// A queue entry: the face's error (as f32 bits, which order like the numbers for
/// errors ≥ 0) above its index. An entry whose key differs from its face's current one is
/// stale; an f32 tie between an old and a new error only reorders equal errors.
fn key(error: f64, face: usize) -> u64 {
    (u64::from((error as f32).to_bits()) << 32) | face as u64
}

/// The state of a greedy insertion.
struct Greedy<'h> {
    dt: Delaunay,
    /// The samples, row-major.
    h: &'h [f32],
    nx: usize,
    max_error: f64,
    /// Each face's worst grid point, by face index.
    worst: Vec<Worst>,
    /// Each face's handle and one of its corners (where insertions into it start
    /// walking), by face index.
    faces: Vec<(InnerFace, FixedVertexHandle)>,
    /// The faces worse than the bound, by error: [`key`]s.
    queue: BinaryHeap<u64>,
}

impl Greedy<'_> {
    /// Triangulates the corners of the `nx × ny` grid, then inserts worst points until
    /// every face is within the bound.
    fn run(&mut self, ny: usize) -> Result<(), TinError> {
        let nx = self.nx;
        let mut last = None;
        for (i, j) in [(0, 0), (nx - 1, 0), (nx - 1, ny - 1), (0, ny - 1)] {
            last = Some(self.insert(i + nx * j, last)?);
        }
        let first: Vec<_> = self
            .dt
            .inner_faces()
            .map(|f| (f.fix(), f.positions().map(grid), f.vertices()[0].fix()))
            .collect();
        first.into_iter().for_each(|(f, c, v)| self.scan(f, c, v));
        let mut star = Vec::new();
        while let Some(top) = self.queue.pop() {
            let (face, hint) = self.faces[top as u32 as usize];
            let w = self.worst[face.index()];
            if key(w.error, face.index()) != top || w.error <= self.max_error {
                continue; // the face changed since it was queued
            }
            let v = self.insert(w.at, Some(hint))?;
            star.clear();
            // The star's faces with their corners, read off the edges out of `v`.
            star.extend(self.dt.vertex(v).out_edges().filter_map(|e| {
                let f = e.face().as_inner()?.fix();
                let corners = [e.from(), e.to(), e.next().to()].map(|u| grid(u.position()));
                Some((f, corners))
            }));
            for (f, c) in star.drain(..) {
                self.scan(f, c, v);
            }
        }
        Ok(())
    }

    /// Finds the worst grid point of `face` (grid corners `corners`, one of them the
    /// vertex `corner`) and queues the face if it is over the bound.
    fn scan(&mut self, face: InnerFace, corners: [[i64; 2]; 3], corner: FixedVertexHandle) {
        let z = corners.map(|[i, j]| f64::from(self.h[i as usize + self.nx * j as usize]));
        let w = worst_point(corners, z, self.h, self.nx);
        let k = face.index();
        if self.worst.len() <= k {
            self.worst.resize(k + 1, Worst::default());
            self.faces.resize(k + 1, (face, corner));
        }
        self.worst[k] = w;
        self.faces[k] = (face, corner);
        if w.error > self.max_error {
            self.queue.push(key(w.error, k));
        }
    }

    /// Inserts grid point `at` (index `i + nx·j`), walking from `hint` when given.
    fn insert(
        &mut self,
        at: usize,
        hint: Option<FixedVertexHandle>,
    ) -> Result<FixedVertexHandle, TinError> {
        let p = Point2::new((at % self.nx) as f64, (at / self.nx) as f64);
        match hint {
            Some(h) => self.dt.insert_with_hint(p, h),
            None => self.dt.insert(p),
        }
        .map_err(|e| TinError::Triangulation(e.to_string()))
    }

    /// The finished TIN in `hf`'s frame.
    fn into_tin(self, hf: &Heightfield) -> Tin {
        let (origin, cell, h, nx) = (hf.origin(), hf.cell(), self.h, self.nx);
        let positions = self
            .dt
            .vertices()
            .map(|v| {
                let p = v.position();
                let (i, j) = (p.x as usize, p.y as usize);
                let xy = origin + Vec2::new(i as f32, j as f32) * cell;
                [xy.x, xy.y, h[i + nx * j]]
            })
            .collect();
        let triangles = self
            .dt
            .inner_faces()
            .map(|f| f.vertices().map(|v| v.fix().index() as u32))
            .collect();
        let max_error = self
            .dt
            .fixed_inner_faces()
            .map(|f| self.worst[f.index()].error)
            .fold(0.0, f64::max);
        Tin {
            positions,
            triangles,
            max_error,
        }
    }
}

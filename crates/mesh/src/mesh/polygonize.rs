//! Bound-pruned Marching Cubes over a [`Field`] (Paris et al. 2019 §7): bands, samples, vertices,
//! triangles, each stage parallel over tiles of grid columns.
//!
//! 1. **Bands** ([`columns::tile_bands`]): per cell column, the cell layers that can hold
//!    the surface; per grid column, the elevation usable for direct extraction.
//! 2. **Samples**: the union of the adjacent cells' layers per grid column, laid out tile
//!    by tile; the memory budget is checked here exactly, after a first check before
//!    anything is allocated ([`super::estimate`]).
//! 3. **Values**: field samples on the tile's pruned field, a grid column at a time
//!    through [`Field::eval_column`] where the field shares work along vertical lines (a
//!    heightfield), else via [`Field::eval_block`];
//!    in elevation columns one `h(x, y)` per column gives pseudo-values
//!    `T + (h − z) / dz`, whose sign is the field's and whose linear interpolation puts
//!    vertical-edge vertices at `z = h` and horizontal-edge vertices on the linear root
//!    between the two column heights — no root search.
//! 4. **Vertices**: one per crossed edge, owned by the tile of the edge's lower sample;
//!    normals from [`Field::value_grad`] (or from the elevation's slope); optional
//!    refinement on the true field by regula falsi.
//! 5. **Triangles**: cells in the bands, cases from the shared tables with the
//!    asymptotic decider on ambiguous faces.
//!
//! Every sample is evaluated exactly once and every decision is a function of the stored
//! samples, so tiles agree on shared edges and faces: the mesh is welded and crack-free,
//! and its bytes do not depend on the number of threads.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use glam::{Vec2, Vec3};
use indicatif::ProgressBar;
use rayon::prelude::*;

use super::cell::{ambiguity_mask, edge_t};
use super::columns::{self, Cursor, Elevations, SampleSpan, Spans, TILE, TileGrid, Tiles};
use super::estimate::{COLUMN_BYTES, SAMPLE_BYTES, check_before_bands};
use super::grid::GridSpec;
use super::indexed::Mesh;
use super::stats::MeshStats;
use super::tables::{EDGE_AXIS, EDGE_CORNERS, TABLES};
use super::{MeshError, par_concat, split_parts};
use crate::field::{Aabb, Elevation, Field, ISO, Interval};
use crate::io::{DEFAULT_MEMORY_BUDGET, check_budget};

/// Most field evaluations per vertex with [`MeshOptions::refine`].
const REFINE_ITERATIONS: usize = 24;

/// Refinement stops once the root is bracketed this tightly (fraction of the edge).
const REFINE_TOLERANCE: f32 = 1e-4;

/// Spans shorter than this are evaluated point by point: a block evaluation prunes the
/// field for its block first, which only pays off over many samples (a heightfield's
/// floor costs two samples per column).
const SHORT_SPAN: usize = crate::field::BRICK;

/// How [`polygonize`] works.
#[derive(Clone, Debug)]
pub struct MeshOptions {
    /// Prune with bricks and z-bands (otherwise every cell is visited: plain MC).
    pub prune: bool,
    /// Use [`Field::elevation`] for direct extraction where the field is a heightfield.
    pub elevation: bool,
    /// Move each vertex onto the true surface along its edge (regula falsi).
    pub refine: bool,
    /// Refuse extractions whose sample storage would exceed this many bytes.
    pub budget: u64,
    /// Advanced once per tile and stage when set.
    pub progress: Option<ProgressBar>,
    /// Keep only the triangles of the cell columns `keep[0][0]..keep[0][1]` ×
    /// `keep[1][0]..keep[1][1]` (grid indices): a tile meshed with a halo keeps its core.
    /// `None` keeps all.
    pub keep: Option<[[usize; 2]; 2]>,
}

impl Default for MeshOptions {
    fn default() -> Self {
        MeshOptions {
            prune: true,
            elevation: true,
            refine: false,
            budget: DEFAULT_MEMORY_BUDGET,
            progress: None,
            keep: None,
        }
    }
}

/// Number of stages that advance [`MeshOptions::progress`] once per tile.
const PROGRESS_STAGES: u64 = 4;

/// The length to give [`MeshOptions::progress`] for an extraction on `grid`.
pub fn progress_steps(grid: &GridSpec) -> u64 {
    let tiles = |cells: usize| (cells + 1).div_ceil(TILE) as u64;
    tiles(grid.cells[0]) * tiles(grid.cells[1]) * PROGRESS_STAGES
}

/// Extracts the surface `f = T` of `field` on `grid` (solid where `f > T`): a welded,
/// crack-free, 2-manifold mesh wound counter-clockwise from outside, with outward
/// normals, plus the statistics of Table 1 of Paris et al. 2019. Deterministic for any number of
/// threads. Errors when the sample storage would exceed `opts.budget`.
pub fn polygonize(
    field: &dyn Field,
    grid: &GridSpec,
    opts: &MeshOptions,
) -> Result<(Mesh, MeshStats), MeshError> {
    let layout = TileGrid::new(grid);
    check_before_bands(
        field,
        grid,
        &layout,
        opts.prune,
        opts.elevation,
        opts.budget,
    )?;
    let columns = layout.columns_total();
    let tiles = Tiles::new(layout);
    let tick = || {
        if let Some(p) = &opts.progress {
            p.inc(1);
        }
    };
    let mut stages = Vec::new();

    // 1. Bands.
    let clock = Instant::now();
    let bands: Vec<columns::TileBands<'_>> = (0..tiles.len())
        .into_par_iter()
        .map(|t| {
            let b = if opts.prune {
                columns::tile_bands(field, grid, &layout, t, opts.elevation)
            } else {
                full_bands(grid, &tiles, t)
            };
            tick();
            b
        })
        .collect();
    let mut elevation_parts = Vec::with_capacity(tiles.len());
    let mut cell_parts = Vec::with_capacity(tiles.len());
    for b in bands {
        elevation_parts.push(b.elevation);
        cell_parts.push(b.cells);
    }
    let elevation = Elevations::concat(elevation_parts);
    let cells = Spans::concat(cell_parts);
    let cells_visited: u64 = cells.items().iter().map(|r| (r[1] - r[0]) as u64).sum();
    stages.push(("bands", clock.elapsed()));

    // 2. Sample layout.
    let clock = Instant::now();
    let mut sample_parts: Vec<(Vec<u32>, Vec<SampleSpan>)> = (0..tiles.len())
        .into_par_iter()
        .map(|t| columns::tile_samples(grid, &tiles, &cells, &elevation, t))
        .collect();
    let mut tile_samples = vec![0usize; tiles.len() + 1];
    for (t, (_, spans)) in sample_parts.iter().enumerate() {
        let n = spans
            .last()
            .map_or(0, |s| s.offset + (s.k1 - s.k0) as usize);
        tile_samples[t + 1] = tile_samples[t] + n;
    }
    sample_parts
        .par_iter_mut()
        .zip(&tile_samples[..tiles.len()])
        .for_each(|((_, spans), &base)| {
            for s in spans.iter_mut() {
                s.offset += base;
            }
        });
    let total = tile_samples[tiles.len()];
    check_budget(
        format!(
            "{total} samples of a {}×{}×{} grid",
            grid.cells[0], grid.cells[1], grid.cells[2]
        ),
        total as u64 * SAMPLE_BYTES + columns * COLUMN_BYTES,
        opts.budget,
    )?;
    let samples = Spans::concat(sample_parts);
    stages.push(("layout", clock.elapsed()));

    let ctx = Ctx {
        field,
        grid,
        tiles: &tiles,
        cells: &cells,
        samples: &samples,
        elevation: &elevation,
        refine: opts.refine,
        keep: opts.keep,
    };
    let sizes: Vec<usize> = (0..tiles.len())
        .map(|t| tile_samples[t + 1] - tile_samples[t])
        .collect();

    // 3. Values.
    let clock = Instant::now();
    let mut values = vec![0f32; total];
    let counts: Vec<(u64, u64, u64)> = split_parts(&mut values, &sizes)
        .into_par_iter()
        .enumerate()
        .map(|(t, part)| {
            let c = ctx.tile_values(t, tile_samples[t], part);
            tick();
            c
        })
        .collect();
    let field_evaluations = counts.iter().map(|c| c.0).sum();
    let height_evaluations: u64 = counts.iter().map(|c| c.1).sum();
    let elevation_columns = counts.iter().map(|c| c.2).sum();
    stages.push(("values", clock.elapsed()));

    // 4. Vertices.
    let clock = Instant::now();
    let mut slots = vec![[0u32; 3]; total];
    let verts: Vec<TileVertices> = split_parts(&mut slots, &sizes)
        .into_par_iter()
        .enumerate()
        .map(|(t, part)| {
            let v = ctx.tile_vertices(t, tile_samples[t], &values, part);
            tick();
            v
        })
        .collect();
    let mut vertex_base = vec![0u32; tiles.len() + 1];
    for (t, v) in verts.iter().enumerate() {
        vertex_base[t + 1] = vertex_base[t] + v.positions.len() as u32;
    }
    stages.push(("vertices", clock.elapsed()));

    // 5. Triangles.
    let clock = Instant::now();
    let tris: Vec<Vec<[u32; 3]>> = (0..tiles.len())
        .into_par_iter()
        .map(|t| {
            let v = ctx.tile_triangles(t, &values, &slots, &vertex_base);
            tick();
            v
        })
        .collect();
    let mut mesh = Mesh {
        positions: par_concat(verts.iter().map(|v| &v.positions[..])),
        normals: par_concat(verts.iter().map(|v| &v.normals[..])),
        triangles: par_concat(tris.iter().map(|t| &t[..])),
        attributes: Vec::new(),
    };
    let vertex_evaluations = verts.iter().map(|v| v.evaluations).sum();
    let gradient_evaluations = verts.iter().map(|v| v.gradients).sum();
    let vertex_height_evaluations = verts.iter().map(|v| v.heights).sum();
    drop((verts, tris));
    drop_unused_vertices(&mut mesh);
    mesh.repair_normals();
    stages.push(("triangles", clock.elapsed()));

    let stats = MeshStats {
        grid_points: grid.point_count(),
        cells: grid.cell_count(),
        cells_visited,
        columns,
        elevation_columns,
        field_evaluations,
        height_evaluations,
        vertex_evaluations,
        vertex_height_evaluations,
        gradient_evaluations,
        vertices: mesh.positions.len() as u64,
        triangles: mesh.triangles.len() as u64,
        stages,
    };
    Ok((mesh, stats))
}

/// Every cell of every column: the unpruned baseline.
fn full_bands<'f>(grid: &GridSpec, tiles: &Tiles, t: usize) -> columns::TileBands<'f> {
    let (mut counts, mut items) = (Vec::new(), Vec::new());
    for (i, j) in tiles.columns(t) {
        let has_cells = i < grid.cells[0] && j < grid.cells[1];
        counts.push(has_cells as u32);
        if has_cells {
            items.push([0, grid.cells[2] as u32]);
        }
    }
    let n = counts.len();
    columns::TileBands {
        cells: (counts, items),
        elevation: (vec![columns::NO_ELEVATION; n], Vec::new()),
    }
}

/// Removes vertices no triangle uses (an edge crossed between two stored samples whose
/// cells all fell outside the bands through rounding), keeping the order of the rest.
fn drop_unused_vertices(mesh: &mut Mesh) {
    let used: Vec<AtomicBool> = (0..mesh.positions.len())
        .map(|_| AtomicBool::new(false))
        .collect();
    mesh.triangles.par_iter().for_each(|t| {
        for &v in t {
            used[v as usize].store(true, Ordering::Relaxed);
        }
    });
    let used: Vec<bool> = used.into_iter().map(AtomicBool::into_inner).collect();
    if used.par_iter().all(|&u| u) {
        return;
    }
    let mut remap = vec![u32::MAX; used.len()];
    let mut next = 0usize;
    for (old, &u) in used.iter().enumerate() {
        if u {
            remap[old] = next as u32;
            mesh.positions[next] = mesh.positions[old];
            mesh.normals[next] = mesh.normals[old];
            next += 1;
        }
    }
    mesh.positions.truncate(next);
    mesh.normals.truncate(next);
    mesh.triangles
        .par_iter_mut()
        .for_each(|t| *t = t.map(|v| remap[v as usize]));
}

/// The vertices one tile creates, with tile-local indices.
struct TileVertices {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    evaluations: u64,
    gradients: u64,
    heights: u64,
}

/// One endpoint of a crossed edge.
#[derive(Clone, Copy)]
struct End {
    p: Vec3,
    /// Stored value minus `T`.
    v: f32,
    elevation: bool,
}

/// What every stage reads.
struct Ctx<'a, 'f> {
    field: &'f dyn Field,
    grid: &'a GridSpec,
    tiles: &'a Tiles,
    cells: &'a Spans<[u32; 2]>,
    samples: &'a Spans<SampleSpan>,
    elevation: &'a Elevations<'f>,
    refine: bool,
    keep: Option<[[usize; 2]; 2]>,
}

impl<'f> Ctx<'_, 'f> {
    /// The tile's grid columns `lo..=hi` (plus `extra` columns) times the z-range of its
    /// samples, and a field pruned to it.
    fn tile_region(&self, t: usize, extra: isize) -> Aabb {
        let (lo, hi) = self.tiles.range(t);
        let (mut k0, mut k1) = (u32::MAX, 0);
        for (i, j) in self.tiles.columns(t) {
            for s in self.samples.of(self.tiles.id(i, j)) {
                k0 = k0.min(s.k0);
                k1 = k1.max(s.k1);
            }
        }
        let fp = columns::footprint(
            self.grid,
            [lo[0] as isize, lo[1] as isize],
            [hi[0] as isize - 1 + extra, hi[1] as isize - 1 + extra],
        );
        let z = |k: u32| self.grid.origin.z + k as f32 * self.grid.spacing.z;
        let top = (k1 as usize + extra as usize).min(self.grid.cells[2]) as u32;
        fp.extrude(Interval::new(z(k0.min(top)), z(top)))
    }

    /// Stage 3 for tile `t`: returns (field evaluations, height evaluations, elevation
    /// columns).
    fn tile_values(&self, t: usize, base: usize, out: &mut [f32]) -> (u64, u64, u64) {
        let region = self.tile_region(t, 0);
        let pruned = self.field.prune(&region);
        let f: &dyn Field = pruned.as_deref().unwrap_or(self.field);
        let (mut evals, mut heights, mut elev_columns) = (0, 0, 0);
        let dz = self.grid.spacing.z;
        let (mut zs, mut line) = (Vec::new(), Vec::new());
        for (i, j) in self.tiles.columns(t) {
            let id = self.tiles.id(i, j);
            let spans = self.samples.of(id);
            // The column's field samples as one vertical line, where the field shares work
            // along it (a heightfield's elevation lookup): each at its grid point.
            zs.clear();
            for s in spans.iter().filter(|s| !s.elevation) {
                zs.extend((s.k0..s.k1).map(|k| self.grid.point(i, j, k as usize).z));
            }
            line.resize(zs.len(), 0.0);
            let xy = self.grid.point(i, j, 0).truncate();
            let lined = !zs.is_empty() && f.eval_column(xy, &zs, &mut line);
            let mut from = 0;
            let mut h = None;
            for s in spans {
                let n = (s.k1 - s.k0) as usize;
                let dst = &mut out[s.offset - base..s.offset - base + n];
                let p0 = self.grid.point(i, j, s.k0 as usize);
                if s.elevation {
                    let h = *h.get_or_insert_with(|| {
                        heights += 1;
                        elev_columns += 1;
                        let e = self
                            .elevation
                            .get(id)
                            .expect("elevation span without elevation");
                        e.source.height(Vec2::new(p0.x, p0.y))
                    });
                    for (k, d) in dst.iter_mut().enumerate() {
                        let z = self.grid.point(i, j, s.k0 as usize + k).z;
                        *d = ISO + (h - z) / dz;
                    }
                } else if lined {
                    dst.copy_from_slice(&line[from..from + n]);
                    from += n;
                    evals += n as u64;
                } else if n < SHORT_SPAN {
                    for (k, d) in dst.iter_mut().enumerate() {
                        *d = f.value(self.grid.point(i, j, s.k0 as usize + k));
                    }
                    evals += n as u64;
                } else {
                    f.eval_block(p0, self.grid.spacing, [1, 1, n], dst);
                    evals += n as u64;
                }
            }
        }
        (evals, heights, elev_columns)
    }

    /// Stage 4 for tile `t`: a vertex on every crossed edge whose lower sample the tile
    /// owns; its tile-local index goes to that sample's slot for the edge's axis.
    fn tile_vertices(
        &self,
        t: usize,
        base: usize,
        values: &[f32],
        slots: &mut [[u32; 3]],
    ) -> TileVertices {
        let region = self.tile_region(t, 1);
        let pruned = self.field.prune(&region);
        let f: &dyn Field = pruned.as_deref().unwrap_or(self.field);
        let mut out = TileVertices {
            positions: Vec::new(),
            normals: Vec::new(),
            evaluations: 0,
            gradients: 0,
            heights: 0,
        };
        let n = self.tiles.layout.n;
        for (i, j) in self.tiles.columns(t) {
            let id = self.tiles.id(i, j);
            let spans = self.samples.of(id);
            let mut nx =
                (i + 1 < n[0]).then(|| Cursor::new(self.samples.of(self.tiles.id(i + 1, j))));
            let mut ny =
                (j + 1 < n[1]).then(|| Cursor::new(self.samples.of(self.tiles.id(i, j + 1))));
            for (si, s) in spans.iter().enumerate() {
                for k in s.k0..s.k1 {
                    let p = s.offset + (k - s.k0) as usize;
                    let solid = values[p] > ISO;
                    let z_next = if k + 1 < s.k1 {
                        Some((p + 1, s))
                    } else {
                        spans
                            .get(si + 1)
                            .filter(|n| n.k0 == k + 1)
                            .map(|n| (n.offset, n))
                    };
                    let neighbours = [
                        nx.as_mut()
                            .and_then(|c| c.find(k))
                            .map(|(q, qs)| (q, qs, [i + 1, j])),
                        ny.as_mut()
                            .and_then(|c| c.find(k))
                            .map(|(q, qs)| (q, qs, [i, j + 1])),
                        z_next.map(|(q, qs)| (q, qs, [i, j])),
                    ];
                    for (axis, nb) in neighbours.into_iter().enumerate() {
                        let Some((q, qs, [qi, qj])) = nb else {
                            continue;
                        };
                        if solid == (values[q] > ISO) {
                            continue;
                        }
                        let a = End {
                            p: self.grid.point(i, j, k as usize),
                            v: values[p] - ISO,
                            elevation: s.elevation,
                        };
                        let kq = if axis == 2 { k + 1 } else { k };
                        let b = End {
                            p: self.grid.point(qi, qj, kq as usize),
                            v: values[q] - ISO,
                            elevation: qs.elevation,
                        };
                        slots[p - base][axis] = out.positions.len() as u32;
                        self.vertex(f, id, axis, a, b, &mut out);
                    }
                }
            }
        }
        out
    }

    /// Places the vertex on the crossed edge `a → b` and its normal.
    fn vertex(
        &self,
        f: &dyn Field,
        owner: usize,
        axis: usize,
        a: End,
        b: End,
        out: &mut TileVertices,
    ) {
        let (pos, normal) = if a.elevation && b.elevation {
            let e = self
                .elevation
                .get(owner)
                .expect("elevation sample without elevation");
            let mut t = edge_t(a.v, b.v);
            if self.refine && axis != 2 {
                let g = |s: f32| {
                    let p = a.p.lerp(b.p, s);
                    e.source.height(Vec2::new(p.x, p.y)) - p.z
                };
                let dz = self.grid.spacing.z;
                t = regula_falsi(g, t, a.v * dz, b.v * dz, &mut out.heights);
            }
            let pos = a.p.lerp(b.p, t);
            (pos, self.elevation_normal(&e, pos, &mut out.heights))
        } else {
            let (mut va, mut vb) = (a.v, b.v);
            if a.elevation {
                va = f.value(a.p) - ISO;
                out.evaluations += 1;
            } else if b.elevation {
                vb = f.value(b.p) - ISO;
                out.evaluations += 1;
            }
            let mut t = edge_t(va, vb);
            if self.refine {
                let g = |s: f32| f.value(a.p.lerp(b.p, s)) - ISO;
                t = regula_falsi(g, t, va, vb, &mut out.evaluations);
            }
            let pos = a.p.lerp(b.p, t);
            out.gradients += 1;
            (pos, -f.value_grad(pos).1.normalize_or_zero())
        };
        out.positions.push(pos.into());
        out.normals.push(normal.into());
    }

    /// Unit normal of the surface `z = h(x, y)` by central differences of the elevation.
    fn elevation_normal(&self, e: &Elevation<'_>, p: Vec3, heights: &mut u64) -> Vec3 {
        let (ex, ey) = (0.5 * self.grid.spacing.x, 0.5 * self.grid.spacing.y);
        let h = |x: f32, y: f32| e.source.height(Vec2::new(x, y));
        let hx = (h(p.x + ex, p.y) - h(p.x - ex, p.y)) / (2.0 * ex);
        let hy = (h(p.x, p.y + ey) - h(p.x, p.y - ey)) / (2.0 * ey);
        *heights += 4;
        Vec3::new(-hx, -hy, 1.0).normalize_or_zero()
    }

    /// Stage 5 for tile `t`: triangles of the cells in its cell columns' bands.
    fn tile_triangles(
        &self,
        t: usize,
        values: &[f32],
        slots: &[[u32; 3]],
        vertex_base: &[u32],
    ) -> Vec<[u32; 3]> {
        let tables = &*TABLES;
        let [ncx, ncy, _] = self.grid.cells;
        let tile_of = |i: usize, j: usize| (i / TILE) + self.tiles.layout.count[0] * (j / TILE);
        let mut out = Vec::new();
        for (i, j) in self.tiles.columns(t) {
            if i >= ncx || j >= ncy {
                continue;
            }
            if let Some([x, y]) = self.keep
                && !((x[0]..x[1]).contains(&i) && (y[0]..y[1]).contains(&j))
            {
                continue;
            }
            let cols = [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)];
            let mut cursors =
                cols.map(|(ci, cj)| Cursor::new(self.samples.of(self.tiles.id(ci, cj))));
            let vbase = cols.map(|(ci, cj)| vertex_base[tile_of(ci, cj)]);
            for &[ka, kb] in self.cells.of(self.tiles.id(i, j)) {
                // Each corner column stores layers ka..=kb at consecutive indices: they lie
                // in one range of its sample union, whose spans are laid out in order.
                let mut q0 = [0usize; 4];
                let mut complete = true;
                for (c, cur) in cursors.iter_mut().enumerate() {
                    match cur.find(ka) {
                        Some((q, _)) => q0[c] = q,
                        None => complete = false,
                    }
                }
                debug_assert!(complete, "cells ({i}, {j}, {ka}..) lack a corner sample");
                if !complete {
                    continue;
                }
                for k in ka..kb {
                    let d = (k - ka) as usize;
                    let p: [usize; 8] = std::array::from_fn(|c| q0[c & 3] + d + (c >> 2));
                    debug_assert!(
                        (0..8)
                            .all(|c| cursors[c & 3].find(k + (c >> 2) as u32).map(|x| x.0)
                                == Some(p[c])),
                        "cell ({i}, {j}, {k}): corner samples not consecutive"
                    );
                    let v: [f32; 8] = p.map(|q| values[q] - ISO);
                    let mut case = 0usize;
                    for (c, &x) in v.iter().enumerate() {
                        case |= ((x > 0.0) as usize) << c;
                    }
                    if case == 0 || case == 255 {
                        continue;
                    }
                    let entry = &tables.cases[case];
                    let mask = ambiguity_mask(entry, &v);
                    let mut ev = [0u32; 12];
                    let mut edges = entry.edges;
                    while edges != 0 {
                        let e = edges.trailing_zeros() as usize;
                        edges &= edges - 1;
                        let c = EDGE_CORNERS[e][0] as usize;
                        ev[e] = vbase[c & 3] + slots[p[c]][EDGE_AXIS[e] as usize];
                    }
                    for tri in tables.triangles(case, mask) {
                        out.push(tri.map(|e| ev[e as usize]));
                    }
                }
            }
        }
        out
    }
}

/// Illinois regula falsi for the root of `g` on `[0, 1]` starting from `t`, with
/// `g(0) = g0` and `g(1) = g1` of opposite signs; counts evaluations in `evals`.
///
/// Safeguarded by bisection: when two steps have not halved the bracket (a field with a
/// kink, such as a heightfield's `min(σ, f_P)` at its walls, can stall regula falsi on
/// one side), the next point is the bracket's midpoint. Stops once the bracket is
/// narrower than [`REFINE_TOLERANCE`] or after [`REFINE_ITERATIONS`] evaluations.
fn regula_falsi(g: impl Fn(f32) -> f32, t: f32, g0: f32, g1: f32, evals: &mut u64) -> f32 {
    let p = g0 * g1;
    if p.is_nan() || p >= 0.0 {
        return t;
    }
    let (mut a, mut fa, mut b, mut fb) = (0.0f32, g0, 1.0f32, g1);
    let mut t = t;
    let mut side = 0i8;
    // Bracket widths two steps and one step ago (none before the start).
    let mut widths = [f32::INFINITY, 1.0];
    for _ in 0..REFINE_ITERATIONS {
        let ft = g(t);
        *evals += 1;
        if ft == 0.0 || !ft.is_finite() {
            return edge_t_clamp(t);
        }
        if (ft > 0.0) == (fa > 0.0) {
            a = t;
            fa = ft;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        } else {
            b = t;
            fb = ft;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        }
        let next = (a * fb - b * fa) / (fb - fa);
        if b - a <= REFINE_TOLERANCE {
            t = if next.is_finite() {
                next
            } else {
                0.5 * (a + b)
            };
            break;
        }
        let stalled = b - a > 0.5 * widths[0];
        widths = [widths[1], b - a];
        t = if next.is_finite() && !stalled {
            next
        } else {
            0.5 * (a + b)
        };
    }
    edge_t_clamp(t)
}

fn edge_t_clamp(t: f32) -> f32 {
    t.clamp(super::cell::EDGE_T_MIN, 1.0 - super::cell::EDGE_T_MIN)
}

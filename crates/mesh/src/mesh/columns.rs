//! Bound pruning (Paris et al. 2019 §7, Fig. 22): which cells of each grid column can hold the
//! surface, and which samples must therefore be evaluated.
//!
//! Paris et al. bound the surface's elevation at each grid *vertex* and dilate the bounds
//! over the vertex's 1-ring so that the cells between vertices stay covered. We ask the
//! field's [`Field::z_bands`] over the footprint of each *cell column* instead: the
//! contract makes those bands sound over the whole footprint, so every cell with a sign
//! change is kept without a dilation step. The samples of a grid column are then the
//! union of the cells of its four adjacent cell columns (the 1-ring union in sample
//! space), so every kept cell has its eight corners and no corner is evaluated twice.
//!
//! Before the per-column bands, whole bricks of a tile are culled when
//! [`Field::interval`] excludes `T`, and each tile works on [`Field::prune`]'s cheaper
//! field.
//!
//! Columns are numbered tile by tile (tiles of [`TILE`]² grid columns, row-major inside),
//! so each tile's columns, samples and vertices are contiguous and tiles run in parallel.

use glam::Vec2;

use rayon::prelude::*;

use super::grid::GridSpec;
use super::{par_concat, split_parts};
use crate::field::{Elevation, Field, ISO, Interval, Rect, ZBands};

/// Grid columns per tile side.
pub const TILE: usize = 32;

/// Cell layers per brick for interval culling.
pub const BRICK_LAYERS: usize = 8;

/// Cell columns per side of a brick for interval culling (divides [`TILE`]).
pub const BRICK_COLUMNS: usize = 16;

/// Slack, in cells, when turning a z-band into cell indices (guards rounding).
const BAND_SLACK: f32 = 1e-3;

/// How the `(cells + 1)²` grid columns are cut into tiles: sizes only, no allocation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileGrid {
    /// Grid columns per axis (`cells + 1`).
    pub n: [usize; 2],
    /// Tiles per axis.
    pub count: [usize; 2],
}

impl TileGrid {
    /// The tiling of a grid's columns.
    pub fn new(grid: &GridSpec) -> Self {
        let n = [grid.cells[0] + 1, grid.cells[1] + 1];
        TileGrid {
            n,
            count: [n[0].div_ceil(TILE), n[1].div_ceil(TILE)],
        }
    }

    /// Number of grid columns.
    pub fn columns_total(&self) -> u64 {
        self.n[0] as u64 * self.n[1] as u64
    }

    /// Number of tiles.
    pub fn len(&self) -> usize {
        self.count[0] * self.count[1]
    }

    /// Always false: a grid has at least one column.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Grid-column range `[lo, hi)` of tile `t`.
    pub fn range(&self, t: usize) -> ([usize; 2], [usize; 2]) {
        let (ti, tj) = (t % self.count[0], t / self.count[0]);
        let lo = [ti * TILE, tj * TILE];
        (
            lo,
            [(lo[0] + TILE).min(self.n[0]), (lo[1] + TILE).min(self.n[1])],
        )
    }

    /// Columns of tile `t` in id order.
    pub fn columns(&self, t: usize) -> impl Iterator<Item = (usize, usize)> + use<> {
        let (lo, hi) = self.range(t);
        (lo[1]..hi[1]).flat_map(move |j| (lo[0]..hi[0]).map(move |i| (i, j)))
    }
}

/// The tiling of the grid columns with their numbering: one `u32` per column, so the
/// column count is checked against the budget before this is built.
pub struct Tiles {
    /// The tiling.
    pub layout: TileGrid,
    /// Column id of each `(i, j)`: `id[i + n[0]·j]`.
    id: Vec<u32>,
    /// First column id of each tile, plus the total.
    pub start: Vec<usize>,
}

impl Tiles {
    /// Numbers the columns of `layout`, tile by tile.
    pub fn new(layout: TileGrid) -> Self {
        let n = layout.n;
        let mut id = vec![0u32; n[0] * n[1]];
        let mut start = Vec::with_capacity(layout.len() + 1);
        let mut next = 0u32;
        for t in 0..layout.len() {
            start.push(next as usize);
            for (i, j) in layout.columns(t) {
                id[i + n[0] * j] = next;
                next += 1;
            }
        }
        start.push(next as usize);
        Tiles { layout, id, start }
    }

    /// Number of tiles.
    pub fn len(&self) -> usize {
        self.layout.len()
    }

    /// Always false: a grid has at least one column.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Grid-column range `[lo, hi)` of tile `t`.
    pub fn range(&self, t: usize) -> ([usize; 2], [usize; 2]) {
        self.layout.range(t)
    }

    /// Columns of tile `t` in id order.
    pub fn columns(&self, t: usize) -> impl Iterator<Item = (usize, usize)> + use<> {
        self.layout.columns(t)
    }

    /// Id of grid column `(i, j)`.
    #[inline]
    pub fn id(&self, i: usize, j: usize) -> usize {
        self.id[i + self.layout.n[0] * j] as usize
    }
}

/// Compressed lists of `u32` ranges per column (column id order).
#[derive(Default)]
pub struct Spans<S> {
    start: Vec<u32>,
    items: Vec<S>,
}

impl<S: Copy + Default + Send + Sync> Spans<S> {
    /// Builds from per-tile parts, each `(items per column, items)` in column id order.
    pub fn concat(parts: Vec<(Vec<u32>, Vec<S>)>) -> Self {
        let mut item_base = Vec::with_capacity(parts.len());
        let mut next = 0u32;
        for (_, items) in &parts {
            item_base.push(next);
            next += items.len() as u32;
        }
        let col_lens: Vec<usize> = parts.iter().map(|p| p.0.len()).collect();
        let mut start = vec![0u32; col_lens.iter().sum::<usize>() + 1];
        split_parts(&mut start[1..], &col_lens)
            .into_par_iter()
            .zip(&parts)
            .zip(item_base)
            .for_each(|((dst, (counts, _)), base)| {
                let mut at = base;
                for (d, &c) in dst.iter_mut().zip(counts) {
                    at += c;
                    *d = at;
                }
            });
        let items = par_concat(parts.iter().map(|p| &p.1[..]));
        Spans { start, items }
    }

    /// The items of column `id`.
    #[inline]
    pub fn of(&self, id: usize) -> &[S] {
        &self.items[self.start[id] as usize..self.start[id + 1] as usize]
    }

    /// All items.
    pub fn items(&self) -> &[S] {
        &self.items
    }
}

/// A run of samples `k0..k1` of one grid column, stored from `offset` in the sample arrays.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SampleSpan {
    /// First sample layer.
    pub k0: u32,
    /// One past the last sample layer.
    pub k1: u32,
    /// Index of sample `k0` in the sample arrays.
    pub offset: usize,
    /// The samples hold the elevation's pseudo-values, not field values.
    pub elevation: bool,
}

/// Finds samples of one column by layer, for increasing layers (amortised O(1)).
pub struct Cursor<'s> {
    spans: &'s [SampleSpan],
    at: usize,
}

impl<'s> Cursor<'s> {
    /// A cursor at the column's first span.
    pub fn new(spans: &'s [SampleSpan]) -> Self {
        Cursor { spans, at: 0 }
    }

    /// The sample index and span of layer `k`, if stored; `k` must not decrease between
    /// calls.
    #[inline]
    pub fn find(&mut self, k: u32) -> Option<(usize, &'s SampleSpan)> {
        while self.at < self.spans.len() && self.spans[self.at].k1 <= k {
            self.at += 1;
        }
        let s = self.spans.get(self.at)?;
        (s.k0 <= k).then(|| (s.offset + (k - s.k0) as usize, s))
    }
}

/// The layers `[a, b)` of the cells (of `n` layers) that overlap the z-band `band`, or
/// `None`. A cell `k` spans `[z0 + k·dz, z0 + (k+1)·dz]`.
pub fn cells_of_band(band: Interval, z0: f32, dz: f32, n: usize) -> Option<[u32; 2]> {
    let (lo, hi) = ((band.lo - z0) / dz, (band.hi - z0) / dz);
    if lo.is_nan() || hi.is_nan() {
        return Some([0, n as u32]);
    }
    let a = ceil(lo - 1.0 - BAND_SLACK).max(0.0);
    let b = (floor(hi + BAND_SLACK) + 1.0).min(n as f32);
    (a < b).then_some([a as u32, b as u32])
}

/// `x.floor()` without a libm call on targets without SSE4.1 (NaN stays NaN).
#[inline]
fn floor(x: f32) -> f32 {
    // Beyond 2^23 every f32 is an integer.
    if !(x.abs() < 8_388_608.0) {
        return x;
    }
    let t = x as i32 as f32;
    if t > x { t - 1.0 } else { t }
}

/// `x.ceil()`, like [`floor`].
#[inline]
fn ceil(x: f32) -> f32 {
    -floor(-x)
}

/// Adds `[a, b)` to a sorted list of disjoint ranges, merging overlapping or touching ones.
pub fn push_range(list: &mut Vec<[u32; 2]>, r: [u32; 2]) {
    // Most ranges come in order: after the last one, or merging into it.
    match list.last_mut() {
        None => return list.push(r),
        Some(last) if last[1] < r[0] => return list.push(r),
        Some(last) if last[0] <= r[0] => {
            last[1] = last[1].max(r[1]);
            return;
        }
        Some(_) => {}
    }
    let at = list.partition_point(|x| x[1] < r[0]);
    let mut merged = r;
    let mut end = at;
    while end < list.len() && list[end][0] <= merged[1] {
        merged = [merged[0].min(list[end][0]), merged[1].max(list[end][1])];
        end += 1;
    }
    list.splice(at..end, [merged]);
}

/// The elevation answering for each grid column, if any, as an index per column into a
/// short list (one entry per tile that is a heightfield throughout).
pub struct Elevations<'f> {
    index: Vec<u32>,
    list: Vec<Elevation<'f>>,
}

/// The index of a column without elevation.
pub const NO_ELEVATION: u32 = u32::MAX;

impl<'f> Elevations<'f> {
    /// Builds from per-tile parts `(index per column, elevations)` in column id order,
    /// each index relative to its part's list.
    pub fn concat(parts: Vec<(Vec<u32>, Vec<Elevation<'f>>)>) -> Self {
        let mut index = Vec::with_capacity(parts.iter().map(|p| p.0.len()).sum());
        let mut list = Vec::new();
        for (idx, part) in parts {
            let base = list.len() as u32;
            index.extend(idx.iter().map(|&i| {
                if i == NO_ELEVATION {
                    NO_ELEVATION
                } else {
                    base + i
                }
            }));
            list.extend(part);
        }
        Elevations { index, list }
    }

    /// The elevation of column `id`.
    #[inline]
    pub fn get(&self, id: usize) -> Option<Elevation<'f>> {
        let i = self.index[id];
        (i != NO_ELEVATION).then(|| self.list[i as usize])
    }
}

/// What the bands stage found for one tile.
pub struct TileBands<'f> {
    /// Cell ranges per grid column of the tile (none for the last row/column, which has
    /// no cells).
    pub cells: (Vec<u32>, Vec<[u32; 2]>),
    /// The elevation answering for each grid column of the tile, if any: an index per
    /// column into the list (see [`Elevations::concat`]).
    pub elevation: (Vec<u32>, Vec<Elevation<'f>>),
}

/// Footprint of grid columns `lo..=hi` (inclusive indices), clamped to the grid.
pub fn footprint(grid: &GridSpec, lo: [isize; 2], hi: [isize; 2]) -> Rect {
    let clamp = |v: isize, axis: usize| v.clamp(0, grid.cells[axis] as isize) as usize;
    let a = grid.point(clamp(lo[0], 0), clamp(lo[1], 1), 0);
    let b = grid.point(clamp(hi[0], 0), clamp(hi[1], 1), 0);
    Rect::new(Vec2::new(a.x, a.y), Vec2::new(b.x, b.y))
}

/// The bands stage for tile `t`: cell ranges from brick culling and per-column z-bands,
/// and the elevations usable for direct extraction.
pub fn tile_bands<'f>(
    field: &'f dyn Field,
    grid: &GridSpec,
    tiles: &TileGrid,
    t: usize,
    use_elevation: bool,
) -> TileBands<'f> {
    let (lo, hi) = tiles.range(t);
    let [ncx, ncy, ncz] = grid.cells;
    let (z0, dz) = (grid.origin.z, grid.spacing.z);
    let z_of = |k: usize| z0 + k as f32 * dz;
    let cell_hi = [hi[0].min(ncx), hi[1].min(ncy)];
    let mut counts = Vec::with_capacity(TILE * TILE);
    let mut items = Vec::new();
    if cell_hi[0] > lo[0] && cell_hi[1] > lo[1] {
        let fp = footprint(
            grid,
            [lo[0] as isize, lo[1] as isize],
            [cell_hi[0] as isize, cell_hi[1] as isize],
        );
        let tile_box = fp.extrude(Interval::new(z_of(0), z_of(ncz)));
        let pruned = field.prune(&tile_box);
        let f: &dyn Field = pruned.as_deref().unwrap_or(field);
        // Bricks are culled over footprints of BRICK_COLUMNS² cell columns.
        let blocks = TILE / BRICK_COLUMNS;
        let block_runs: Vec<Vec<[usize; 2]>> = (0..blocks * blocks)
            .map(|b| {
                let a = [
                    lo[0] + (b % blocks) * BRICK_COLUMNS,
                    lo[1] + (b / blocks) * BRICK_COLUMNS,
                ];
                let e = [
                    (a[0] + BRICK_COLUMNS).min(cell_hi[0]),
                    (a[1] + BRICK_COLUMNS).min(cell_hi[1]),
                ];
                if e[0] <= a[0] || e[1] <= a[1] {
                    return Vec::new();
                }
                let fp = footprint(
                    grid,
                    [a[0] as isize, a[1] as isize],
                    [e[0] as isize, e[1] as isize],
                );
                brick_runs(f, &fp, grid)
            })
            .collect();
        // Where the field's bands do not depend on the range searched, one search per
        // column serves all its runs.
        let clip = f.z_bands_clip();
        let mut bands = ZBands::new();
        let mut list = Vec::new();
        for (i, j) in tiles.columns(t) {
            if i >= ncx || j >= ncy {
                counts.push(0);
                continue;
            }
            let runs =
                &block_runs[(i - lo[0]) / BRICK_COLUMNS + blocks * ((j - lo[1]) / BRICK_COLUMNS)];
            let cfp = footprint(
                grid,
                [i as isize, j as isize],
                [i as isize + 1, j as isize + 1],
            );
            bands.clear();
            list.clear();
            if let (true, Some(first), Some(last)) = (clip, runs.first(), runs.last()) {
                f.z_bands(
                    &cfp,
                    Interval::new(z_of(first[0]), z_of(last[1])),
                    &mut bands,
                );
            }
            for &[a, b] in runs {
                let run_z = Interval::new(z_of(a), z_of(b));
                if !clip {
                    bands.clear();
                    f.z_bands(&cfp, run_z, &mut bands);
                }
                for band in bands.as_slice() {
                    // as a search inside `run_z` would have clipped it (and dropped it empty)
                    let band = if clip { band.intersect(run_z) } else { *band };
                    if band.is_empty() {
                        continue;
                    }
                    if let Some([ca, cb]) = cells_of_band(band, z0, dz, ncz) {
                        let r = [ca.max(a as u32), cb.min(b as u32)];
                        if r[0] < r[1] {
                            push_range(&mut list, r);
                        }
                    }
                }
            }
            counts.push(list.len() as u32);
            items.extend_from_slice(&list);
        }
    } else {
        counts.resize(tiles.columns(t).count(), 0);
    }
    let n = counts.len();
    let elevation = if !use_elevation {
        (vec![NO_ELEVATION; n], Vec::new())
    } else {
        let whole = footprint(
            grid,
            [lo[0] as isize - 1, lo[1] as isize - 1],
            [hi[0] as isize, hi[1] as isize],
        );
        match field.elevation(&whole) {
            Some(e) => (vec![0; n], vec![e]),
            None => {
                let (mut index, mut list) = (Vec::with_capacity(n), Vec::new());
                for (i, j) in tiles.columns(t) {
                    let (i, j) = (i as isize, j as isize);
                    match field.elevation(&footprint(grid, [i - 1, j - 1], [i + 1, j + 1])) {
                        Some(e) => {
                            index.push(list.len() as u32);
                            list.push(e);
                        }
                        None => index.push(NO_ELEVATION),
                    }
                }
                (index, list)
            }
        }
    };
    TileBands {
        cells: (counts, items),
        elevation,
    }
}

/// Runs `[a, b)` of cell layers of the bricks over `fp` whose interval contains `T`.
fn brick_runs(f: &dyn Field, fp: &Rect, grid: &GridSpec) -> Vec<[usize; 2]> {
    let ncz = grid.cells[2];
    let z_of = |k: usize| grid.origin.z + k as f32 * grid.spacing.z;
    let mut runs: Vec<[usize; 2]> = Vec::new();
    for a in (0..ncz).step_by(BRICK_LAYERS) {
        let b = (a + BRICK_LAYERS).min(ncz);
        if !f
            .interval(&fp.extrude(Interval::new(z_of(a), z_of(b))))
            .contains(ISO)
        {
            continue;
        }
        match runs.last_mut() {
            Some(last) if last[1] == a => last[1] = b,
            _ => runs.push([a, b]),
        }
    }
    runs
}

/// Sample spans of tile `t`: per grid column, the union of the cell ranges of its four
/// adjacent cell columns (as sample layers), split where an elevation's z-range starts
/// and ends. Offsets are relative to the tile's first sample.
pub fn tile_samples(
    grid: &GridSpec,
    tiles: &Tiles,
    cells: &Spans<[u32; 2]>,
    elevation: &Elevations<'_>,
    t: usize,
) -> (Vec<u32>, Vec<SampleSpan>) {
    let (z0, dz) = (grid.origin.z, grid.spacing.z);
    let nk = grid.cells[2] as u32 + 1;
    let mut counts = Vec::new();
    let mut spans = Vec::new();
    let mut list: Vec<[u32; 2]> = Vec::new();
    let mut offset = 0usize;
    for (i, j) in tiles.columns(t) {
        list.clear();
        for (di, dj) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            if i >= di && j >= dj {
                for &[a, b] in cells.of(tiles.id(i - di, j - dj)) {
                    push_range(&mut list, [a, b + 1]);
                }
            }
        }
        let split = elevation.get(tiles.id(i, j)).map(|e| {
            let a = ceil((e.z.lo - z0) / dz + BAND_SLACK).clamp(0.0, nk as f32) as u32;
            let b = floor((e.z.hi - z0) / dz - BAND_SLACK) + 1.0;
            [a, b.clamp(0.0, nk as f32) as u32]
        });
        let before = spans.len();
        for &[a, b] in &list {
            let mut push = |k0: u32, k1: u32, elevation: bool| {
                if k0 < k1 {
                    spans.push(SampleSpan {
                        k0,
                        k1,
                        offset,
                        elevation,
                    });
                    offset += (k1 - k0) as usize;
                }
            };
            match split {
                Some([ea, eb]) if ea < eb => {
                    push(a, b.min(ea), false);
                    push(a.max(ea), b.min(eb), true);
                    push(a.max(eb), b, false);
                }
                _ => push(a, b, false),
            }
        }
        counts.push((spans.len() - before) as u32);
    }
    (counts, spans)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn band_to_cells_is_conservative() {
        // Cells of size 1 from z = 0; a band [2.5, 3.0] touches cells 2 and 3 (closed).
        assert_eq!(
            cells_of_band(Interval::new(2.5, 3.0), 0.0, 1.0, 10),
            Some([2, 4])
        );
        assert_eq!(
            cells_of_band(Interval::new(2.5, 2.6), 0.0, 1.0, 10),
            Some([2, 3])
        );
        assert_eq!(cells_of_band(Interval::new(-5.0, -2.0), 0.0, 1.0, 10), None);
        assert_eq!(
            cells_of_band(Interval::new(-5.0, 50.0), 0.0, 1.0, 10),
            Some([0, 10])
        );
    }

    #[test]
    fn ranges_merge() {
        let mut l = vec![];
        push_range(&mut l, [5, 7]);
        push_range(&mut l, [1, 2]);
        push_range(&mut l, [2, 5]);
        push_range(&mut l, [9, 10]);
        assert_eq!(l, vec![[1, 7], [9, 10]]);
    }

    #[test]
    fn tiles_number_columns_contiguously() {
        let g = GridSpec::new(Vec3::ZERO, Vec3::ONE, [40, 20, 3]).unwrap();
        let tiles = Tiles::new(TileGrid::new(&g));
        let mut seen = vec![false; 41 * 21];
        for t in 0..tiles.len() {
            for (n, (i, j)) in tiles.columns(t).enumerate() {
                let id = tiles.id(i, j);
                assert_eq!(id, tiles.start[t] + n);
                assert!(!seen[id]);
                seen[id] = true;
            }
        }
        assert!(seen.iter().all(|&s| s));
    }
}

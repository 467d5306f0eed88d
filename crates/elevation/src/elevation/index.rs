//! A uniform grid over the supports of a blend's children (Génevaux et al. 2015 §5.1: a
//! blend "combined to a grid acceleration structure"): a point query visits only the
//! children whose support box covers its cell — for a disc, only the cells its disc
//! meets.

use glam::Vec2;

use crate::field::Rect;

/// Most cells per child: bounds the index's memory whatever the supports.
const CELLS_PER_CHILD: usize = 64;
/// Rectangles spanning more cells than this are answered with every child.
const MAX_QUERY_CELLS: usize = 16;

/// Children's indices per grid cell, in compressed rows.
#[derive(Clone, Debug)]
pub struct GridIndex {
    origin: Vec2,
    inv_cell: f32,
    dims: [usize; 2],
    offsets: Vec<u32>,
    items: Vec<u32>,
    count: usize,
}

impl GridIndex {
    /// An index of `boxes` (finite, non-empty; one per child), or `None` when they are
    /// too few or not finite. `discs[k]` is child `k`'s disc `(centre, radius)` when its
    /// weight is 0 off that disc: the child is then listed only in the cells the disc
    /// meets (with a margin, so a point of a cell it is not listed in is far enough off
    /// the disc that its weight evaluates to exactly 0).
    pub fn new(boxes: &[Rect], discs: &[Option<(Vec2, f32)>]) -> Option<GridIndex> {
        if boxes.len() < 8
            || boxes
                .iter()
                .any(|b| !(b.min.is_finite() && b.max.is_finite()))
        {
            return None;
        }
        let (lo, hi) = boxes
            .iter()
            .fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(l, h), b| {
                (l.min(b.min), h.max(b.max))
            });
        // Cells about a quarter of the median support's size, capped in number: a cell's
        // list is then little more than the supports that hold its points.
        let mut sizes: Vec<f32> = boxes
            .iter()
            .map(|b| (b.max - b.min).max_element())
            .collect();
        sizes.sort_by(f32::total_cmp);
        let span = (hi - lo).max(Vec2::splat(1e-3));
        let mut cell = (sizes[sizes.len() / 2] * 0.25).max(1e-3);
        let budget = CELLS_PER_CHILD * boxes.len();
        while ((span.x / cell).ceil() as usize) * ((span.y / cell).ceil() as usize) > budget {
            cell *= 1.5;
        }
        let dims = [
            ((span.x / cell).ceil() as usize).max(1),
            ((span.y / cell).ceil() as usize).max(1),
        ];
        let mut index = GridIndex {
            origin: lo,
            inv_cell: 1.0 / cell,
            dims,
            offsets: Vec::new(),
            items: Vec::new(),
            count: boxes.len(),
        };
        // How far a point of a cell may lie outside the cell's rectangle, with the f32
        // roundings of its cell's index and of its offset from a disc's centre.
        let reach = lo.abs().max(hi.abs()).max_element() as f64;
        let margin = 1e-3 * cell as f64 + 1e-5 * reach;
        let mut per_cell: Vec<Vec<u32>> = vec![Vec::new(); dims[0] * dims[1]];
        for (k, b) in boxes.iter().enumerate() {
            let (i0, i1, j0, j1) = index.cells(b)?;
            let disc = discs.get(k).copied().flatten();
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let meets = disc.is_none_or(|(c, r)| {
                        let corner = |i: usize, o: f32| o as f64 + i as f64 * cell as f64;
                        let (x0, y0) = (corner(i, lo.x), corner(j, lo.y));
                        let (x1, y1) = (x0 + cell as f64, y0 + cell as f64);
                        let (cx, cy) = (c.x as f64, c.y as f64);
                        let dx = (x0 - cx).max(cx - x1).max(0.0);
                        let dy = (y0 - cy).max(cy - y1).max(0.0);
                        let r = r.abs() as f64;
                        // NaN radii and centres stay listed.
                        !((dx * dx + dy * dy).sqrt() > r * (1.0 + 1e-5) + 2.0 * margin)
                    });
                    if meets {
                        per_cell[i + dims[0] * j].push(k as u32);
                    }
                }
            }
        }
        index.offsets.push(0);
        for c in per_cell {
            index.items.extend(c);
            index.offsets.push(index.items.len() as u32);
        }
        Some(index)
    }

    /// The cell range `(i0, i1, j0, j1)` under `r`, clamped; `None` when `r` misses the grid.
    fn cells(&self, r: &Rect) -> Option<(usize, usize, usize, usize)> {
        let a = (r.min - self.origin) * self.inv_cell;
        let b = (r.max - self.origin) * self.inv_cell;
        let (nx, ny) = (self.dims[0] as f32, self.dims[1] as f32);
        if !(b.x >= 0.0 && b.y >= 0.0 && a.x < nx && a.y < ny) {
            return None;
        }
        let c = |v: f32, n: usize| (v.max(0.0) as usize).min(n - 1);
        Some((
            c(a.x, self.dims[0]),
            c(b.x, self.dims[0]),
            c(a.y, self.dims[1]),
            c(b.y, self.dims[1]),
        ))
    }

    /// The children whose support may hold `p`.
    #[inline]
    pub fn at(&self, p: Vec2) -> &[u32] {
        self.cell(p).map_or(&[], |k| self.list(k))
    }

    /// How many cells the grid has.
    #[inline]
    pub fn cell_count(&self) -> usize {
        self.dims[0] * self.dims[1]
    }

    /// The cell (`0..cell_count()`) holding `p`; `None` off the grid and where `p` is not
    /// finite.
    #[inline]
    pub fn cell(&self, p: Vec2) -> Option<usize> {
        let u = (p - self.origin) * self.inv_cell;
        if !(u.x >= 0.0 && u.y >= 0.0) {
            return None;
        }
        let (i, j) = (u.x as usize, u.y as usize);
        (i < self.dims[0] && j < self.dims[1]).then(|| i + self.dims[0] * j)
    }

    /// The children listed in cell `k` (`k < cell_count()`).
    #[inline]
    pub fn list(&self, k: usize) -> &[u32] {
        &self.items[self.offsets[k] as usize..self.offsets[k + 1] as usize]
    }

    /// The children whose support may meet `r`, sorted, without repeats (every child when
    /// `r` spans many cells).
    pub fn over(&self, r: &Rect) -> Vec<u32> {
        let Some((i0, i1, j0, j1)) = self.cells(r) else {
            return Vec::new();
        };
        if (i1 - i0 + 1) * (j1 - j0 + 1) > MAX_QUERY_CELLS {
            return (0..self.count as u32).collect();
        }
        let mut v = Vec::new();
        for j in j0..=j1 {
            for i in i0..=i1 {
                v.extend_from_slice(self.list(i + self.dims[0] * j));
            }
        }
        v.sort_unstable();
        v.dedup();
        v
    }
}

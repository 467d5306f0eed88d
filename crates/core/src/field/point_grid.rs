//! A uniform grid over the items of a blend's [`super::bvh::ChildBvh`], for point queries.
//!
//! A point query through the BVH descends several levels of nodes, each a cache miss once
//! the leaves outgrow the cache (100k children make 3.2 MB of leaves). Here the point's
//! cell is computed in a few operations and lists, contiguously, every item whose box
//! meets the cell: one lookup of the cell's range, one run of entries, and a point in
//! empty space is rejected at the first. The entries are packed four by four, structure
//! of arrays: round kernels (noise-free points and spheres, the bulk of generated trees)
//! are evaluated there four lanes at once, so their nodes are never read, and a query
//! runs without data-dependent branches, which lets the processor overlap the cache misses
//! of consecutive queries. [`PointGrid::sums_at`] answers a batch of queries by blocks,
//! asking for a block's cells together.
//!
//! **Same sums as the BVH.** A cell lists its items in the order the BVH's point query
//! visits them, so the sum over the items whose boxes contain the point is done in the
//! same order, to the bit. An item is listed in the cells from `cell(lo)` to `cell(hi)` of
//! its box, axis by axis, and `cell` is monotone (a subtraction, a product by a positive
//! step and a truncation), so a point the box contains lies in one of them whatever the
//! rounding. A round kernel is evaluated without its box test: outside its support it is
//! 0 and adding ±0 leaves the sum unchanged (the sum starts at +0 and never becomes −0).
//!
//! **Bounded.** At most [`CELLS_PER_ITEM`] cells and [`ENTRIES_PER_ITEM`] entries per item,
//! a cell's entries in groups of four (128 bytes a group), so at most `cells + entries / 4`
//! groups: at most 548 bytes per child with the other arrays (the BVH itself takes about
//! 40). The grid is not built (the BVH answers) when the items' sizes would make it
//! larger, or its lists long on average. It is a compile-time structure proportional to
//! the tree, like the BVH, so it is not checked against the grids' memory budget.

use std::ops::Range;

use glam::{Vec3, Vec4};

use super::bounds::Aabb;
use super::primitive::Round;
use crate::cache::prefetch;

/// Most cells per item.
const CELLS_PER_ITEM: usize = 2;

/// Most entries (an item in each cell its box meets) per item.
const ENTRIES_PER_ITEM: usize = 8;

/// Most entries per cell on average; longer lists are the BVH's job.
const MEAN_LIST: usize = 16;

/// Points whose cells [`PointGrid::sums_at`] looks up together.
const BLOCK: usize = 32;

/// Four entries of a cell, by lanes: round kernels `[c.x, c.y, c.z, r, R, 1/R, E]`
/// ([`Round::params`]), and in a lane that holds another child (or nothing) a kernel that
/// is 0 everywhere (`E = 0`).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Group {
    k: [Vec4; 7],
    /// Per lane: 0, or `1 +` the index in [`PointGrid::children`] of the child it holds.
    child: [u32; 4],
}

const _: () = assert!(std::mem::size_of::<Group>() == 128);

impl Group {
    const EMPTY: Group = Group {
        k: [
            Vec4::ZERO,
            Vec4::ZERO,
            Vec4::ZERO,
            Vec4::ZERO,
            Vec4::ONE,
            Vec4::ONE,
            Vec4::ZERO,
        ],
        child: [0; 4],
    };

    fn set(&mut self, lane: usize, params: [f32; 7]) {
        for (k, v) in self.k.iter_mut().zip(params) {
            k[lane] = v;
        }
    }

    /// The four kernels' values at `p`: the operations of the round kernel's
    /// [`Primitive::value`](super::Primitive), lane by lane, so each lane is that value to
    /// the bit.
    #[inline(always)]
    fn values(&self, p: &[Vec4; 3]) -> Vec4 {
        let [cx, cy, cz, r, big_r, inv_r, e] = self.k;
        let (dx, dy, dz) = (p[0] - cx, p[1] - cy, p[2] - cz);
        let len = (dx * dx + dy * dy + dz * dz).sqrt();
        let d = (len - r).max(Vec4::ZERO);
        let t = Vec4::select(d.cmpge(big_r), Vec4::ONE, d * inv_r);
        let s = Vec4::ONE - t * t;
        let g = Vec4::select(t.cmpge(Vec4::ONE), Vec4::ZERO, s * s * s);
        e * g
    }
}

/// The cells along the three axes: `bounds` cut into `dims` equal steps.
struct Cells {
    bounds: Aabb,
    /// Cells per unit length (0 on a flat axis).
    inv_step: Vec3,
    dims: [usize; 3],
}

impl Cells {
    fn new(bounds: Aabb, dims: [usize; 3]) -> Self {
        let size = bounds.size();
        let inv = |a: usize| {
            if size[a] > 0.0 {
                dims[a] as f32 / size[a]
            } else {
                0.0
            }
        };
        Cells {
            bounds,
            inv_step: Vec3::new(inv(0), inv(1), inv(2)),
            dims,
        }
    }

    fn len(&self) -> usize {
        self.dims.iter().product()
    }

    /// The cell of `p` along each axis, for `p` inside the bounds: monotone in `p`.
    #[inline(always)]
    fn axes(&self, p: Vec3) -> [usize; 3] {
        let f = (p - self.bounds.min) * self.inv_step;
        [0, 1, 2].map(|a| (f[a] as usize).min(self.dims[a] - 1))
    }

    /// The index of the cell holding `p`, or `None` outside the bounds (and for NaN).
    #[inline(always)]
    fn index(&self, p: Vec3) -> Option<usize> {
        if !self.bounds.contains(p) {
            return None;
        }
        let [i, j, k] = self.axes(p);
        Some(i + self.dims[0] * (j + self.dims[1] * k))
    }

    /// The cells a box inside the bounds meets, along each axis.
    fn span(&self, b: &Aabb) -> [Range<usize>; 3] {
        let (lo, hi) = (self.axes(b.min), self.axes(b.max));
        [0, 1, 2].map(|a| lo[a]..hi[a] + 1)
    }

    /// Calls `f(cell)` for each cell `b` meets.
    fn each(&self, b: &Aabb, mut f: impl FnMut(usize)) {
        let [xs, ys, zs] = self.span(b);
        for k in zs {
            for j in ys.clone() {
                let row = self.dims[0] * (j + self.dims[1] * k);
                xs.clone().for_each(|i| f(row + i));
            }
        }
    }

    /// Entries needed to list every item in each cell it meets.
    fn entries(&self, items: &[(Aabb, u32)]) -> usize {
        items
            .iter()
            .map(|(b, _)| self.span(b).iter().map(Range::len).product::<usize>())
            .sum()
    }
}

/// The grid: per cell, its entries in groups, contiguous (`groups[first[c]..first[c +
/// 1]]`).
pub(super) struct PointGrid {
    cells: Cells,
    first: Vec<u32>,
    groups: Vec<Group>,
    /// The items that are not round kernels: their supports and payloads.
    children: Vec<(Aabb, u32)>,
}

impl PointGrid {
    /// The grid over `items` (each box with its payload, in the order queries sum them),
    /// with `round(payload)` the round kernel of an item, if any. `None` when it would
    /// exceed its bounds on memory or on the lists' length.
    ///
    /// The steps are twice the items' median extent along each axis (so an item meets
    /// about 1.5 cells per axis), coarsened, the axis with the most cells first, until the
    /// cells and the entries fit their bounds.
    pub(super) fn new(items: &[(Aabb, u32)], round: impl Fn(u32) -> Option<Round>) -> Option<Self> {
        // A box that is not ordered on every axis contains no point: leave it out.
        let items: Vec<(Aabb, u32)> = items
            .iter()
            .filter(|(b, _)| b.min.cmple(b.max).all())
            .copied()
            .collect();
        let n = items.len();
        if n == 0 {
            return None;
        }
        let bounds = items.iter().fold(Aabb::EMPTY, |u, (b, _)| u.union(*b));
        let size = bounds.size();
        let max_cells = CELLS_PER_ITEM * n;
        let mut dims = [0, 1, 2].map(|a| {
            let mut ext: Vec<f32> = items.iter().map(|(b, _)| b.max[a] - b.min[a]).collect();
            let median = *ext.select_nth_unstable_by(n / 2, f32::total_cmp).1;
            let want = if size[a] <= 0.0 {
                1.0
            } else if median > 0.0 {
                (size[a] / (2.0 * median)).ceil()
            } else {
                max_cells as f32
            };
            want.clamp(1.0, max_cells as f32) as usize
        });
        let coarsen = |dims: &mut [usize; 3]| {
            let a = (0..3).rev().max_by_key(|&a| dims[a]).expect("three axes");
            dims[a] = dims[a].div_ceil(2);
        };
        while dims.iter().product::<usize>() > max_cells {
            coarsen(&mut dims);
        }
        let (cells, total) = loop {
            let cells = Cells::new(bounds, dims);
            let total = cells.entries(&items);
            if total <= ENTRIES_PER_ITEM * n {
                break (cells, total);
            }
            coarsen(&mut dims);
        };
        if total > MEAN_LIST * cells.len() {
            return None;
        }
        // Groups per cell: its entries, four by four.
        let mut count = vec![0u32; cells.len()];
        for (b, _) in &items {
            cells.each(b, |c| count[c] += 1);
        }
        let mut first = Vec::with_capacity(cells.len() + 1);
        let mut groups = 0usize;
        first.push(0);
        for &k in &count {
            groups += k.div_ceil(4) as usize;
            first.push(u32::try_from(groups).ok()?);
        }
        let mut groups = vec![Group::EMPTY; groups];
        let mut children = Vec::new();
        count.fill(0);
        for &(support, payload) in &items {
            let (params, child) = match round(payload) {
                Some(k) => (k.params(), 0),
                None => {
                    children.push((support, payload));
                    (Group::EMPTY.k.map(|v| v.x), children.len() as u32)
                }
            };
            cells.each(&support, |c| {
                let at = count[c] as usize;
                let g = &mut groups[first[c] as usize + at / 4];
                g.set(at % 4, params);
                g.child[at % 4] = child;
                count[c] += 1;
            });
        }
        Some(PointGrid {
            cells,
            first,
            groups,
            children,
        })
    }

    /// The groups of cell `c`.
    #[inline(always)]
    fn run(&self, c: usize) -> Range<usize> {
        self.first[c] as usize..self.first[c + 1] as usize
    }

    /// `Σ value(payload)` over the items whose boxes contain `p`, in the items' order (a
    /// round kernel adds its own value instead).
    #[inline(always)]
    pub(super) fn sum_at(&self, p: Vec3, value: impl FnMut(u32) -> f32) -> f32 {
        match self.cells.index(p) {
            Some(c) => self.sum_over(p, self.run(c), value),
            None => 0.0,
        }
    }

    /// [`PointGrid::sum_at`] at every point, into `out`, `value(payload, p)` for the items
    /// that are not round kernels. The points go by blocks of [`BLOCK`]: the cells of a
    /// block are computed and their ranges asked for, then the ranges read and the first
    /// groups asked for, then the sums done, so the cache misses of a block's queries
    /// overlap (one query alone waits for two dependent misses) and each cell is computed
    /// once.
    pub(super) fn sums_at(
        &self,
        pts: &[Vec3],
        out: &mut [f32],
        mut value: impl FnMut(u32, Vec3) -> f32,
    ) {
        for (pts, out) in pts.chunks(BLOCK).zip(out.chunks_mut(BLOCK)) {
            let mut cells = [None; BLOCK];
            for (c, &p) in cells.iter_mut().zip(pts) {
                *c = self.cells.index(p);
                if let Some(c) = *c {
                    prefetch(&self.first[c]);
                }
            }
            // A point outside the grid has no groups (its sum is +0).
            let mut runs = [const { 0..0 }; BLOCK];
            for (r, c) in runs.iter_mut().zip(&cells[..pts.len()]) {
                if let Some(c) = *c {
                    *r = self.run(c);
                    if let Some(g) = self.groups[r.clone()].first() {
                        prefetch(g);
                        prefetch(&g.k[4]);
                    }
                }
            }
            for ((o, &p), r) in out.iter_mut().zip(pts).zip(runs) {
                *o = self.sum_over(p, r, |c| value(c, p));
            }
        }
    }

    /// The sum of [`PointGrid::sum_at`] at `p` over the groups `run` of its cell.
    #[inline(always)]
    fn sum_over(&self, p: Vec3, run: Range<usize>, mut value: impl FnMut(u32) -> f32) -> f32 {
        let mut sum = 0.0;
        let q = [Vec4::splat(p.x), Vec4::splat(p.y), Vec4::splat(p.z)];
        for g in &self.groups[run] {
            let v = g.values(&q).to_array();
            if g.child == [0; 4] {
                // In order, as one by one: ((sum + v₀) + v₁) + …
                sum = sum + v[0] + v[1] + v[2] + v[3];
                continue;
            }
            for (v, &child) in v.into_iter().zip(&g.child) {
                sum += v;
                if child != 0 {
                    let (support, payload) = &self.children[child as usize - 1];
                    if support.contains(p) {
                        sum += value(*payload);
                    }
                }
            }
        }
        sum
    }

    /// Bytes held.
    #[cfg(test)]
    pub(super) fn bytes(&self) -> usize {
        self.first.len() * 4
            + self.groups.len() * std::mem::size_of::<Group>()
            + self.children.len() * std::mem::size_of::<(Aabb, u32)>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::Field;
    use crate::field::primitive::{Primitive, PrimitiveSpec};

    /// Each lane of a group is its primitive's value to the bit: inside, on the falloff's
    /// edge, beyond it, at the centre; and a lane without a kernel is +0.
    #[test]
    fn lanes_are_the_primitives_values_to_the_bit() {
        let specs = [
            "(shape: Sphere(center: (1.5, -2, 7), radius: 1.5), falloff: 3)",
            "(shape: Point(center: (0.25, 0.5, -1)), falloff: 5.1, energy: -0.45)",
            "(shape: Sphere(center: (-3, 4, 0), radius: 0.2), falloff: 0.7, energy: 2)",
        ];
        let prims: Vec<Primitive> = specs
            .iter()
            .map(|s| Primitive::from_spec(&ron::from_str::<PrimitiveSpec>(s).unwrap(), 0))
            .collect();
        let mut g = Group::EMPTY;
        for (lane, p) in prims.iter().enumerate() {
            g.set(lane, Round::of(p).expect("a round kernel").params());
        }
        let mut rng = crate::rng::Rng::new(7);
        let mut rnd = || rng.unit();
        let mut points = vec![Vec3::new(1.5, -2.0, 7.0), Vec3::new(0.25, 0.5, -1.0)];
        points.push(Vec3::new(1.5, -2.0, 7.0 + 4.5));
        points.push(Vec3::new(0.25 + 5.1, 0.5, -1.0));
        points.extend((0..20_000).map(|_| Vec3::new(rnd(), rnd(), rnd()) * 20.0 - 10.0));
        for p in points {
            let v = g.values(&[Vec4::splat(p.x), Vec4::splat(p.y), Vec4::splat(p.z)]);
            for (lane, prim) in prims.iter().enumerate() {
                assert_eq!(
                    v[lane].to_bits(),
                    prim.value(p).to_bits(),
                    "{p} lane {lane}"
                );
            }
            assert_eq!(v[3].to_bits(), 0, "{p}");
        }
    }
}

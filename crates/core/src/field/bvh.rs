//! A BVH over the support boxes of a blend's children, so a query touches only the
//! children that can be non-zero there.
//!
//! obvhs builds a binary SAH tree with up to [`WIDTH`] items per leaf; we flatten it into
//! two arrays of [`WIDTH`]-wide nodes that hold their slot boxes inline,
//! structure-of-arrays, so a node test is a few SIMD compares on its own cache lines:
//!
//! * inner nodes, each slot an inner node or a leaf, laid out depth first; they are few
//!   (about one per five leaves), so the descent mostly runs in cache;
//! * leaves, each obvhs leaf's items with their exact boxes (the children's supports), so
//!   a query tests an item's box before the caller ever touches the item, and the items of
//!   a leaf are contiguous.

use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::time::Duration;

use glam::{Vec3, Vec3A, Vec4};
use obvhs::{BvhBuildParams, aabb::Aabb as BvhAabb, bvh2::Bvh2, bvh2::builder::build_bvh2};

use super::bounds::Aabb;
use super::point_grid::PointGrid;
use super::primitive::Round;

/// Blends with at least this many children get a BVH; below it a linear scan of the
/// children's supports is faster.
pub const BVH_MIN_CHILDREN: usize = 16;

/// Boxes with a coordinate beyond this are kept out of the tree (the SAH of the build
/// would overflow) and tested one by one.
const HUGE: f32 = 1e15;

/// Slots per node, and most items per leaf.
const WIDTH: usize = 8;

/// SIMD groups of four slots per node.
const GROUPS: usize = WIDTH / 4;

/// Depth of the traversal stack kept on the machine stack; deeper trees use the heap.
const STACK: usize = 64;

/// One node: the boxes of its slots (x, y, z of the lower then upper corners, one lane per
/// slot) and what each slot holds. Unused slots have empty boxes.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Wide {
    lo: [[Vec4; GROUPS]; 3],
    hi: [[Vec4; GROUPS]; 3],
    /// In an inner node, the index of the inner node or leaf; in a leaf, the payload.
    slot: [u32; WIDTH],
    /// In an inner node, bit `i` set when slot `i` is a leaf.
    leaves: u32,
}

impl Wide {
    const EMPTY: Wide = Wide {
        lo: [[Vec4::INFINITY; GROUPS]; 3],
        hi: [[Vec4::NEG_INFINITY; GROUPS]; 3],
        slot: [0; WIDTH],
        leaves: 0,
    };

    fn set(&mut self, i: usize, b: &Aabb, slot: u32, leaf: bool) {
        for a in 0..3 {
            self.lo[a][i / 4][i % 4] = b.min[a];
            self.hi[a][i / 4][i % 4] = b.max[a];
        }
        self.slot[i] = slot;
        if leaf {
            self.leaves |= 1 << i;
        }
    }

    /// The box of slot `i`.
    fn slot_box(&self, i: usize) -> Aabb {
        let lane =
            |v: &[[Vec4; GROUPS]; 3]| Vec3::from_array([0, 1, 2].map(|a| v[a][i / 4][i % 4]));
        Aabb::new(lane(&self.lo), lane(&self.hi))
    }

    /// Bit mask of the slots that hold something (a non-empty box).
    fn used(&self) -> u32 {
        (0..GROUPS).fold(0, |m, g| {
            m | (self.lo[0][g].cmple(self.hi[0][g])).bitmask() << (4 * g)
        })
    }

    /// True when no slot holds anything (every box empty).
    fn is_empty(&self) -> bool {
        self.used() == 0
    }

    /// Bit mask of the slots whose box contains `p`.
    #[inline(always)]
    fn containing(&self, p: &[Vec4; 3]) -> u32 {
        let mut mask = 0;
        for g in 0..GROUPS {
            let m = self.lo[0][g].cmple(p[0])
                & p[0].cmple(self.hi[0][g])
                & self.lo[1][g].cmple(p[1])
                & p[1].cmple(self.hi[1][g])
                & self.lo[2][g].cmple(p[2])
                & p[2].cmple(self.hi[2][g]);
            mask |= m.bitmask() << (4 * g);
        }
        mask
    }

    /// Bit mask of the slots whose box overlaps the box `lo..hi`.
    #[inline(always)]
    fn overlapping(&self, lo: &[Vec4; 3], hi: &[Vec4; 3]) -> u32 {
        let mut mask = 0;
        for g in 0..GROUPS {
            let m = self.lo[0][g].cmple(hi[0])
                & lo[0].cmple(self.hi[0][g])
                & self.lo[1][g].cmple(hi[1])
                & lo[1].cmple(self.hi[1][g])
                & self.lo[2][g].cmple(hi[2])
                & lo[2].cmple(self.hi[2][g]);
            mask |= m.bitmask() << (4 * g);
        }
        mask
    }

    /// The slots whose (non-empty) box the ray crosses within its span, as a bit mask,
    /// with the parameters where it enters (at least the span's start) and leaves them.
    #[inline(always)]
    fn slabs(&self, r: &SlabRay) -> (u32, [f32; WIDTH], [f32; WIDTH]) {
        let (mut mask, mut enters, mut leaves) = (0, [0.0; WIDTH], [0.0; WIDTH]);
        for g in 0..GROUPS {
            let mut enter = r.t0;
            let mut leave = r.t1;
            for a in 0..3 {
                let p = (self.lo[a][g] - r.o[a]) * r.inv[a];
                let q = (self.hi[a][g] - r.o[a]) * r.inv[a];
                enter = enter.max(p.min(q));
                leave = leave.min(p.max(q));
            }
            let m = enter.cmple(leave + r.pad) & self.lo[0][g].cmple(self.hi[0][g]);
            mask |= m.bitmask() << (4 * g);
            enters[4 * g..4 * g + 4].copy_from_slice(&enter.to_array());
            leaves[4 * g..4 * g + 4].copy_from_slice(&leave.to_array());
        }
        (mask, enters, leaves)
    }
}

/// A ray for slab tests against [`Wide`] nodes: origin and reciprocal direction splatted
/// over the lanes, the parameter range to test, and a slack: a box counts as crossed when
/// the ray's entry is at most `pad` after its exit, so rounding never loses a box the ray
/// grazes.
pub struct SlabRay {
    o: [Vec4; 3],
    inv: [Vec4; 3],
    t0: Vec4,
    t1: Vec4,
    pad: Vec4,
}

impl SlabRay {
    /// The ray `origin + t·dir` over `t ∈ [t0, t1]`, with slack `pad`. A zero direction
    /// component gets a huge finite reciprocal, so a ray in a slab's plane is inside it
    /// (never `0·∞`).
    pub fn new(origin: Vec3, dir: Vec3, (t0, t1): (f32, f32), pad: f32) -> Self {
        let inv = dir.recip().clamp(Vec3::splat(-1e30), Vec3::splat(1e30));
        SlabRay {
            o: [origin.x, origin.y, origin.z].map(Vec4::splat),
            inv: [inv.x, inv.y, inv.z].map(Vec4::splat),
            t0: Vec4::splat(t0),
            t1: Vec4::splat(t1),
            pad: Vec4::splat(pad),
        }
    }

    /// The parameter range where the ray is inside `b` (empty when `lo > hi`), over all
    /// `t`; [`SlabRay::new`]'s span is not applied.
    pub fn clip(&self, b: &Aabb) -> (f32, f32) {
        if b.is_empty() {
            return (f32::INFINITY, f32::NEG_INFINITY);
        }
        let inv = Vec3::new(self.inv[0].x, self.inv[1].x, self.inv[2].x);
        let o = Vec3::new(self.o[0].x, self.o[1].x, self.o[2].x);
        let (a, c) = ((b.min - o) * inv, (b.max - o) * inv);
        (a.min(c).max_element(), a.max(c).min_element())
    }
}

/// A BVH over boxes, each with a `u32` payload (a blend stores the child's node id).
/// Queries call back with the payloads of the boxes that contain a point or overlap a box,
/// exactly those a linear scan with [`Aabb::contains`] / [`Aabb::overlaps`] finds.
pub struct ChildBvh {
    /// Inner nodes; the root is the first.
    nodes: Vec<Wide>,
    /// Leaves: items' boxes and payloads.
    leaves: Vec<Wide>,
    /// Items with boxes too large for the tree, tested one by one.
    huge: Vec<(Aabb, u32)>,
    /// Whether a traversal can need more than [`STACK`] entries.
    deep: bool,
    /// The index of point queries, when [`ChildBvh::index_points`] built one.
    grid: Option<PointGrid>,
}

struct Boxed(BvhAabb);

impl obvhs::Boundable for Boxed {
    fn aabb(&self) -> BvhAabb {
        self.0
    }
}

/// The flattening of an obvhs [`Bvh2`] into inner nodes and leaves.
struct Collapse<'a> {
    bvh: &'a Bvh2,
    boxes: &'a [Aabb],
    payloads: &'a [u32],
    nodes: Vec<Wide>,
    leaves: Vec<Wide>,
    depth: usize,
}

impl Collapse<'_> {
    fn is_leaf(&self, n: u32) -> bool {
        self.bvh.nodes[n as usize].prim_count > 0
    }

    fn aabb(&self, n: u32) -> Aabb {
        let b = self.bvh.nodes[n as usize].aabb();
        Aabb::new(Vec3::from(b.min), Vec3::from(b.max))
    }

    /// Emits obvhs leaf `n` as a leaf; returns its index.
    fn leaf(&mut self, n: u32) -> u32 {
        let node = &self.bvh.nodes[n as usize];
        let first = node.first_index as usize;
        let items = &self.bvh.primitive_indices[first..first + node.prim_count as usize];
        assert!(
            items.len() <= WIDTH,
            "obvhs was asked for at most {WIDTH} items per leaf"
        );
        let mut leaf = Wide::EMPTY;
        for (i, &k) in items.iter().enumerate() {
            leaf.set(i, &self.boxes[k as usize], self.payloads[k as usize], false);
        }
        self.leaves.push(leaf);
        (self.leaves.len() - 1) as u32
    }

    /// Emits the inner node holding the obvhs nodes `open` (opening its largest inner
    /// nodes until the slots are used) and the subtrees below; returns its index.
    fn node(&mut self, mut open: Vec<u32>, depth: usize) -> u32 {
        self.depth = self.depth.max(depth);
        while open.len() < WIDTH {
            let widest = open
                .iter()
                .enumerate()
                .filter(|&(_, &m)| !self.is_leaf(m))
                .max_by(|a, b| {
                    let area = |m: u32| self.bvh.nodes[m as usize].aabb().half_area();
                    area(*a.1).total_cmp(&area(*b.1))
                })
                .map(|(i, &m)| (i, m));
            let Some((i, m)) = widest else { break };
            let first = self.bvh.nodes[m as usize].first_index;
            open.splice(i..=i, [first, first + 1]);
        }
        let at = self.nodes.len();
        self.nodes.push(Wide::EMPTY);
        for (i, m) in open.into_iter().enumerate() {
            let b = self.aabb(m);
            if self.is_leaf(m) {
                let leaf = self.leaf(m);
                self.nodes[at].set(i, &b, leaf, true);
            } else {
                let first = self.bvh.nodes[m as usize].first_index;
                let child = self.node(vec![first, first + 1], depth + 1);
                self.nodes[at].set(i, &b, child, false);
            }
        }
        at as u32
    }
}

impl ChildBvh {
    /// Builds the BVH over `boxes`, item `i` carrying `payloads[i]`. Empty boxes are left
    /// out (they contain nothing).
    pub fn new(boxes: &[Aabb], payloads: &[u32]) -> Self {
        assert_eq!(boxes.len(), payloads.len(), "one payload per box");
        let huge = |b: &Aabb| b.min.abs().max_element() > HUGE || b.max.abs().max_element() > HUGE;
        let mut kept_boxes = Vec::new();
        let mut kept_payloads = Vec::new();
        let mut huge_items = Vec::new();
        for (b, &payload) in boxes.iter().zip(payloads) {
            if b.is_empty() {
                continue;
            }
            if huge(b) {
                huge_items.push((*b, payload));
            } else {
                kept_boxes.push(*b);
                kept_payloads.push(payload);
            }
        }
        let mut bvh = ChildBvh {
            nodes: Vec::new(),
            leaves: Vec::new(),
            huge: huge_items,
            deep: false,
            grid: None,
        };
        if kept_boxes.is_empty() {
            return bvh;
        }
        let prims: Vec<Boxed> = kept_boxes
            .iter()
            .map(|b| Boxed(BvhAabb::new(Vec3A::from(b.min), Vec3A::from(b.max))))
            .collect();
        // Full leaves (a high traversal cost in the collapse) keep the inner nodes few, and
        // a full reinsertion pass cuts the overlap a point query wades through by half.
        let mut params = BvhBuildParams::medium_build();
        params.max_prims_per_leaf = WIDTH as u32;
        params.collapse_traversal_cost = 10.0;
        params.reinsertion_batch_ratio = 1.0;
        let bvh2 = build_bvh2(&prims, params, &mut Duration::default());
        let mut c = Collapse {
            bvh: &bvh2,
            boxes: &kept_boxes,
            payloads: &kept_payloads,
            nodes: Vec::new(),
            leaves: Vec::new(),
            depth: 0,
        };
        c.node(vec![0], 1);
        bvh.deep = c.depth * (WIDTH - 1) + 1 > STACK;
        bvh.nodes = c.nodes;
        bvh.leaves = c.leaves;
        bvh
    }

    /// Adds a grid index for [`ChildBvh::sum_at`] (see [`PointGrid`]), `round(payload)`
    /// being the round kernel of an item that is one; none is kept when the items' sizes
    /// would make it larger than its bound or slow.
    pub(super) fn index_points(&mut self, round: impl Fn(u32) -> Option<Round>) {
        let mut items = Vec::new();
        self.traverse(Wide::used, |leaf, i| {
            items.push((leaf.slot_box(i), leaf.slot[i]));
        });
        self.grid = PointGrid::new(&items, round);
    }

    /// The BVH of the items whose boxes overlap `region`, each payload replaced by
    /// `map(payload)` (items mapped to `None` are dropped), without a rebuild: the nodes
    /// that meet `region` are copied with their slots in place, so a query visits the kept
    /// items in the order this BVH visits them. `map` is called in that order. The point
    /// index is not kept.
    pub fn restricted(&self, region: &Aabb, mut map: impl FnMut(u32) -> Option<u32>) -> Self {
        let lo = [region.min.x, region.min.y, region.min.z].map(Vec4::splat);
        let hi = [region.max.x, region.max.y, region.max.z].map(Vec4::splat);
        let mut out = ChildBvh {
            nodes: Vec::new(),
            leaves: Vec::new(),
            huge: Vec::new(),
            deep: self.deep,
            grid: None,
        };
        if !self.nodes.is_empty() {
            self.restrict_node(0, &lo, &hi, &mut map, &mut out);
        }
        out.huge = self
            .huge
            .iter()
            .filter(|(b, _)| b.overlaps(region))
            .filter_map(|&(b, payload)| map(payload).map(|q| (b, q)))
            .collect();
        out
    }

    /// Copies inner node `n` restricted to `lo..hi` into `out` (depth first, the node
    /// before its subtrees); its index there, or `None` when nothing of it is kept.
    fn restrict_node(
        &self,
        n: u32,
        lo: &[Vec4; 3],
        hi: &[Vec4; 3],
        map: &mut impl FnMut(u32) -> Option<u32>,
        out: &mut ChildBvh,
    ) -> Option<u32> {
        let node = &self.nodes[n as usize];
        let at = out.nodes.len();
        out.nodes.push(Wide::EMPTY);
        let mut kept = Wide::EMPTY;
        let mut mask = node.overlapping(lo, hi);
        while mask != 0 {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            let leaf = node.leaves & (1 << i) != 0;
            let slot = if leaf {
                self.restrict_leaf(node.slot[i], lo, hi, map, out)
            } else {
                self.restrict_node(node.slot[i], lo, hi, map, out)
            };
            if let Some(slot) = slot {
                kept.set(i, &node.slot_box(i), slot, leaf);
            }
        }
        if kept.is_empty() {
            out.nodes.truncate(at);
            return None;
        }
        out.nodes[at] = kept;
        Some(at as u32)
    }

    /// Copies leaf `n`'s items that overlap `lo..hi` and that `map` keeps into `out`.
    fn restrict_leaf(
        &self,
        n: u32,
        lo: &[Vec4; 3],
        hi: &[Vec4; 3],
        map: &mut impl FnMut(u32) -> Option<u32>,
        out: &mut ChildBvh,
    ) -> Option<u32> {
        let leaf = &self.leaves[n as usize];
        let mut kept = Wide::EMPTY;
        let mut mask = leaf.overlapping(lo, hi);
        while mask != 0 {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            if let Some(payload) = map(leaf.slot[i]) {
                kept.set(i, &leaf.slot_box(i), payload, false);
            }
        }
        if kept.is_empty() {
            return None;
        }
        out.leaves.push(kept);
        Some((out.leaves.len() - 1) as u32)
    }

    /// Number of inner nodes and of leaves.
    pub fn node_count(&self) -> (usize, usize) {
        (self.nodes.len(), self.leaves.len())
    }

    /// Depth-first traversal: `hit(node)` gives the mask of slots to follow;
    /// `visit(leaf, slot)` is called for each item found.
    #[inline(always)]
    fn traverse(&self, hit: impl Fn(&Wide) -> u32, mut visit: impl FnMut(&Wide, usize)) {
        if self.nodes.is_empty() {
            return;
        }
        let deep = self.deep;
        let mut stack = Stack::new();
        let mut at = 0u32;
        loop {
            let node = &self.nodes[at as usize];
            let mask = hit(node);
            let mut leaves = mask & node.leaves;
            while leaves != 0 {
                let leaf = &self.leaves[node.slot[leaves.trailing_zeros() as usize] as usize];
                let mut items = hit(leaf);
                while items != 0 {
                    visit(leaf, items.trailing_zeros() as usize);
                    items &= items - 1;
                }
                leaves &= leaves - 1;
            }
            let mut inner = mask & !node.leaves;
            while inner != 0 {
                stack.push(node.slot[inner.trailing_zeros() as usize], deep);
                inner &= inner - 1;
            }
            match stack.pop(deep) {
                Some(n) => at = n,
                None => break,
            }
        }
    }

    /// Calls `visit(payload)` for every item of the tree (not the huge ones) whose box
    /// contains `p`.
    #[inline(always)]
    fn at_tree_point(&self, p: Vec3, mut visit: impl FnMut(u32)) {
        let q = [Vec4::splat(p.x), Vec4::splat(p.y), Vec4::splat(p.z)];
        self.traverse(|n| n.containing(&q), |leaf, i| visit(leaf.slot[i]));
    }

    /// Calls `visit(payload)` for every item whose box contains `p`.
    #[inline]
    pub fn at_point(&self, p: Vec3, mut visit: impl FnMut(u32)) {
        self.at_tree_point(p, &mut visit);
        for (b, payload) in &self.huge {
            if b.contains(p) {
                visit(*payload);
            }
        }
    }

    /// `Σ value(payload)` over the items whose boxes contain `p`, summed in the order
    /// [`ChildBvh::at_point`] visits them (so to the bit), through the point index when
    /// there is one: there an item that is a round kernel adds its own value (0 where
    /// its box does not contain `p`) and `value` is not called for it.
    #[inline]
    pub(super) fn sum_at(&self, p: Vec3, mut value: impl FnMut(u32) -> f32) -> f32 {
        let mut sum = match &self.grid {
            Some(grid) => grid.sum_at(p, &mut value),
            None => {
                let mut sum = 0.0;
                self.at_tree_point(p, |c| sum += value(c));
                sum
            }
        };
        for (b, payload) in &self.huge {
            if b.contains(p) {
                sum += value(*payload);
            }
        }
        sum
    }

    /// `out[i]` = [`ChildBvh::sum_at`]`(pts[i], |c| value(c, pts[i]))` for every point, to
    /// the bit; through the point index, a batch's cache misses overlap (see
    /// [`PointGrid::sums_at`]).
    pub(super) fn sums_at(
        &self,
        pts: &[Vec3],
        out: &mut [f32],
        mut value: impl FnMut(u32, Vec3) -> f32,
    ) {
        let Some(grid) = &self.grid else {
            for (o, &p) in out.iter_mut().zip(pts) {
                *o = self.sum_at(p, |c| value(c, p));
            }
            return;
        };
        grid.sums_at(pts, out, &mut value);
        for (o, &p) in out.iter_mut().zip(pts) {
            for (b, payload) in &self.huge {
                if b.contains(p) {
                    *o += value(*payload, p);
                }
            }
        }
    }

    /// Calls `visit(payload)` for every item whose box overlaps `b`.
    pub fn overlapping(&self, b: &Aabb, mut visit: impl FnMut(u32)) {
        let lo = [b.min.x, b.min.y, b.min.z].map(Vec4::splat);
        let hi = [b.max.x, b.max.y, b.max.z].map(Vec4::splat);
        self.traverse(|n| n.overlapping(&lo, &hi), |leaf, i| visit(leaf.slot[i]));
        for (h, payload) in &self.huge {
            if h.overlaps(b) {
                visit(*payload);
            }
        }
    }

    /// Starts a traversal along `ray` ([`ChildBvh::advance`]); visits the items too large
    /// for the tree that the ray crosses, as `visit(payload, enter, leave)`.
    pub fn start(
        &self,
        ray: &SlabRay,
        cursor: &mut RayCursor,
        mut visit: impl FnMut(u32, f32, f32),
    ) {
        cursor.heap.clear();
        if !self.nodes.is_empty() {
            cursor.heap.push(Pending {
                key: ray.t0.x,
                node: 0,
            });
        }
        for (b, payload) in &self.huge {
            let (enter, leave) = ray.clip(b);
            let enter = enter.max(ray.t0.x);
            if enter <= leave.min(ray.t1.x) + ray.pad.x {
                visit(*payload, enter, leave);
            }
        }
    }

    /// Continues the traversal started by [`ChildBvh::start`]: opens every node the ray
    /// enters at or before `upto` that was not opened yet, and visits the items of the
    /// leaves among them that the ray crosses, as `visit(payload, enter, leave)` (`enter`
    /// at least the ray's start; an item may be entered after `upto`). Nodes entered later
    /// wait in the cursor, nearest first, so every item the ray enters by `upto` has been
    /// visited, each once, and nothing far beyond is opened.
    pub fn advance(
        &self,
        ray: &SlabRay,
        cursor: &mut RayCursor,
        upto: f32,
        mut visit: impl FnMut(u32, f32, f32),
    ) {
        while let Some(&top) = cursor.heap.peek()
            && top.key <= upto
        {
            cursor.heap.pop();
            // The nodes reached by `upto` are opened depth first, without the heap.
            cursor.open.push(top.node);
            while let Some(n) = cursor.open.pop() {
                if n & LEAF != 0 {
                    let leaf = &self.leaves[(n & !LEAF) as usize];
                    let (mut mask, enters, leaves) = leaf.slabs(ray);
                    while mask != 0 {
                        let i = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        visit(leaf.slot[i], enters[i], leaves[i]);
                    }
                    continue;
                }
                let node = &self.nodes[n as usize];
                let (mut mask, enters, _) = node.slabs(ray);
                while mask != 0 {
                    let i = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    let child = node.slot[i] | if node.leaves & (1 << i) != 0 { LEAF } else { 0 };
                    if enters[i] <= upto {
                        cursor.open.push(child);
                    } else {
                        cursor.heap.push(Pending {
                            key: enters[i],
                            node: child,
                        });
                    }
                }
            }
        }
    }
}

/// In a [`RayCursor`], the bit marking a leaf's index.
const LEAF: u32 = 1 << 31;

/// The state of a traversal along a ray: the nodes reached but not opened, nearest entry
/// first. Reuse one: [`ChildBvh::start`] clears it.
#[derive(Debug, Default)]
pub struct RayCursor {
    heap: BinaryHeap<Pending>,
    /// Scratch for [`ChildBvh::advance`]'s depth-first opening.
    open: Vec<u32>,
}

/// A node (an inner node's index, or a leaf's with [`LEAF`] set) the ray enters at `key`.
#[derive(Clone, Copy, Debug)]
struct Pending {
    key: f32,
    node: u32,
}

impl PartialEq for Pending {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other).is_eq()
    }
}

impl Eq for Pending {}

impl PartialOrd for Pending {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// Reversed on `key`: the heap's top is the nearest entry.
impl Ord for Pending {
    fn cmp(&self, other: &Self) -> Ordering {
        other.key.total_cmp(&self.key)
    }
}

/// The traversal stack: on the machine stack, spilling to the heap for deep trees.
struct Stack {
    local: [u32; STACK],
    len: usize,
    spill: Vec<u32>,
}

impl Stack {
    #[inline(always)]
    fn new() -> Self {
        Stack {
            local: [0; STACK],
            len: 0,
            spill: Vec::new(),
        }
    }

    #[inline(always)]
    fn push(&mut self, n: u32, deep: bool) {
        if deep && self.len == STACK {
            self.spill.push(n);
        } else {
            self.local[self.len] = n;
            self.len += 1;
        }
    }

    #[inline(always)]
    fn pop(&mut self, deep: bool) -> Option<u32> {
        if deep && let Some(n) = self.spill.pop() {
            return Some(n);
        }
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        Some(self.local[self.len])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f32 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (self.0 >> 40) as f32 / (1u64 << 24) as f32
        }
        fn point(&mut self, lo: f32, hi: f32) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next()) * (hi - lo) + Vec3::splat(lo)
        }
    }

    /// Random boxes, with duplicates, flat and point boxes, empty and unbounded ones.
    fn boxes(n: usize, rng: &mut Rng) -> Vec<Aabb> {
        (0..n)
            .map(|i| match i % 17 {
                0 => Aabb::EMPTY,
                1 => Aabb::new(Vec3::splat(-f32::MAX), Vec3::splat(f32::MAX)),
                2 => {
                    let c = rng.point(-50.0, 50.0);
                    Aabb::new(c, c)
                }
                3 => {
                    let c = rng.point(-50.0, 50.0);
                    Aabb::new(c, c + Vec3::new(3.0, 0.0, 1.0))
                }
                4 if i > 4 => Aabb::around(Vec3::splat(1.0), 2.0),
                _ => Aabb::around(rng.point(-50.0, 50.0), 0.5 + 6.0 * rng.next()),
            })
            .collect()
    }

    fn sorted(mut v: Vec<u32>) -> Vec<u32> {
        v.sort_unstable();
        v
    }

    /// The flattened tree answers exactly like a linear scan of the boxes, for points and
    /// boxes, whatever the number of items (one, a partly filled node, thousands).
    #[test]
    fn answers_like_a_linear_scan() {
        let mut rng = Rng(3);
        for n in [1, 2, 3, 5, 16, 100, 3000] {
            let boxes = boxes(n, &mut rng);
            let payloads: Vec<u32> = (0..n as u32).map(|i| i * 7 + 1).collect();
            let bvh = ChildBvh::new(&boxes, &payloads);
            let mut points: Vec<Vec3> = (0..500).map(|_| rng.point(-60.0, 60.0)).collect();
            // Corners of the boxes: the closed-box convention must match exactly.
            points.extend(
                boxes
                    .iter()
                    .filter(|b| !b.is_empty())
                    .flat_map(|b| [b.min, b.max]),
            );
            for p in points {
                let mut got = Vec::new();
                bvh.at_point(p, |i| got.push(i));
                let want: Vec<u32> = (0..n)
                    .filter(|&i| boxes[i].contains(p))
                    .map(|i| payloads[i])
                    .collect();
                assert_eq!(sorted(got), want, "{n} items, point {p}");
            }
            for _ in 0..300 {
                let q = Aabb::around(rng.point(-60.0, 60.0), 10.0 * rng.next());
                let mut got = Vec::new();
                bvh.overlapping(&q, |i| got.push(i));
                let want: Vec<u32> = (0..n)
                    .filter(|&i| boxes[i].overlaps(&q))
                    .map(|i| payloads[i])
                    .collect();
                assert_eq!(sorted(got), want, "{n} items, box {q:?}");
            }
        }
    }

    /// Restricted to a region, the tree answers like a linear scan of the items that
    /// overlap the region and that the map keeps, with the mapped payloads, and it visits
    /// them in the order the whole tree does.
    #[test]
    fn restricted_answers_like_the_whole_tree_in_its_region() {
        let mut rng = Rng(11);
        let n = 3000;
        let boxes = boxes(n, &mut rng);
        let payloads: Vec<u32> = (0..n as u32).collect();
        let bvh = ChildBvh::new(&boxes, &payloads);
        for _ in 0..40 {
            let region = Aabb::around(rng.point(-60.0, 60.0), 25.0 * rng.next());
            // Drop every third payload; shift the others.
            let keep = |i: u32| (!i.is_multiple_of(3)).then_some(i + 100_000);
            let mut mapped = Vec::new();
            let small = bvh.restricted(&region, |i| {
                let q = keep(i);
                mapped.extend(q);
                q
            });
            let want: Vec<u32> = (0..n)
                .filter(|&i| boxes[i].overlaps(&region))
                .filter_map(|i| keep(i as u32))
                .collect();
            assert_eq!(sorted(mapped), sorted(want));
            for _ in 0..200 {
                let t = Vec3::new(rng.next(), rng.next(), rng.next());
                let p = region.min + t * (region.max - region.min);
                let (mut got, mut whole) = (Vec::new(), Vec::new());
                small.at_point(p, |i| got.push(i));
                bvh.at_point(p, |i| whole.extend(keep(i)));
                assert_eq!(got, whole, "point {p} of {region:?}");
            }
        }
    }

    /// Through its point index, the tree sums exactly the items its traversal visits, in
    /// the traversal's order (so the sums are the same to the bit): for random points, for
    /// points on the boxes' corners and faces and just outside them, and outside them all.
    /// An index that missed an item, listed one twice or out of order would fail here.
    #[test]
    fn point_index_sums_in_the_traversal_order() {
        let mut rng = Rng(17);
        for n in [16, 100, 3000] {
            let boxes = boxes(n, &mut rng);
            let payloads: Vec<u32> = (0..n as u32).map(|i| i * 3 + 2).collect();
            let mut bvh = ChildBvh::new(&boxes, &payloads);
            bvh.index_points(|_| None);
            let grid = bvh.grid.as_ref().expect("an index");
            assert!(
                grid.bytes() <= 548 * n,
                "{} bytes for {n} items",
                grid.bytes()
            );
            let mut points: Vec<Vec3> = (0..2000).map(|_| rng.point(-70.0, 70.0)).collect();
            points.extend([Vec3::splat(1e4), Vec3::NAN]);
            for b in boxes.iter().filter(|b| !b.is_empty()) {
                let c = b.center();
                let just = |v: Vec3, up: bool| -> Vec3 {
                    v.to_array()
                        .map(|x| if up { x.next_up() } else { x.next_down() })
                        .into()
                };
                points.extend([b.min, b.max, c, Vec3::new(b.min.x, c.y, b.max.z)]);
                points.extend([just(b.min, false), just(b.max, true)]);
            }
            let weight = |c: u32| 1.0 / (c as f32 + 0.37);
            for p in points {
                let mut want = Vec::new();
                bvh.at_point(p, |c| want.push(c));
                let mut got = Vec::new();
                let sum = bvh.sum_at(p, |c| {
                    got.push(c);
                    weight(c)
                });
                assert_eq!(got, want, "{n} items, point {p}");
                let want_sum = want.iter().fold(0.0f32, |s, &c| s + weight(c));
                assert_eq!(sum.to_bits(), want_sum.to_bits(), "{n} items, point {p}");
            }
        }
    }

    /// Leaves hold several items and inner nodes several leaves, so the inner nodes the
    /// descent reads are few.
    #[test]
    fn nodes_are_filled() {
        let mut rng = Rng(5);
        let boxes: Vec<Aabb> = (0..4000)
            .map(|_| Aabb::around(rng.point(0.0, 1000.0), 2.0))
            .collect();
        let payloads: Vec<u32> = (0..4000).collect();
        let bvh = ChildBvh::new(&boxes, &payloads);
        let (inner, leaves) = bvh.node_count();
        assert!(
            leaves <= 4000 / 4 && inner <= leaves / 2,
            "{inner} inner nodes, {leaves} leaves"
        );
        assert!(bvh.huge.is_empty() && !bvh.deep);
    }
}

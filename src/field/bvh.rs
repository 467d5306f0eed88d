//! A BVH over the support boxes of a blend's children, so a query touches only the
//! children that can be non-zero there.
//!
//! obvhs builds a binary SAH tree (one child per leaf); we collapse it into a flat array
//! of 4-wide nodes that hold their four slot boxes inline, structure-of-arrays, so one
//! node test is a handful of SIMD compares on two cache lines. A slot is either an inner
//! node or one item, whose box is the item's exact support: a query tests the item's box
//! before the caller ever touches the item. Nodes are laid out depth first, so the top of
//! the tree stays in cache and a subtree is contiguous.

use std::time::Duration;

use glam::{Vec3, Vec3A, Vec4};
use obvhs::{BvhBuildParams, aabb::Aabb as BvhAabb, bvh2::Bvh2, bvh2::builder::build_bvh2};

use super::bounds::Aabb;

/// Blends with at least this many children get a BVH; below it a linear scan of the
/// children's supports is faster.
pub const BVH_MIN_CHILDREN: usize = 16;

/// Boxes with a coordinate beyond this are kept out of the tree (the SAH of the build
/// would overflow) and tested one by one.
const HUGE: f32 = 1e15;

/// Width of the collapsed nodes.
const WIDTH: usize = 4;

/// Depth of the traversal stack kept on the machine stack; deeper trees use the heap.
const STACK: usize = 64;

/// One 4-wide node: the boxes of its slots (x, y, z of the lower then upper corners, one
/// lane per slot) and what each slot holds. Unused slots have empty boxes.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Wide {
    lo: [Vec4; 3],
    hi: [Vec4; 3],
    /// Index of the inner node, or the item's payload.
    slot: [u32; WIDTH],
    /// Bit `i` set when slot `i` holds an item.
    items: u32,
}

impl Wide {
    const EMPTY: Wide = Wide {
        lo: [Vec4::INFINITY; 3],
        hi: [Vec4::NEG_INFINITY; 3],
        slot: [0; WIDTH],
        items: 0,
    };

    fn set(&mut self, i: usize, b: &Aabb, slot: u32, item: bool) {
        for a in 0..3 {
            self.lo[a][i] = b.min[a];
            self.hi[a][i] = b.max[a];
        }
        self.slot[i] = slot;
        if item {
            self.items |= 1 << i;
        }
    }

    /// Bit mask of the slots whose box contains `p`.
    #[inline(always)]
    fn containing(&self, p: &[Vec4; 3]) -> u32 {
        let m = self.lo[0].cmple(p[0])
            & p[0].cmple(self.hi[0])
            & self.lo[1].cmple(p[1])
            & p[1].cmple(self.hi[1])
            & self.lo[2].cmple(p[2])
            & p[2].cmple(self.hi[2]);
        m.bitmask()
    }

    /// Bit mask of the slots whose box overlaps the box `lo..hi`.
    #[inline(always)]
    fn overlapping(&self, lo: &[Vec4; 3], hi: &[Vec4; 3]) -> u32 {
        let m = self.lo[0].cmple(hi[0])
            & lo[0].cmple(self.hi[0])
            & self.lo[1].cmple(hi[1])
            & lo[1].cmple(self.hi[1])
            & self.lo[2].cmple(hi[2])
            & lo[2].cmple(self.hi[2]);
        m.bitmask()
    }
}

/// A BVH over boxes, each with a `u32` payload (a blend stores the child's node id).
/// Queries call back with the payloads of the boxes that contain a point or overlap a box,
/// exactly those a linear scan with [`Aabb::contains`] / [`Aabb::overlaps`] finds.
pub struct ChildBvh {
    nodes: Vec<Wide>,
    /// Items with boxes too large for the tree, tested one by one.
    huge: Vec<(Aabb, u32)>,
    /// Whether a traversal can need more than [`STACK`] entries.
    deep: bool,
}

struct Boxed(BvhAabb);

impl obvhs::Boundable for Boxed {
    fn aabb(&self) -> BvhAabb {
        self.0
    }
}

/// A slot of a wide node before it is emitted.
#[derive(Clone, Copy)]
enum Slot {
    /// Item `i` of the input.
    Item(usize),
    /// obvhs inner node `n`.
    Inner(u32),
}

/// The flattening of an obvhs [`Bvh2`] with one item per leaf into [`Wide`] nodes.
struct Collapse<'a> {
    bvh: &'a Bvh2,
    boxes: &'a [Aabb],
    payloads: &'a [u32],
    nodes: Vec<Wide>,
    depth: usize,
}

impl Collapse<'_> {
    fn slot(&self, n: u32) -> Slot {
        let node = &self.bvh.nodes[n as usize];
        if node.prim_count == 0 {
            Slot::Inner(n)
        } else {
            assert_eq!(node.prim_count, 1, "obvhs was asked for one item per leaf");
            Slot::Item(self.bvh.primitive_indices[node.first_index as usize] as usize)
        }
    }

    fn half_area(&self, s: Slot) -> f32 {
        match s {
            Slot::Inner(n) => self.bvh.nodes[n as usize].aabb().half_area(),
            Slot::Item(_) => f32::NEG_INFINITY,
        }
    }

    /// Emits the wide node holding `open` (opening its largest inner nodes until the
    /// slots are used) and the subtrees below; returns its index.
    fn node(&mut self, mut open: Vec<Slot>, depth: usize) -> u32 {
        self.depth = self.depth.max(depth);
        while open.len() < WIDTH {
            let (i, widest) = open
                .iter()
                .enumerate()
                .max_by(|a, b| self.half_area(*a.1).total_cmp(&self.half_area(*b.1)))
                .expect("a node has a slot");
            let Slot::Inner(n) = *widest else { break };
            let first = self.bvh.nodes[n as usize].first_index;
            open.splice(i..=i, [self.slot(first), self.slot(first + 1)]);
        }
        let at = self.nodes.len();
        self.nodes.push(Wide::EMPTY);
        for (i, s) in open.into_iter().enumerate() {
            match s {
                Slot::Item(k) => self.nodes[at].set(i, &self.boxes[k], self.payloads[k], true),
                Slot::Inner(n) => {
                    let b = self.bvh.nodes[n as usize].aabb();
                    let b = Aabb::new(Vec3::from(b.min), Vec3::from(b.max));
                    let first = self.bvh.nodes[n as usize].first_index;
                    let child = self.node(vec![self.slot(first), self.slot(first + 1)], depth + 1);
                    self.nodes[at].set(i, &b, child, false);
                }
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
            huge: huge_items,
            deep: false,
        };
        if kept_boxes.is_empty() {
            return bvh;
        }
        let prims: Vec<Boxed> = kept_boxes
            .iter()
            .map(|b| Boxed(BvhAabb::new(Vec3A::from(b.min), Vec3A::from(b.max))))
            .collect();
        let mut params = BvhBuildParams::medium_build();
        params.max_prims_per_leaf = 1;
        let bvh2 = build_bvh2(&prims, params, &mut Duration::default());
        let mut c = Collapse {
            bvh: &bvh2,
            boxes: &kept_boxes,
            payloads: &kept_payloads,
            nodes: Vec::with_capacity(kept_boxes.len() / (WIDTH - 1) + 1),
            depth: 0,
        };
        c.node(vec![c.slot(0)], 1);
        bvh.deep = c.depth * (WIDTH - 1) + 1 > STACK;
        bvh.nodes = c.nodes;
        bvh
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

impl ChildBvh {
    /// Number of wide nodes (for tests and statistics).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Depth-first traversal: `hit(node)` gives the mask of slots to follow.
    #[inline(always)]
    fn traverse(&self, hit: impl Fn(&Wide) -> u32, mut visit: impl FnMut(u32)) {
        if !self.nodes.is_empty() {
            let deep = self.deep;
            let mut stack = Stack::new();
            let mut at = 0u32;
            loop {
                let node = &self.nodes[at as usize];
                let mask = hit(node);
                let mut items = mask & node.items;
                while items != 0 {
                    visit(node.slot[items.trailing_zeros() as usize]);
                    items &= items - 1;
                }
                let mut inner = mask & !node.items;
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
    }

    /// Calls `visit(payload)` for every item whose box contains `p`.
    #[inline]
    pub fn at_point(&self, p: Vec3, mut visit: impl FnMut(u32)) {
        let q = [Vec4::splat(p.x), Vec4::splat(p.y), Vec4::splat(p.z)];
        self.traverse(|n| n.containing(&q), &mut visit);
        for (b, payload) in &self.huge {
            if b.contains(p) {
                visit(*payload);
            }
        }
    }

    /// Calls `visit(payload)` for every item whose box overlaps `b`.
    pub fn overlapping(&self, b: &Aabb, mut visit: impl FnMut(u32)) {
        let lo = [b.min.x, b.min.y, b.min.z].map(Vec4::splat);
        let hi = [b.max.x, b.max.y, b.max.z].map(Vec4::splat);
        self.traverse(|n| n.overlapping(&lo, &hi), &mut visit);
        for (h, payload) in &self.huge {
            if h.overlaps(b) {
                visit(*payload);
            }
        }
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

    /// Opening the widest inner nodes fills the slots: at most one wide node for two
    /// items (a binary tree has one per item).
    #[test]
    fn nodes_are_filled() {
        let mut rng = Rng(5);
        let boxes: Vec<Aabb> = (0..4000)
            .map(|_| Aabb::around(rng.point(0.0, 1000.0), 2.0))
            .collect();
        let payloads: Vec<u32> = (0..4000).collect();
        let bvh = ChildBvh::new(&boxes, &payloads);
        assert!(bvh.node_count() <= 4000 / 2, "{} nodes", bvh.node_count());
        assert!(bvh.huge.is_empty() && !bvh.deep);
    }
}

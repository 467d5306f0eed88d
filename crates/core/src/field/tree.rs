//! The compiled tree: a flat arena of nodes in post-order with their cached bounds.

use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};

use super::bound::Bound;
use super::bounds::{Aabb, Interval, Rect, ZBands};
use super::bvh::{BVH_MIN_CHILDREN, ChildBvh};
use super::contract::{Elevation, Field};
use super::erode::Erosion;
use super::falloff::ISO;
use super::node::{Node, NodeId, spectral_norm};
use super::primitive::{Primitive, Round};
use super::replace::Transition;
use super::slope_grid::blend_lipschitz;
use super::warp::Warp;

/// What the compiler caches for every node.
#[derive(Clone, Debug)]
pub struct NodeInfo {
    /// Where the node can be non-zero.
    pub support: Aabb,
    /// A range containing every value of the node, and its global Lipschitz bound.
    pub bound: Bound,
    /// The user's name for the node, if any.
    pub name: Option<String>,
}

/// A compiled implicit construction tree: the single thing the mesher, the tracers and the
/// editor consume. It answers the whole [`Field`] contract.
///
/// The arena is split hot and cold: evaluation reads `nodes` (primitives inline) and
/// `supports`; the other cached bounds and the names live in `info`.
pub struct Tree {
    pub(super) nodes: Vec<Node>,
    pub(super) supports: Vec<Aabb>,
    pub(super) info: Vec<NodeInfo>,
    pub(super) root: NodeId,
    /// Whether [`super::Line`]s keep lists: some blend has a BVH, and no node has several
    /// parents (in a DAG a node can be reached along several paths with different maps).
    pub(super) line_lists: bool,
}

/// Builds a [`Tree`] bottom-up: children first, then their parents.
#[derive(Default)]
pub struct TreeBuilder {
    nodes: Vec<Node>,
    info: Vec<NodeInfo>,
}

impl TreeBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        Self::default()
    }

    fn push(&mut self, node: Node, name: Option<String>) -> NodeId {
        let info = self.compute_info(&node, name);
        self.nodes.push(node);
        self.info.push(info);
        (self.nodes.len() - 1) as NodeId
    }

    /// The support box of a node built so far.
    pub fn support(&self, id: NodeId) -> Aabb {
        self.info[id as usize].support
    }

    /// A skeletal primitive, stored inline in the arena.
    pub fn primitive(&mut self, p: Primitive, name: Option<String>) -> NodeId {
        self.push(Node::Primitive(p), name)
    }

    /// A leaf field (use [`TreeBuilder::primitive`] for a [`Primitive`]).
    pub fn leaf(&mut self, field: Arc<dyn Field>, name: Option<String>) -> NodeId {
        self.push(Node::Leaf(field), name)
    }

    /// A constant field (its support is everything when non-zero).
    pub fn constant(&mut self, v: f32, name: Option<String>) -> NodeId {
        self.push(Node::Constant(v), name)
    }

    /// `Σ children`.
    pub fn blend(&mut self, children: Vec<NodeId>, name: Option<String>) -> NodeId {
        let bvh = (children.len() >= BVH_MIN_CHILDREN).then(|| {
            let supports: Vec<Aabb> = children
                .iter()
                .map(|&c| self.info[c as usize].support)
                .collect();
            let mut bvh = ChildBvh::new(&supports, &children);
            bvh.index_points(|c| match &self.nodes[c as usize] {
                Node::Primitive(p) => Round::of(p),
                _ => None,
            });
            bvh
        });
        self.blend_with(children, bvh, name)
    }

    /// `Σ children`, with `bvh` over their supports (its payloads are the children's ids).
    pub(super) fn blend_with(
        &mut self,
        children: Vec<NodeId>,
        bvh: Option<ChildBvh>,
        name: Option<String>,
    ) -> NodeId {
        self.push(
            Node::Blend {
                children: children.into(),
                bvh,
            },
            name,
        )
    }

    /// `max children`.
    pub fn union(&mut self, children: Vec<NodeId>, name: Option<String>) -> NodeId {
        self.push(Node::Union(children.into()), name)
    }

    /// `min children`.
    pub fn intersection(&mut self, children: Vec<NodeId>, name: Option<String>) -> NodeId {
        self.push(Node::Intersection(children.into()), name)
    }

    /// `base` with every `carves` subtree removed.
    pub fn difference(
        &mut self,
        base: NodeId,
        carves: Vec<NodeId>,
        name: Option<String>,
    ) -> NodeId {
        self.push(
            Node::Difference {
                base,
                carves: carves.into(),
            },
            name,
        )
    }

    /// `child` moved by `to_parent` (child space → parent space); must be invertible.
    pub fn transform(
        &mut self,
        child: NodeId,
        to_parent: Affine3A,
        name: Option<String>,
    ) -> NodeId {
        let to_child = to_parent.inverse();
        let stretch = spectral_norm(to_child.matrix3);
        self.push(
            Node::Affine {
                child,
                to_child,
                stretch,
            },
            name,
        )
    }

    /// `base`, replaced by `by` inside `mix`'s region (see [`Transition`]).
    pub fn replace(
        &mut self,
        base: NodeId,
        by: NodeId,
        mix: Transition,
        name: Option<String>,
    ) -> NodeId {
        self.push(
            Node::Replace {
                base,
                by,
                mix: Box::new(mix),
            },
            name,
        )
    }

    /// `child` seen through the turbulence warp `warp`.
    pub fn warp(&mut self, child: NodeId, warp: Warp, name: Option<String>) -> NodeId {
        self.push(
            Node::Warp {
                child,
                warp: Box::new(warp),
            },
            name,
        )
    }

    /// `child` worn away by `erosion` where the rock is soft (Paris et al. 2019 §6).
    pub fn erode(&mut self, child: NodeId, erosion: Erosion, name: Option<String>) -> NodeId {
        self.push(
            Node::Erode {
                child,
                erosion: Box::new(erosion),
            },
            name,
        )
    }

    /// Finishes the tree with `root` as its root.
    pub fn build(self, root: NodeId) -> Tree {
        let mut parents = vec![0u8; self.nodes.len()];
        for c in self.nodes.iter().flat_map(Node::children) {
            parents[c as usize] = parents[c as usize].saturating_add(1);
        }
        let bvh_blends = self
            .nodes
            .iter()
            .any(|n| matches!(n, Node::Blend { bvh: Some(_), .. }));
        Tree {
            line_lists: bvh_blends && parents.iter().all(|&n| n <= 1),
            nodes: self.nodes,
            supports: self.info.iter().map(|i| i.support).collect(),
            info: self.info,
            root,
        }
    }

    fn compute_info(&self, node: &Node, name: Option<String>) -> NodeInfo {
        let info = |c: &NodeId| &self.info[*c as usize];
        let everywhere = Aabb::new(Vec3::splat(-f32::MAX), Vec3::splat(f32::MAX));
        let hull = |cs: &[NodeId]| cs.iter().fold(Aabb::EMPTY, |b, c| b.union(info(c).support));
        let (support, bound) = match node {
            Node::Constant(v) => (
                if *v == 0.0 { Aabb::EMPTY } else { everywhere },
                Bound::constant(*v),
            ),
            Node::Primitive(_) | Node::Leaf(_) => {
                let f = node.leaf().expect("a leaf");
                let s = f.support();
                (s, Bound::new(f.interval(&s), f.lipschitz()).hull_zero())
            }
            Node::Blend { children, .. } => {
                let range = children
                    .iter()
                    .fold(Interval::ZERO, |r, c| r + info(c).bound.range);
                // ∇ of a sum is the sum of the gradients of the children non-zero at a
                // point: a sharper slope than the sum rule's where supports are apart.
                let slopes: Vec<(Aabb, f32)> = children
                    .iter()
                    .map(|c| (info(c).support, info(c).bound.lipschitz))
                    .collect();
                (hull(children), Bound::new(range, blend_lipschitz(&slopes)))
            }
            Node::Union(children) | Node::Intersection(children) => {
                let is_union = matches!(node, Node::Union(_));
                let bounds = children.iter().map(|c| info(c).bound);
                let bound = if is_union {
                    bounds.reduce(Bound::max)
                } else {
                    bounds.reduce(Bound::min)
                }
                .unwrap_or(Bound::ZERO);
                let any_negative = children.iter().any(|c| info(c).bound.range.lo < 0.0);
                let support = if is_union || any_negative {
                    hull(children)
                } else {
                    children
                        .iter()
                        .fold(hull(children), |b, c| b.intersection(info(c).support))
                };
                (support, bound.hull_zero())
            }
            Node::Difference { base, carves } => {
                // `min(f_base, 2T − max f_c)`: the carves' maximum, which is negative
                // where every carve is (negative energies), not clamped at 0.
                let carve = carves.iter().map(|c| info(c).bound).reduce(Bound::max);
                let bound = match carve {
                    Some(c) => info(base).bound.min(c.scale(-1.0).shift(2.0 * ISO)),
                    None => info(base).bound,
                };
                let support = if carve.is_some_and(|c| c.range.hi > 2.0 * ISO) {
                    carves
                        .iter()
                        .fold(info(base).support, |b, c| b.union(info(c).support))
                } else {
                    info(base).support
                };
                (support, bound.hull_zero())
            }
            Node::Replace { base, by, mix } => {
                let (b, v) = (info(base), info(by));
                let support = b.support.union(v.support.intersection(*mix.region()));
                let w = Interval::new(0.0, 1.0);
                (support, b.bound.mix(v.bound, w, mix.lipschitz()))
            }
            Node::Affine {
                child,
                to_child,
                stretch,
            } => {
                let s = info(child).support;
                let to_parent = to_child.inverse();
                let support = if s.is_empty() {
                    s
                } else {
                    Aabb::from_points(s.corners().map(|c| to_parent.transform_point3(c)))
                };
                (support, info(child).bound.warped(*stretch))
            }
            Node::Warp { child, warp } => {
                let s = info(child).support;
                let support = if s.is_empty() {
                    s
                } else {
                    s.dilate(warp.reach())
                };
                (support, info(child).bound.warped(warp.lipschitz()))
            }
            Node::Erode { child, erosion } => {
                let c = info(child);
                // f − e with e ∈ [0, a], non-zero only in the region.
                let support = if erosion.strength() > 0.0 {
                    c.support.union(*erosion.region())
                } else {
                    c.support
                };
                let e = Bound::new(Interval::new(0.0, erosion.strength()), erosion.lipschitz());
                (support, (c.bound + e.scale(-1.0)).hull_zero())
            }
        };
        NodeInfo {
            support,
            bound,
            name,
        }
    }
}

impl Tree {
    /// Whether tracing along [`super::Line`]s pays: some blend has a BVH (and the tree is
    /// not a DAG). Without lists a line answers through the BVHs like the tree itself.
    pub fn keeps_line_lists(&self) -> bool {
        self.line_lists
    }

    /// The root node.
    pub fn root(&self) -> NodeId {
        self.root
    }

    /// All nodes, children before parents.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// Cached bounds and name of a node.
    pub fn info(&self, id: NodeId) -> &NodeInfo {
        &self.info[id as usize]
    }

    /// The node with the user name `name`.
    pub fn find(&self, name: &str) -> Option<NodeId> {
        self.info
            .iter()
            .position(|i| i.name.as_deref() == Some(name))
            .map(|i| i as NodeId)
    }

    /// The subtree rooted at `id` as a tree of its own (shares leaves, no copy of data).
    pub fn subtree(&self, id: NodeId) -> SubTree<'_> {
        SubTree { tree: self, id }
    }
}

impl Tree {
    /// [`Field::eval_column`] of node `id`: where the node is a leaf, the leaf's own
    /// (0 outside the node's support, as [`Tree::value_at`] gives); `false` otherwise.
    pub fn eval_column_at(&self, id: NodeId, xy: Vec2, zs: &[f32], out: &mut [f32]) -> bool {
        let Node::Leaf(f) = &self.nodes[id as usize] else {
            return false;
        };
        if !f.eval_column(xy, zs, out) {
            return false;
        }
        let support = &self.supports[id as usize];
        for (o, &z) in out.iter_mut().zip(zs) {
            if !support.contains(xy.extend(z)) {
                *o = 0.0;
            }
        }
        true
    }

    /// [`Field::z_bands_clip`] of node `id`: a leaf's own (its support's clipping is an
    /// intersection too); `false` otherwise.
    pub fn z_bands_clip_at(&self, id: NodeId) -> bool {
        matches!(&self.nodes[id as usize], Node::Leaf(f) if f.z_bands_clip())
    }
}

/// A view of one node of a tree as a [`Field`].
#[derive(Clone, Copy)]
pub struct SubTree<'t> {
    pub(super) tree: &'t Tree,
    pub(super) id: NodeId,
}

impl Field for SubTree<'_> {
    fn value(&self, p: Vec3) -> f32 {
        self.tree.value_at(self.id, p)
    }
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        self.tree.value_grad_at(self.id, p)
    }
    fn support(&self) -> Aabb {
        self.tree.info(self.id).support
    }
    fn interval(&self, b: &Aabb) -> Interval {
        self.tree.interval_at(self.id, b)
    }
    fn lipschitz(&self) -> f32 {
        self.tree.info(self.id).bound.lipschitz
    }
    fn lipschitz_box(&self, b: &Aabb) -> f32 {
        self.tree.lipschitz_box_at(self.id, b)
    }
    fn lipschitz_segment(&self, a: Vec3, b: Vec3) -> f32 {
        self.tree.lipschitz_segment_at(self.id, a, b)
    }
    fn z_bands(&self, fp: &Rect, z: Interval, out: &mut ZBands) {
        self.tree.z_bands_at(self.id, fp, z, out)
    }
    fn elevation(&self, fp: &Rect) -> Option<Elevation<'_>> {
        self.tree.elevation_at(self.id, fp)
    }
    fn prune(&self, region: &Aabb) -> Option<Box<dyn Field + '_>> {
        Some(Box::new(self.tree.pruned(self.id, region)))
    }
    fn eval_block(&self, origin: Vec3, step: Vec3, dims: [usize; 3], out: &mut [f32]) {
        self.tree.eval_block_at(self.id, origin, step, dims, out)
    }
    fn eval_column(&self, xy: Vec2, zs: &[f32], out: &mut [f32]) -> bool {
        self.tree.eval_column_at(self.id, xy, zs, out)
    }
    fn z_bands_clip(&self) -> bool {
        self.tree.z_bands_clip_at(self.id)
    }
}

impl Field for Tree {
    fn value(&self, p: Vec3) -> f32 {
        self.value_at(self.root, p)
    }
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        self.value_grad_at(self.root, p)
    }
    fn support(&self) -> Aabb {
        self.info(self.root).support
    }
    fn interval(&self, b: &Aabb) -> Interval {
        self.interval_at(self.root, b)
    }
    fn lipschitz(&self) -> f32 {
        self.info(self.root).bound.lipschitz
    }
    fn lipschitz_box(&self, b: &Aabb) -> f32 {
        self.lipschitz_box_at(self.root, b)
    }
    fn lipschitz_segment(&self, a: Vec3, b: Vec3) -> f32 {
        self.lipschitz_segment_at(self.root, a, b)
    }
    fn z_bands(&self, fp: &Rect, z: Interval, out: &mut ZBands) {
        self.z_bands_at(self.root, fp, z, out)
    }
    fn elevation(&self, fp: &Rect) -> Option<Elevation<'_>> {
        self.elevation_at(self.root, fp)
    }
    fn prune(&self, region: &Aabb) -> Option<Box<dyn Field + '_>> {
        Some(Box::new(self.pruned(self.root, region)))
    }
    fn eval_block(&self, origin: Vec3, step: Vec3, dims: [usize; 3], out: &mut [f32]) {
        self.eval_block_at(self.root, origin, step, dims, out)
    }
    fn eval_column(&self, xy: Vec2, zs: &[f32], out: &mut [f32]) -> bool {
        self.eval_column_at(self.root, xy, zs, out)
    }
    fn z_bands_clip(&self) -> bool {
        self.z_bands_clip_at(self.root)
    }
    /// The tree itself, so consumers can read its size (the renderer prunes small trees
    /// per tile).
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

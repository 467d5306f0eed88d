//! The tree restricted to a line: per-ray lists of the children of its large blends.
//!
//! A tracer asks the same tree for values and segment bounds many times along one ray, and
//! each ask of a blend with thousands of children descends the blend's BVH. A [`Line`]
//! keeps instead, for every blend with a BVH that the ray reaches through blends, unions,
//! differences and affine maps, the children whose supports the ray crosses, with the ray
//! parameters where it is inside them; [`Line::value`], [`Line::lipschitz`] and
//! [`Line::value_grad`] scan these short lists, and the first two evaluate point blobs
//! from their profile along the ray — the per-ray gathering of segment tracing (Galin et
//! al. 2020 §5). The lists grow lazily: each blend traverses its BVH along the ray
//! ([`ChildBvh::advance`]) only as far as the queries go.
//!
//! Affine maps send lines to lines with the same parameter, so the lists of blends below
//! them are indexed by the root ray's `t`. Warps bend the line: what lies below one is
//! evaluated as usual. The answers are those of the whole tree: a list only drops
//! children whose supports the ray does not reach, and every listed child that is not a
//! profiled blob is still tested against its support.

use std::mem::take;

use glam::Vec3;

use super::bounds::Aabb;
use super::bvh::{ChildBvh, RayCursor, SlabRay};
use super::node::{Node, NodeId};
use super::profile::LineProfile;
use super::tree::Tree;

/// Where a blend finds the children that can be non-zero at a query.
pub(super) trait Candidates: Copy {
    /// `Σ value(c)` over the children `c` of blend `id` whose supports contain `p`.
    fn sum_containing(
        self,
        tree: &Tree,
        id: NodeId,
        children: &[NodeId],
        bvh: &Option<ChildBvh>,
        p: Vec3,
        value: impl FnMut(NodeId) -> f32,
    ) -> f32;

    /// `Σ bound(c)` over the children `c` of blend `id` whose supports overlap `b`.
    fn sum_overlapping(
        self,
        tree: &Tree,
        id: NodeId,
        children: &[NodeId],
        bvh: &Option<ChildBvh>,
        b: &Aabb,
        bound: impl FnMut(NodeId) -> f32,
    ) -> f32;

    /// Calls `visit(c)` for each child `c` of blend `id` whose support contains `p`, as
    /// a node (a listed blob too: gradients need the node, not its profile).
    fn each_containing(
        self,
        tree: &Tree,
        id: NodeId,
        children: &[NodeId],
        bvh: &Option<ChildBvh>,
        p: Vec3,
        visit: impl FnMut(NodeId),
    );
}

/// Queries anywhere: the blends' BVHs (or a scan of small blends' children).
#[derive(Clone, Copy)]
pub(super) struct Anywhere;

impl Candidates for Anywhere {
    #[inline(always)]
    fn sum_containing(
        self,
        tree: &Tree,
        id: NodeId,
        children: &[NodeId],
        bvh: &Option<ChildBvh>,
        p: Vec3,
        mut value: impl FnMut(NodeId) -> f32,
    ) -> f32 {
        match bvh {
            Some(bvh) => bvh.sum_at(p, value),
            None => {
                let mut sum = 0.0;
                self.each_containing(tree, id, children, bvh, p, |c| sum += value(c));
                sum
            }
        }
    }

    #[inline(always)]
    fn each_containing(
        self,
        tree: &Tree,
        _: NodeId,
        children: &[NodeId],
        bvh: &Option<ChildBvh>,
        p: Vec3,
        mut visit: impl FnMut(NodeId),
    ) {
        match bvh {
            Some(bvh) => bvh.at_point(p, visit),
            None => children
                .iter()
                .filter(|&&c| tree.supports[c as usize].contains(p))
                .for_each(|&c| visit(c)),
        }
    }

    #[inline(always)]
    fn sum_overlapping(
        self,
        tree: &Tree,
        _: NodeId,
        children: &[NodeId],
        bvh: &Option<ChildBvh>,
        b: &Aabb,
        mut bound: impl FnMut(NodeId) -> f32,
    ) -> f32 {
        let mut sum = 0.0;
        tree.blend_children_in(children, bvh, b, |c| sum += bound(c));
        sum
    }
}

/// Queries at ray parameters `t0..=t1` of a restricted [`Line`].
#[derive(Clone, Copy)]
pub(super) struct OnLine<'a> {
    line: &'a Line<'a>,
    t0: f32,
    t1: f32,
}

impl<'a> OnLine<'a> {
    /// The listed children of blend `id` whose parameter ranges meet `t0..=t1`; `None`
    /// when `id` has no list.
    #[inline(always)]
    fn listed(self, id: NodeId) -> Option<impl Iterator<Item = &'a Crossing>> {
        let at = self.line.slot.get(id as usize).copied().unwrap_or(NONE);
        let (t0, t1) = (self.t0, self.t1);
        (at != NONE).then(|| {
            self.line.fronts[at as usize]
                .items
                .iter()
                .filter(move |c| c.enter <= t1 && c.leave >= t0)
        })
    }

    /// Sums over [`OnLine::listed`]: `profiled(profile)` for the children with a
    /// [`LineProfile`], `each(c)` for the others that pass `keep`.
    #[inline(always)]
    fn sum_listed(
        self,
        id: NodeId,
        profiled: impl Fn(&LineProfile) -> f32,
        keep: impl Fn(NodeId) -> bool,
        mut each: impl FnMut(NodeId) -> f32,
    ) -> Option<f32> {
        let items = self.listed(id)?;
        let mut sum = 0.0;
        for c in items {
            match &c.profile {
                Some(profile) => sum += profiled(profile),
                None if keep(c.child) => sum += each(c.child),
                None => {}
            }
        }
        Some(sum)
    }
}

impl Candidates for OnLine<'_> {
    #[inline(always)]
    fn sum_containing(
        self,
        tree: &Tree,
        id: NodeId,
        children: &[NodeId],
        bvh: &Option<ChildBvh>,
        p: Vec3,
        mut value: impl FnMut(NodeId) -> f32,
    ) -> f32 {
        let t = self.t0;
        let inside = |c: NodeId| tree.supports[c as usize].contains(p);
        self.sum_listed(id, |pr| pr.value(t), inside, &mut value)
            .unwrap_or_else(|| Anywhere.sum_containing(tree, id, children, bvh, p, value))
    }

    #[inline(always)]
    fn sum_overlapping(
        self,
        tree: &Tree,
        id: NodeId,
        children: &[NodeId],
        bvh: &Option<ChildBvh>,
        b: &Aabb,
        mut bound: impl FnMut(NodeId) -> f32,
    ) -> f32 {
        let (t0, t1) = (self.t0, self.t1);
        let meets = |c: NodeId| tree.supports[c as usize].overlaps(b);
        self.sum_listed(id, |pr| pr.lipschitz(t0, t1), meets, &mut bound)
            .unwrap_or_else(|| Anywhere.sum_overlapping(tree, id, children, bvh, b, bound))
    }

    #[inline(always)]
    fn each_containing(
        self,
        tree: &Tree,
        id: NodeId,
        children: &[NodeId],
        bvh: &Option<ChildBvh>,
        p: Vec3,
        mut visit: impl FnMut(NodeId),
    ) {
        match self.listed(id) {
            Some(items) => items
                .filter(|c| tree.supports[c.child as usize].contains(p))
                .for_each(|c| visit(c.child)),
            None => Anywhere.each_containing(tree, id, children, bvh, p, visit),
        }
    }
}

/// `Line::slot` of a node without a list.
const NONE: u32 = u32::MAX;

/// A child of a blend that the ray crosses, where, and the child along the ray when it
/// is a point blob (then it is evaluated and bounded from the profile alone).
#[derive(Clone, Copy, Debug)]
struct Crossing {
    child: NodeId,
    enter: f32,
    leave: f32,
    profile: Option<LineProfile>,
}

/// A ray through a [`Tree`], with the lists of the children of its BVH blends that the
/// ray crosses. Reuse one per thread: [`Line::restrict`] keeps its buffers.
///
/// The lists grow as the queries go down the ray: each blend traverses its BVH along the
/// ray ([`ChildBvh::advance`]) only as far as asked, so a ray that meets the surface
/// early never opens what lies behind. Queries must stay within the restricted span.
pub struct Line<'t> {
    tree: &'t Tree,
    origin: Vec3,
    dir: Vec3,
    /// Slack for rounding, in parameter units.
    pad: f32,
    /// Every child the ray enters before `reach` is listed.
    reach: f32,
    /// Per node: the index of its front in `fronts`, or [`NONE`].
    slot: Vec<u32>,
    /// The blends' traversals; the first `used` are in use.
    fronts: Vec<Front<'t>>,
    used: usize,
    /// Children below which the tree is still to be walked (they hold BVH blends).
    pending: Vec<(NodeId, Vec3, Vec3, (f32, f32))>,
}

/// One blend's traversal along the line, in the blend's space.
struct Front<'t> {
    blend: NodeId,
    bvh: &'t ChildBvh,
    ray: SlabRay,
    o: Vec3,
    d: Vec3,
    /// The blend's range on the line.
    span: (f32, f32),
    cursor: RayCursor,
    /// The children listed so far, in no order.
    items: Vec<Crossing>,
}

impl<'t> Line<'t> {
    /// A line through `tree`, not yet restricted to a ray.
    pub fn new(tree: &'t Tree) -> Self {
        Line {
            tree,
            origin: Vec3::ZERO,
            dir: Vec3::ZERO,
            pad: 0.0,
            reach: f32::INFINITY,
            slot: vec![NONE; tree.nodes.len()],
            fronts: Vec::new(),
            used: 0,
            pending: Vec::new(),
        }
    }

    /// Restricts the tree to the ray `origin + t·dir`, `t ∈ span`. Each blend with a BVH
    /// that the ray reaches without crossing a warp will list the children whose supports
    /// it crosses, as far as the queries go.
    pub fn restrict(&mut self, origin: Vec3, dir: Vec3, span: (f32, f32)) {
        for f in &self.fronts[..self.used] {
            self.slot[f.blend as usize] = NONE;
        }
        self.used = 0;
        (self.origin, self.dir) = (origin, dir);
        // A ten-thousandth of the span: metres along a unit ray.
        self.pad = 1e-4 * (span.1 - span.0).abs().max(1e-3);
        self.reach = f32::NEG_INFINITY;
        // Without lists, queries use the BVHs (see `Tree::keeps_line_lists`).
        if self.tree.line_lists && !(span.0 > span.1) {
            self.walk(self.tree.root, origin, dir, span);
            self.walk_pending();
        }
    }

    /// `f` at parameter `t`: the value of the whole tree at the point [`Line::at`]`(t)`.
    pub fn value(&mut self, t: f32) -> f32 {
        self.reach_to(t);
        let on = OnLine {
            line: self,
            t0: t,
            t1: t,
        };
        self.tree.value_at_with(self.tree.root, self.at(t), on)
    }

    /// `(f, ∇f)` at parameter `t`: the whole tree's [`Tree::value_grad_at`] at
    /// [`Line::at`]`(t)` (for shading the hit).
    pub fn value_grad(&mut self, t: f32) -> (f32, Vec3) {
        self.reach_to(t);
        let on = OnLine {
            line: self,
            t0: t,
            t1: t,
        };
        self.tree.value_grad_at_with(self.tree.root, self.at(t), on)
    }

    /// A Lipschitz bound on the segment between parameters `t0 ≤ t1`: the whole tree's
    /// [`Tree::lipschitz_segment_at`] there (per metre of the segment).
    pub fn lipschitz(&mut self, t0: f32, t1: f32) -> f32 {
        self.reach_to(t1);
        let on = OnLine { line: self, t0, t1 };
        let tree = self.tree;
        tree.lipschitz_segment_with(tree.root, self.at(t0), self.at(t1), on)
    }

    /// Whether the line is (restricted to) the ray `origin + t·dir`.
    pub fn runs_along(&self, origin: Vec3, dir: Vec3) -> bool {
        self.origin == origin && self.dir == dir
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }

    /// Lists every child the ray enters up to `t` (and the rounding slack).
    fn reach_to(&mut self, t: f32) {
        let upto = t + self.pad;
        if upto <= self.reach {
            return;
        }
        let tree = self.tree;
        // Fronts opened on the way (blends below listed children) are advanced too.
        let mut k = 0;
        while k < self.used {
            let f = &mut self.fronts[k];
            let visit = lister(
                tree,
                f.o,
                f.d,
                f.span,
                self.pad,
                &mut f.items,
                &mut self.pending,
            );
            f.bvh.advance(&f.ray, &mut f.cursor, upto, visit);
            self.walk_pending();
            k += 1;
        }
        self.reach = upto;
    }

    /// Walks the subtrees below the children listed since the last call.
    fn walk_pending(&mut self) {
        while let Some((c, o, d, span)) = self.pending.pop() {
            self.walk(c, o, d, span);
        }
    }

    /// Opens a front for each BVH blend of the subtree `id` that the line `o + t·d`
    /// reaches over `span` through blends, unions, differences and affine maps.
    fn walk(&mut self, id: NodeId, o: Vec3, d: Vec3, span: (f32, f32)) {
        let tree = self.tree;
        let pad = self.pad;
        let ray = SlabRay::new(o, d, span, pad);
        let (enter, leave) = ray.clip(&tree.supports[id as usize]);
        let span = (enter.max(span.0), leave.min(span.1));
        if span.0 > span.1 + pad {
            return;
        }
        match &tree.nodes[id as usize] {
            Node::Constant(_) | Node::Primitive(_) | Node::Leaf(_) | Node::Warp { .. } => {}
            Node::Blend {
                bvh: Some(bvh),
                children: _,
            } => {
                // A reused front keeps its buffers.
                let (cursor, items) = match self.fronts.get_mut(self.used) {
                    Some(f) => (take(&mut f.cursor), take(&mut f.items)),
                    None => Default::default(),
                };
                let mut f = Front {
                    blend: id,
                    bvh,
                    ray: SlabRay::new(o, d, span, pad),
                    o,
                    d,
                    span,
                    cursor,
                    items,
                };
                f.items.clear();
                let visit = lister(tree, o, d, span, pad, &mut f.items, &mut self.pending);
                bvh.start(&f.ray, &mut f.cursor, visit);
                match self.fronts.get_mut(self.used) {
                    Some(slot) => *slot = f,
                    None => self.fronts.push(f),
                }
                self.slot[id as usize] = self.used as u32;
                self.used += 1;
            }
            Node::Blend {
                children,
                bvh: None,
            }
            | Node::Union(children)
            | Node::Intersection(children) => {
                for &c in children.iter() {
                    self.walk(c, o, d, span);
                }
            }
            Node::Difference { base, carves } => {
                self.walk(*base, o, d, span);
                for &c in carves.iter() {
                    self.walk(c, o, d, span);
                }
            }
            Node::Replace { base, by, .. } => {
                self.walk(*base, o, d, span);
                self.walk(*by, o, d, span);
            }
            Node::Erode { child, .. } => self.walk(*child, o, d, span),
            Node::Affine {
                child, to_child, ..
            } => {
                let (co, cd) = (to_child.transform_point3(o), to_child.transform_vector3(d));
                self.walk(*child, co, cd, span);
            }
        }
    }
}

/// What lists a front's crossings, given a child's payload and where the ray enters and
/// leaves its support: its profile when it is a point blob, and, when it is not a leaf, a
/// walk of the subtree below it for later ([`Line::walk_pending`]).
fn lister<'a>(
    tree: &'a Tree,
    o: Vec3,
    d: Vec3,
    span: (f32, f32),
    pad: f32,
    items: &'a mut Vec<Crossing>,
    pending: &'a mut Vec<(NodeId, Vec3, Vec3, (f32, f32))>,
) -> impl FnMut(u32, f32, f32) + 'a {
    move |c, mut enter, mut leave| {
        let profile = match &tree.nodes[c as usize] {
            Node::Primitive(p) => p.along_line(o, d),
            _ => None,
        };
        // A blob is listed over the chord of its ball, not of its box: half the boxes a
        // ray crosses miss their ball.
        if let Some(profile) = &profile {
            let Some((a, b)) = profile.reach() else {
                return;
            };
            (enter, leave) = (enter.max(a), leave.min(b));
        }
        let (enter, leave) = (enter - pad, leave.min(span.1) + pad);
        if enter > leave {
            return;
        }
        if profile.is_none() && !is_leaf(&tree.nodes[c as usize]) {
            pending.push((c, o, d, (enter, leave)));
        }
        items.push(Crossing {
            child: c,
            enter,
            leave,
            profile,
        });
    }
}

fn is_leaf(n: &Node) -> bool {
    matches!(n, Node::Constant(_) | Node::Primitive(_) | Node::Leaf(_))
}

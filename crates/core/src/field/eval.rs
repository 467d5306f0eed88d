//! Point evaluation of the tree: values and analytic gradients.

use glam::Vec3;

use super::contract::Field;

use super::falloff::ISO;
use super::line::{Anywhere, Candidates};
use super::node::{Node, NodeId};
use super::tree::Tree;

impl Tree {
    /// `f(p)` of node `id`.
    #[inline]
    pub fn value_at(&self, id: NodeId, p: Vec3) -> f32 {
        self.value_at_with(id, p, Anywhere)
    }

    /// `f(p)` of node `id`, its blends finding their children through `at`.
    #[inline]
    pub(super) fn value_at_with(&self, id: NodeId, p: Vec3, at: impl Candidates) -> f32 {
        if self.supports[id as usize].contains(p) {
            self.value_inside(id, p, at)
        } else {
            0.0
        }
    }

    /// `f(p)` of node `id`, for `p` known to lie in its support.
    pub(super) fn value_inside(&self, id: NodeId, p: Vec3, at: impl Candidates) -> f32 {
        match &self.nodes[id as usize] {
            Node::Constant(v) => *v,
            Node::Primitive(f) => f.value(p),
            Node::Leaf(f) => f.value(p),
            // The candidates are children whose supports contain `p`.
            Node::Blend { children, bvh } => {
                at.sum_containing(self, id, children, bvh, p, |c| self.value_inside(c, p, at))
            }
            Node::Union(children) => children
                .iter()
                .map(|&c| self.value_at_with(c, p, at))
                .fold(f32::NEG_INFINITY, f32::max),
            Node::Intersection(children) => children
                .iter()
                .map(|&c| self.value_at_with(c, p, at))
                .fold(f32::INFINITY, f32::min),
            Node::Difference { base, carves } => carves
                .iter()
                .fold(self.value_at_with(*base, p, at), |v, &c| {
                    v.min(2.0 * ISO - self.value_at_with(c, p, at))
                }),
            // Only the child that matters where the weight is 0 or 1.
            Node::Replace { base, by, mix } => match mix.weight(p) {
                w if w <= 0.0 => self.value_at_with(*base, p, at),
                w if w >= 1.0 => self.value_at_with(*by, p, at),
                w => {
                    let fb = self.value_at_with(*base, p, at);
                    fb + w * (self.value_at_with(*by, p, at) - fb)
                }
            },
            // An affine map keeps the line's parameter: the child's lists still apply.
            Node::Affine {
                child, to_child, ..
            } => self.value_at_with(*child, to_child.transform_point3(p), at),
            // A warp bends it: below one, blends use their BVHs.
            Node::Warp { child, warp } => self.value_at(*child, warp.apply(p)),
            // The point stays: the child's lists still apply.
            Node::Erode { child, erosion } => self.value_at_with(*child, p, at) - erosion.amount(p),
        }
    }

    /// `(f(p), ∇f(p))` of node `id`. At the kinks of min/max the gradient of the selected
    /// child is returned.
    pub fn value_grad_at(&self, id: NodeId, p: Vec3) -> (f32, Vec3) {
        self.value_grad_at_with(id, p, Anywhere)
    }

    /// [`Tree::value_grad_at`], its blends finding their children through `at`.
    pub(super) fn value_grad_at_with(
        &self,
        id: NodeId,
        p: Vec3,
        at: impl Candidates,
    ) -> (f32, Vec3) {
        if !self.supports[id as usize].contains(p) {
            return (0.0, Vec3::ZERO);
        }
        let pick = |children: &[NodeId], better: fn(f32, f32) -> bool| {
            let mut best = self.value_grad_at_with(children[0], p, at);
            for &c in &children[1..] {
                let vg = self.value_grad_at_with(c, p, at);
                if better(vg.0, best.0) {
                    best = vg;
                }
            }
            best
        };
        match &self.nodes[id as usize] {
            Node::Constant(v) => (*v, Vec3::ZERO),
            Node::Primitive(f) => f.value_grad(p),
            Node::Leaf(f) => f.value_grad(p),
            Node::Blend { children, bvh } => {
                let mut acc = (0.0, Vec3::ZERO);
                at.each_containing(self, id, children, bvh, p, |c| {
                    let (v, g) = self.value_grad_at_with(c, p, at);
                    acc.0 += v;
                    acc.1 += g;
                });
                acc
            }
            Node::Union(children) => pick(children, |a, b| a > b),
            Node::Intersection(children) => pick(children, |a, b| a < b),
            Node::Difference { base, carves } => {
                let mut best = self.value_grad_at_with(*base, p, at);
                for &c in carves.iter() {
                    let (v, g) = self.value_grad_at_with(c, p, at);
                    if 2.0 * ISO - v < best.0 {
                        best = (2.0 * ISO - v, -g);
                    }
                }
                best
            }
            Node::Replace { base, by, mix } => match mix.weight_grad(p) {
                (w, _) if w <= 0.0 => self.value_grad_at_with(*base, p, at),
                (w, _) if w >= 1.0 => self.value_grad_at_with(*by, p, at),
                (w, gw) => {
                    let (fb, gb) = self.value_grad_at_with(*base, p, at);
                    let (fv, gv) = self.value_grad_at_with(*by, p, at);
                    (fb + w * (fv - fb), gb + w * (gv - gb) + gw * (fv - fb))
                }
            },
            // An affine map keeps the line's parameter: the child's lists still apply.
            Node::Affine {
                child, to_child, ..
            } => {
                let (v, g) = self.value_grad_at_with(*child, to_child.transform_point3(p), at);
                (
                    v,
                    Vec3::from(to_child.matrix3.transpose() * glam::Vec3A::from(g)),
                )
            }
            // A warp bends it: below one, blends use their BVHs.
            Node::Warp { child, warp } => {
                let (q, j) = warp.apply_jacobian(p);
                let (v, g) = self.value_grad_at(*child, q);
                (v, j.transpose() * g)
            }
            Node::Erode { child, erosion } => {
                let (v, g) = self.value_grad_at_with(*child, p, at);
                let (e, ge) = erosion.amount_grad(p);
                (v - e, g - ge)
            }
        }
    }
}

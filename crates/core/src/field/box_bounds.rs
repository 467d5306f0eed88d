//! Bounds of the tree over a box: sound value intervals and local Lipschitz constants.

use glam::{Affine3A, Vec3};

use super::bound::{gap, mix_lipschitz};
use super::bounds::{Aabb, Interval};
use super::contract::Field;
use super::falloff::ISO;
use super::line::{Anywhere, Candidates};
use super::node::{Node, NodeId};
use super::replace::Transition;
use super::tree::Tree;

/// The box of `b`'s corners mapped by `m`: contains the image of `b`.
pub fn map_box(m: &Affine3A, b: &Aabb) -> Aabb {
    Aabb::from_points(b.corners().map(|c| m.transform_point3(c)))
}

impl Tree {
    /// Calls `visit` for each child of the blend `children` whose support overlaps `b`.
    pub(super) fn blend_children_in(
        &self,
        children: &[NodeId],
        bvh: &Option<super::bvh::ChildBvh>,
        b: &Aabb,
        mut visit: impl FnMut(NodeId),
    ) {
        match bvh {
            Some(bvh) => bvh.overlapping(b, visit),
            None => children
                .iter()
                .filter(|&&c| self.supports[c as usize].overlaps(b))
                .for_each(|&c| visit(c)),
        }
    }

    /// A range containing every value of node `id` over `b`.
    pub fn interval_at(&self, id: NodeId, b: &Aabb) -> Interval {
        let support = &self.supports[id as usize];
        if !support.overlaps(b) {
            return Interval::ZERO;
        }
        let r = match &self.nodes[id as usize] {
            Node::Constant(v) => Interval::point(*v),
            Node::Primitive(f) => f.interval(b),
            Node::Leaf(f) => f.interval(b),
            Node::Blend { children, bvh } => {
                let mut sum = Interval::ZERO;
                self.blend_children_in(children, bvh, b, |c| sum = sum + self.interval_at(c, b));
                sum
            }
            Node::Union(children) => children
                .iter()
                .map(|&c| self.interval_at(c, b))
                .reduce(Interval::max)
                .unwrap_or(Interval::ZERO),
            Node::Intersection(children) => children
                .iter()
                .map(|&c| self.interval_at(c, b))
                .reduce(Interval::min)
                .unwrap_or(Interval::ZERO),
            Node::Difference { base, carves } => {
                carves.iter().fold(self.interval_at(*base, b), |r, &c| {
                    let ci = self.interval_at(c, b);
                    r.min(Interval::new(2.0 * ISO - ci.hi, 2.0 * ISO - ci.lo))
                })
            }
            Node::Replace { base, by, mix } => {
                let w = mix.interval(b);
                if w.hi <= 0.0 {
                    self.interval_at(*base, b)
                } else if w.lo >= 1.0 {
                    self.interval_at(*by, b)
                } else {
                    Transition::mix_interval(
                        w,
                        self.interval_at(*base, b),
                        self.interval_at(*by, b),
                    )
                }
            }
            Node::Affine {
                child, to_child, ..
            } => self.interval_at(*child, &map_box(to_child, b)),
            Node::Warp { child, warp } => self.interval_at(*child, &b.dilate(warp.reach())),
            Node::Erode { child, erosion } => {
                let (c, e) = (self.interval_at(*child, b), erosion.interval(b));
                Interval::new(c.lo - e.hi, c.hi - e.lo)
            }
        };
        if support.contains_box(b) {
            r
        } else {
            r.hull(Interval::ZERO)
        }
    }

    /// A Lipschitz bound of node `id` valid inside `b`.
    pub fn lipschitz_box_at(&self, id: NodeId, b: &Aabb) -> f32 {
        if !self.supports[id as usize].overlaps(b) {
            return 0.0;
        }
        let max_of = |children: &[NodeId]| {
            children
                .iter()
                .map(|&c| self.lipschitz_box_at(c, b))
                .fold(0.0, f32::max)
        };
        match &self.nodes[id as usize] {
            Node::Constant(_) => 0.0,
            Node::Primitive(f) => f.lipschitz_box(b),
            Node::Leaf(f) => f.lipschitz_box(b),
            Node::Blend { children, bvh } => {
                let mut sum = 0.0;
                self.blend_children_in(children, bvh, b, |c| sum += self.lipschitz_box_at(c, b));
                sum
            }
            Node::Union(children) | Node::Intersection(children) => max_of(children),
            Node::Difference { base, carves } => {
                max_of(carves).max(self.lipschitz_box_at(*base, b))
            }
            Node::Replace { base, by, mix } => {
                let w = mix.interval(b);
                if w.lo >= 1.0 {
                    return self.lipschitz_box_at(*by, b);
                }
                let lb = self.lipschitz_box_at(*base, b);
                if w.hi <= 0.0 {
                    return lb;
                }
                let gap = gap(self.interval_at(*base, b), self.interval_at(*by, b));
                mix_lipschitz(w, lb, self.lipschitz_box_at(*by, b), gap, mix.lipschitz())
            }
            Node::Affine {
                child,
                to_child,
                stretch,
            } => self.lipschitz_box_at(*child, &map_box(to_child, b)) * stretch,
            Node::Warp { child, warp } => {
                self.lipschitz_box_at(*child, &b.dilate(warp.reach())) * warp.lipschitz()
            }
            Node::Erode { child, erosion } => {
                self.lipschitz_box_at(*child, b) + erosion.lipschitz_box(b)
            }
        }
    }

    /// A Lipschitz bound of node `id` on the segment `[a, b]`: like
    /// [`Tree::lipschitz_box_at`] on the segment's box, but leaves answer for the segment
    /// itself ([`Field::lipschitz_segment`]) and affine nodes map its ends, so a blend sums
    /// what its children see along the segment, not over its box.
    pub fn lipschitz_segment_at(&self, id: NodeId, a: Vec3, b: Vec3) -> f32 {
        self.lipschitz_segment_with(id, a, b, Anywhere)
    }

    /// [`Tree::lipschitz_segment_at`], its blends finding their children through `at`.
    pub(super) fn lipschitz_segment_with(
        &self,
        id: NodeId,
        a: Vec3,
        b: Vec3,
        at: impl Candidates,
    ) -> f32 {
        let bx = Aabb::new(a, b);
        if !self.supports[id as usize].overlaps(&bx) {
            return 0.0;
        }
        let max_of = |children: &[NodeId]| {
            children
                .iter()
                .map(|&c| self.lipschitz_segment_with(c, a, b, at))
                .fold(0.0, f32::max)
        };
        match &self.nodes[id as usize] {
            Node::Constant(_) => 0.0,
            Node::Primitive(f) => f.lipschitz_segment(a, b),
            Node::Leaf(f) => f.lipschitz_segment(a, b),
            Node::Blend { children, bvh } => {
                at.sum_overlapping(self, id, children, bvh, &bx, |c| {
                    self.lipschitz_segment_with(c, a, b, at)
                })
            }
            Node::Union(children) | Node::Intersection(children) => max_of(children),
            Node::Difference { base, carves } => {
                max_of(carves).max(self.lipschitz_segment_with(*base, a, b, at))
            }
            Node::Replace { base, by, mix } => {
                let w = mix.interval(&bx);
                if w.lo >= 1.0 {
                    return self.lipschitz_segment_with(*by, a, b, at);
                }
                let lb = self.lipschitz_segment_with(*base, a, b, at);
                if w.hi <= 0.0 {
                    return lb;
                }
                let gap = gap(self.interval_at(*base, &bx), self.interval_at(*by, &bx));
                mix_lipschitz(
                    w,
                    lb,
                    self.lipschitz_segment_with(*by, a, b, at),
                    gap,
                    mix.lipschitz(),
                )
            }
            Node::Affine {
                child,
                to_child,
                stretch,
            } => {
                let (ca, cb) = (to_child.transform_point3(a), to_child.transform_point3(b));
                self.lipschitz_segment_with(*child, ca, cb, at) * stretch
            }
            Node::Warp { .. } => self.lipschitz_box_at(id, &bx),
            Node::Erode { child, erosion } => {
                self.lipschitz_segment_with(*child, a, b, at) + erosion.lipschitz_box(&bx)
            }
        }
    }
}

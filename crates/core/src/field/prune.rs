//! Pruning: the tree restricted to a region, with every child that cannot matter there
//! dropped (fidget-style tape simplification, done per brick by the grid evaluator).

use std::collections::HashMap;

use super::bounds::{Aabb, Interval};
use super::box_bounds::map_box;
use super::bvh::BVH_MIN_CHILDREN;
use super::falloff::ISO;
use super::node::{Node, NodeId};
use super::tree::{Tree, TreeBuilder};

struct Pruner<'t> {
    tree: &'t Tree,
    out: TreeBuilder,
    memo: HashMap<(NodeId, [u32; 6]), Option<NodeId>>,
}

fn key(b: &Aabb) -> [u32; 6] {
    [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z].map(f32::to_bits)
}

impl Pruner<'_> {
    /// The pruned copy of `id` valid in `b`; `None` when it is 0 throughout `b`.
    fn node(&mut self, id: NodeId, b: &Aabb) -> Option<NodeId> {
        // A primitive is copied as it is: no memo (a second parent gets a second copy).
        if let Node::Primitive(f) = &self.tree.nodes[id as usize] {
            let info = &self.tree.info[id as usize];
            return info
                .support
                .overlaps(b)
                .then(|| self.out.primitive(f.clone(), info.name.clone()));
        }
        let memo_key = (id, key(b));
        if let Some(r) = self.memo.get(&memo_key) {
            return *r;
        }
        let r = self.node_uncached(id, b);
        self.memo.insert(memo_key, r);
        r
    }

    fn node_uncached(&mut self, id: NodeId, b: &Aabb) -> Option<NodeId> {
        let tree = self.tree;
        let info = &tree.info[id as usize];
        if !info.support.overlaps(b) {
            return None;
        }
        let name = info.name.clone();
        match &tree.nodes[id as usize] {
            Node::Constant(v) => (*v != 0.0).then(|| self.out.constant(*v, name)),
            Node::Primitive(f) => Some(self.out.primitive(f.clone(), name)),
            Node::Leaf(f) => Some(self.out.leaf(f.clone(), name)),
            // The BVH is restricted to the region rather than rebuilt: the kept children
            // are summed in the order the whole blend sums them.
            Node::Blend { bvh: Some(bvh), .. } => {
                let mut kept = Vec::new();
                let bvh = bvh.restricted(b, |c| {
                    let n = self.node(c, b)?;
                    kept.push(n);
                    Some(n)
                });
                match kept.len() {
                    0 => None,
                    1 => Some(kept[0]),
                    n if n < BVH_MIN_CHILDREN => Some(self.out.blend(kept, name)),
                    _ => {
                        kept.sort_unstable();
                        Some(self.out.blend_with(kept, Some(bvh), name))
                    }
                }
            }
            Node::Blend { children, bvh } => {
                let mut kept = Vec::new();
                tree.blend_children_in(children, bvh, b, |c| kept.push(c));
                kept.sort_unstable();
                let kept: Vec<NodeId> = kept.into_iter().filter_map(|c| self.node(c, b)).collect();
                match kept.len() {
                    0 => None,
                    1 => Some(kept[0]),
                    _ => Some(self.out.blend(kept, name)),
                }
            }
            Node::Union(children) | Node::Intersection(children) => {
                let union = matches!(tree.nodes[id as usize], Node::Union(_));
                let ivs: Vec<Interval> = children.iter().map(|&c| tree.interval_at(c, b)).collect();
                // A child that can never be the max (min) here is dropped.
                let bar = if union {
                    ivs.iter().map(|i| i.lo).fold(f32::NEG_INFINITY, f32::max)
                } else {
                    ivs.iter().map(|i| i.hi).fold(f32::INFINITY, f32::min)
                };
                let mut kept = Vec::new();
                let mut zero_dropped = false;
                let mut kept_lo = f32::INFINITY;
                for (&c, iv) in children.iter().zip(&ivs) {
                    let beaten = if union { iv.hi < bar } else { iv.lo > bar };
                    if beaten {
                        continue;
                    }
                    match self.node(c, b) {
                        Some(n) => {
                            kept.push(n);
                            kept_lo = kept_lo.min(iv.lo);
                        }
                        None => zero_dropped = true,
                    }
                }
                if zero_dropped {
                    // A dropped child is 0 here. With non-negative siblings, max(0, …) is the
                    // rest and min(0, …) is 0; otherwise keep the 0 in the max/min.
                    if kept.is_empty() || (!union && kept_lo >= 0.0) {
                        return None;
                    }
                    if kept_lo < 0.0 {
                        kept.push(self.out.constant(0.0, None));
                    }
                }
                match kept.len() {
                    0 => None,
                    1 => Some(kept[0]),
                    _ if union => Some(self.out.union(kept, name)),
                    _ => Some(self.out.intersection(kept, name)),
                }
            }
            Node::Difference { base, carves } => {
                let bi = tree.interval_at(*base, b);
                let mut kept = Vec::new();
                for &c in carves.iter() {
                    let ci = tree.interval_at(c, b);
                    // The carve wins nowhere when 2T − f_c ≥ f_base throughout.
                    if 2.0 * ISO - ci.hi >= bi.hi {
                        continue;
                    }
                    match self.node(c, b) {
                        Some(n) => kept.push(n),
                        None => {
                            // A zero carve gives 2T, which only matters if f_base can exceed it.
                            if bi.hi > 2.0 * ISO {
                                kept.push(self.out.constant(0.0, None));
                            }
                        }
                    }
                }
                let base = self.node(*base, b);
                match (base, kept.is_empty()) {
                    (base, true) => base,
                    (Some(base), false) => Some(self.out.difference(base, kept, name)),
                    (None, false) => {
                        let zero = self.out.constant(0.0, None);
                        Some(self.out.difference(zero, kept, name))
                    }
                }
            }
            Node::Replace { base, by, mix } => {
                let w = mix.interval(b);
                if w.hi <= 0.0 {
                    return self.node(*base, b);
                }
                if w.lo >= 1.0 {
                    return self.node(*by, b);
                }
                let (base, by) = (self.node(*base, b), self.node(*by, b));
                let mut or_zero =
                    |n: Option<NodeId>| n.unwrap_or_else(|| self.out.constant(0.0, None));
                let (base, by) = match (base, by) {
                    (None, None) => return None,
                    (base, by) => (or_zero(base), or_zero(by)),
                };
                Some(self.out.replace(base, by, **mix, name))
            }
            Node::Affine {
                child, to_child, ..
            } => {
                let child = self.node(*child, &map_box(to_child, b))?;
                Some(self.out.transform(child, to_child.inverse(), name))
            }
            Node::Warp { child, warp } => {
                let child = self.node(*child, &b.dilate(warp.reach()))?;
                Some(self.out.warp(child, (**warp).clone(), name))
            }
            Node::Erode { child, erosion } => {
                let pruned = self.node(*child, b);
                if erosion.interval(b).hi <= 0.0 {
                    return pruned;
                }
                let child = pruned.unwrap_or_else(|| self.out.constant(0.0, None));
                Some(self.out.erode(child, (**erosion).clone(), name))
            }
        }
    }
}

impl Tree {
    /// Node `id` restricted to `region`: equal to it at every point of `region`.
    pub fn pruned(&self, id: NodeId, region: &Aabb) -> Tree {
        let mut p = Pruner {
            tree: self,
            out: TreeBuilder::new(),
            memo: HashMap::new(),
        };
        match p.node(id, region) {
            Some(root) => p.out.build(root),
            None => {
                let root = p.out.constant(0.0, None);
                p.out.build(root)
            }
        }
    }

    /// The constant value of the tree, when it is a constant.
    pub fn as_constant(&self) -> Option<f32> {
        match self.nodes[self.root as usize] {
            Node::Constant(v) => Some(v),
            _ => None,
        }
    }
}

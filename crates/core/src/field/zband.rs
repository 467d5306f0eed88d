//! Where the surface can lie over a footprint (Paris et al. 2019 §7): z-bands for the mesher's
//! pruning, and the heightfield shortcut for direct elevation extraction.

use super::bounds::{Aabb, Interval, Rect, ZBands};
use super::contract::{Elevation, Field, z_bands_by_interval};
use super::falloff::ISO;
use super::node::{Node, NodeId};
use super::replace::Transition;
use super::tree::Tree;

/// The z-ranges covered by at least two of `ranges`: where several children of a sum can
/// be non-zero together, so the surface of the sum can lie anywhere.
fn overlaps_of(ranges: &mut [Interval], out: &mut ZBands) {
    ranges.sort_by(|a, b| a.lo.total_cmp(&b.lo));
    // Sweep: keep the largest `hi` seen so far; any range starting below it overlaps.
    let mut reach = f32::NEG_INFINITY;
    for r in ranges.iter() {
        if r.lo <= reach {
            out.push(Interval::new(r.lo, r.hi.min(reach)));
        }
        reach = reach.max(r.hi);
    }
}

impl Tree {
    /// Children of node `id` whose support meets the column `fp × z`.
    fn children_in_column(&self, id: NodeId, fp: &Rect, z: Interval) -> Vec<NodeId> {
        let column = fp.extrude(z);
        match &self.nodes[id as usize] {
            Node::Blend { children, bvh } => {
                let mut v = Vec::new();
                self.blend_children_in(children, bvh, &column, |c| v.push(c));
                v.sort_unstable();
                v
            }
            node => node
                .children()
                .into_iter()
                .filter(|&c| self.info[c as usize].support.overlaps(&column))
                .collect(),
        }
    }

    /// Adds the z-bands of node `id` over `fp`, inside `z`, to `out`.
    pub fn z_bands_at(&self, id: NodeId, fp: &Rect, z: Interval, out: &mut ZBands) {
        let support = &self.info[id as usize].support;
        let z = z.intersect(support.z());
        if z.is_empty() || !support.footprint().overlaps(fp) {
            return;
        }
        match &self.nodes[id as usize] {
            Node::Constant(v) => {
                if *v == ISO {
                    out.push(z);
                }
            }
            Node::Primitive(f) => f.z_bands(fp, z, out),
            Node::Leaf(f) => f.z_bands(fp, z, out),
            Node::Blend { .. } => {
                let children = self.children_in_column(id, fp, z);
                let mut zs: Vec<Interval> = children
                    .iter()
                    .map(|&c| self.info[c as usize].support.z().intersect(z))
                    .collect();
                for &c in &children {
                    self.z_bands_at(c, fp, z, out);
                }
                overlaps_of(&mut zs, out);
            }
            Node::Union(_) | Node::Intersection(_) | Node::Difference { .. } => {
                for c in self.children_in_column(id, fp, z) {
                    self.z_bands_at(c, fp, z, out);
                }
            }
            Node::Replace { base, by, mix } => {
                self.replace_bands(id, [*base, *by], mix, fp, z, out)
            }
            // Outside the region the node is its child; inside, interval subdivision.
            Node::Erode { child, erosion } => {
                if erosion.region().footprint().overlaps(fp) {
                    z_bands_by_interval(&self.subtree(id), fp, z, out);
                } else {
                    self.z_bands_at(*child, fp, z, out);
                }
            }
            Node::Warp { child, warp } => {
                // The child is evaluated at most `r` away: its bands, widened by `r`.
                let r = warp.reach();
                let mut child_bands = ZBands::new();
                self.z_bands_at(*child, &fp.dilate(r), z.dilate(r), &mut child_bands);
                for b in child_bands.as_slice() {
                    out.push(b.dilate(r).intersect(z));
                }
            }
            Node::Affine {
                child, to_child, ..
            } => {
                let m = to_child.matrix3;
                let vertical_only = m.x_axis.z == 0.0
                    && m.y_axis.z == 0.0
                    && m.z_axis.x == 0.0
                    && m.z_axis.y == 0.0;
                if !vertical_only || m.z_axis.z == 0.0 {
                    z_bands_by_interval(&self.subtree(id), fp, z, out);
                    return;
                }
                // z' = a·z + c and (x', y') does not depend on z: map the column and back.
                let (a, c) = (m.z_axis.z, to_child.translation.z);
                let corners = [
                    fp.min,
                    glam::Vec2::new(fp.max.x, fp.min.y),
                    glam::Vec2::new(fp.min.x, fp.max.y),
                    fp.max,
                ];
                let mapped = corners.map(|q| to_child.transform_point3(q.extend(0.0)).truncate());
                let child_fp = Rect::new(
                    mapped.iter().copied().reduce(glam::Vec2::min).unwrap(),
                    mapped.iter().copied().reduce(glam::Vec2::max).unwrap(),
                );
                let mut child_bands = ZBands::new();
                self.z_bands_at(
                    *child,
                    &child_fp,
                    Interval::new(a * z.lo + c, a * z.hi + c),
                    &mut child_bands,
                );
                for b in child_bands.as_slice() {
                    out.push(Interval::new((b.lo - c) / a, (b.hi - c) / a));
                }
            }
        }
    }

    /// The z-bands of the replace node `id`: its base's outside the region; inside, the
    /// bands of both children, and the gaps between them where the mix's interval holds
    /// `T` (there the children can disagree on the side, and the mix crosses between).
    fn replace_bands(
        &self,
        id: NodeId,
        [base, by]: [NodeId; 2],
        mix: &Transition,
        fp: &Rect,
        z: Interval,
        out: &mut ZBands,
    ) {
        let region = mix.region();
        if !region.footprint().overlaps(fp) {
            return self.z_bands_at(base, fp, z, out);
        }
        let inside = z.intersect(region.z());
        if inside.is_empty() {
            return self.z_bands_at(base, fp, z, out);
        }
        // Above and below the region: the base alone.
        for outside in [
            Interval::new(z.lo, inside.lo),
            Interval::new(inside.hi, z.hi),
        ] {
            if outside.width() > 0.0 {
                self.z_bands_at(base, fp, outside, out);
            }
        }
        let mut own = ZBands::new();
        self.z_bands_at(base, fp, inside, &mut own);
        self.z_bands_at(by, fp, inside, &mut own);
        let subtree = self.subtree(id);
        let mut lo = inside.lo;
        for b in own.as_slice().iter().chain(&[Interval::point(inside.hi)]) {
            let gap = Interval::new(lo, b.lo.max(lo));
            if gap.width() > 0.0 && self.children_disagree([base, by], mix, &fp.extrude(gap)) {
                z_bands_by_interval(&subtree, fp, gap, out);
            }
            lo = lo.max(b.hi);
        }
        out.extend(&own);
    }

    /// Whether the mix of `base` and `by` can cross `T` in `slab`, a box neither child's
    /// surface crosses (a gap between their bands): each child then keeps one side of
    /// `T` over the whole (connected) slab, which its value at the centre tells. Where
    /// the weight is 0 or 1 all over, the mix is one child, without a surface there; where
    /// both children are on one side, so is `(1 − w)·f_base + w·f_by`. Only where they
    /// disagree across the transition can the mix cross `T`.
    fn children_disagree(&self, [base, by]: [NodeId; 2], mix: &Transition, slab: &Aabb) -> bool {
        let w = mix.interval(slab);
        if w.hi <= 0.0 || w.lo >= 1.0 {
            return false;
        }
        let c = slab.center();
        let side = |id: NodeId| self.value_at(id, c) - ISO;
        side(base) * side(by) <= 0.0
    }

    /// The heightfield that node `id` equals over `fp`, with where that holds.
    pub fn elevation_at(&self, id: NodeId, fp: &Rect) -> Option<Elevation<'_>> {
        let support = &self.info[id as usize].support;
        match &self.nodes[id as usize] {
            Node::Primitive(f) => f.elevation(fp),
            Node::Leaf(f) => f.elevation(fp),
            // Outside the region the node is its base.
            Node::Replace { base, mix, .. } if !mix.region().footprint().overlaps(fp) => {
                self.elevation_at(*base, fp)
            }
            Node::Erode { child, erosion } if !erosion.region().footprint().overlaps(fp) => {
                self.elevation_at(*child, fp)
            }
            Node::Blend { .. } | Node::Union(_) | Node::Difference { .. } => {
                let children = self.children_in_column(id, fp, support.z());
                let (base, others): (NodeId, Vec<NodeId>) = match &self.nodes[id as usize] {
                    Node::Difference { base, .. } => {
                        (*base, children.into_iter().filter(|c| c != base).collect())
                    }
                    _ => {
                        // The one child that is a heightfield here; the others must vanish
                        // in the band we keep.
                        let hf = *children
                            .iter()
                            .find(|&&c| self.elevation_at(c, fp).is_some())?;
                        (hf, children.into_iter().filter(|&c| c != hf).collect())
                    }
                };
                let mut e = self.elevation_at(base, fp)?;
                for c in others {
                    let cz = self.info[c as usize].support.z();
                    if !cz.overlaps(&e.z) {
                        continue;
                    }
                    // Keep the larger piece of e.z outside the other child's support.
                    let below = Interval::new(e.z.lo, cz.lo.min(e.z.hi));
                    let above = Interval::new(cz.hi.max(e.z.lo), e.z.hi);
                    let below = if cz.lo > e.z.lo {
                        below
                    } else {
                        Interval::EMPTY
                    };
                    let above = if cz.hi < e.z.hi {
                        above
                    } else {
                        Interval::EMPTY
                    };
                    e.z = match (below.is_empty(), above.is_empty()) {
                        (true, true) => return None,
                        (false, true) => below,
                        (true, false) => above,
                        (false, false) if below.width() >= above.width() => below,
                        _ => above,
                    };
                }
                Some(e)
            }
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overlap_sweep_finds_double_coverage() {
        let mut out = ZBands::new();
        let mut r = vec![
            Interval::new(0.0, 2.0),
            Interval::new(5.0, 6.0),
            Interval::new(1.0, 3.0),
            Interval::new(2.5, 5.5),
        ];
        overlaps_of(&mut r, &mut out);
        assert_eq!(
            out.as_slice(),
            &[
                Interval::new(1.0, 2.0),
                Interval::new(2.5, 3.0),
                Interval::new(5.0, 5.5)
            ]
        );
    }
}

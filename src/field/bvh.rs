//! A BVH (obvhs) over the support boxes of a blend's children, so a query touches only the
//! children that can be non-zero there.

use std::time::Duration;

use glam::Vec3A;
use obvhs::{BvhBuildParams, aabb::Aabb as BvhAabb, bvh2::Bvh2, bvh2::builder::build_bvh2};

use super::bounds::Aabb;

/// Blends with at least this many children get a BVH; below it a linear scan of the
/// children's supports is faster.
pub const BVH_MIN_CHILDREN: usize = 16;

/// A BVH over child support boxes; queries return positions in the blend's child list.
pub struct ChildBvh {
    bvh: Bvh2,
}

struct Boxed(BvhAabb);

impl obvhs::Boundable for Boxed {
    fn aabb(&self) -> BvhAabb {
        self.0
    }
}

fn to_bvh(b: &Aabb) -> BvhAabb {
    BvhAabb::new(b.min.into(), b.max.into())
}

impl ChildBvh {
    /// Builds the BVH over `supports` (one box per child, in child order).
    pub fn new(supports: &[Aabb]) -> Self {
        let prims: Vec<Boxed> = supports.iter().map(|b| Boxed(to_bvh(b))).collect();
        let mut params = BvhBuildParams::medium_build();
        params.max_prims_per_leaf = 4;
        let bvh = build_bvh2(&prims, params, &mut Duration::default());
        ChildBvh { bvh }
    }

    /// Calls `visit(i)` for every child `i` whose support box contains `p`.
    #[inline]
    pub fn at_point(&self, p: glam::Vec3, mut visit: impl FnMut(usize)) {
        let bvh = &self.bvh;
        bvh.point_traverse(Vec3A::from(p), |bvh, node| {
            let n = &bvh.nodes[node as usize];
            for k in n.first_index..n.first_index + n.prim_count {
                visit(bvh.primitive_indices[k as usize] as usize);
            }
            true
        });
    }

    /// Calls `visit(i)` for every child `i` whose support box overlaps `b`.
    pub fn overlapping(&self, b: &Aabb, mut visit: impl FnMut(usize)) {
        self.bvh.aabb_traverse(to_bvh(b), |bvh, node| {
            let n = &bvh.nodes[node as usize];
            for k in n.first_index..n.first_index + n.prim_count {
                visit(bvh.primitive_indices[k as usize] as usize);
            }
            true
        });
    }
}

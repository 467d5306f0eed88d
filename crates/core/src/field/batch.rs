//! Batched point queries: many points at once, in parallel.
//!
//! Sorting the points along a Morton curve first (so consecutive queries share BVH nodes
//! in cache) was measured and dropped: on 1 M uniform points over 100k spheres the sort
//! cost more than the cache misses it saved (5.7 M/s against 8.2 M/s unsorted, 2 cores).

use glam::Vec3;
use rayon::prelude::*;

use super::contract::Field;
use super::line::Anywhere;
use super::node::Node;
use super::tree::Tree;

/// Points per parallel task.
const CHUNK: usize = 4096;

impl Tree {
    /// `out[i] = f(pts[i])` for every point: the same values as [`Field::value`], to the
    /// bit, in parallel over chunks of points.
    ///
    /// # Panics
    /// When `out` and `pts` differ in length (a caller's bug, not user data).
    pub fn values(&self, pts: &[Vec3], out: &mut [f32]) {
        assert_eq!(pts.len(), out.len(), "one value per point");
        // A root blend with a BVH sums a chunk's points together, so that through its
        // point index the queries' cache misses overlap instead of following one another.
        let blend = match &self.nodes[self.root as usize] {
            Node::Blend { bvh: Some(bvh), .. } => Some(bvh),
            _ => None,
        };
        out.par_chunks_mut(CHUNK)
            .zip(pts.par_chunks(CHUNK))
            .for_each(|(o, p)| match blend {
                // As `value`: the blend's sum inside its support, else 0.
                Some(bvh) => {
                    bvh.sums_at(p, o, |c, q| self.value_inside(c, q, Anywhere));
                    let support = &self.supports[self.root as usize];
                    for (o, q) in o.iter_mut().zip(p) {
                        if !support.contains(*q) {
                            *o = 0.0;
                        }
                    }
                }
                None => {
                    for (o, &q) in o.iter_mut().zip(p) {
                        *o = self.value(q);
                    }
                }
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::TreeBuilder;
    use crate::field::primitive::{Primitive, PrimitiveSpec};

    /// To the bit, through the point index by blocks: spheres alone, then with a segment
    /// (evaluated through its node) and a constant (a child no box bounds, summed after
    /// the index); points inside and far outside the support.
    #[test]
    fn batch_values_equal_point_values() {
        let mut rng = crate::rng::Rng::new(1);
        let mut rnd = || rng.unit();
        for others in [false, true] {
            let mut b = TreeBuilder::new();
            let mut kids = Vec::new();
            for i in 0..64 {
                let c = Vec3::new(rnd() * 40.0, rnd() * 40.0, rnd() * 10.0);
                let (x, y, z) = (c.x, c.y, c.z);
                let shape = match i % 4 {
                    0 if others => {
                        format!("Segment(a: ({x}, {y}, {z}), b: ({}, {y}, {z}))", x + 3.0)
                    }
                    _ => format!("Sphere(center: ({x}, {y}, {z}), radius: 1.5)"),
                };
                let spec: PrimitiveSpec =
                    ron::from_str(&format!("(shape: {shape}, falloff: 3.0)")).unwrap();
                kids.push(b.primitive(Primitive::from_spec(&spec, 0), None));
            }
            if others {
                kids.push(b.constant(0.125, None));
            }
            let root = b.blend(kids, None);
            let tree = b.build(root);
            for n in [10, 20_000] {
                let mut pts: Vec<Vec3> = (0..n)
                    .map(|_| Vec3::new(rnd() * 44.0 - 2.0, rnd() * 44.0 - 2.0, rnd() * 14.0 - 2.0))
                    .collect();
                pts.extend((0..n / 10).map(|_| Vec3::new(rnd(), rnd(), rnd()) * 200.0 - 100.0));
                let mut out = vec![f32::NAN; pts.len()];
                tree.values(&pts, &mut out);
                let inside = out.iter().filter(|&&v| v > 0.125).count();
                assert!(inside > n / 20, "{inside} of {n} points see a sphere");
                for (p, v) in pts.iter().zip(&out) {
                    assert_eq!(v.to_bits(), tree.value(*p).to_bits(), "at {p}");
                }
            }
        }
    }
}

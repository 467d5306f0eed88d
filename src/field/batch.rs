//! Batched point queries: many points at once, in the order that suits the tree.
//!
//! Random points make a point query memory-bound: every query walks the blend BVHs from
//! the root and misses the cache on most nodes and leaves. Sorted along a Morton curve, the
//! queries that follow one another share their path and leaves, which stay in cache; the
//! points are then evaluated in parallel and the values written back in the caller's order.

use glam::Vec3;
use rayon::prelude::*;

use super::contract::Field;
use super::tree::Tree;

/// Below this many points the batch is evaluated in the given order (sorting costs more).
const SORT_MIN: usize = 4096;

/// Points per parallel task.
const CHUNK: usize = 2048;

/// Bits per axis of the Morton key.
const BITS: u32 = 21;

/// Spreads the low 21 bits of `x` to every third bit.
#[inline]
fn spread(mut x: u64) -> u64 {
    x &= (1 << BITS) - 1;
    x = (x | x << 32) & 0x001f_0000_0000_ffff;
    x = (x | x << 16) & 0x001f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

impl Tree {
    /// `out[i] = f(pts[i])` for every point: the same values as [`Field::value`], computed
    /// in Morton order over the points' bounding box and in parallel.
    ///
    /// # Panics
    /// When `out` and `pts` differ in length (a caller's bug, not user data).
    pub fn values(&self, pts: &[Vec3], out: &mut [f32]) {
        assert_eq!(pts.len(), out.len(), "one value per point");
        if pts.len() < SORT_MIN {
            for (o, &p) in out.iter_mut().zip(pts) {
                *o = self.value(p);
            }
            return;
        }
        let (lo, hi) = pts
            .par_iter()
            .fold(
                || (Vec3::INFINITY, Vec3::NEG_INFINITY),
                |(lo, hi), &p| (lo.min(p), hi.max(p)),
            )
            .reduce(
                || (Vec3::INFINITY, Vec3::NEG_INFINITY),
                |a, b| (a.0.min(b.0), a.1.max(b.1)),
            );
        // Non-finite coordinates key to a corner; they are still evaluated.
        let scale = ((1u32 << BITS) - 1) as f32 / (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
        let key = |p: Vec3| {
            let q = ((p - lo) * scale).clamp(Vec3::ZERO, Vec3::splat(((1u32 << BITS) - 1) as f32));
            spread(q.x as u64) | spread(q.y as u64) << 1 | spread(q.z as u64) << 2
        };
        let mut order: Vec<(u64, u32)> = pts
            .par_iter()
            .enumerate()
            .map(|(i, &p)| (key(p), i as u32))
            .collect();
        order.par_sort_unstable();
        let mut values = vec![0.0f32; pts.len()];
        values
            .par_chunks_mut(CHUNK)
            .zip(order.par_chunks(CHUNK))
            .for_each(|(v, o)| {
                for (v, &(_, i)) in v.iter_mut().zip(o) {
                    *v = self.value(pts[i as usize]);
                }
            });
        for (&(_, i), v) in order.iter().zip(values) {
            out[i as usize] = v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::TreeBuilder;
    use crate::field::primitive::{Primitive, PrimitiveSpec};

    #[test]
    fn spread_interleaves_bits() {
        assert_eq!(spread(0b1), 0b1);
        assert_eq!(spread(0b11), 0b1001);
        assert_eq!(spread((1 << BITS) - 1).count_ones(), BITS);
        assert_eq!(spread(1 << (BITS - 1)), 1 << (3 * (BITS - 1)));
    }

    #[test]
    fn batch_values_equal_point_values_in_the_callers_order() {
        let mut b = TreeBuilder::new();
        let mut kids = Vec::new();
        let mut s = 1u32;
        let mut rnd = || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s as f32 / u32::MAX as f32
        };
        for _ in 0..64 {
            let c = Vec3::new(rnd() * 40.0, rnd() * 40.0, rnd() * 10.0);
            let spec: PrimitiveSpec = ron::from_str(&format!(
                "(shape: Sphere(center: ({}, {}, {}), radius: 1.5), falloff: 3.0)",
                c.x, c.y, c.z
            ))
            .unwrap();
            kids.push(b.primitive(Primitive::from_spec(&spec, 0), None));
        }
        let root = b.blend(kids, None);
        let tree = b.build(root);
        for n in [10, 20_000] {
            let pts: Vec<Vec3> = (0..n)
                .map(|_| Vec3::new(rnd() * 44.0 - 2.0, rnd() * 44.0 - 2.0, rnd() * 14.0 - 2.0))
                .collect();
            let mut out = vec![f32::NAN; n];
            tree.values(&pts, &mut out);
            let inside = out.iter().filter(|&&v| v > 0.0).count();
            assert!(inside > n / 20, "{inside} of {n} points see a sphere");
            for (p, v) in pts.iter().zip(&out) {
                assert_eq!(*v, tree.value(*p), "at {p}");
            }
        }
    }
}

//! Polyline storage shared by the polyline and curve skeletons: segments grouped in
//! chunks of consecutive segments with bounding boxes, so a query skips the chunks that
//! cannot hold the closest point.

use glam::Vec3;

use super::{Project, Segment};
use crate::field::bounds::Aabb;

/// Segments per chunk.
const CHUNK: usize = 8;

/// A connected polyline: the union of its segments.
#[derive(Clone, Debug, PartialEq)]
pub struct Chain {
    segments: Vec<Segment>,
    /// Bounding box of each run of [`CHUNK`] consecutive segments.
    chunks: Vec<Aabb>,
    bounds: Aabb,
}

impl Chain {
    /// The polyline through `points` (consecutive duplicates dropped; a single distinct
    /// point gives a point). Panics only on an empty input, which specs rule out.
    pub fn new(points: impl IntoIterator<Item = Vec3>) -> Self {
        let mut pts: Vec<Vec3> = Vec::new();
        for p in points {
            if pts.last() != Some(&p) {
                pts.push(p);
            }
        }
        assert!(!pts.is_empty(), "a chain needs at least one point");
        if pts.len() == 1 {
            pts.push(pts[0]);
        }
        let segments: Vec<Segment> = pts.windows(2).map(|w| Segment::new(w[0], w[1])).collect();
        let chunks: Vec<Aabb> = segments
            .chunks(CHUNK)
            .map(|c| c.iter().fold(Aabb::EMPTY, |b, s| b.union(s.bounds())))
            .collect();
        let bounds = chunks.iter().fold(Aabb::EMPTY, |b, c| b.union(*c));
        Chain {
            segments,
            chunks,
            bounds,
        }
    }

    /// The segments, in order.
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// The vertices, in order.
    pub fn points(&self) -> impl Iterator<Item = Vec3> + '_ {
        std::iter::once(self.segments[0].a()).chain(self.segments.iter().map(|s| s.b()))
    }

    /// `(index of the nearest segment, squared distance)` among segments closer than
    /// `cap`, or `None`.
    fn nearest(&self, p: Vec3, cap: f32) -> Option<(usize, f32)> {
        let mut best = cap * cap;
        let mut at = None;
        for (c, b) in self.chunks.iter().enumerate() {
            let gap = p - b.clamp(p);
            if gap.length_squared() >= best {
                continue;
            }
            let start = c * CHUNK;
            for (i, s) in self.segments[start..(start + CHUNK).min(self.segments.len())]
                .iter()
                .enumerate()
            {
                let d2 = s.distance_squared(p);
                if d2 < best {
                    best = d2;
                    at = Some(start + i);
                }
            }
        }
        at.map(|i| (i, best))
    }

    /// `min(distance(p), cap)`. Never inlined: it keeps [`super::Skeleton`]'s dispatch
    /// small enough to inline into the single-piece kinds' hot paths (a sphere's value
    /// runs twice as fast).
    #[inline(never)]
    pub fn distance_capped(&self, p: Vec3, cap: f32) -> f32 {
        self.nearest(p, cap).map_or(cap, |(_, d2)| d2.sqrt())
    }

    /// The closest point of the polyline.
    pub fn closest(&self, p: Vec3) -> Vec3 {
        let (i, _) = self
            .nearest(p, f32::INFINITY)
            .expect("a chain has segments");
        self.segments[i].closest(p)
    }

    /// A box holding the polyline.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// See [`super::Skeleton::visit_pieces`]: the pieces are the segments.
    pub fn visit_segments(
        &self,
        p: Vec3,
        mut reach: f32,
        f: &mut dyn FnMut(&dyn Project, f32) -> f32,
    ) {
        for (c, b) in self.chunks.iter().enumerate() {
            if b.distance(p) >= reach {
                continue;
            }
            let start = c * CHUNK;
            for s in &self.segments[start..(start + CHUNK).min(self.segments.len())] {
                let rho = s.distance(p);
                if rho < reach {
                    reach = f(s, rho);
                }
            }
        }
    }
}

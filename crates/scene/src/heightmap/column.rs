//! The top of one column: the highest `z` where the field crosses `T` going down.
//!
//! The tree's z-bands over the column (Paris et al. 2019 §7) say where the surface can
//! lie; between and above them the field keeps its side, and above the highest band it
//! is empty. Where the tree is a heightfield over the column and no band rises above
//! the heightfield's range, the top is the elevation itself (direct elevation
//! extraction, Paris et al. 2019 §7). Elsewhere each band, from the highest down, is
//! traced downwards with local Lipschitz bounds over candidate segments (Génevaux et al.
//! 2015 §7.2) along the tree restricted to the vertical line, and the first crossing is
//! located to the tolerance by the tracer's bracketing refinement.

use glam::{Vec2, Vec3};

use crate::field::{Field, ISO, Interval, Rect, Tree, ZBands};
use crate::render::{Method, Ray, TraceParams, Tracer};

/// How a column's top is found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TopOptions {
    /// The crossing is located to within this many metres.
    pub tolerance: f32,
    /// Read the top straight off a heightfield where the tree is one over the column;
    /// `false` traces every column (for checking the shortcut).
    pub direct: bool,
}

/// Finds column tops in one tree; keep one per thread (it reuses its buffers).
pub struct Columns<'t> {
    tree: &'t Tree,
    tracer: Tracer<'t>,
    bands: ZBands,
    params: TraceParams,
    direct: bool,
    /// Half the side of the footprint the bands are asked over.
    pad: f32,
}

impl<'t> Columns<'t> {
    /// A column finder for `tree` with `opts`.
    pub fn new(tree: &'t Tree, opts: &TopOptions) -> Self {
        let params = TraceParams {
            // The tracer locates a bracketed crossing to a tenth of ε.
            epsilon: opts.tolerance,
            ..TraceParams::for_scene(Method::Segment, 1.0)
        };
        Columns {
            tree,
            tracer: Tracer::new(tree),
            bands: ZBands::new(),
            params,
            direct: opts.direct,
            pad: opts.tolerance,
        }
    }

    /// The top of the solid over `xy`, or `None` where the column holds no solid.
    pub fn top(&mut self, xy: Vec2) -> Option<f32> {
        let support = self.tree.support();
        // A footprint of a tolerance around the point: bands over it hold those over the
        // point, and some nodes' interval bounds miss the surface over a degenerate
        // (zero-width) box.
        let fp = Rect::new(xy - self.pad, xy + self.pad);
        if !support.footprint().overlaps(&fp) {
            return None;
        }
        self.bands.clear();
        self.tree.z_bands(&fp, support.z(), &mut self.bands);
        let highest = self.bands.as_slice().last()?.hi;
        if self.direct
            && let Some(e) = self.tree.elevation(&fp)
        {
            let h = e.source.height(xy);
            if h.is_finite() && e.z.contains(h) && highest <= e.z.hi {
                return Some(h);
            }
        }
        (0..self.bands.as_slice().len())
            .rev()
            .find_map(|k| self.top_in(xy, self.bands.as_slice()[k]))
    }

    /// The highest crossing into the solid inside `band` (empty above it).
    fn top_in(&mut self, xy: Vec2, band: Interval) -> Option<f32> {
        let ray = Ray {
            origin: Vec3::new(xy.x, xy.y, band.hi),
            dir: Vec3::NEG_Z,
        };
        // The band's top may round into the solid: the surface is there.
        if self.tree.value(ray.origin) > ISO {
            return Some(band.hi);
        }
        // Every step advances at least ε: with this many, the march reaches the band's
        // bottom before giving up. A tracer out of steps declares a miss, and a missed
        // band would put the top on a lower one (a loose local bound over the band, as
        // around noisy carved primitives, makes steps of millimetres).
        let params = TraceParams {
            max_steps: (band.width() / self.params.epsilon)
                .ceil()
                .min(u32::MAX as f32) as u32
                + self.params.max_steps,
            ..self.params
        };
        let hit = self.tracer.trace(&ray, (0.0, band.width()), &params);
        hit.hit().then_some(band.hi - hit.t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::{Heightfield, HeightfieldField, ImplicitParams};
    use crate::field::TreeBuilder;
    use std::sync::Arc;

    /// A tilted, bumpy heightfield as a one-leaf tree.
    fn terrain() -> (Tree, Arc<HeightfieldField>) {
        let n = 33;
        let z = (0..n * n)
            .map(|k| {
                let (x, y) = ((k % n) as f32, (k / n) as f32);
                100.0 + 2.0 * x + 8.0 * (0.3 * y).sin()
            })
            .collect();
        let hf = Heightfield::new(n, n, Vec2::ZERO, Vec2::splat(10.0), z).unwrap();
        let leaf =
            Arc::new(HeightfieldField::new(&hf, &ImplicitParams::with_falloff(20.0)).unwrap());
        let mut b = TreeBuilder::new();
        let id = b.leaf(leaf.clone(), None);
        (b.build(id), leaf)
    }

    #[test]
    fn traced_tops_match_the_elevation() {
        let (tree, leaf) = terrain();
        let tol = 0.01;
        for direct in [true, false] {
            let mut c = Columns::new(
                &tree,
                &TopOptions {
                    tolerance: tol,
                    direct,
                },
            );
            for k in 0..200 {
                // Inside the domain: it ends a falloff (20 m) inside the grid.
                let xy = Vec2::new(25.3 + 1.35 * k as f32, 294.0 - 1.33 * k as f32);
                let top = c.top(xy).expect("a surface");
                let h = leaf.height(xy);
                assert!((top - h).abs() <= tol, "{xy} direct {direct}: {top} vs {h}");
            }
            assert_eq!(c.top(Vec2::new(-500.0, 0.0)), None);
        }
    }
}

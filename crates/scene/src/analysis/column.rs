//! What a vertical line meets: the surface crossings of a tree along the column through a
//! point, found inside the tree's z-bands (Paris et al. 2019 §7) with Lipschitz-bounded
//! steps along a [`Line`] (Génevaux et al. 2015 §7.2), not by sampling the whole height.

use glam::{Vec2, Vec3};

use crate::field::{Field, ISO, Interval, Line, Rect, Tree, ZBands};

/// What the vertical line through a point meets, top down.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Column {
    /// Altitude of the highest surface crossing (where the line enters solid), `None`
    /// when the line meets no solid.
    pub top: Option<f32>,
    /// Solid runs along the line: 1 over plain ground, 2 or more where solid lies over
    /// empty space (a cave's roof over its floor, an arch over the valley, an overhang).
    pub solid_runs: u32,
}

/// Bisection steps that refine a crossing.
const BISECTIONS: u32 = 16;

/// Probes vertical lines through a tree; reuse one per thread.
pub struct ColumnProbe<'t> {
    tree: &'t Tree,
    line: Line<'t>,
    bands: ZBands,
    z: Interval,
    min_step: f32,
}

impl<'t> ColumnProbe<'t> {
    /// A probe of `tree` that steps at least `min_step` metres: empty gaps (or solid
    /// layers) thinner than that may be missed.
    pub fn new(tree: &'t Tree, min_step: f32) -> Self {
        ColumnProbe {
            tree,
            line: Line::new(tree),
            bands: ZBands::new(),
            z: tree.support().z(),
            min_step: min_step.max(1e-4),
        }
    }

    /// The column through `xy`.
    pub fn probe(&mut self, xy: Vec2) -> Column {
        let mut col = Column::default();
        if self.z.is_empty() {
            return col;
        }
        self.bands.clear();
        let fp = Rect::new(xy, xy).dilate(1e-3);
        self.tree.z_bands(&fp, self.z, &mut self.bands);
        self.bands.clip(self.z);
        let top = self.z.hi;
        self.line.restrict(
            Vec3::new(xy.x, xy.y, top),
            Vec3::NEG_Z,
            (0.0, self.z.width()),
        );
        // Above the highest band the sign is the one at the support's top.
        let mut solid = self.line.value(0.0) > ISO;
        if solid {
            col.solid_runs = 1;
            col.top = Some(top);
        }
        for k in (0..self.bands.as_slice().len()).rev() {
            let band = self.bands.as_slice()[k];
            self.march(top - band.hi, top - band.lo, &mut solid, &mut col);
        }
        col
    }

    /// Marches `t ∈ [t0, t1]` down the line, counting the entries into solid.
    fn march(&mut self, t0: f32, t1: f32, solid: &mut bool, col: &mut Column) {
        let mut t = t0;
        let mut f = self.line.value(t);
        // The sign may differ from the one above the band only at a crossing exactly on
        // its top: count it there.
        self.cross(t, t, f, solid, col);
        let mut reach = t1 - t0;
        while t < t1 {
            let end = (t + reach).min(t1);
            let l = self.line.lipschitz(t, end).max(f32::MIN_POSITIVE);
            let safe = (f - ISO).abs() / l;
            let step = if safe >= end - t {
                end - t
            } else {
                safe.max(self.min_step).min(t1 - t)
            };
            let (tn, fnext) = (t + step, self.line.value(t + step));
            self.cross(t, tn, fnext, solid, col);
            // Segment tracing: try twice as far next time.
            reach = (2.0 * step).max(self.min_step);
            (t, f) = (tn, fnext);
        }
    }

    /// Records a crossing in `[ta, tb]` when the value `fb` at `tb` changes the side.
    fn cross(&mut self, ta: f32, tb: f32, fb: f32, solid: &mut bool, col: &mut Column) {
        let now = fb > ISO;
        if now == *solid {
            return;
        }
        *solid = now;
        if now {
            col.solid_runs += 1;
            if col.top.is_none() {
                let (mut lo, mut hi) = (ta, tb);
                for _ in 0..BISECTIONS {
                    let m = 0.5 * (lo + hi);
                    if self.line.value(m) > ISO {
                        hi = m;
                    } else {
                        lo = m;
                    }
                }
                col.top = Some(self.z.hi - 0.5 * (lo + hi));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::skeleton::{Point, Skeleton};
    use crate::field::{Primitive, TreeBuilder};

    /// Balls of radius 4 (energy 1, falloff radius 8) at the given heights over `(0, 0)`.
    fn balls(zs: &[f32]) -> Tree {
        let mut b = TreeBuilder::new();
        let ids = zs
            .iter()
            .map(|&z| {
                let s = Skeleton::Point(Point {
                    center: Vec3::new(0.0, 0.0, z),
                });
                b.primitive(Primitive::new(s, 8.0, 1.0, None).unwrap(), None)
            })
            .collect();
        let root = b.union(ids, None);
        b.build(root)
    }

    #[test]
    fn one_ball_is_one_run_and_its_top_is_on_the_surface() {
        let tree = balls(&[10.0]);
        let mut p = ColumnProbe::new(&tree, 0.05);
        let c = p.probe(Vec2::ZERO);
        assert_eq!(c.solid_runs, 1);
        let top = c.top.unwrap();
        assert!(tree.value(Vec3::new(0.0, 0.0, top - 0.01)) > ISO);
        assert!(tree.value(Vec3::new(0.0, 0.0, top + 0.01)) < ISO);
        assert_eq!(p.probe(Vec2::new(100.0, 0.0)), Column::default());
    }

    #[test]
    fn a_ball_over_a_ball_is_two_runs_topped_by_the_upper_one() {
        let tree = balls(&[0.0, 30.0]);
        let mut p = ColumnProbe::new(&tree, 0.05);
        let c = p.probe(Vec2::ZERO);
        assert_eq!(c.solid_runs, 2);
        assert!(c.top.unwrap() > 30.0);
    }
}

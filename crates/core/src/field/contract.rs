//! The one contract every node of the field answers (ARCHITECTURE.md, "Invariants").

use glam::{Vec2, Vec3};

use super::bounds::{Aabb, Interval, Rect, ZBands};
use super::falloff::ISO;

/// A scalar field `f: R³ → R` in the BlobTree convention: solid where `f > T`.
///
/// Every bound must be **sound**: the true values lie inside the reported interval, the true
/// slope never exceeds the reported Lipschitz bound, and the surface never lies outside the
/// reported z-bands. Tests sample every implementation to check it.
pub trait Field: Send + Sync {
    /// `f(p)`.
    fn value(&self, p: Vec3) -> f32;

    /// `(f(p), ∇f(p))`; analytic where the maths allows.
    fn value_grad(&self, p: Vec3) -> (f32, Vec3);

    /// A box outside which `f = 0`.
    fn support(&self) -> Aabb;

    /// A range containing `f(p)` for every `p` in `b`.
    fn interval(&self, b: &Aabb) -> Interval;

    /// A global Lipschitz bound: `|f(p) − f(q)| ≤ λ‖p − q‖`.
    fn lipschitz(&self) -> f32;

    /// A Lipschitz bound valid for pairs of points inside `b`.
    fn lipschitz_box(&self, b: &Aabb) -> f32;

    /// A Lipschitz bound valid on the segment `[a, b]`.
    fn lipschitz_segment(&self, a: Vec3, b: Vec3) -> f32 {
        self.lipschitz_box(&Aabb::new(a, b))
    }

    /// Adds to `out` the z-intervals where the surface `f = T` can lie over the footprint
    /// `fp`, searched inside `z`. The default subdivides `z` with [`Field::interval`].
    fn z_bands(&self, fp: &Rect, z: Interval, out: &mut ZBands) {
        z_bands_by_interval(self, fp, z, out);
    }

    /// Whether [`Field::z_bands`] searched inside `z` are always the bands searched inside
    /// any larger range, intersected with `z` (the bands do not depend on where they are
    /// searched): one search per footprint then serves several ranges. Default `false`.
    fn z_bands_clip(&self) -> bool {
        false
    }

    /// A field equal to this one inside `region` and cheaper to evaluate there (children
    /// that cannot matter in `region` dropped), or `None` when nothing can be dropped.
    fn prune(&self, _region: &Aabb) -> Option<Box<dyn Field + '_>> {
        None
    }

    /// Values on a block of grid points: `out[i + nx·(j + ny·k)] = f(origin + (i, j, k)·step)`
    /// for `dims = [nx, ny, nz]`. Trees override it to prune once per block.
    fn eval_block(&self, origin: Vec3, step: Vec3, dims: [usize; 3], out: &mut [f32]) {
        let [nx, ny, nz] = dims;
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let p = origin + Vec3::new(i as f32, j as f32, k as f32) * step;
                    out[i + nx * (j + ny * k)] = self.value(p);
                }
            }
        }
    }

    /// Values along the vertical line over `xy`, when the field can share work between
    /// them: `out[k] = f(xy, zs[k])`, bit for bit what [`Field::value`] gives at those
    /// points, and `true`. The default shares nothing and answers `false`, leaving `out`
    /// as it is; a heightfield leaf (one elevation lookup per line instead of one per
    /// point) and a tree whose root is such a leaf override it. The mesher evaluates its
    /// sample columns this way where it can.
    fn eval_column(&self, _xy: Vec2, _zs: &[f32], _out: &mut [f32]) -> bool {
        false
    }

    /// When, over the footprint `fp`, the field is a heightfield's, returns it: for
    /// `p` in `fp × e.z`, `f(p) > T ⇔ p.z < e.height(p.xy)` and the surface is `z = h`.
    /// The mesher then places vertices straight on the elevation (Paris et al. 2019 §7).
    fn elevation(&self, _fp: &Rect) -> Option<Elevation<'_>> {
        None
    }

    /// The concrete leaf as [`std::any::Any`], for encoders that translate known leaf
    /// kinds (the GPU tape, `tape::tape_from_tree`). Leaves that want to be
    /// recognised return `Some(self)`; the default is opaque.
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        None
    }
}

/// An elevation function `h(x, y)` in the tree's frame (metres).
pub trait ElevationSource: Send + Sync {
    /// `h(xy)`; may be NaN outside the source's domain.
    fn height(&self, xy: Vec2) -> f32;
}

/// Answer of [`Field::elevation`]: the field is a heightfield `h` inside `fp × z`.
#[derive(Clone, Copy)]
pub struct Elevation<'a> {
    /// The elevation.
    pub source: &'a dyn ElevationSource,
    /// Where the equivalence holds.
    pub z: Interval,
}

/// Depth of the generic z-band search: bands are resolved to `z.width() / 2^depth` at
/// most.
const Z_BAND_DEPTH: u32 = 6;

/// The generic z-band search stops halving a slab once it is at most this many times as
/// tall as the footprint is wide. The mesher's footprints are one cell wide, so its bands
/// come in slabs of up to this many cells: an interval query of a Feature Volume costs
/// several evaluations (its bricks' bounds, the noise's, a value at the centre), and its
/// bounds on a cell-sized box are loose by the displacement noise's amplitude anyway, so
/// halving slabs down to a cell cost more queries than the evaluations it saved (on the
/// main view's feature cells, 0.20 s of bands for 0.03 s of values; at 8, 0.05 s each).
const Z_BAND_ASPECT: f32 = 8.0;

/// Sound z-bands by interval subdivision: keeps every slab whose interval contains `T`,
/// halved while it is taller than [`Z_BAND_ASPECT`] footprints (and [`Z_BAND_DEPTH`]
/// times at most).
pub fn z_bands_by_interval<F: Field + ?Sized>(f: &F, fp: &Rect, z: Interval, out: &mut ZBands) {
    /// Keeps the slabs of `z` taller than `tall` halved, `depth` times at most.
    fn rec<F: Field + ?Sized>(
        f: &F,
        fp: &Rect,
        z: Interval,
        tall: f32,
        depth: u32,
        out: &mut ZBands,
    ) {
        if !f.interval(&fp.extrude(z)).contains(ISO) {
            return;
        }
        if depth == 0 || z.width() <= tall {
            out.push(z);
            return;
        }
        let m = z.mid();
        rec(f, fp, Interval::new(z.lo, m), tall, depth - 1, out);
        rec(f, fp, Interval::new(m, z.hi), tall, depth - 1, out);
    }
    if !z.is_empty() {
        let tall = Z_BAND_ASPECT * (fp.max - fp.min).max_element();
        rec(f, fp, z, tall, Z_BAND_DEPTH, out);
    }
}

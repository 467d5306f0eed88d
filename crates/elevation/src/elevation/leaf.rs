//! The 3D leaf of an elevation tree: Paris et al. 2019 §5.1's implicit heightfield over the
//! tree's elevation function instead of a raster.
//!
//! `f = min(σ_R(h(p.xy) − p.z), f_P(p))` exactly as [`crate::dem::HeightfieldField`], with
//! the same prism ([`crate::dem::prism::Prism`]) over the rectangle `Ω = extent` (whose
//! clearance is exact and 1-Lipschitz). Where the raster leaf reads its min/max and slope
//! pyramids, this one asks the tree for its bounds over the footprint (Génevaux et al.
//! 2015 §7.3): the range of `h` is the tree's range intersected with
//! `h(centre) ± λ_h · half-diagonal`, and `λ_h` is the tree's local Lipschitz bound, so
//! `λ ≤ σ'_max √(1 + λ_h²)` as for the raster. `h` is evaluated at every query: the leaf
//! can be meshed at any cell size. Its gradient is a central difference of `h` (Génevaux
//! et al. 2015 §3).

use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::geometry::{clearance, clearance_grad, clearance_range, rect_centre};
use super::{ElevationError, ElevationTree, Lod};
use crate::dem::prism::Prism;
use crate::field::contract::{Elevation, ElevationSource};
use crate::field::falloff::{
    ISO, WYVILL_MAX_SLOPE, sigma, sigma_d, sigma_interval, sigma_max_slope, sigma_slope,
    wyvill_interval, wyvill_slope,
};
use crate::field::{Aabb, Field, Interval, Rect, ZBands};

/// Step of the central differences of `h`, metres.
const GRAD_STEP: f32 = 0.02;

/// Parameters of the implicitization.
#[derive(Clone, Debug, PartialEq)]
pub struct ElevationParams {
    /// The domain `Ω` (tree frame).
    pub extent: Rect,
    /// Falloff distance `R` (> 0), metres.
    pub falloff: f32,
    /// How far below the lowest elevation the prism's floor lies (≥ 0).
    pub base_depth: f32,
    /// The level of detail `h` is evaluated at.
    pub lod: Lod,
}

/// The implicit leaf of an elevation tree.
#[derive(Clone, Debug)]
pub struct ElevationField {
    tree: Arc<ElevationTree>,
    params: ElevationParams,
    prism: Prism,
    lip_h: f32,
    support: Aabb,
}

impl ElevationField {
    /// Implicitizes `tree` with `params`.
    pub fn new(
        tree: Arc<ElevationTree>,
        params: ElevationParams,
    ) -> Result<ElevationField, ElevationError> {
        let bad = |s: String| Err(ElevationError::Leaf(s));
        let (r, ext) = (params.falloff, params.extent);
        if !(r > 0.0 && r.is_finite()) {
            return bad(format!("`falloff` must be > 0, got {r}"));
        }
        if !(params.base_depth >= 0.0 && params.base_depth.is_finite()) {
            return bad(format!(
                "`base_depth` must be >= 0, got {}",
                params.base_depth
            ));
        }
        if !(ext.min.is_finite() && ext.max.is_finite() && ext.min.cmplt(ext.max).all()) {
            return bad(format!(
                "`extent` must be a finite rectangle with min < max, got {} .. {}",
                ext.min, ext.max
            ));
        }
        let b = tree.bounds(&ext, &params.lod);
        if !(b.f.range.lo.is_finite() && b.f.range.hi.is_finite() && b.f.lipschitz.is_finite()) {
            return bad("the tree's elevations are not bounded over `extent`".into());
        }
        let dz = Interval::new(b.f.range.lo - params.base_depth, b.f.range.hi + r);
        Ok(ElevationField {
            support: ext.extrude(Interval::new(dz.lo - r, dz.hi)),
            prism: Prism { r, dz },
            lip_h: b.f.lipschitz,
            tree,
            params,
        })
    }

    /// The elevation tree.
    pub fn tree(&self) -> &ElevationTree {
        &self.tree
    }

    /// The parameters it was built with.
    pub fn params(&self) -> &ElevationParams {
        &self.params
    }

    /// The prism's vertical extent `Δz`.
    pub fn prism_z(&self) -> Interval {
        self.prism.dz
    }

    /// Global Lipschitz bound of `h` over the extent.
    pub fn lipschitz_h(&self) -> f32 {
        self.lip_h
    }

    /// `h(xy)` at the leaf's level of detail.
    #[inline]
    pub fn height(&self, xy: Vec2) -> f32 {
        self.tree.height(xy, &self.params.lod)
    }

    /// `(h, ∇h)` by central differences.
    fn height_grad(&self, xy: Vec2) -> (f32, Vec2) {
        let d = |e: Vec2| (self.height(xy + e) - self.height(xy - e)) / (2.0 * GRAD_STEP);
        (
            self.height(xy),
            Vec2::new(d(Vec2::X * GRAD_STEP), d(Vec2::Y * GRAD_STEP)),
        )
    }

    /// The range of `h` over `fp` and a Lipschitz bound of `h` there.
    fn h_bounds(&self, fp: &Rect) -> (Interval, f32) {
        let ext = &self.params.extent;
        let fp = Rect {
            min: fp.min.max(ext.min),
            max: fp.max.min(ext.max),
        };
        if fp.min.cmpgt(fp.max).any() {
            return (Interval::EMPTY, 0.0);
        }
        let b = self.tree.bounds(&fp, &self.params.lod);
        let (c, hd) = rect_centre(&fp);
        let hc = self.height(c);
        let reach = b.f.lipschitz * hd * (1.0 + 1e-5) + self.prism.eps(hc.abs());
        let near = Interval::new(hc - reach, hc + reach);
        let h = Interval::new(b.f.range.lo.max(near.lo), b.f.range.hi.min(near.hi));
        let eps = self.prism.eps(h.lo.abs().max(h.hi.abs()));
        (h.dilate(eps), b.f.lipschitz)
    }
}

impl Field for ElevationField {
    #[inline]
    fn value(&self, p: Vec3) -> f32 {
        let xy = p.truncate();
        let e = clearance(&self.params.extent, xy);
        if e <= 0.0 {
            return 0.0;
        }
        let r = self.prism.r;
        sigma(self.height(xy) - p.z, r).min(self.prism.value((r - e).max(0.0), p.z))
    }

    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let xy = p.truncate();
        let (e, ge) = clearance_grad(&self.params.extent, xy);
        if e <= 0.0 {
            return (0.0, Vec3::ZERO);
        }
        let r = self.prism.r;
        let (h, gh) = self.height_grad(xy);
        let (ft, dft) = sigma_d(h - p.z, r);
        let (fp, gfp) = self.prism.value_grad((r - e).max(0.0), -ge, p.z);
        if ft <= fp {
            (ft, gh.extend(-1.0) * dft)
        } else {
            (fp, gfp)
        }
    }

    fn support(&self) -> Aabb {
        self.support
    }

    fn interval(&self, b: &Aabb) -> Interval {
        let fp = b.footprint();
        let e = clearance_range(&self.params.extent, &fp);
        if e.hi <= 0.0 {
            return Interval::ZERO;
        }
        let (h, _) = self.h_bounds(&fp);
        if h.is_empty() {
            return Interval::ZERO;
        }
        let (z, r) = (b.z(), self.prism.r);
        let ft = sigma_interval(Interval::new(h.lo - z.hi, h.hi - z.lo), r);
        let d = self.prism.dist_range(e, z);
        let f = ft.min(wyvill_interval(d.scale(1.0 / r)).scale(2.0 * ISO));
        if e.lo <= 0.0 {
            f.hull(Interval::ZERO)
        } else {
            f
        }
    }

    fn lipschitz(&self) -> f32 {
        let r = self.prism.r;
        let lt = sigma_max_slope(r) * (1.0 + self.lip_h * self.lip_h).sqrt();
        lt.max(2.0 * ISO * WYVILL_MAX_SLOPE / r)
    }

    fn lipschitz_box(&self, b: &Aabb) -> f32 {
        let fp = b.footprint();
        let e = clearance_range(&self.params.extent, &fp);
        if e.hi <= 0.0 {
            return 0.0;
        }
        let (h, s) = self.h_bounds(&fp);
        let (z, r) = (b.z(), self.prism.r);
        let lt = if h.is_empty() {
            0.0
        } else {
            sigma_slope(Interval::new(h.lo - z.hi, h.hi - z.lo), r) * (1.0 + s * s).sqrt()
        };
        let d = self.prism.dist_range(e, z);
        lt.max(2.0 * ISO * wyvill_slope(d.scale(1.0 / r)) / r)
    }

    fn z_bands(&self, fp: &Rect, z: Interval, out: &mut ZBands) {
        let e = clearance_range(&self.params.extent, fp);
        if e.hi <= 0.0 {
            return;
        }
        self.prism.z_bands(e, self.h_bounds(fp).0, z, out);
    }

    fn eval_block(&self, origin: Vec3, step: Vec3, dims: [usize; 3], out: &mut [f32]) {
        let [nx, ny, nz] = dims;
        let plane = nx * ny;
        let r = self.prism.r;
        for j in 0..ny {
            for i in 0..nx {
                let xy = (origin + Vec3::new(i as f32, j as f32, 0.0) * step).truncate();
                let e = clearance(&self.params.extent, xy);
                let base = i + nx * j;
                if e <= 0.0 {
                    for k in 0..nz {
                        out[base + plane * k] = 0.0;
                    }
                    continue;
                }
                let (h, dxy) = (self.height(xy), (r - e).max(0.0));
                for k in 0..nz {
                    let z = origin.z + k as f32 * step.z;
                    out[base + plane * k] = sigma(h - z, r).min(self.prism.value(dxy, z));
                }
            }
        }
    }

    fn elevation(&self, fp: &Rect) -> Option<Elevation<'_>> {
        (clearance_range(&self.params.extent, fp).lo >= self.prism.r).then_some(Elevation {
            source: self,
            z: self.prism.dz,
        })
    }

    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

impl ElevationSource for ElevationField {
    fn height(&self, xy: Vec2) -> f32 {
        ElevationField::height(self, xy)
    }
}

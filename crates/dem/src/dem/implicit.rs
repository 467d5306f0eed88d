//! The implicit heightfield primitive of Paris et al. 2019 §5.1.
//!
//! Given an elevation `h` over a horizontal domain Ω (see [`super::domain`]):
//!
//! * surface field `f_T(p) = σ_R(h(p.xy) − p.z)` — `σ` is [`falloff::sigma`], monotone with
//!   `σ(0) = T`, so `f_T > T` exactly below the terrain (see `falloff.rs` for why our `σ`
//!   differs from the paper's);
//! * prism `P = (Ω ⊖ B(R)) × Δz` with `Δz = [z_min − base_depth, z_max + R]`, and prism
//!   field `f_P(p) = 2T · g(d(p, P) / R)` (Wyvill `g`). The paper says "equal to T within the
//!   prism", but `f = min(f_T, f_P)` must equal `f_T` inside the prism, where `f_T` reaches
//!   `2T`, so we scale `g` by `2T`: `f_P = 2T` inside `P`, 0 beyond distance `R`;
//! * `f = min(f_T, f_P)`.
//!
//! The distance to `P` is computed as `√(d_xy² + d_z²)` with `d_xy = max(0, R − e(xy))`,
//! `e` the clearance of Ω. This equals the Euclidean distance to `P` wherever the nearest
//! point of the eroded domain is reached straight across the boundary (all convex domains);
//! in narrow necks it is a lower bound, so the prism is never thinner than the paper's. It
//! vanishes exactly on `Ω ⊖ B(R) = {e ≥ R}` and reaches `R` on `∂Ω`, so `f = 0` outside Ω.
//!
//! The solid is the terrain inside `{e ≥ R}`, closed by side walls where `f_P = T`
//! (`d = d* = R·√(1 − 2^(−1/3)) ≈ 0.454 R`, i.e. `e ≈ 0.546 R`) and a floor at
//! `Δz.lo − d*`.
//!
//! With [`ImplicitParams::detail`], `h` becomes `h(x, y) + d(p)`, the 3D detail of Frasson
//! et al. §5 ([`super::detail`]): the bounds widen by the detail's reach and slope, and
//! [`HeightfieldField::height`] answers the detailed surface.
//!
//! With an inset ([`HeightfieldField::with_inset`]), `h` becomes `h(x, y) + δ(x, y)`: `δ` a
//! fine grid of changes over a rectangle, zero on its border, such as the eroded
//! amplification of the scene's erosion module. Its cells have a pyramid of their own: over
//! a footprint, the range and slope bound of `h + δ` are those of `h` plus those of `δ` over
//! the inset's cells under the footprint (0 where it reaches past the inset).

use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::detail::{Detail, DetailParams};
use super::domain::Domain;
use super::grid::{Heightfield, Interpolation};
use super::inset::Inset;
use super::prism::Prism;
use super::pyramid::MinMaxPyramid;
use super::{DemError, Georef};
use crate::field::contract::{Elevation, ElevationSource};
use crate::field::falloff::{
    ISO, WYVILL_MAX_SLOPE, sigma, sigma_d, sigma_interval, sigma_max_slope, sigma_slope,
    wyvill_interval, wyvill_slope,
};
use crate::field::{Aabb, Bound, Field, Interval, Rect, ZBands};

/// Parameters of the implicitization (validated by [`HeightfieldField::new`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ImplicitParams {
    /// Falloff distance `R` in metres (> 0): the width of the field's transition band
    /// around the terrain, and the erosion of the domain.
    pub falloff: f32,
    /// How far below the lowest elevation the prism's floor lies (≥ 0).
    pub base_depth: f32,
    /// Elevations are multiplied by this...
    pub vertical_scale: f32,
    /// ...then this is added (metres).
    pub vertical_offset: f32,
    /// Where the heightfield's sample `(0, 0)` is placed in the tree frame (local `(0, 0)`
    /// for a DEM as read, i.e. its south-west sample).
    pub placement: Vec2,
    /// An optional polygon (tree frame) cutting the domain.
    pub domain: Option<Vec<Vec2>>,
    /// Interpolation between samples.
    pub interpolation: Interpolation,
    /// Detail amplification (Frasson et al. §5), if any.
    pub detail: Option<DetailParams>,
}

impl ImplicitParams {
    /// Defaults for falloff `r`: base depth `r`, no scaling, no move, whole grid, bilinear.
    pub fn with_falloff(r: f32) -> ImplicitParams {
        ImplicitParams {
            falloff: r,
            base_depth: r,
            vertical_scale: 1.0,
            vertical_offset: 0.0,
            placement: Vec2::ZERO,
            domain: None,
            interpolation: Interpolation::Bilinear,
            detail: None,
        }
    }
}

/// What the points of one vertical line share ([`HeightfieldField::column`]).
struct Column {
    xy: Vec2,
    /// `h(xy)`, without detail.
    h: f32,
    /// Horizontal distance to the eroded domain, `max(0, R − e(xy))`.
    dxy: f32,
    /// The detail's reach `A·m(xy)`.
    reach: f32,
}

/// The implicit heightfield leaf: `f = min(σ_R(h − z), 2T·g(d(p, P)/R))`.
#[derive(Clone, Debug)]
pub struct HeightfieldField {
    hf: Heightfield,
    interp: Interpolation,
    r: f32,
    dz: Interval,
    domain: Domain,
    /// Per cell `[min h, max h, slope bound of h, detail reach A·max m]`: one query
    /// answers what every bound needs.
    cells: MinMaxPyramid<4>,
    lip_h: f32,
    detail: Option<Detail>,
    /// The changes `δ` added to `h` over the inset's extent (tree frame), 0 beyond it,
    /// and per inset cell `[min δ, max δ, slope bound of δ]`.
    inset: Option<(Arc<Inset>, MinMaxPyramid<3>)>,
    support: Aabb,
    params: ImplicitParams,
    georef: Option<Georef>,
}

impl HeightfieldField {
    /// Implicitizes `hf` (in its local frame) with `params`.
    pub fn new(hf: &Heightfield, params: &ImplicitParams) -> Result<HeightfieldField, DemError> {
        let p = params;
        let bad = |what: String| Err(DemError::Invalid { what });
        if !(p.falloff > 0.0 && p.falloff.is_finite()) {
            return bad(format!(
                "heightfield falloff must be > 0, got {}",
                p.falloff
            ));
        }
        if !(p.base_depth >= 0.0 && p.base_depth.is_finite()) {
            return bad(format!(
                "heightfield base_depth must be >= 0, got {}",
                p.base_depth
            ));
        }
        if !(p.vertical_scale.is_finite()
            && p.vertical_offset.is_finite()
            && p.placement.is_finite())
        {
            return bad("heightfield scale, offset and placement must be finite".into());
        }
        let z: Vec<f32> = hf
            .samples()
            .iter()
            .map(|&v| v * p.vertical_scale + p.vertical_offset)
            .collect();
        let placed = Heightfield::new(hf.nx(), hf.ny(), hf.origin() + p.placement, hf.cell(), z)?;
        HeightfieldField::placed(placed, p.clone(), None)
    }

    /// The leaf with `h + δ` in place of `h`: `δ` the inset's changes, in the tree frame,
    /// whose border samples are 0 (so that `h` stays continuous across the inset's edge),
    /// inside the DEM's extent. The leaf's other parameters and georeference are kept.
    pub fn with_inset(&self, inset: Arc<Inset>) -> Result<HeightfieldField, DemError> {
        let bad = |what: String| Err(DemError::Invalid { what });
        let delta = inset.delta();
        let (nx, ny) = (delta.nx(), delta.ny());
        let border = (0..nx)
            .flat_map(|i| [(i, 0), (i, ny - 1)])
            .chain((0..ny).flat_map(|j| [(0, j), (nx - 1, j)]));
        if let Some((i, j)) = border.into_iter().find(|&(i, j)| delta.at(i, j) != 0.0) {
            return bad(format!(
                "an inset's border samples must be 0; ({i}, {j}) is not"
            ));
        }
        if delta.nodata_count() > 0 {
            return bad("an inset has no nodata samples".into());
        }
        let (e, x) = (delta.extent(), self.hf.extent());
        if !x.contains_rect(&e) {
            return bad(format!(
                "the inset {e:?} is not inside the DEM's extent {x:?}"
            ));
        }
        let mut out = HeightfieldField::placed(self.hf.clone(), self.params.clone(), Some(inset))?;
        out.georef = self.georef.clone();
        Ok(out)
    }

    /// The leaf over the placed, scaled grid `placed`, with an optional inset.
    fn placed(
        placed: Heightfield,
        p: ImplicitParams,
        inset: Option<Arc<Inset>>,
    ) -> Result<HeightfieldField, DemError> {
        let bad = |what: String| Err(DemError::Invalid { what });
        let interp = p.interpolation;
        let domain = Domain::new(&placed, interp, p.domain.as_deref())?;
        let (cx, cy) = placed.cells();
        let detail = p
            .detail
            .as_ref()
            .map(|d| Detail::new(&placed, d))
            .transpose()?;
        let slopes = placed.cell_slopes(interp);
        let per_cell = placed
            .cell_ranges(interp)
            .into_iter()
            .zip(slopes)
            .enumerate()
            .map(|(k, ([lo, hi], [_, s]))| {
                let reach = detail
                    .as_ref()
                    .map_or(0.0, |d| d.cell_reach(k % cx, k / cx));
                [lo, hi, s, reach]
            })
            .collect();
        let cells = MinMaxPyramid::new(cx, cy, per_cell);
        let inset = inset.map(|i| {
            let d = i.delta();
            let (dx, dy) = d.cells();
            let per_cell = d
                .cell_ranges(interp)
                .into_iter()
                .zip(d.cell_slopes(interp))
                .map(|([lo, hi], [_, s])| [lo, hi, s])
                .collect();
            (i, MinMaxPyramid::new(dx, dy, per_cell))
        });
        let [zmin, zmax, lip_h, _] = cells.total();
        // δ is 0 on the inset's border, so its range holds 0
        let [dlo, dhi, ds] = inset.as_ref().map_or([0.0; 3], |(_, p)| p.total());
        let (zmin, zmax, lip_h) = (zmin + dlo, zmax + dhi, lip_h + ds);
        if zmin > zmax {
            return bad("the heightfield has no cell with a surface (too much nodata)".into());
        }
        let lip_h = lip_h.max(0.0);
        let reach = detail.as_ref().map_or(0.0, Detail::reach_total);
        let r = p.falloff;
        let dz = Interval::new(zmin - reach - p.base_depth, zmax + reach + r);
        let support = domain.bounds().extrude(Interval::new(dz.lo - r, dz.hi));
        Ok(HeightfieldField {
            hf: placed,
            interp,
            r,
            dz,
            domain,
            cells,
            lip_h,
            detail,
            inset,
            support,
            params: p,
            georef: None,
        })
    }

    /// Attaches the georeference of the DEM this leaf was built from (its local frame is the
    /// one the readers return: the south-west sample at `(0, 0)`).
    pub fn with_georef(mut self, georef: Georef) -> HeightfieldField {
        self.georef = Some(georef);
        self
    }

    /// The DEM's georeference, when the leaf was loaded from a file.
    pub fn georef(&self) -> Option<&Georef> {
        self.georef.as_ref()
    }

    /// CRS coordinates (f64) of a tree-frame point, undoing the placement.
    pub fn tree_to_crs(&self, xy: Vec2) -> Option<[f64; 2]> {
        let local = xy - self.params.placement;
        self.georef
            .as_ref()
            .map(|g| g.local_to_crs([f64::from(local.x), f64::from(local.y)]))
    }

    /// Tree-frame position of CRS coordinates (`None` without a georeference).
    pub fn crs_to_tree(&self, crs: [f64; 2]) -> Option<Vec2> {
        self.georef.as_ref().map(|g| {
            let l = g.crs_to_local(crs);
            Vec2::new(l[0] as f32, l[1] as f32) + self.params.placement
        })
    }

    /// The placed, scaled heightfield this leaf evaluates.
    pub fn heightfield(&self) -> &Heightfield {
        &self.hf
    }

    /// The parameters it was built with.
    pub fn params(&self) -> &ImplicitParams {
        &self.params
    }

    /// The prism's vertical extent `Δz`.
    pub fn prism_z(&self) -> Interval {
        self.dz
    }

    /// Global Lipschitz bound of `h` (after vertical scaling).
    pub fn lipschitz_h(&self) -> f32 {
        self.lip_h
    }

    /// The detail amplification, if any.
    pub fn detail(&self) -> Option<&Detail> {
        self.detail.as_ref()
    }

    /// The DEM's elevation `h(xy)` in the tree frame, without detail (NaN outside the
    /// cells with a surface).
    #[inline]
    pub fn base_height(&self, xy: Vec2) -> f32 {
        let h = self.hf.sample(xy, self.interp);
        // δ is NaN beyond the inset, where it is 0
        match self
            .inset
            .as_ref()
            .map(|(d, _)| d.delta().sample(xy, self.interp))
        {
            Some(dh) if !dh.is_nan() => h + dh,
            _ => h,
        }
    }

    /// `(h(xy), ∇h(xy))` with the inset's changes, if any.
    #[inline]
    fn base_height_grad(&self, xy: Vec2) -> (f32, Vec2) {
        let (h, g) = self.hf.sample_grad(xy, self.interp);
        match self
            .inset
            .as_ref()
            .map(|(d, _)| d.delta().sample_grad(xy, self.interp))
        {
            Some((dh, dg)) if !dh.is_nan() => (h + dh, g + dg),
            _ => (h, g),
        }
    }

    /// The inset (its changes `δ` in the tree frame, and their traces), if the leaf has one.
    pub fn inset(&self) -> Option<&Inset> {
        self.inset.as_ref().map(|(i, _)| &**i)
    }

    /// The elevation of the terrain surface over `xy` (NaN outside the cells with a
    /// surface): `h(xy)`, or with detail the highest `z` where `h(xy) + d(xy, z) = z`.
    ///
    /// Found by stepping down from `h + A·m`, where `h + d − z ≤ 0`, by
    /// `(z − h − d)/(1 + |∂d/∂z|)`: a step never passes a root, so it converges to the
    /// highest one, linearly at worst (48 steps at most).
    pub fn height(&self, xy: Vec2) -> f32 {
        let h = self.base_height(xy);
        let Some(d) = &self.detail else {
            return h;
        };
        let reach = d.reach_at(xy);
        if h.is_nan() || reach == 0.0 {
            return h;
        }
        let rate = 1.0 + d.slope_z(reach);
        let g = |z: f32| h + d.value(xy.extend(z)) - z;
        let tol = 1e-5 * (h.abs() + reach);
        let mut z = h + reach;
        let mut gz = g(z);
        for _ in 0..48 {
            if gz >= -tol {
                break;
            }
            z += gz / rate;
            gz = g(z);
        }
        z
    }

    /// The prism closing the terrain (shared with the elevation-tree leaf).
    #[inline]
    fn prism_shape(&self) -> Prism {
        Prism {
            r: self.r,
            dz: self.dz,
        }
    }

    /// `f_P` from the horizontal distance to the eroded domain and the height.
    #[inline]
    fn prism(&self, dxy: f32, z: f32) -> f32 {
        self.prism_shape().value(dxy, z)
    }

    /// The range of `h` over the cells under `fp` (`cells`, from the min/max pyramid)
    /// sharpened for footprints inside Ω (clearance `e_lo > 0`, so `h` is
    /// defined on all of `fp`): `h` is `s`-Lipschitz on the cells under `fp` (`s` from the
    /// slope pyramid) and `fp` is convex, so `|h(x) − h(c)| ≤ s·|x − c|` around its centre
    /// `c`. For a footprint smaller than a cell this is far tighter than the cells' ranges —
    /// it is what lets a ray step close to the terrain (Génevaux et al. 2015 §7.2: the
    /// Lipschitz bound of `h` along the ray).
    #[inline]
    fn h_range_near(&self, fp: &Rect, cells: Interval, slope: f32, e_lo: f32) -> Interval {
        if e_lo <= 0.0 || cells.is_empty() {
            return cells;
        }
        let c = (fp.min + fp.max) * 0.5;
        let hc = self.base_height(c);
        if hc.is_nan() {
            return cells;
        }
        let reach = slope * (fp.max - c).length() * (1.0 + 1e-5) + self.eps(hc.abs());
        Interval::new((hc - reach).max(cells.lo), (hc + reach).min(cells.hi))
    }

    /// Over the cells `i0..=i1 × j0..=j1`, from one pyramid query: the range of `h`
    /// (empty where no cell has a surface), the slope bound `s ≥ 0` of `h` and the
    /// detail's reach `A·max m ≥ 0` (0 without detail).
    #[inline]
    fn cells_under(
        &self,
        fp: &Rect,
        (i0, i1, j0, j1): (usize, usize, usize, usize),
    ) -> (Interval, f32, f32) {
        let [lo, hi, s, reach] = self.cells.query(i0, i1, j0, j1);
        let mut h = Bound::new(Interval { lo, hi }, s);
        if lo <= hi
            && let Some(d) = self.inset_under(fp)
        {
            h = h + d;
        }
        (h.range, h.lipschitz.max(0.0), reach.max(0.0))
    }

    /// The bound of the inset's `δ` over the footprint `fp` (0 included where `fp` reaches
    /// past the inset), `None` without an inset or where `fp` misses it.
    #[inline]
    fn inset_under(&self, fp: &Rect) -> Option<Bound> {
        let (inset, cells) = self.inset.as_ref()?;
        let d = inset.delta();
        let (a0, a1, b0, b1) = d.cells_overlapping(fp)?;
        let [lo, hi, s] = cells.query(a0, a1, b0, b1);
        let b = Bound::new(Interval { lo, hi }, s);
        Some(if d.extent().contains_rect(fp) {
            b
        } else {
            b.hull_zero()
        })
    }

    /// The range of `d` over `b` where `|d| ≤ reach` (`A·max m` over the cells under `b`;
    /// zero without detail), narrowed around the box's centre by the detail's slope (one
    /// more noise evaluation).
    #[inline]
    fn detail_range(&self, b: &Aabb, reach: f32) -> Interval {
        let Some(d) = &self.detail else {
            return Interval::ZERO;
        };
        let c = b.center();
        let (dc, rad) = (d.value(c), d.slope(reach) * b.radius() * (1.0 + 1e-5));
        let eps = self.eps(reach);
        Interval::new((dc - rad).max(-reach) - eps, (dc + rad).min(reach) + eps)
    }

    /// Range of the distance to `P` over `b`, from the clearance range `e`.
    fn dist_range(&self, e: Interval, z: Interval) -> Interval {
        self.prism_shape().dist_range(e, z)
    }

    /// What every point of the vertical line over `xy` shares: `None` where the field is
    /// 0 (outside Ω or where `h` is undefined).
    #[inline]
    fn column(&self, xy: Vec2) -> Option<Column> {
        let e = self.domain.clearance(xy);
        if e <= 0.0 {
            return None;
        }
        let h = self.base_height(xy);
        if h.is_nan() {
            return None;
        }
        Some(Column {
            xy,
            h,
            dxy: (self.r - e).max(0.0),
            reach: self.reach_at(xy),
        })
    }

    /// `f` at height `z` on the line `c`: `min(σ_R(h + d − z), f_P)`, the detail left out
    /// where σ is saturated whatever it is (`|h − z| ≥ R + A·m`).
    #[inline]
    fn column_value(&self, c: &Column, z: f32) -> f32 {
        let hd = c.h + self.detail_in_column(c.reach, c.h, c.xy.extend(z));
        sigma(hd - z, self.r).min(self.prism(c.dxy, z))
    }

    /// The detail's reach `A·m` over the column at `xy` (0 without detail).
    #[inline]
    fn reach_at(&self, xy: Vec2) -> f32 {
        self.detail.as_ref().map_or(0.0, |d| d.reach_at(xy))
    }

    /// The detail `d(p)` over the elevation `h` in a column of reach `reach`
    /// ([`Self::reach_at`]), or 0 where it cannot matter: without detail, or where σ is
    /// saturated whatever it is (`|h − z| ≥ R + A·m`).
    #[inline]
    fn detail_in_column(&self, reach: f32, h: f32, p: Vec3) -> f32 {
        match &self.detail {
            Some(d) if reach > 0.0 && (h - p.z).abs() < self.r + reach => {
                reach * d.params().noise.value(p)
            }
            _ => 0.0,
        }
    }

    /// A Lipschitz bound over `b`, or, with `dir = Some((|u_xy|, |u_z|))` for a unit
    /// direction `u`, of the derivative along `u` on a segment of direction `u` inside `b`.
    ///
    /// `f = min(f_T, f_P)`: where `σ` is saturated at 0 over `b` (`h + d − z ≤ −R`, the air
    /// above the terrain's band), `f = 0` whatever `f_P ≥ 0` is, so the bound is 0. Along
    /// `u`, `|∂(h + d − z)/∂u| ≤ s·|u_xy| + |u_z| + |∇d|` (`s` the slope of `h`), never
    /// above the isotropic `√(1 + s²) + |∇d|` (Cauchy–Schwarz) and far below it along
    /// the nearly level rays that graze the terrain.
    fn lipschitz_along(&self, b: &Aabb, dir: Option<(f32, f32)>) -> f32 {
        let fp = b.footprint();
        let e = self.domain.clearance_range(&fp);
        let Some((i0, i1, j0, j1)) = self.hf.cells_overlapping(&fp) else {
            return 0.0;
        };
        if e.hi <= 0.0 {
            return 0.0;
        }
        let (cells, s, reach) = self.cells_under(&fp, (i0, i1, j0, j1));
        let z = b.z();
        // h + d − z over b, with |d| ≤ reach (the centre's detail would sharpen σ's slope
        // only where it is small anyway)
        let v_of = |h: Interval| Interval::new(h.lo - reach - z.hi, h.hi + reach - z.lo);
        let lt = if cells.is_empty() || v_of(cells).lo >= self.r {
            // no surface, or σ saturated at 2T whatever h is: f = f_P
            0.0
        } else if v_of(cells).hi <= -self.r {
            return 0.0;
        } else {
            let h = self.h_range_near(&fp, cells, s, e.lo);
            let v = v_of(h);
            if v.hi <= -self.r {
                return 0.0;
            }
            // |∇(h + d − z)| ≤ √(1 + s²) + |∇d|
            let ld = self.detail.as_ref().map_or(0.0, |d| d.slope(reach));
            let lh = match dir {
                Some((uxy, uz)) => s * uxy + uz,
                None => (1.0 + s * s).sqrt(),
            };
            sigma_slope(v, self.r) * (lh + ld)
        };
        let d = self.dist_range(e, z);
        let lp = 2.0 * ISO * wyvill_slope(d.scale(1.0 / self.r)) / self.r * self.domain.lipschitz();
        lt.max(lp)
    }

    /// A float tolerance for bands around elevations of magnitude `m`.
    #[inline]
    fn eps(&self, m: f32) -> f32 {
        self.prism_shape().eps(m)
    }
}

impl Field for HeightfieldField {
    #[inline]
    fn value(&self, p: Vec3) -> f32 {
        self.column(p.truncate())
            .map_or(0.0, |c| self.column_value(&c, p.z))
    }

    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let xy = p.truncate();
        let (e, ge) = self.domain.clearance_grad(xy);
        if e <= 0.0 {
            return (0.0, Vec3::ZERO);
        }
        let (h, gh) = self.base_height_grad(xy);
        if h.is_nan() {
            return (0.0, Vec3::ZERO);
        }
        // h + d and ∇(h + d − z); where σ is saturated whatever d is (the floor, deep
        // rock), d is left out as in `value`: σ' = 0 there, so only signed zeros of the
        // gradient could tell
        let (dd, gdd) = match &self.detail {
            Some(d) if (h - p.z).abs() < self.r + self.reach_at(xy) => d.value_grad(p),
            _ => (0.0, Vec3::ZERO),
        };
        let (h, gh) = (h + dd, gh.extend(-1.0) + gdd);
        let (ft, dft) = sigma_d(h - p.z, self.r);
        let (fp, gfp) = self
            .prism_shape()
            .value_grad((self.r - e).max(0.0), -ge, p.z);
        if ft <= fp { (ft, gh * dft) } else { (fp, gfp) }
    }

    fn support(&self) -> Aabb {
        self.support
    }

    fn interval(&self, b: &Aabb) -> Interval {
        let fp = b.footprint();
        let e = self.domain.clearance_range(&fp);
        let Some((i0, i1, j0, j1)) = self.hf.cells_overlapping(&fp) else {
            return Interval::ZERO;
        };
        let (h, s, reach) = self.cells_under(&fp, (i0, i1, j0, j1));
        if e.hi <= 0.0 || h.is_empty() {
            return Interval::ZERO;
        }
        let h = self.h_range_near(&fp, h, s, e.lo);
        let dd = self.detail_range(b, reach);
        let z = b.z();
        let ft = sigma_interval(
            Interval::new(h.lo + dd.lo - z.hi, h.hi + dd.hi - z.lo),
            self.r,
        );
        let d = self.dist_range(e, z);
        let fp = wyvill_interval(d.scale(1.0 / self.r)).scale(2.0 * ISO);
        let f = ft.min(fp);
        if e.lo <= 0.0 {
            f.hull(Interval::ZERO)
        } else {
            f
        }
    }

    fn lipschitz(&self) -> f32 {
        let ld = self
            .detail
            .as_ref()
            .map_or(0.0, |d| d.slope(d.reach_total()));
        let lt = sigma_max_slope(self.r) * ((1.0 + self.lip_h * self.lip_h).sqrt() + ld);
        let lp = 2.0 * ISO * WYVILL_MAX_SLOPE / self.r * self.domain.lipschitz();
        lt.max(lp)
    }

    fn lipschitz_box(&self, b: &Aabb) -> f32 {
        self.lipschitz_along(b, None)
    }

    /// Along the segment only the slope of `h + d − z` in the segment's direction counts:
    /// see [`HeightfieldField::lipschitz_along`].
    fn lipschitz_segment(&self, a: Vec3, b: Vec3) -> f32 {
        let u = (b - a).normalize_or_zero();
        let dir = (u != Vec3::ZERO).then(|| (u.truncate().length(), u.z.abs()));
        self.lipschitz_along(&Aabb::new(a, b), dir)
    }

    fn z_bands(&self, fp: &Rect, z: Interval, out: &mut ZBands) {
        let e = self.domain.clearance_range(fp);
        if e.hi <= 0.0 {
            return;
        }
        let Some((i0, i1, j0, j1)) = self.hf.cells_overlapping(fp) else {
            return self.prism_shape().z_bands(e, Interval::EMPTY, z, out);
        };
        let (cells, s, reach) = self.cells_under(fp, (i0, i1, j0, j1));
        // Sharpened around the footprint's centre where the footprint lies inside Ω: a
        // mesh column's band is then about as tall as the relief under it, not as a
        // whole DEM cell's.
        let h = self.h_range_near(fp, cells, s, e.lo);
        let reach = match &self.detail {
            Some(d) if e.lo > 0.0 => d.reach_near(fp, reach),
            _ => reach,
        };
        // the terrain z = h + d lies within the detail's reach of h
        let h = if h.is_empty() {
            h
        } else {
            Interval::new(h.lo - reach, h.hi + reach)
        };
        self.prism_shape().z_bands(e, h, z, out);
    }

    /// The bands are the terrain's and the prism's over `fp`, intersected with `z`.
    fn z_bands_clip(&self) -> bool {
        true
    }

    fn eval_block(&self, origin: Vec3, step: Vec3, dims: [usize; 3], out: &mut [f32]) {
        let [nx, ny, nz] = dims;
        let plane = nx * ny;
        for j in 0..ny {
            for i in 0..nx {
                let p = origin + Vec3::new(i as f32, j as f32, 0.0) * step;
                let column = self.column(p.truncate());
                let base = i + nx * j;
                for k in 0..nz {
                    let z = (origin + Vec3::new(i as f32, j as f32, k as f32) * step).z;
                    out[base + plane * k] =
                        column.as_ref().map_or(0.0, |c| self.column_value(c, z));
                }
            }
        }
    }

    /// One elevation lookup for the whole line (and none of the points' tree walks).
    fn eval_column(&self, xy: Vec2, zs: &[f32], out: &mut [f32]) -> bool {
        let column = self.column(xy);
        for (o, &z) in out.iter_mut().zip(zs) {
            *o = column.as_ref().map_or(0.0, |c| self.column_value(c, z));
        }
        true
    }

    /// Inside the eroded domain; with detail, only where `|∂d/∂z| ≤ ½` over `fp`, so that
    /// `h + d − z` falls strictly with `z` and the surface is the graph of
    /// [`HeightfieldField::height`] (elsewhere the noise may fold it into small overhangs).
    fn elevation(&self, fp: &Rect) -> Option<Elevation<'_>> {
        if let Some(d) = &self.detail {
            let (i0, i1, j0, j1) = self.hf.cells_overlapping(fp)?;
            if d.slope_z(d.reach(i0, i1, j0, j1)) > 0.5 {
                return None;
            }
        }
        (self.domain.clearance_range(fp).lo >= self.r).then_some(Elevation {
            source: self,
            z: self.dz,
        })
    }
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

impl ElevationSource for HeightfieldField {
    fn height(&self, xy: Vec2) -> f32 {
        HeightfieldField::height(self, xy)
    }
}

//! The S field as an implicit leaf of the construction tree.
//!
//! ```text
//!   f(p) = min( σ_R(∓S'(p)),  2T·(1 − g(d_in(p) / R_f)) )     inside the domain box
//!   f(p) = 0                                                    outside it
//!   S'(p) = S(p) − α(p)·fbm(β(p)·(p − origin))
//! ```
//!
//! `S` is the interpolated surface field (positive on the normals' side, the air; negative
//! behind, the rock), `−S'` for [`Orientation::Solid`], `+S'` for [`Orientation::Air`]. σ is
//! the tree's sigmoid ([`crate::field::falloff::sigma`]): the surface `f = T` is exactly
//! `S' = 0`. `d_in` is the distance to the nearest face of the domain box (0 outside), `g`
//! Wyvill's falloff: the field fades to 0 within `R_f` of the faces, so its support is
//! the domain box. Every term is Lipschitz, so are the `min`, and the bounds below are
//! sound (tests sample them).

use std::sync::Arc;

use glam::Vec3;
use rayon::prelude::*;

use super::expand::Expanded;
use super::pipeline::{BrickBounds, Stats, Volume};
use super::sparse::{BRICK, Bricks, NONE, locate, trilinear_grad};
use super::tricubic::{Cubic, CubicBounds, Interpolation};
use crate::curves::Orientation;
use crate::field::falloff::{
    ISO, WYVILL_MAX_SLOPE, sigma, sigma_d, sigma_interval, sigma_max_slope, sigma_slope, wyvill,
    wyvill_d, wyvill_interval, wyvill_slope,
};
use crate::field::{Aabb, Fbm, Field, Interval};

/// How S becomes a field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldParams {
    /// The domain box: the support.
    pub domain: Aabb,
    /// The finest voxel size (metres): the default cell of [`SField::extract`].
    pub voxel: f32,
    /// Solid side.
    pub orientation: Orientation,
    /// Sigmoid width `R` (metres).
    pub transition: f32,
    /// Face falloff width `R_f` (metres).
    pub falloff: f32,
    /// The displacement noise, evaluated at `β·(p − domain.min)`: wavelength 1 there, so
    /// β is the first octave's frequency (1/m).
    pub fbm: Fbm,
    /// Interpolation of S between the nodes.
    pub interpolation: Interpolation,
}

/// `max |fbm|`: the shared fBm is normalised to `[−1, 1]` (proven in `field::noise`).
const FBM_AMPLITUDE: f32 = 1.0;

/// Bricks visited by a bound query before it falls back to a level's global bounds.
const MAX_QUERY_BRICKS: i64 = 4096;

/// The S-field primitive: Feature Curves compiled by the voxel pipeline.
#[derive(Clone, Debug)]
pub struct SField {
    vol: Arc<Volume>,
    params: FieldParams,
    /// Per level: bounds over all bricks.
    level_bounds: Vec<BrickBounds>,
    /// `max |∇S|` over all levels.
    lip_s: f32,
    /// Lipschitz bound of the displacement `α·fbm(β·(p − o))`, 0 without noise.
    lip_noise: f32,
    /// `max |α·fbm|`.
    noise_amp: f32,
    /// The curves Feature Curve expansion added before the run that made this field.
    expanded: Option<Arc<Expanded>>,
    /// The finest level's tricubic blend, with [`Interpolation::Tricubic`].
    cubic: Option<Arc<Cubic>>,
}

fn hull(a: &BrickBounds, b: &BrickBounds) -> BrickBounds {
    let r = |x: [f32; 2], y: [f32; 2]| [x[0].min(y[0]), x[1].max(y[1])];
    BrickBounds {
        s: r(a.s, b.s),
        alpha: r(a.alpha, b.alpha),
        beta: r(a.beta, b.beta),
        grad_s: a.grad_s.max(b.grad_s),
        grad_alpha: a.grad_alpha.max(b.grad_alpha),
        grad_beta: a.grad_beta.max(b.grad_beta),
    }
}

const EMPTY_BOUNDS: BrickBounds = BrickBounds {
    s: [f32::INFINITY, f32::NEG_INFINITY],
    alpha: [f32::INFINITY, f32::NEG_INFINITY],
    beta: [f32::INFINITY, f32::NEG_INFINITY],
    grad_s: Vec3::ZERO,
    grad_alpha: 0.0,
    grad_beta: 0.0,
};

/// Lipschitz bound of the displacement `α·fbm(β q)`, `q = p − origin`, where α, β and
/// their slopes are bounded by `b` and `‖q‖ ≤ reach`:
/// `∇(α n(β q)) = n ∇α + α [β ∇n + (∇n · q) ∇β]`, with `|n| ≤ 1` and `|∇n| ≤` the fBm's
/// proven Lipschitz constant (in its argument `β q`).
fn noise_lipschitz(params: &FieldParams, b: &BrickBounds, reach: f32) -> f32 {
    let (a, l) = (FBM_AMPLITUDE, params.fbm.lipschitz());
    b.grad_alpha * a + b.alpha[1].max(0.0) * l * (b.beta[1].max(0.0) + reach * b.grad_beta)
}

/// Bounds of `S'` over a box.
struct SBox {
    range: Interval,
    lip: f32,
}

/// `max |∇S|` with the tricubic blend on the finest level: per finest brick, the blend's
/// bounds over the bricks its cells' stencils reach (its 26 neighbours and itself); the
/// coarser levels' trilinear slopes.
fn cubic_lipschitz(vol: &Volume, level_bounds: &[BrickBounds], c: &Cubic) -> f32 {
    let last = vol.levels.len() - 1;
    let fine = &vol.levels[last];
    let coarse = level_bounds[..last]
        .iter()
        .fold(EMPTY_BOUNDS, |a, x| hull(&a, x))
        .grad_s
        .length();
    (0..fine.len())
        .into_par_iter()
        .map(|b| {
            let (mut bb, mut cb) = (EMPTY_BOUNDS, CubicBounds::EMPTY);
            for &k in fine.neighbours(b).iter().filter(|&&k| k != NONE) {
                bb = hull(&bb, &vol.bounds[last][k as usize]);
                cb = cb.hull(c.brick(k as usize));
            }
            cb.widen(&bb, fine.geom.h).grad_s.length()
        })
        .reduce(|| coarse, f32::max)
}

impl SField {
    /// The field of a pipeline result.
    pub fn new(vol: Arc<Volume>, params: FieldParams) -> Self {
        let level_bounds: Vec<BrickBounds> = vol
            .bounds
            .iter()
            .map(|b| b.iter().fold(EMPTY_BOUNDS, |a, x| hull(&a, x)))
            .collect();
        let cubic = match (params.interpolation, vol.levels.last(), vol.s.last()) {
            (Interpolation::Tricubic, Some(b), Some(s)) => Some(Arc::new(Cubic::new(b, s))),
            _ => None,
        };
        let all = level_bounds.iter().fold(EMPTY_BOUNDS, |a, x| hull(&a, x));
        let lip_s = match &cubic {
            Some(c) => cubic_lipschitz(&vol, &level_bounds, c),
            None => all.grad_s.length(),
        };
        let noise_amp = all.alpha[1].max(0.0) * FBM_AMPLITUDE;
        let lip_noise = if noise_amp > 0.0 {
            noise_lipschitz(&params, &all, params.domain.size().length())
        } else {
            0.0
        };
        SField {
            vol,
            params,
            level_bounds,
            lip_s,
            lip_noise,
            noise_amp,
            expanded: None,
            cubic,
        }
    }

    /// This field, recording the expansion whose curves its run included.
    pub fn with_expansion(self, e: Expanded) -> Self {
        SField {
            expanded: Some(Arc::new(e)),
            ..self
        }
    }

    /// The curves Feature Curve expansion (§4.5) added, when the volume asked for it.
    pub fn expanded(&self) -> Option<&Expanded> {
        self.expanded.as_deref()
    }

    /// True when there was no seed primitive: the field is 0 everywhere.
    pub fn is_empty(&self) -> bool {
        self.vol.levels.is_empty()
    }

    /// The pipeline's statistics.
    pub fn stats(&self) -> &Stats {
        &self.vol.stats
    }

    /// The parameters.
    pub fn params(&self) -> &FieldParams {
        &self.params
    }

    /// The grid levels (dense base first).
    pub fn levels(&self) -> &[Bricks] {
        &self.vol.levels
    }

    /// The pipeline's grids: levels, S, α, β and the per-brick bounds (for encoders such
    /// as the GPU tape).
    pub fn volume(&self) -> &Volume {
        &self.vol
    }

    /// The finest level's tricubic blend, with [`Interpolation::Tricubic`].
    pub fn cubic(&self) -> Option<&Cubic> {
        self.cubic.as_deref()
    }

    /// `max |α·fbm|` over the field: 0 when there is no displacement noise.
    pub fn noise_amplitude(&self) -> f32 {
        self.noise_amp
    }

    /// Bytes held by the field's grids.
    pub fn memory_bytes(&self) -> u64 {
        self.vol.stats.field_bytes + self.cubic.as_ref().map_or(0, |c| c.bytes())
    }

    /// A global Lipschitz bound of `S'` (the S slopes of every brick plus the widening by
    /// the noise displacement); `f`'s bound is this times `σ`'s slope.
    pub fn s_lipschitz(&self) -> f32 {
        self.lip_s + self.lip_noise
    }

    /// The diffused guidance normal N at `p` (clamped to the domain), when the run kept
    /// them ([`super::Params::keep_normals`]); not normalised between nodes.
    pub fn guidance_normal(&self, p: Vec3) -> Option<Vec3> {
        if self.vol.normals.is_empty() {
            return None;
        }
        let q = self.params.domain.clamp(p);
        Some(super::sparse::sample(
            &self.vol.levels,
            &self.vol.normals,
            q,
        ))
    }

    /// `S'(p)`: the displaced surface field at `p` clamped to the domain (`+∞` when empty).
    pub fn s_value(&self, p: Vec3) -> f32 {
        self.s_eval::<false>(p, f32::INFINITY).0
    }

    /// `(S'(p), ∇S'(p))` at `p` clamped to the domain.
    pub fn s_grad(&self, p: Vec3) -> (f32, Vec3) {
        let (s, g, _) = self.s_eval::<true>(p, f32::INFINITY);
        (s, g)
    }

    /// `(S'(p), ∇S'(p), 0)`, the gradient only when `GRAD` (else zero): the same
    /// arithmetic for the value either way, without the gradient's cost when only the
    /// value is asked (the march). Where `|S(p)| ≥ far + α(p)` the fBm is skipped and
    /// `(S(p), ∇S(p), α(p))` returned instead: `S'` lies within the margin `α` of it.
    /// With `far` the sigmoid's width the field is then the same with `S` itself (the
    /// noise cannot bring `S'` into its range): most of a terrain-aware volume lies far
    /// from the surface. With the tricubic blend and without `GRAD`, the blend's 64-node
    /// stencil is skipped too where the trilinear `|L(p)| ≥ far + α(p) + E` (`E` the
    /// cell's bound of `|S − L|`, [`Cubic::cell_error`]): `(L(p), ∇L(p), α(p) + E)`.
    #[inline(always)]
    fn s_eval<const GRAD: bool>(&self, p: Vec3, far: f32) -> (f32, Vec3, f32) {
        self.s_eval_with::<GRAD, true>(p, far, 0.0)
    }

    /// [`Self::s_eval`]; without `CUBIC` the finest level is read trilinearly, `cubic_err`
    /// being a bound of the blend's departure from that at `p`
    /// ([`CubicBounds::value_error`]): the third member then bounds `|S'(p) − answer|`.
    #[inline(always)]
    fn s_eval_with<const GRAD: bool, const CUBIC: bool>(
        &self,
        p: Vec3,
        far: f32,
        cubic_err: f32,
    ) -> (f32, Vec3, f32) {
        let q = self.params.domain.clamp(p);
        let Some((l, idx, f)) = locate(&self.vol.levels, q) else {
            return (f32::INFINITY, Vec3::ZERO, 0.0);
        };
        let h = self.vol.levels[l].geom.h;
        let mut lin = trilinear_grad(&self.vol.s[l], &idx, f, h);
        let (a, ga) = if self.noise_amp == 0.0 {
            (0.0, Vec3::ZERO)
        } else {
            trilinear_grad(&self.vol.alpha[l], &idx, f, h)
        };
        let mut err = 0.0;
        if let Some(c) = &self.cubic
            && l + 1 == self.vol.levels.len()
        {
            if !CUBIC {
                err = cubic_err;
            } else if !GRAD && lin.0.abs() >= far + a * FBM_AMPLITUDE + c.cell_error(idx[0]) {
                // The blend cannot bring S' within `far`: the 64-node stencil is skipped.
                err = c.cell_error(idx[0]);
            } else {
                lin = c.eval::<GRAD>(&self.vol.levels[l], &self.vol.s[l], &idx, f, lin);
            }
        }
        let (s, gs) = lin;
        if self.noise_amp == 0.0 {
            return (s, gs, err);
        }
        let margin = a * FBM_AMPLITUDE + err;
        if s.abs() >= far + margin {
            return (s, gs, margin);
        }
        let (b, gb) = trilinear_grad(&self.vol.beta[l], &idx, f, h);
        let o = q - self.params.domain.min;
        if !GRAD {
            return (s - a * self.params.fbm.value(o * b), Vec3::ZERO, err);
        }
        let (n, gn) = self.params.fbm.value_grad(o * b);
        let gd = ga * n + (gn * b + gb * gn.dot(o)) * a;
        (s - a * n, gs - gd, err)
    }

    /// `±S'` by orientation.
    fn signed(&self, s: f32) -> f32 {
        match self.params.orientation {
            Orientation::Solid => -s,
            Orientation::Air => s,
        }
    }

    /// Distance to the nearest face of the domain (0 outside) and its gradient.
    fn d_in(&self, p: Vec3) -> (f32, Vec3) {
        let d = &self.params.domain;
        let (lo, hi) = (p - d.min, d.max - p);
        let mut best = (f32::INFINITY, Vec3::ZERO);
        for a in 0..3 {
            let mut e = Vec3::ZERO;
            e[a] = 1.0;
            if lo[a] < best.0 {
                best = (lo[a], e);
            }
            if hi[a] < best.0 {
                best = (hi[a], -e);
            }
        }
        if best.0 <= 0.0 {
            (0.0, Vec3::ZERO)
        } else {
            best
        }
    }

    /// Range of `d_in` over `b`.
    fn d_in_range(&self, b: &Aabb) -> Interval {
        let d = &self.params.domain;
        let lo = (b.min - d.min).min(d.max - b.max).min_element().max(0.0);
        let hi = (b.max - d.min).min(d.max - b.min).min_element().max(0.0);
        Interval::new(lo, hi)
    }

    /// Bounds over the bricks whose nodes the field can read inside `b` (clamped to the
    /// domain), across all levels; with the tricubic blend, over its stencils too, widened.
    /// Also returns the tricubic blend's `E` over those stencils
    /// ([`CubicBounds::value_error`]; 0 without the blend): `|S − L| ≤ E` in `b`.
    fn box_bounds(&self, b: &Aabb) -> (BrickBounds, f32) {
        let mut acc = EMPTY_BOUNDS;
        let mut cubic = CubicBounds::EMPTY;
        let finest = self.vol.levels.len().saturating_sub(1);
        // Nodes read around a point: its cell's corners, or the tricubic stencil.
        let reach = if self.cubic.is_some() { 2.0 } else { 1.0 };
        for (l, bricks) in self.vol.levels.iter().enumerate() {
            let g = bricks.geom;
            let tc = self.cubic.as_deref().filter(|_| l == finest);
            let lo = ((b.min - g.origin) / g.h - Vec3::splat(reach))
                .floor()
                .as_ivec3()
                .max(glam::IVec3::ZERO)
                / BRICK;
            let hi = ((b.max - g.origin) / g.h + Vec3::splat(reach))
                .ceil()
                .as_ivec3()
                .min(g.dims - glam::IVec3::ONE)
                / BRICK;
            let count = (hi - lo + glam::IVec3::ONE)
                .max(glam::IVec3::ZERO)
                .as_i64vec3()
                .element_product();
            if count > MAX_QUERY_BRICKS {
                acc = hull(&acc, &self.level_bounds[l]);
                if let Some(c) = tc {
                    cubic = cubic.hull(c.all());
                }
                continue;
            }
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let k = bricks.brick(glam::IVec3::new(x, y, z));
                        if k != NONE {
                            acc = hull(&acc, &self.vol.bounds[l][k as usize]);
                            if let Some(c) = tc {
                                cubic = cubic.hull(c.brick(k as usize));
                            }
                        }
                    }
                }
            }
        }
        match self.vol.levels.last() {
            Some(f) if self.cubic.is_some() => {
                (cubic.widen(&acc, f.geom.h), cubic.value_error(f.geom.h))
            }
            _ => (acc, 0.0),
        }
    }

    /// A conservative range of `S'` over `b` clamped to the domain (`b` must overlap it;
    /// `+∞` for an empty field).
    pub fn s_interval(&self, b: &Aabb) -> Interval {
        if self.is_empty() {
            return Interval::point(f32::INFINITY);
        }
        self.s_box(&b.intersection(self.params.domain)).range
    }

    /// A Lipschitz bound of `S'` over `b` clamped to the domain (`b` must overlap it).
    pub fn s_lipschitz_box(&self, b: &Aabb) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        self.s_box(&b.intersection(self.params.domain)).lip
    }

    /// Range and Lipschitz bound of `S'` over `bc` (inside the domain): the brick ranges
    /// widened by the noise, intersected with the Lipschitz bound around the centre
    /// (tighter on small boxes); both are sound, so is their intersection.
    fn s_box(&self, bc: &Aabb) -> SBox {
        let (bb, cubic_err) = self.box_bounds(bc);
        let (amp, lip_noise) = if self.noise_amp > 0.0 {
            // The farthest corner from the origin, axis by axis.
            let o = self.params.domain.min;
            let reach = (bc.min - o).abs().max((bc.max - o).abs()).length();
            (
                bb.alpha[1].max(0.0) * FBM_AMPLITUDE,
                noise_lipschitz(&self.params, &bb, reach),
            )
        } else {
            (0.0, 0.0)
        };
        let lip = bb.grad_s.length() + lip_noise;
        let bricks = Interval::new(bb.s[0], bb.s[1]).dilate(amp);
        let reach = lip * bc.radius();
        // The trilinear value at the centre, within `E` of the blend: the tricubic stencil
        // (64 nodes) is the dearest part of an evaluation, and bounds are asked as often
        // as values.
        let (sc, _, margin) = self.s_eval_with::<false, false>(
            bc.center(),
            self.params.transition + reach,
            cubic_err,
        );
        let around = Interval::point(sc).dilate(reach + margin);
        let mut s = bricks.intersect(around);
        if s.is_empty() {
            s = bricks;
        }
        let range = s.dilate(1e-5 * (1.0 + s.lo.abs().max(s.hi.abs())));
        SBox { range, lip }
    }

    fn face_falloff(&self, d: f32) -> f32 {
        2.0 * ISO * (1.0 - wyvill(d / self.params.falloff))
    }
}

impl Field for SField {
    fn value(&self, p: Vec3) -> f32 {
        if self.is_empty() || !self.params.domain.contains(p) {
            return 0.0;
        }
        let s = self.s_eval::<false>(p, self.params.transition).0;
        let v = sigma(self.signed(s), self.params.transition);
        v.min(self.face_falloff(self.d_in(p).0))
    }

    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        if self.is_empty() || !self.params.domain.contains(p) {
            return (0.0, Vec3::ZERO);
        }
        let (s, gs) = self.s_grad(p);
        let sign = if self.params.orientation == Orientation::Solid {
            -1.0
        } else {
            1.0
        };
        let (v, dv) = sigma_d(sign * s, self.params.transition);
        let (d, gd) = self.d_in(p);
        let rf = self.params.falloff;
        let (w, dw) = wyvill_d(d / rf);
        let face = 2.0 * ISO * (1.0 - w);
        if face < v {
            (face, gd * (-2.0 * ISO * dw / rf))
        } else {
            (v, gs * (sign * dv))
        }
    }

    fn support(&self) -> Aabb {
        if self.is_empty() {
            Aabb::EMPTY
        } else {
            self.params.domain
        }
    }

    fn interval(&self, b: &Aabb) -> Interval {
        if self.is_empty() || !b.overlaps(&self.params.domain) {
            return Interval::ZERO;
        }
        let bc = b.intersection(self.params.domain);
        let s = self.s_box(&bc).range;
        let x = if self.params.orientation == Orientation::Solid {
            s.scale(-1.0)
        } else {
            s
        };
        let v = sigma_interval(x, self.params.transition);
        let d = self.d_in_range(&bc);
        let wi = wyvill_interval(d.scale(1.0 / self.params.falloff));
        let face = Interval::new(2.0 * ISO * (1.0 - wi.hi), 2.0 * ISO * (1.0 - wi.lo));
        let f = v.min(face);
        if self.params.domain.contains_box(b) {
            f
        } else {
            f.hull(Interval::ZERO)
        }
    }

    fn lipschitz(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let sig = sigma_max_slope(self.params.transition) * (self.lip_s + self.lip_noise);
        sig.max(2.0 * ISO * WYVILL_MAX_SLOPE / self.params.falloff)
    }

    fn lipschitz_box(&self, b: &Aabb) -> f32 {
        if self.is_empty() || !b.overlaps(&self.params.domain) {
            return 0.0;
        }
        let bc = b.intersection(self.params.domain);
        let SBox { range: s, lip: ls } = self.s_box(&bc);
        let x = if self.params.orientation == Orientation::Solid {
            s.scale(-1.0)
        } else {
            s
        };
        let sig = sigma_slope(x, self.params.transition) * ls;
        let d = self.d_in_range(&bc);
        let face =
            2.0 * ISO * wyvill_slope(d.scale(1.0 / self.params.falloff)) / self.params.falloff;
        sig.max(face)
    }

    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

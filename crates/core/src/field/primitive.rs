//! The skeletal primitive (Paris et al. 2019 §5.2): `f(p) = E · g(d̃(p))` with Wyvill's falloff
//! `g`, a [`Skeleton`], a radius of influence `R` and an energy `E` (negative carves).
//!
//! Without noise `d̃ = d / R`, `d` the Euclidean distance to the skeleton. With noise of
//! amplitude `A < R` it is the anisotropic distance of Paris et al. 2019 §5.2,
//! `d̃(p) = ‖p − s(p)‖ / (R + A·t(v(p)))` with `s` the projection on the skeleton,
//! `u = (p − s)/‖p − s‖` and `v = s + R·u`: the turbulence `t` is read on the shell at
//! distance `R`, so it is constant along each ray from the skeleton and every ray crosses
//! each level set once (star-shaped, "rocks look rocky without holes").
//!
//! A skeleton that is not convex (polyline, curve, concave prism) has a projection that
//! jumps across its medial axis, and so would `t∘v`, tearing the surface. We therefore
//! take the formula on each convex piece `i` of the skeleton and use
//! `d̃ = minᵢ d̃ᵢ`: continuous, equal to the paper's formula for a convex skeleton, and a
//! union of star-shaped sets around connected pieces.
//!
//! # Lipschitz bound of the noisy primitive
//!
//! On a convex piece (dropping `i`), with `ρ = ‖p − s‖`, `D = R + A t(v) ∈ [R − A, R + A]`:
//! `∇d̃ = u/D − (ρ A / D²) J_vᵀ ∇t(v)` where `J_v = J_s + (R/ρ)(I − uuᵀ)(I − J_s)`. For a
//! projection on a convex set `‖J_s‖ ≤ 1` and `‖I − J_s‖ ≤ 1`, so `‖J_v‖ ≤ 1 + R/ρ` and
//! `|∇d̃| ≤ (1 + A L_t (ρ + R)/D) / D = (1 + A L_t (d̃ + R/D)) / D`. Only points with
//! `d̃ < 1` matter (`g` is flat beyond), hence globally
//! `|∇d̃| ≤ (1 + A L_t (1 + R/(R − A))) / (R − A)`, and the min over pieces keeps the
//! bound. The field's bound is `|E| · max|g'| ·` that.

use glam::{Mat3, Vec3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::bounds::{Aabb, Interval, Rect, ZBands};
use super::contract::{Field, z_bands_by_interval};
use super::falloff::{ISO, WYVILL_MAX_SLOPE, wyvill, wyvill_d, wyvill_interval, wyvill_slope};
use super::noise::{Fbm, NoiseSpec};
use super::profile::LineProfile;
use super::skeleton::{Project, Skeleton, SkeletonSpec};
use crate::value::{Finite, Positive};

/// Largest noise amplitude, as a fraction of the falloff radius `R`.
pub const MAX_AMPLITUDE_RATIO: f32 = 0.9;

/// Anisotropic noise of a primitive: turbulence and its amplitude `A` in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Noise {
    /// The turbulence `t`.
    pub fbm: Fbm,
    /// Amplitude `A`, `0 ≤ A ≤ 0.9 R`.
    pub amplitude: f32,
}

/// Why a primitive cannot be built.
#[derive(Debug, Error, PartialEq)]
pub enum PrimitiveError {
    /// The falloff radius is not a positive finite number.
    #[error("the falloff radius must be > 0, found {0}")]
    Radius(f32),
    /// The energy is not finite.
    #[error("the energy must be a finite number, found {0}")]
    Energy(f32),
    /// The noise amplitude is too large for the falloff radius (holes would appear).
    #[error("the noise amplitude {amplitude} must be at most 0.9 × falloff = {max}")]
    Amplitude {
        /// Requested amplitude.
        amplitude: f32,
        /// Largest allowed.
        max: f32,
    },
}

/// A skeletal primitive `E · g(d̃)`. Build it with [`Primitive::new`] or
/// [`Primitive::from_spec`].
#[derive(Clone, Debug, PartialEq)]
pub struct Primitive {
    skeleton: Skeleton,
    radius: f32,
    inv_radius: f32,
    energy: f32,
    noise: Option<Noise>,
    support: Aabb,
    /// `skeleton.bounds()`.
    skeleton_bounds: Aabb,
    /// Global bound of `|∇d̃|` where `d̃ < 1`.
    slope: f32,
}

impl Primitive {
    /// The primitive `energy · g(d̃)` around `skeleton` with falloff radius `radius`.
    pub fn new(
        skeleton: Skeleton,
        radius: f32,
        energy: f32,
        noise: Option<Noise>,
    ) -> Result<Self, PrimitiveError> {
        if !(radius.is_finite() && radius > 0.0) {
            return Err(PrimitiveError::Radius(radius));
        }
        if !energy.is_finite() {
            return Err(PrimitiveError::Energy(energy));
        }
        let noise = noise.filter(|n| n.amplitude > 0.0);
        if let Some(n) = noise {
            let max = MAX_AMPLITUDE_RATIO * radius;
            if n.amplitude.is_nan() || n.amplitude > max {
                return Err(PrimitiveError::Amplitude {
                    amplitude: n.amplitude,
                    max,
                });
            }
        }
        let a = noise.map_or(0.0, |n| n.amplitude);
        // Grown by one part in 10⁵ so rounding never puts a non-zero value outside.
        let skeleton_bounds = skeleton.bounds();
        let support = skeleton_bounds.dilate((radius + a) * 1.000_01);
        let mut p = Primitive {
            skeleton,
            radius,
            inv_radius: 1.0 / radius,
            energy,
            noise,
            support,
            skeleton_bounds,
            slope: 0.0,
        };
        p.slope = p.dt_slope(1.0, radius - a);
        Ok(p)
    }

    /// Compiles a tree-file spec; `scene_seed` is the tree's global seed. Specs parsed
    /// from RON are valid; for one built in code an amplitude above `0.9 R` is clamped
    /// (see [`PrimitiveSpec::check`]).
    pub fn from_spec(spec: &PrimitiveSpec, scene_seed: u32) -> Primitive {
        let radius = spec.falloff.get();
        let noise = spec.noise.map(|n| Noise {
            fbm: Fbm::new(&n, scene_seed),
            amplitude: n.amplitude.get().min(MAX_AMPLITUDE_RATIO * radius),
        });
        Primitive::new(
            Skeleton::from_spec(&spec.shape),
            radius,
            spec.energy.get(),
            noise,
        )
        .expect("validated types and clamped amplitude")
    }

    /// The skeleton.
    pub fn skeleton(&self) -> &Skeleton {
        &self.skeleton
    }

    /// Falloff radius `R`.
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// Energy `E`: the value on the skeleton (inside a volumetric one).
    pub fn energy(&self) -> f32 {
        self.energy
    }

    /// The primitive along the line `o + t·d` (`d ≠ 0`) as a polynomial in `t`, when it
    /// has one: a point skeleton without noise.
    #[inline]
    pub fn along_line(&self, o: Vec3, d: Vec3) -> Option<LineProfile> {
        match (&self.skeleton, self.noise) {
            (Skeleton::Point(pt), None) => Some(LineProfile::new(
                pt.center,
                self.inv_radius,
                self.energy,
                o,
                d,
            )),
            _ => None,
        }
    }

    /// The anisotropic noise, if any.
    pub fn noise(&self) -> Option<&Noise> {
        self.noise.as_ref()
    }

    /// Amplitude `A` (0 without noise).
    #[inline]
    fn amplitude(&self) -> f32 {
        self.noise.map_or(0.0, |n| n.amplitude)
    }

    /// Bound of `|∇d̃|` at points where `d̃ ≤ x_hi ≤ 1` and `R + A·t∘v ≥ den_lo` (see
    /// the module doc): `(1 + A L_t (x_hi + R/den_lo)) / den_lo`.
    fn dt_slope(&self, x_hi: f32, den_lo: f32) -> f32 {
        match self.noise {
            None => self.inv_radius,
            Some(n) => {
                let k = n.amplitude * n.fbm.lipschitz() * (x_hi.min(1.0) + self.radius / den_lo);
                (1.0 + k) / den_lo
            }
        }
    }

    /// The normalised distance `d̃(p)`, capped at 1 (where the field vanishes).
    #[inline]
    pub fn normalized_distance(&self, p: Vec3) -> f32 {
        match self.noise {
            None => {
                let d = self.skeleton.distance_capped(p, self.radius);
                if d >= self.radius {
                    1.0
                } else {
                    d * self.inv_radius
                }
            }
            Some(n) => self.noisy::<false>(&n, p).0,
        }
    }

    /// `(d̃(p), ∇d̃(p))`, `d̃` capped at 1 (gradient 0 there).
    #[inline]
    pub fn normalized_distance_grad(&self, p: Vec3) -> (f32, Vec3) {
        match self.noise {
            None => {
                let (d, g) = self.skeleton.distance_grad(p);
                if d >= self.radius {
                    (1.0, Vec3::ZERO)
                } else {
                    (d * self.inv_radius, g * self.inv_radius)
                }
            }
            Some(n) => self.noisy::<true>(&n, p),
        }
    }

    /// `minᵢ d̃ᵢ` over the convex pieces, capped at 1, with its gradient when `GRAD`.
    fn noisy<const GRAD: bool>(&self, n: &Noise, p: Vec3) -> (f32, Vec3) {
        let r = self.radius;
        let outer = r + n.amplitude;
        let mut reach = outer;
        if self.skeleton.convex().is_none() {
            // Many pieces: the nearest one gives d̃ ≤ ρ_min/(R − A), so pieces farther than
            // ρ_min·(R + A)/(R − A) cannot win (ρᵢ/(R + A) ≤ d̃ᵢ). A cheap distance pass
            // first spares their turbulence.
            let rho_min = self.skeleton.distance_capped(p, outer);
            if rho_min >= outer {
                return (1.0, Vec3::ZERO);
            }
            if rho_min <= 0.0 {
                return (0.0, Vec3::ZERO);
            }
            reach = outer.min(rho_min * outer / (r - n.amplitude) * 1.000_1);
        }
        let mut best = (1.0f32, Vec3::ZERO);
        self.skeleton.visit_pieces(p, reach, &mut |piece, rho| {
            let cand = if rho <= 0.0 {
                (0.0, Vec3::ZERO)
            } else {
                piece_distance::<GRAD>(piece, n, r, p, rho)
            };
            if cand.0 < best.0 {
                best = cand;
            }
            best.0 * outer
        });
        best
    }

    /// What holds over the box `b`: the range of `min(d̃, 1)` and a lower bound of the
    /// denominator `R + A·t∘v`.
    ///
    /// The distance range is `d(c) ± r` (`c` the centre, `r` the half-diagonal), raised to
    /// the distance between `b` and the skeleton's bounds. With noise, on a convex
    /// skeleton not touching `b`, the turbulence is read at `v(c) ± (1 + R/ρ_lo)·r`
    /// (`‖J_v‖ ≤ 1 + R/ρ`), which narrows the denominator from `R ± A`; and `min(d̃, 1)`,
    /// being globally Lipschitz, is also within `d̃(c) ± r·λ_d̃`.
    fn local(&self, b: &Aabb) -> Local {
        let a = self.amplitude();
        let r = self.radius;
        let c = b.center();
        let half = b.radius();
        let reach = r + a;
        let dc = self.skeleton.distance_capped(c, reach + half);
        let skel = self.skeleton_bounds;
        let gap = (skel.min - b.max)
            .max(b.min - skel.max)
            .max(Vec3::ZERO)
            .length();
        let rho = Interval::new((dc - half).max(gap), dc + half);
        let (mut den_lo, mut den_hi) = (r - a, r + a);
        let mut xs = Interval::new(rho.lo / den_hi, rho.hi / den_lo);
        if let Some(n) = self.noise.filter(|_| rho.lo < reach) {
            let xc = match self.skeleton.convex().filter(|_| rho.lo > 0.0) {
                Some(piece) => {
                    let s = piece.closest(c);
                    let tc = n.fbm.value(s + (c - s) * (r / dc));
                    let spread = n.fbm.lipschitz() * (1.0 + r / rho.lo) * half;
                    den_lo = den_lo.max(r + a * (tc - spread));
                    den_hi = den_hi.min(r + a * (tc + spread));
                    xs = Interval::new(rho.lo / den_hi, rho.hi / den_lo);
                    if dc < reach { dc / (r + a * tc) } else { 1.0 }
                }
                None => self.normalized_distance(c),
            };
            let by_slope = Interval::point(xc.min(1.0)).dilate(half * self.slope);
            let both = xs.intersect(by_slope);
            if !both.is_empty() {
                xs = both;
            }
        }
        Local {
            xs: Interval::new(xs.lo.clamp(0.0, 1.0), xs.hi.clamp(0.0, 1.0)),
            den_lo,
        }
    }

    /// Distance from the skeleton within which the surface `f = T` can lie, or `None`
    /// when `f` never reaches `T`.
    fn surface_reach(&self) -> Option<f32> {
        if self.energy < ISO {
            return None;
        }
        // g(x) = T/E at x = √(1 − (T/E)^⅓).
        let x = (1.0 - (ISO / self.energy).cbrt()).max(0.0).sqrt();
        Some((self.radius + self.amplitude()) * x.min(1.0))
    }
}

/// A noise-free point or sphere primitive: `E·g(max(‖p − c‖ − r, 0)/R)`, evaluated with
/// the same operations as [`Primitive::value`], so the values are the same to the bit. The
/// grid evaluator and the blends' point index evaluate these kernels without the node.
#[derive(Clone, Copy, Debug)]
pub(super) struct Round {
    c: Vec3,
    r: f32,
    big_r: f32,
    inv_r: f32,
    e: f32,
}

impl Round {
    /// The kernel of `p`, when it is a noise-free point or sphere.
    pub(super) fn of(p: &Primitive) -> Option<Round> {
        if p.noise().is_some() {
            return None;
        }
        let (c, r) = match p.skeleton() {
            Skeleton::Point(s) => (s.center, 0.0),
            Skeleton::Sphere(s) => (s.inner().center, s.radius()),
            _ => return None,
        };
        Some(Round {
            c,
            r,
            big_r: p.radius(),
            inv_r: 1.0 / p.radius(),
            e: p.energy(),
        })
    }

    /// The value at squared distance `len2` from the centre (`dx² + dy² + dz²`, summed in
    /// that order as `Vec3::length` does).
    #[inline(always)]
    fn at_squared(&self, len2: f32) -> f32 {
        let len = len2.sqrt();
        let d = (len - self.r).max(0.0);
        let t = if d >= self.big_r { 1.0 } else { d * self.inv_r };
        let s = 1.0 - t * t;
        let g = if t >= 1.0 { 0.0 } else { s * s * s };
        self.e * g
    }

    /// The parameters `[c.x, c.y, c.z, r, R, 1/R, E]`, for kernels packed by lanes.
    pub(super) fn params(&self) -> [f32; 7] {
        [
            self.c.x, self.c.y, self.c.z, self.r, self.big_r, self.inv_r, self.e,
        ]
    }

    /// Adds the values at `(x, y, z)` for `x` in `xs` to `out`.
    #[inline]
    pub(super) fn add_row(&self, xs: &[f32], y: f32, z: f32, out: &mut [f32]) {
        let (dyy, dzz) = (
            (y - self.c.y) * (y - self.c.y),
            (z - self.c.z) * (z - self.c.z),
        );
        for (o, &x) in out.iter_mut().zip(xs) {
            let dx = x - self.c.x;
            *o += self.at_squared(dx * dx + dyy + dzz);
        }
    }

    /// The x-interval outside which the row at `(y, z)` is 0, or `None` when all of it is;
    /// widened by a relative margin far above the rounding of the value's computation.
    pub(super) fn row_extent(&self, y: f32, z: f32) -> Option<(f32, f32)> {
        let reach = (self.r + self.big_r) * (1.0 + 1e-4);
        let (dy, dz) = (y - self.c.y, z - self.c.z);
        let rest = reach * reach - (dy * dy + dz * dz);
        (rest >= 0.0).then(|| {
            let h = rest.sqrt() * (1.0 + 1e-4) + reach * 1e-4;
            (self.c.x - h, self.c.x + h)
        })
    }
}

/// See [`Primitive::local`].
struct Local {
    xs: Interval,
    den_lo: f32,
}

/// `(d̃ᵢ, ∇d̃ᵢ)` of one convex piece at distance `rho > 0`.
#[inline]
fn piece_distance<const GRAD: bool>(
    piece: &dyn Project,
    n: &Noise,
    r: f32,
    p: Vec3,
    rho: f32,
) -> (f32, Vec3) {
    let a = n.amplitude;
    if !GRAD {
        let s = piece.closest(p);
        let u = (p - s) / rho;
        let den = r + a * n.fbm.value(s + u * r);
        return (rho / den, Vec3::ZERO);
    }
    let (s, j): (Vec3, Mat3) = piece.closest_jacobian(p);
    let u = (p - s) / rho;
    let (t, gt) = n.fbm.value_grad(s + u * r);
    let den = r + a * t;
    // J_vᵀ ∇t with J_v = J + (R/ρ)(I − uuᵀ)(I − J).
    let jt = j.transpose();
    let perp = gt - u * u.dot(gt);
    let jv_t = jt * gt + (perp - jt * perp) * (r / rho);
    (rho / den, u / den - jv_t * (rho * a / (den * den)))
}

impl Field for Primitive {
    #[inline]
    fn value(&self, p: Vec3) -> f32 {
        self.energy * wyvill(self.normalized_distance(p))
    }

    #[inline]
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let (x, g) = self.normalized_distance_grad(p);
        let (v, dv) = wyvill_d(x);
        (self.energy * v, g * (self.energy * dv))
    }

    fn support(&self) -> Aabb {
        self.support
    }

    fn interval(&self, b: &Aabb) -> Interval {
        if !b.overlaps(&self.support) {
            return Interval::ZERO;
        }
        wyvill_interval(self.local(b).xs).scale(self.energy)
    }

    fn lipschitz(&self) -> f32 {
        self.energy.abs() * WYVILL_MAX_SLOPE * self.slope
    }

    /// For a point skeleton without noise, the exact bound of the directional derivative
    /// along the segment ([`LineProfile::lipschitz`]): a long ray segment passing beside a
    /// blob sees the slope of the blob along it, which is zero at the foot of the
    /// perpendicular and smaller the farther the line passes. The box of the segment
    /// otherwise.
    fn lipschitz_segment(&self, a: Vec3, b: Vec3) -> f32 {
        if a == b {
            return 0.0;
        }
        match self.along_line(a, b - a) {
            Some(profile) => profile.lipschitz(0.0, 1.0),
            None => self.lipschitz_box(&Aabb::new(a, b)),
        }
    }

    fn lipschitz_box(&self, b: &Aabb) -> f32 {
        if !b.overlaps(&self.support) {
            return 0.0;
        }
        let l = self.local(b);
        self.energy.abs() * wyvill_slope(l.xs) * self.dt_slope(l.xs.hi, l.den_lo)
    }

    /// The default interval subdivision, restricted to the z range where the surface can
    /// be: nothing when the footprint misses the support or `E < T` (no surface at all).
    fn z_bands(&self, fp: &Rect, z: Interval, out: &mut ZBands) {
        let Some(reach) = self.surface_reach() else {
            return;
        };
        let around = self.skeleton_bounds.dilate(reach);
        if !fp.overlaps(&around.footprint()) {
            return;
        }
        let z = z.intersect(around.z());
        if !z.is_empty() {
            z_bands_by_interval(self, fp, z, out);
        }
    }

    /// Fills blocks outside the support, or where the interval is a single saturated
    /// value (0 or the energy), at once; evaluates point by point otherwise.
    fn eval_block(&self, origin: Vec3, step: Vec3, dims: [usize; 3], out: &mut [f32]) {
        let [nx, ny, nz] = dims;
        let n = nx * ny * nz;
        if n == 0 {
            return;
        }
        let far = origin + step * Vec3::new((nx - 1) as f32, (ny - 1) as f32, (nz - 1) as f32);
        let iv = self.interval(&Aabb::new(origin, far));
        // Only a saturated interval (all air beyond the reach, or all inside the skeleton)
        // is the points' value to the bit: elsewhere a box too thin to widen it still has
        // its one value computed along the interval's path, not the point's.
        if iv.lo == iv.hi && (iv.lo == 0.0 || iv.lo == self.energy) {
            out[..n].fill(iv.lo);
            return;
        }
        for k in 0..nz {
            for j in 0..ny {
                let row = origin + Vec3::new(0.0, j as f32, k as f32) * step;
                let at = nx * (j + ny * k);
                for (i, o) in out[at..at + nx].iter_mut().enumerate() {
                    *o = self.value(row + Vec3::X * (i as f32 * step.x));
                }
            }
        }
    }

    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

/// An optional name written without `Some(...)`.
mod bare_name {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(name: &Option<String>, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(name.as_deref().unwrap_or_default())
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<String>, D::Error> {
        String::deserialize(d).map(Some)
    }
}

fn one() -> Finite {
    Finite(1.0)
}

/// A primitive as written in a tree file:
///
/// ```text
/// Primitive(
///     name: "rock",                                   // optional
///     shape: Sphere(center: (0, 0, 0), radius: 3),    // a SkeletonSpec
///     falloff: 2.0,                                   // R, metres, > 0
///     energy: 1.0,                                    // optional, default 1; < 0 carves
///     noise: Some((amplitude: 0.5, wavelength: 4.0, octaves: 4)),  // optional, A ≤ 0.9 R
/// )
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawPrimitiveSpec", rename = "Primitive")]
pub struct PrimitiveSpec {
    /// Unique node name, written as a bare string: `name: "rock"`.
    #[serde(
        skip_serializing_if = "Option::is_none",
        serialize_with = "bare_name::serialize"
    )]
    pub name: Option<String>,
    /// The skeleton.
    pub shape: SkeletonSpec,
    /// Falloff radius `R` in metres.
    pub falloff: Positive,
    /// Energy `E`.
    pub energy: Finite,
    /// Anisotropic noise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise: Option<NoiseSpec>,
}

/// What a tree file holds, before the checks across fields.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Primitive")]
struct RawPrimitiveSpec {
    #[serde(default, deserialize_with = "bare_name::deserialize")]
    name: Option<String>,
    shape: SkeletonSpec,
    falloff: Positive,
    #[serde(default = "one")]
    energy: Finite,
    #[serde(default)]
    noise: Option<NoiseSpec>,
}

impl TryFrom<RawPrimitiveSpec> for PrimitiveSpec {
    type Error = String;

    fn try_from(r: RawPrimitiveSpec) -> Result<Self, String> {
        let spec = PrimitiveSpec {
            name: r.name,
            shape: r.shape,
            falloff: r.falloff,
            energy: r.energy,
            noise: r.noise,
        };
        spec.check()?;
        Ok(spec)
    }
}

impl PrimitiveSpec {
    /// The checks across fields: the shape's ([`SkeletonSpec::check`]) and
    /// `noise.amplitude ≤ 0.9 · falloff`. Run when parsing; run it after editing a spec
    /// in code.
    pub fn check(&self) -> Result<(), String> {
        self.shape.check()?;
        if let Some(n) = &self.noise {
            let max = MAX_AMPLITUDE_RATIO * self.falloff.get();
            if n.amplitude.get() > max {
                return Err(format!(
                    "noise amplitude {} is too large for falloff {}: at most {max} (0.9 × falloff)",
                    n.amplitude, self.falloff
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere(e: f32, noise: Option<&str>) -> Primitive {
        let n = noise.map_or(String::new(), |n| format!(", noise: Some({n})"));
        let s = format!(
            "Primitive(shape: Sphere(center: (1, 2, 3), radius: 2), falloff: 3, energy: {e}{n})"
        );
        Primitive::from_spec(&ron::from_str(&s).unwrap(), 7)
    }

    #[test]
    fn sphere_values() {
        let p = sphere(2.0, None);
        assert_eq!(p.value(Vec3::new(1.0, 2.0, 3.0)), 2.0);
        assert_eq!(p.value(Vec3::new(1.0, 2.0, 4.9)), 2.0);
        assert_eq!(p.value(Vec3::new(1.0, 2.0, 8.0)), 0.0);
        let x: f32 = 1.5 / 3.0;
        let expect = 2.0 * (1.0 - x * x).powi(3);
        assert!((p.value(Vec3::new(1.0, 2.0, 6.5)) - expect).abs() < 1e-6);
        assert!(
            p.support()
                .contains_box(&Aabb::around(Vec3::new(1.0, 2.0, 3.0), 5.0))
        );
        let carve = sphere(-1.0, None);
        assert_eq!(carve.value(Vec3::new(1.0, 2.0, 3.0)), -1.0);
        let mut bands = ZBands::new();
        carve.z_bands(
            &Rect::new(glam::Vec2::ZERO, glam::Vec2::ONE),
            Interval::new(-10.0, 10.0),
            &mut bands,
        );
        assert!(bands.is_empty(), "a carving primitive alone has no surface");
    }

    #[test]
    fn spec_syntax_defaults_and_errors() {
        let s: PrimitiveSpec = ron::from_str(
            "Primitive(name: \"rock\", shape: Sphere(center: (0,0,0), radius: 3), falloff: 2.0, \
             energy: 1.0, noise: Some((amplitude: 0.5, wavelength: 4.0, octaves: 4)))",
        )
        .unwrap();
        assert_eq!(s.name.as_deref(), Some("rock"));
        assert_eq!(
            ron::from_str::<PrimitiveSpec>(&ron::to_string(&s).unwrap()).unwrap(),
            s
        );
        let d: PrimitiveSpec =
            ron::from_str("(shape: Point(center: (0, 0, 0)), falloff: 1)").unwrap();
        assert_eq!((d.energy.get(), d.noise, d.name), (1.0, None, None));
        let e = ron::from_str::<PrimitiveSpec>(
            "Primitive(shape: Point(center: (0, 0, 0)), falloff: 1,\n noise: Some((amplitude: 0.95, wavelength: 1)))",
        )
        .unwrap_err();
        assert_eq!(e.span.start.line, 2);
        assert!(e.to_string().contains("at most 0.9"), "{e}");
        let e = ron::from_str::<PrimitiveSpec>("(shape: Point(center: (0, 0, 0)),\n falloff: 0)")
            .unwrap_err();
        assert_eq!(e.span.start.line, 2);
        let e = ron::from_str::<PrimitiveSpec>(
            "(shape: Point(center: (0, 0, 0)), falloff: 1, radius: 2)",
        )
        .unwrap_err();
        assert!(e.to_string().contains("radius"), "{e}");
        let e = ron::from_str::<PrimitiveSpec>(
            "(shape: Cone(base: (0, 0, 0), apex: (0, 0, 0), radius: 1), falloff: 1)",
        )
        .unwrap_err();
        assert!(e.to_string().contains("apex"), "{e}");
        assert!(matches!(
            Primitive::new(
                Skeleton::from_spec(&d.shape),
                1.0,
                1.0,
                Some(Noise {
                    fbm: Fbm::with(0, 1.0, 1),
                    amplitude: 2.0
                })
            ),
            Err(PrimitiveError::Amplitude { .. })
        ));
    }

    #[test]
    fn noisy_sphere_stays_star_shaped_and_bounded() {
        let p = sphere(1.0, Some("(amplitude: 1.5, wavelength: 2, octaves: 3)"));
        let c = Vec3::new(1.0, 2.0, 3.0);
        // Along rays from the centre, the field never increases (no holes, no islands).
        for i in 0..200 {
            let dir = Vec3::new(
                (i as f32 * 0.7).sin(),
                (i as f32 * 1.3).cos(),
                (i as f32 * 0.37).sin(),
            )
            .normalize();
            let mut last = f32::INFINITY;
            for k in 0..400 {
                let v = p.value(c + dir * (k as f32 * 0.02));
                assert!(v <= last + 1e-6, "ray {i} step {k}");
                last = v;
            }
            // Zero beyond R + A of the sphere's surface, full inside it.
            assert_eq!(p.value(c + dir * (2.0 + 3.0 + 1.5 + 1e-3)), 0.0);
            assert_eq!(p.value(c + dir * 1.9), 1.0);
        }
    }

    /// The pruned search over pieces finds the same minimum as trying every piece.
    #[test]
    fn noisy_pieces_pruning_is_exact() {
        for shape in [
            "Curve(points: [(0, 0, 0), (5, 0, 1), (6, 5, 0), (1, 6, 2), (0, 2, 0)])",
            "Prism(polygon: [(0, 0), (6, 0), (6, 2), (2, 2), (2, 6), (0, 6)], z: (0, 3))",
        ] {
            let s = format!(
                "(shape: {shape}, falloff: 2, noise: Some((amplitude: 1.2, wavelength: 1.5)))"
            );
            let prim = Primitive::from_spec(&ron::from_str(&s).unwrap(), 3);
            let n = *prim.noise().unwrap();
            let b = prim.support();
            for i in 0..3000 {
                let f = |k: u32| (crate::field::noise::mix32(i * 3 + k) >> 8) as f32 / 16_777_216.0;
                let p = b.min + Vec3::new(f(0), f(1), f(2)) * b.size();
                let mut brute = 1.0f32;
                prim.skeleton()
                    .visit_pieces(p, f32::INFINITY, &mut |piece, rho| {
                        let x = if rho <= 0.0 {
                            0.0
                        } else {
                            piece_distance::<false>(piece, &n, 2.0, p, rho).0
                        };
                        brute = brute.min(x);
                        f32::INFINITY
                    });
                assert_eq!(prim.normalized_distance(p), brute, "{shape} at {p}");
                assert_eq!(prim.normalized_distance_grad(p).0, brute, "{shape} at {p}");
            }
        }
    }
}

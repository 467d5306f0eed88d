//! Noise on the tape: the encoding of an [`Fbm`] for `shaders/noise.wgsl` (the same seeded
//! simplex noise, hash and gradients, in f32), the noisy primitive `NPRIM` (the
//! anisotropic distance of seed 002 §5.2) and the turbulence warp `TWARP` (seed 002 §5.3),
//! with their CPU twins.
//!
//! The CPU twins evaluate the noise with the tree's own [`Fbm`] (kept in [`Tape::noises`],
//! indexed by the encoding), so the tape's values are the tree's and the tests compare
//! the WGSL port against the reference implementation itself.
//!
//! | op | params | meaning |
//! | --- | --- | --- |
//! | `NPRIM` | `R, E, A, λ_d̃, fbm[7], shape…` | `E·g(d̃)`, `d̃ = min(ρ/(R + A·t(s + R·u)), 1)`, `ρ` the distance to the convex shape, `s` its projection, `u = (p − s)/ρ` |
//! | `TWARP` | `A, reach, L_ω, region?, min.xyz, max.xyz, falloff, fbm[7] × 3` | `p ← p + A·f_D(p)·(t₀, t₁, t₂)(p)`, `r ← r + reach`; the matching `UNWARP` scales the bound by `L_ω` |
//!
//! An encoded fBm is `index, seed & 0xffff, seed >> 16, 1/λ, octaves, norm, L_t` (the seed
//! split in halves, each exact in f32).
//!
//! [`Tape::noises`]: super::Tape::noises

use glam::Vec3;

use super::tape::project;
use crate::field::falloff::{wyvill, wyvill_slope};
use crate::field::{Aabb, Fbm, Interval, Noise, Warp};

/// Floats of an encoded fBm.
pub const FBM_PARAMS: usize = 7;
/// Floats of a noisy primitive's parameters before its shape.
pub const NPRIM_HEAD: usize = 4 + FBM_PARAMS;
/// Floats of a turbulence warp's parameters.
pub const TWARP_PARAMS: usize = 11 + 3 * FBM_PARAMS;

/// `fbm` as `shaders/noise.wgsl` reads it; `index` is its place in [`super::Tape::noises`].
pub fn encode_fbm(index: usize, fbm: &Fbm) -> [f32; FBM_PARAMS] {
    let seed = fbm.seed();
    [
        index as f32,
        (seed & 0xffff) as f32,
        (seed >> 16) as f32,
        fbm.inv_wavelength(),
        fbm.octaves() as f32,
        fbm.norm(),
        fbm.lipschitz(),
    ]
}

/// The global bound of `|∇d̃|` where `d̃ < 1`, as [`crate::field::Primitive`] computes it:
/// `(1 + A·L_t·(1 + R/(R − A))) / (R − A)`.
pub fn noisy_slope(radius: f32, noise: &Noise) -> f32 {
    dt_slope(
        radius,
        noise.amplitude,
        noise.fbm.lipschitz(),
        1.0,
        radius - noise.amplitude,
    )
}

/// `(1 + A L_t (x_hi + R/den_lo)) / den_lo` (see `crate::field::primitive`).
fn dt_slope(r: f32, a: f32, lt: f32, x_hi: f32, den_lo: f32) -> f32 {
    (1.0 + a * lt * (x_hi.min(1.0) + r / den_lo)) / den_lo
}

/// The parameters of a noisy primitive (`noise` is the fBm's index in the tape's list).
pub fn nprim_head(radius: f32, energy: f32, noise: &Noise, index: usize) -> [f32; NPRIM_HEAD] {
    let mut h = [0.0; NPRIM_HEAD];
    h[..4].copy_from_slice(&[radius, energy, noise.amplitude, noisy_slope(radius, noise)]);
    h[4..].copy_from_slice(&encode_fbm(index, &noise.fbm));
    h
}

/// The parameters of a turbulence warp; `first` is the index of its x turbulence (the y
/// and z ones follow).
pub fn twarp_params(w: &Warp, first: usize) -> [f32; TWARP_PARAMS] {
    let mut q = [0.0; TWARP_PARAMS];
    let (has, b, fall) = match w.region() {
        Some((b, f)) => (1.0, b, f),
        None => (0.0, Aabb::new(Vec3::ZERO, Vec3::ZERO), 1.0),
    };
    q[..11].copy_from_slice(&[
        w.amplitude(),
        w.reach(),
        w.lipschitz(),
        has,
        b.min.x,
        b.min.y,
        b.min.z,
        b.max.x,
        b.max.y,
        b.max.z,
        fall,
    ]);
    for (k, f) in w.turbulence().iter().enumerate() {
        let at = 11 + k * FBM_PARAMS;
        q[at..at + FBM_PARAMS].copy_from_slice(&encode_fbm(first + k, f));
    }
    q
}

/// `ω⁻¹(p)` of the turbulence warp with parameters `q` ([`twarp_params`]), as
/// [`Warp::apply`] computes it.
pub fn twarp_apply(q: &[f32], noises: &[Fbm], p: Vec3) -> Vec3 {
    let fd = if q[3] != 0.0 {
        let b = Aabb {
            min: Vec3::new(q[4], q[5], q[6]),
            max: Vec3::new(q[7], q[8], q[9]),
        };
        let d = (p - b.clamp(p)).length();
        if d == 0.0 { 1.0 } else { wyvill(d / q[10]) }
    } else {
        1.0
    };
    if fd == 0.0 {
        return p;
    }
    let t = |k: usize| noises[q[11 + k * FBM_PARAMS] as usize].value(p);
    p + Vec3::new(t(0), t(1), t(2)) * (q[0] * fd)
}

/// `d̃` at a point at signed distance `sd` from the shape, `t` the turbulence read for it:
/// 0 inside, 1 beyond `R + A`, else `min(ρ/(R + A·t), 1)`.
fn noisy_d(r: f32, a: f32, sd: f32, t: f32) -> f32 {
    let rho = sd.max(0.0);
    if rho >= r + a {
        1.0
    } else if rho <= 0.0 {
        0.0
    } else {
        (rho / (r + a * t)).min(1.0)
    }
}

/// The turbulence of a noisy primitive for `x`, projected at `(s, ρ)` (`ρ > 0`): read at
/// `s + R·(x − s)/ρ`, as `shaders/noise.wgsl` reads it.
fn turbulence(t: &Fbm, r: f32, x: Vec3, (s, rho): (Vec3, f32)) -> f32 {
    t.value(s + (x - s) * (r / rho))
}

/// `(value at p, Lipschitz bound over B(c, r))` of the noisy primitive with parameters
/// `q`: [`crate::field::Primitive`]'s local bound (its `local` and `lipschitz_box`) with
/// the box replaced by the ball, whose half-diagonal is `r`.
pub fn noisy_primitive(
    kind: u32,
    q: &[f32],
    noises: &[Fbm],
    (p, c, rb): (Vec3, Vec3, f32),
    bound: bool,
) -> (f32, f32) {
    let (r, e, a, slope) = (q[0], q[1], q[2], q[3]);
    let t = &noises[q[4] as usize];
    let shape = &q[NPRIM_HEAD..];
    let reach = r + a;
    let pp = project(kind, shape, p);
    let tp = if pp.1 > 0.0 && pp.1 < reach {
        turbulence(t, r, p, pp)
    } else {
        0.0
    };
    let dp = noisy_d(r, a, pp.1, tp);
    let v = e * wyvill(dp);
    if !bound {
        return (v, 0.0);
    }
    let lt = t.lipschitz();
    let pc = if c == p { pp } else { project(kind, shape, c) };
    let dc = pc.1.max(0.0);
    let rho = Interval::new((dc - rb).max(0.0), dc + rb);
    let (mut den_lo, mut den_hi) = (r - a, r + a);
    let mut xs = Interval::new(rho.lo / den_hi, rho.hi / den_lo);
    if rho.lo < reach {
        let tc = if dc <= 0.0 {
            0.0
        } else if c == p && dc < reach {
            tp
        } else {
            turbulence(t, r, c, pc)
        };
        let xc = noisy_d(r, a, pc.1, tc);
        if rho.lo > 0.0 {
            let spread = lt * (1.0 + r / rho.lo) * rb;
            den_lo = den_lo.max(r + a * (tc - spread));
            den_hi = den_hi.min(r + a * (tc + spread));
            xs = Interval::new(rho.lo / den_hi, rho.hi / den_lo);
        }
        let by_slope = Interval::point(xc).dilate(rb * slope);
        let both = xs.intersect(by_slope);
        if !both.is_empty() {
            xs = both;
        }
    }
    let xs = Interval::new(xs.lo.clamp(0.0, 1.0), xs.hi.clamp(0.0, 1.0));
    let l = e.abs() * wyvill_slope(xs) * dt_slope(r, a, lt, xs.hi, den_lo);
    (v, l)
}

//! Noise on the tape: the encoding of an [`Fbm`] for `crates/render/shaders/noise.wgsl` (the same seeded
//! simplex noise, hash and gradients, in f32), the noisy primitive `NPRIM` (the
//! anisotropic distance of Paris et al. 2019 §5.2) and the turbulence warp `TWARP`
//! (Paris et al. 2019 §5.3), with their CPU twins.
//!
//! The CPU twins evaluate the noise with the tree's own [`Fbm`] (kept in [`Tape::noises`],
//! indexed by the encoding), so the tape's values are the tree's and the tests compare
//! the WGSL port against the reference implementation itself.
//!
//! | op | params | meaning |
//! | --- | --- | --- |
//! | `NPRIM` | [`nprim`]: `R, E, A, λ_d̃, fbm, shape…` | `E·g(d̃)`, `d̃ = min(ρ/(R + A·t(s + R·u)), 1)`, `ρ` the distance to the convex shape, `s` its projection, `u = (p − s)/ρ` |
//! | `TWARP` | [`twarp`]: `A, reach, L_ω, region?, min.xyz, max.xyz, falloff, fbm × 3` | `p ← p + A·f_D(p)·(t₀, t₁, t₂)(p)`, `r ← r + reach`; the matching `UNWARP` scales the bound by `L_ω` |
//!
//! An encoded fBm ([`fbm`]) is `index, seed & 0xffff, seed >> 16, 1/λ, octaves, norm,
//! L_t` (the seed split in halves, each exact in f32).
//!
//! [`Tape::noises`]: super::Tape::noises

use glam::Vec3;

use super::format::{fbm, get3, nprim, set3, twarp};
use super::shape::project;
use crate::field::falloff::{wyvill, wyvill_slope};
use crate::field::{Aabb, Fbm, Interval, Noise, Warp};

/// `f` as `crates/render/shaders/noise.wgsl` reads it ([`fbm`]); `index` is its place in
/// [`super::Tape::noises`].
pub fn encode_fbm(index: usize, f: &Fbm) -> [f32; fbm::LEN] {
    let seed = f.seed();
    let mut q = [0.0; fbm::LEN];
    q[fbm::INDEX] = index as f32;
    q[fbm::SEED_LO] = (seed & 0xffff) as f32;
    q[fbm::SEED_HI] = (seed >> 16) as f32;
    q[fbm::INV_WAVELENGTH] = f.inv_wavelength();
    q[fbm::OCTAVES] = f.octaves() as f32;
    q[fbm::NORM] = f.norm();
    q[fbm::LIPSCHITZ] = f.lipschitz();
    q
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

/// The parameters of a noisy primitive before its shape (`index` is the fBm's index in the
/// tape's list).
pub fn nprim_head(radius: f32, energy: f32, noise: &Noise, index: usize) -> [f32; nprim::SHAPE] {
    let mut h = [0.0; nprim::SHAPE];
    h[nprim::RADIUS] = radius;
    h[nprim::ENERGY] = energy;
    h[nprim::AMPLITUDE] = noise.amplitude;
    h[nprim::SLOPE] = noisy_slope(radius, noise);
    h[nprim::FBM..nprim::FBM + fbm::LEN].copy_from_slice(&encode_fbm(index, &noise.fbm));
    h
}

/// The parameters of a turbulence warp; `first` is the index of its x turbulence (the y
/// and z ones follow).
pub fn twarp_params(w: &Warp, first: usize) -> [f32; twarp::LEN] {
    let mut q = [0.0; twarp::LEN];
    let (has, b, fall) = match w.region() {
        Some((b, f)) => (1.0, b, f),
        None => (0.0, Aabb::new(Vec3::ZERO, Vec3::ZERO), 1.0),
    };
    q[twarp::AMPLITUDE] = w.amplitude();
    q[twarp::REACH] = w.reach();
    q[twarp::LIPSCHITZ] = w.lipschitz();
    q[twarp::HAS_REGION] = has;
    set3(&mut q, twarp::REGION_MIN, b.min);
    set3(&mut q, twarp::REGION_MAX, b.max);
    q[twarp::FALLOFF] = fall;
    for (k, f) in w.turbulence().iter().enumerate() {
        let at = twarp::TURBULENCE + k * fbm::LEN;
        q[at..at + fbm::LEN].copy_from_slice(&encode_fbm(first + k, f));
    }
    q
}

/// `ω⁻¹(p)` of the turbulence warp with parameters `q` ([`twarp_params`]), as
/// [`Warp::apply`] computes it.
pub fn twarp_apply(q: &[f32], noises: &[Fbm], p: Vec3) -> Vec3 {
    let fd = if q[twarp::HAS_REGION] != 0.0 {
        let b = Aabb {
            min: get3(q, twarp::REGION_MIN),
            max: get3(q, twarp::REGION_MAX),
        };
        let d = (p - b.clamp(p)).length();
        if d == 0.0 {
            1.0
        } else {
            wyvill(d / q[twarp::FALLOFF])
        }
    } else {
        1.0
    };
    if fd == 0.0 {
        return p;
    }
    let t = |k: usize| noises[q[twarp::TURBULENCE + k * fbm::LEN + fbm::INDEX] as usize].value(p);
    p + Vec3::new(t(0), t(1), t(2)) * (q[twarp::AMPLITUDE] * fd)
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
/// `s + R·(x − s)/ρ`, as `crates/render/shaders/noise.wgsl` reads it.
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
    let (r, e, a, slope) = (
        q[nprim::RADIUS],
        q[nprim::ENERGY],
        q[nprim::AMPLITUDE],
        q[nprim::SLOPE],
    );
    let t = &noises[q[nprim::FBM + fbm::INDEX] as usize];
    let shape = &q[nprim::SHAPE..];
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

//! Spectral synthesis over simplex noise: fBm (the sum of octaves of
//! [`crate::field::noise::Fbm`]) and Musgrave's ridged and hybrid multifractals (Musgrave
//! 2003, ch. 16 "Procedural Fractal Terrains": `RidgedMultifractal` and
//! `HybridMultifractal`), whose roughness grows with altitude.

use glam::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::field::noise::{Fbm, LACUNARITY, OCTAVE_SHIFT, Octaves, simplex};
use crate::value::Positive;

fn default_octaves() -> Octaves {
    Octaves::new(8).expect("8 octaves is within range")
}

/// A fractal's parameters: `(wavelength: 2000, octaves: 8)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FractalSpec {
    /// Wavelength of the first octave, metres.
    pub wavelength: Positive,
    /// Octaves, `1..=12` (default 8).
    #[serde(default = "default_octaves")]
    pub octaves: Octaves,
}

/// The samples of `f(x, y)` over an `nx × ny` grid of `cell`-metre cells, rows in parallel.
fn sample(nx: usize, ny: usize, cell: f32, f: impl Fn(f32, f32) -> f32 + Sync) -> Vec<f32> {
    let mut z = vec![0.0f32; nx * ny];
    z.par_chunks_mut(nx).enumerate().for_each(|(j, row)| {
        for (i, v) in row.iter_mut().enumerate() {
            *v = f(i as f32 * cell, j as f32 * cell);
        }
    });
    z
}

/// The noise of octave `k` at `(x, y)` in first-octave lattice units.
fn octave(seed: u32, k: u32, x: f32, y: f32) -> f32 {
    let s = LACUNARITY.powi(k as i32);
    simplex(
        seed.wrapping_add(k.wrapping_mul(0x9e37_79b9)),
        Vec3::new(x * s, y * s, 0.0) + k as f32 * OCTAVE_SHIFT,
    )
}

/// fBm: `Σ ½^k n(2^k p / λ)` (the project's turbulence at `z = 0`).
pub fn fbm(s: &FractalSpec, nx: usize, ny: usize, cell: f32, seed: u32) -> Vec<f32> {
    let f = Fbm::with(seed, s.wavelength.get(), s.octaves.get());
    sample(nx, ny, cell, |x, y| f.value(Vec3::new(x, y, 0.0)))
}

/// Ridged multifractal (Musgrave 2003, `RidgedMultifractal` with `H = 1`, offset 1,
/// gain 2): each octave is `(1 − |n|)²`, weighted by the previous octave's signal, so
/// sharp ridges carry the detail and valleys stay smooth.
pub fn ridged(s: &FractalSpec, nx: usize, ny: usize, cell: f32, seed: u32) -> Vec<f32> {
    const OFFSET: f32 = 1.0;
    const GAIN: f32 = 2.0;
    let inv = 1.0 / s.wavelength.get();
    let octaves = s.octaves.get();
    sample(nx, ny, cell, |x, y| {
        let (x, y) = (x * inv, y * inv);
        let mut signal = OFFSET - octave(seed, 0, x, y).abs();
        signal *= signal;
        let mut result = signal;
        for k in 1..octaves {
            let weight = (signal * GAIN).clamp(0.0, 1.0);
            signal = OFFSET - octave(seed, k, x, y).abs();
            signal = signal * signal * weight;
            result += signal * LACUNARITY.powi(-(k as i32));
        }
        result
    })
}

/// Hybrid multifractal (Musgrave 2003, `HybridMultifractal` with `H = 0.25`, offset 0.7):
/// each octave is weighted by the running product of the previous ones, so low ground is
/// smooth and high ground rough.
pub fn hybrid(s: &FractalSpec, nx: usize, ny: usize, cell: f32, seed: u32) -> Vec<f32> {
    const OFFSET: f32 = 0.7;
    const H: f32 = 0.25;
    let inv = 1.0 / s.wavelength.get();
    let octaves = s.octaves.get();
    sample(nx, ny, cell, |x, y| {
        let (x, y) = (x * inv, y * inv);
        let mut result = octave(seed, 0, x, y) + OFFSET;
        let mut weight = result;
        for k in 1..octaves {
            weight = weight.min(1.0);
            let signal = (octave(seed, k, x, y) + OFFSET) * LACUNARITY.powf(-H * k as f32);
            result += weight * signal;
            weight *= signal;
        }
        result
    })
}

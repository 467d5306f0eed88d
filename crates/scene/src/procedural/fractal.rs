//! Spectral synthesis over simplex noise: fBm and Musgrave's ridged and hybrid
//! multifractals (Musgrave 2003, ch. 16 "Procedural Fractal Terrains"), whose roughness
//! grows with altitude. They are the elevation trees' multifractals
//! ([`crate::elevation::multifractal`]) sampled on a grid: one family of fractal noises.

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::elevation::Lod;
use crate::elevation::multifractal::{Kind, Multifractal};
use crate::field::noise::{Fbm, Octaves};
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

/// A multifractal of `kind` with Musgrave's parameters sampled over the grid: the
/// elevation trees' octave sums ([`Multifractal::musgrave`]), so one family of fractal
/// noises serves both.
fn multifractal(
    kind: Kind,
    s: &FractalSpec,
    nx: usize,
    ny: usize,
    cell: f32,
    seed: u32,
) -> Vec<f32> {
    let m = Multifractal::musgrave(kind, s.wavelength.get(), s.octaves.get(), seed);
    sample(nx, ny, cell, |x, y| m.value(Vec2::new(x, y), &Lod::FULL))
}

/// fBm: `Σ ½^k n(2^k p / λ)` (the project's turbulence at `z = 0`).
pub fn fbm(s: &FractalSpec, nx: usize, ny: usize, cell: f32, seed: u32) -> Vec<f32> {
    multifractal(Kind::Fbm, s, nx, ny, cell, seed)
}

/// Ridged multifractal (Musgrave 2003, `RidgedMultifractal` with `H = 1`, offset 1,
/// gain 2): each octave is `(1 − |n|)²`, weighted by the previous octave's signal, so
/// sharp ridges carry the detail and valleys stay smooth. Sampled through
/// [`RIDGE_WARP`].
pub fn ridged(s: &FractalSpec, nx: usize, ny: usize, cell: f32, seed: u32) -> Vec<f32> {
    let m = Multifractal::musgrave(Kind::Ridged, s.wavelength.get(), s.octaves.get(), seed);
    let l = s.wavelength.get();
    let warp = [1u32, 2].map(|k| Fbm::with(seed ^ k.wrapping_mul(0x5bd1_e995), 2.0 * l, 2));
    sample(nx, ny, cell, |x, y| {
        let p = Vec3::new(x, y, 0.0);
        let q = Vec2::new(x, y) + RIDGE_WARP * l * Vec2::new(warp[0].value(p), warp[1].value(p));
        m.value(q, &Lod::FULL)
    })
}

/// How far the ridged generator moves its samples, in first-octave wavelengths: two
/// octaves of fBm twice the first octave's wavelength. Simplex noise is a little weaker
/// on the faces of its lattice's simplices, and a ridged sum (`1 − |n|`) gathers its
/// crests where the noise is weak: unwarped, crests run as straight creases along the
/// lattice's planes across a whole grid. Warped, they meander as ridge lines do.
pub const RIDGE_WARP: f32 = 0.2;

/// Hybrid multifractal (Musgrave 2003, `HybridMultifractal` with `H = 0.25`, offset 0.7):
/// each octave is weighted by the running product of the previous ones, so low ground is
/// smooth and high ground rough.
pub fn hybrid(s: &FractalSpec, nx: usize, ny: usize, cell: f32, seed: u32) -> Vec<f32> {
    multifractal(Kind::Hybrid, s, nx, ny, cell, seed)
}

//! Procedural heightfields from a seed (the survey of basic terrain generation: fBm,
//! multifractals, midpoint displacement, fault lines, particle deposition), optionally
//! eroded ([`crate::erosion`]): [`GenerateSpec`] is the recipe a tree file's `Heightfield`
//! leaf and `karstic generate` take, so a scene is reproducible without a raster.
//!
//! * [`fractal`]: fBm, ridged and hybrid multifractals (Musgrave 2003) over the project's
//!   simplex noise ([`crate::field::noise`]);
//! * [`diamond_square`]: midpoint displacement on a grid (Fournier, Fussell and Carpenter
//!   1982; the diamond–square order of Miller 1986);
//! * [`faults`]: fault lines;
//! * [`deposition`]: particle deposition.
//!
//! Every generator gives the same samples whatever the thread count: the per-sample ones
//! hash the seed with the sample's position, and the sequential ones draw from one seeded
//! generator in a fixed order.

pub mod deposition;
pub mod diamond_square;
pub mod faults;
pub mod fractal;

use serde::{Deserialize, Serialize};

use crate::dem::{DemError, Heightfield};
use crate::erosion::{Eroder, ErosionStage};
use crate::field::noise::mix32;
use crate::value::Positive;

/// The kinds of generator and their parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Generator {
    /// Fractional Brownian motion of simplex noise.
    Fbm(fractal::FractalSpec),
    /// Musgrave's ridged multifractal.
    Ridged(fractal::FractalSpec),
    /// Musgrave's hybrid multifractal.
    Hybrid(fractal::FractalSpec),
    /// Diamond–square midpoint displacement.
    DiamondSquare(diamond_square::DiamondSquareSpec),
    /// Random fault lines.
    Faults(faults::FaultSpec),
    /// Particle deposition.
    Deposition(deposition::DepositionSpec),
}

impl Generator {
    /// Checks the counts a parser cannot bound, naming the field: more faults or particles
    /// than a generator takes are refused, not quietly cut down.
    pub fn validate(&self) -> Result<(), DemError> {
        let bad = |what: String| Err(DemError::Invalid { what });
        match self {
            Generator::Faults(f) if f.count > faults::MAX_FAULTS => bad(format!(
                "Faults.count: at most {}, got {}",
                faults::MAX_FAULTS,
                f.count
            )),
            Generator::Deposition(d)
                if u64::from(d.series) * u64::from(d.particles) > deposition::MAX_PARTICLES =>
            {
                bad(format!(
                    "Deposition: series × particles = {} × {} is over the {} particles a \
                     deposition takes",
                    d.series,
                    d.particles,
                    deposition::MAX_PARTICLES
                ))
            }
            _ => Ok(()),
        }
    }
}

/// A generated (and optionally eroded) heightfield in a tree file or on the command line:
///
/// ```ron
/// (kind: Ridged((wavelength: 2000)), size: (257, 257), cell: 20, relief: 800, seed: 7,
///  erosion: [StreamPower((steps: 100, dt: 20000, uplift: 0.001, k: 2e-4))])
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GenerateSpec {
    /// The generator.
    pub kind: Generator,
    /// Samples along x and y (each at least 2).
    pub size: (u32, u32),
    /// Sample spacing, metres.
    pub cell: Positive,
    /// The generated surface is scaled to span `[0, relief]` metres before erosion.
    pub relief: Positive,
    /// Seed of every random choice.
    #[serde(default)]
    pub seed: u32,
    /// Erosion stages applied in order after generation.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub erosion: Vec<ErosionStage>,
}

/// Bytes a generated sample takes while generating (the grid, and scratch).
const GENERATE_BYTES_PER_SAMPLE: u64 = 16;

impl GenerateSpec {
    /// Generates and erodes the heightfield (south-west sample at the origin), refusing
    /// grids whose working memory is over `budget` bytes. Errors name the field.
    pub fn build(&self, budget: u64) -> Result<Heightfield, DemError> {
        let (nx, ny) = (self.size.0 as usize, self.size.1 as usize);
        if nx < 2 || ny < 2 {
            return Err(DemError::Invalid {
                what: format!(
                    "generate.size: at least (2, 2) samples, got {:?}",
                    self.size
                ),
            });
        }
        let n = (nx as u64) * (ny as u64);
        let per = if self.erosion.is_empty() {
            GENERATE_BYTES_PER_SAMPLE
        } else {
            crate::erosion::BYTES_PER_SAMPLE
        };
        crate::io::check_budget(
            format!("generate.size: a {nx}×{ny} grid"),
            n.saturating_mul(per),
            budget,
        )?;
        self.kind.validate()?;
        for s in &self.erosion {
            s.validate().map_err(|e| DemError::Invalid {
                what: format!("generate.erosion: {e}"),
            })?;
        }
        let cell = self.cell.get();
        let mut z = match &self.kind {
            Generator::Fbm(f) => fractal::fbm(f, nx, ny, cell, self.seed),
            Generator::Ridged(f) => fractal::ridged(f, nx, ny, cell, self.seed),
            Generator::Hybrid(f) => fractal::hybrid(f, nx, ny, cell, self.seed),
            Generator::DiamondSquare(d) => diamond_square::generate(d, nx, ny, self.seed, budget)?,
            Generator::Faults(f) => faults::generate(f, nx, ny, cell, self.seed),
            Generator::Deposition(d) => deposition::generate(d, nx, ny, self.seed),
        };
        normalise(&mut z, self.relief.get());
        let hf = Heightfield::new(nx, ny, glam::Vec2::ZERO, glam::Vec2::splat(cell), z)?;
        if self.erosion.is_empty() {
            return Ok(hf);
        }
        let mut eroder = Eroder::new(&hf, budget)?;
        eroder.run(&self.erosion)?;
        eroder.heightfield()
    }
}

/// Scales `z` to span `[0, relief]` (a flat field becomes 0).
fn normalise(z: &mut [f32], relief: f32) {
    let (lo, hi) = z
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let s = if hi > lo { relief / (hi - lo) } else { 0.0 };
    for v in z {
        *v = (*v - lo) * s;
    }
}

/// A uniform number in `[0, 1)` from a seed and two integers (a sample's position, a
/// fault's index): the same whatever order it is asked in.
pub fn unit_hash(seed: u32, a: u32, b: u32) -> f32 {
    let h = mix32(seed ^ mix32(a.wrapping_add(0x9e37_79b9) ^ mix32(b.wrapping_add(0x85eb_ca6b))));
    (h >> 8) as f32 / (1u32 << 24) as f32
}

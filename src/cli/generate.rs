//! `karstic generate KIND -o out.tif`: a procedural heightfield from a seed.

use std::path::PathBuf;
use std::time::Instant;

use clap::{Args, ValueEnum};
use karstic::dem::{self, Dem, Georef};
use karstic::field::noise::Octaves;
use karstic::procedural::deposition::DepositionSpec;
use karstic::procedural::diamond_square::DiamondSquareSpec;
use karstic::procedural::faults::FaultSpec;
use karstic::procedural::fractal::FractalSpec;
use karstic::procedural::{GenerateSpec, Generator};
use karstic::value::{NonNegative, Positive, Unit};

use super::Budget;

/// The generators.
#[derive(Clone, Copy, Debug, ValueEnum)]
enum Kind {
    /// Fractional Brownian motion of simplex noise.
    Fbm,
    /// Musgrave's ridged multifractal.
    Ridged,
    /// Musgrave's hybrid multifractal.
    Hybrid,
    /// Diamond–square midpoint displacement.
    DiamondSquare,
    /// Random fault lines.
    Faults,
    /// Particle deposition.
    Deposition,
}

/// A procedural heightfield, written as a DEM in a local frame.
#[derive(Args, Debug)]
pub(super) struct GenerateArgs {
    /// The generator.
    kind: Kind,
    /// Output DEM: .tif (float32 GeoTIFF), .png (16-bit + .json sidecar) or .asc.
    #[arg(short, long)]
    output: PathBuf,
    /// Samples along x and y.
    #[arg(long, num_args = 2, value_names = ["NX", "NY"], default_values_t = [513, 513])]
    size: Vec<u32>,
    /// Sample spacing, metres.
    #[arg(value_parser = super::finite, long, value_name = "METRES", default_value_t = 10.0)]
    cell: f32,
    /// Elevations span [0, RELIEF] metres.
    #[arg(value_parser = super::finite, long, value_name = "METRES", default_value_t = 1000.0)]
    relief: f32,
    /// Seed of every random choice.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// fbm, ridged, hybrid: wavelength of the first octave, metres.
    #[arg(value_parser = super::finite, long, value_name = "METRES", default_value_t = 2000.0)]
    wavelength: f32,
    /// fbm, ridged, hybrid: octaves (1 to 12).
    #[arg(long, default_value_t = 8)]
    octaves: u32,
    /// diamond-square: the Hurst exponent H in [0, 1] (1 smooth).
    #[arg(value_parser = super::finite, long, default_value_t = 0.8)]
    roughness: f32,
    /// faults: how many (at most 100,000).
    #[arg(long, default_value_t = 200)]
    faults: u32,
    /// faults: width of the cosine step, metres.
    #[arg(value_parser = super::finite, long, value_name = "METRES", default_value_t = 0.0)]
    width: f32,
    /// deposition: vents, particles per vent (at most 10⁸ particles in all), and the drop
    /// radius in cells.
    #[arg(long, num_args = 3, value_names = ["SERIES", "PARTICLES", "RADIUS"],
          default_values_t = [5, 20000, 8])]
    deposition: Vec<u32>,
    /// No summary.
    #[arg(long)]
    quiet: bool,
    /// Memory budget.
    #[command(flatten)]
    budget: Budget,
}

/// A flag's value checked like a tree file's field.
fn checked<T>(flag: &str, v: f32, ok: fn(f32) -> bool, make: fn(f32) -> T) -> anyhow::Result<T> {
    anyhow::ensure!(v.is_finite() && ok(v), "--{flag}: out of range, got {v}");
    Ok(make(v))
}

impl GenerateArgs {
    /// The recipe the flags describe.
    fn spec(&self) -> anyhow::Result<GenerateSpec> {
        let fractal = || -> anyhow::Result<FractalSpec> {
            Ok(FractalSpec {
                wavelength: checked("wavelength", self.wavelength, |v| v > 0.0, Positive)?,
                octaves: Octaves::new(self.octaves)
                    .ok_or_else(|| anyhow::anyhow!("--octaves: 1 to 12, got {}", self.octaves))?,
            })
        };
        let kind = match self.kind {
            Kind::Fbm => Generator::Fbm(fractal()?),
            Kind::Ridged => Generator::Ridged(fractal()?),
            Kind::Hybrid => Generator::Hybrid(fractal()?),
            Kind::DiamondSquare => Generator::DiamondSquare(DiamondSquareSpec {
                roughness: checked(
                    "roughness",
                    self.roughness,
                    |v| (0.0..=1.0).contains(&v),
                    Unit,
                )?,
            }),
            Kind::Faults => Generator::Faults(FaultSpec {
                count: self.faults,
                width: checked("width", self.width, |v| v >= 0.0, NonNegative)?,
            }),
            Kind::Deposition => Generator::Deposition(DepositionSpec {
                series: self.deposition[0],
                particles: self.deposition[1],
                radius: self.deposition[2],
            }),
        };
        Ok(GenerateSpec {
            kind,
            size: (self.size[0], self.size[1]),
            cell: checked("cell", self.cell, |v| v > 0.0, Positive)?,
            relief: checked("relief", self.relief, |v| v > 0.0, Positive)?,
            seed: self.seed,
            erosion: Vec::new(),
        })
    }
}

/// Runs `karstic generate`.
pub(super) fn run(args: GenerateArgs) -> anyhow::Result<()> {
    dem::files_written(&args.output)?;
    let started = Instant::now();
    let hf = args.spec()?.build(args.budget.max_memory)?;
    let c = f64::from(hf.cell().x);
    let out = Dem {
        heightfield: hf,
        georef: Georef::local(c, c),
        notices: Vec::new(),
    };
    dem::write(&out, &args.output)?;
    if !args.quiet {
        let hf = &out.heightfield;
        eprintln!(
            "wrote {}: {}×{} samples of {c} m, {:?}, seed {}, {:.3} s",
            args.output.display(),
            hf.nx(),
            hf.ny(),
            args.kind,
            args.seed,
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

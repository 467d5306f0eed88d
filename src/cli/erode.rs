//! `karstic erode IN -o OUT`: uplift and stream-power erosion (with optional hillslope
//! diffusion and deposition), then optional thermal erosion, on a DEM.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Args;
use karstic::dem::{self, Dem, ReadOptions};
use karstic::erosion::{Eroder, ErosionStage, StreamPowerSpec, ThermalSpec};
use karstic::value::{NonNegative, Positive};

use super::Budget;

/// Erode a DEM.
#[derive(Args, Debug)]
pub(super) struct ErodeArgs {
    /// Input DEM (.tif, .png, .asc, .hgt).
    input: PathBuf,
    /// Output DEM (.tif, .png, .asc), same georeference.
    #[arg(short, long)]
    output: PathBuf,
    /// Stream-power time steps (0: none).
    #[arg(long, default_value_t = 100)]
    steps: u32,
    /// Length of a step, years.
    #[arg(value_parser = super::finite, long, value_name = "YEARS", default_value_t = 2e4)]
    dt: f32,
    /// Uplift rate of the interior, metres per year.
    #[arg(value_parser = super::finite, long, value_name = "M_PER_YR", default_value_t = 1e-3)]
    uplift: f32,
    /// Erodibility K of the stream-power law.
    #[arg(value_parser = super::finite, long, default_value_t = 2e-4)]
    k: f32,
    /// Drainage-area exponent m.
    #[arg(value_parser = super::finite, long, default_value_t = 0.4)]
    m: f32,
    /// Slope exponent n.
    #[arg(value_parser = super::finite, long, default_value_t = 1.0)]
    n: f32,
    /// Hillslope diffusivity, m²/yr (0: none).
    #[arg(value_parser = super::finite, long, value_name = "M2_PER_YR", default_value_t = 0.0)]
    diffusion: f32,
    /// Deposition coefficient G of the sediment carried down (Yuan et al. 2019): fans and
    /// valley fill where the slope eases (0: none, what is cut leaves the grid).
    #[arg(value_parser = super::finite, long, value_name = "G", default_value_t = 0.0)]
    deposition: f32,
    /// Then thermal erosion down to this talus angle, degrees.
    #[arg(value_parser = super::finite, long, value_name = "DEGREES")]
    talus: Option<f32>,
    /// Print the median time of a stream-power step.
    #[arg(long)]
    timing: bool,
    /// No summary.
    #[arg(long)]
    quiet: bool,
    /// Memory budget.
    #[command(flatten)]
    budget: Budget,
}

/// `v` when it is finite and `ok`, else an error naming the flag.
fn flag(name: &str, v: f32, ok: fn(f32) -> bool) -> anyhow::Result<f32> {
    anyhow::ensure!(v.is_finite() && ok(v), "--{name}: out of range, got {v}");
    Ok(v)
}

/// Runs `karstic erode`.
pub(super) fn run(args: ErodeArgs) -> anyhow::Result<()> {
    let outputs = dem::files_written(&args.output)?;
    let budget = args.budget.max_memory;
    let opts = ReadOptions {
        memory_budget: budget,
        ..ReadOptions::default()
    };
    karstic::io::check_outputs(&dem::files_read(&args.input, &opts), &outputs)?;
    let input = dem::read(&args.input, &opts)?;
    let sp = StreamPowerSpec {
        steps: args.steps,
        dt: Positive(flag("dt", args.dt, |v| v > 0.0)?),
        uplift: NonNegative(flag("uplift", args.uplift, |v| v >= 0.0)?),
        k: Positive(flag("k", args.k, |v| v > 0.0)?),
        m: NonNegative(flag("m", args.m, |v| v >= 0.0)?),
        n: Positive(flag("n", args.n, |v| v > 0.0)?),
        diffusion: NonNegative(flag("diffusion", args.diffusion, |v| v >= 0.0)?),
        deposition: NonNegative(flag("deposition", args.deposition, |v| v >= 0.0)?),
    };
    ErosionStage::StreamPower(sp).validate()?;
    let thermal = match args.talus {
        Some(t) => {
            let t = ThermalSpec {
                talus: Positive(flag("talus", t, |v| v > 0.0 && v < 90.0)?),
                tolerance: Positive(0.01),
                max_iterations: 10_000,
            };
            Some(t)
        }
        None => None,
    };
    let started = Instant::now();
    let mut eroder = Eroder::new(&input.heightfield, budget)?;
    let mut times: Vec<Duration> = Vec::with_capacity(args.steps as usize);
    for _ in 0..args.steps {
        let t = Instant::now();
        eroder.stream_power_step(&sp);
        times.push(t.elapsed());
    }
    let report = thermal.map(|t| eroder.thermal(&t));
    let out = Dem {
        heightfield: eroder.heightfield()?,
        georef: input.georef.clone(),
        notices: Vec::new(),
    };
    dem::write(&out, &args.output)?;
    if args.timing && !times.is_empty() {
        times.sort_unstable();
        println!(
            "median step {:.4} s over {} steps ({}×{} samples)",
            times[times.len() / 2].as_secs_f64(),
            times.len(),
            out.heightfield.nx(),
            out.heightfield.ny()
        );
    }
    if !args.quiet {
        let (lo, hi) = out.heightfield.z_range().unwrap_or((f32::NAN, f32::NAN));
        let thermal = report.map_or(String::new(), |r| {
            format!(
                ", thermal {} passes (largest excess {:.3} m)",
                r.iterations, r.max_excess
            )
        });
        eprintln!(
            "wrote {}: {} steps of {} years{thermal}, z {lo:.2} … {hi:.2} m, {:.3} s",
            args.output.display(),
            args.steps,
            args.dt,
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

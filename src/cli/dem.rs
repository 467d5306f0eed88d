//! `karstic dem info FILE` and `karstic dem convert IN OUT`.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, Subcommand};

use super::Budget;
use karstic::dem::{self, Dem, Interpolation, ReadOptions};
use karstic::io::check_outputs;

/// Inspect and convert DEMs (GeoTIFF, PNG + JSON sidecar, ESRI ASCII, SRTM .hgt).
#[derive(Args, Debug)]
pub(super) struct DemArgs {
    /// What to do.
    #[command(subcommand)]
    command: DemCommand,
}

/// `dem` subcommands.
#[derive(Subcommand, Debug)]
pub(super) enum DemCommand {
    /// Print size, cell size in metres, CRS kind, elevation range and nodata count.
    Info(InfoArgs),
    /// Convert between formats (by extension: .tif, .png, .asc), optionally resampling.
    Convert(ConvertArgs),
}

/// Options shared by every command that reads a DEM.
#[derive(Args, Debug, Clone)]
pub(super) struct ReadArgs {
    /// PNG: the JSON sidecar (default: FILE.json, or P.json for FILE = P_suffix.png).
    #[arg(long, value_name = "JSON")]
    sidecar: Option<PathBuf>,
    /// PNG: elevations of raw 0 and of the largest raw value, overriding the sidecar.
    #[arg(long, num_args = 2, value_names = ["LO", "HI"], allow_negative_numbers = true)]
    z_range: Option<Vec<f64>>,
    /// Cell size in metres for files without a georeference.
    #[arg(long, value_name = "METRES")]
    cell_size: Option<f64>,
    /// Memory budget.
    #[command(flatten)]
    budget: Budget,
}

impl ReadArgs {
    /// The library's read options.
    fn options(&self) -> ReadOptions {
        ReadOptions {
            memory_budget: self.budget.max_memory,
            z_range: self.z_range.as_ref().map(|v| [v[0], v[1]]),
            sidecar: self.sidecar.clone(),
            cell_size: self.cell_size,
        }
    }
}

/// `dem info`.
#[derive(Args, Debug)]
pub(super) struct InfoArgs {
    /// The DEM file.
    file: PathBuf,
    /// Read options.
    #[command(flatten)]
    read: ReadArgs,
}

/// `dem convert`.
#[derive(Args, Debug)]
pub(super) struct ConvertArgs {
    /// Input DEM.
    input: PathBuf,
    /// Output DEM (.tif float32 GeoTIFF, .png 16-bit + .json sidecar, .asc ESRI grid).
    #[arg(short, long)]
    output: PathBuf,
    /// Resample to square cells of this size in metres.
    #[arg(long, value_name = "METRES")]
    resample: Option<f64>,
    /// Interpolation used when resampling.
    #[arg(long, value_enum, default_value = "bilinear")]
    interpolation: InterpArg,
    /// Read options.
    #[command(flatten)]
    read: ReadArgs,
}

/// Interpolation names on the command line.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub(super) enum InterpArg {
    /// Bilinear.
    Bilinear,
    /// Catmull-Rom bicubic.
    Bicubic,
}

impl From<InterpArg> for Interpolation {
    fn from(a: InterpArg) -> Self {
        match a {
            InterpArg::Bilinear => Interpolation::Bilinear,
            InterpArg::Bicubic => Interpolation::Bicubic,
        }
    }
}

/// Runs `karstic dem ...`.
pub(super) fn run(args: DemArgs) -> anyhow::Result<()> {
    match args.command {
        DemCommand::Info(a) => info(a),
        DemCommand::Convert(a) => convert(a),
    }
}

fn print_notices(d: &Dem) {
    for n in &d.notices {
        eprintln!("note: {n}");
    }
}

fn info(a: InfoArgs) -> anyhow::Result<()> {
    let d = dem::read(&a.file, &a.read.options())?;
    print_notices(&d);
    print!("{}", describe(&a.file.display().to_string(), &d));
    Ok(())
}

/// The `dem info` report.
fn describe(name: &str, d: &Dem) -> String {
    let h = &d.heightfield;
    let g = &d.georef;
    let c = h.cell();
    let ext = h.extent();
    let size = ext.max - ext.min;
    let n = h.nx() * h.ny();
    let nodata = h.nodata_count();
    let (lo, hi) = h.z_range().unwrap_or((f32::NAN, f32::NAN));
    let nw = g.north_west_corner(h.ny());
    format!(
        "file        {name}\n\
         size        {} × {} samples, {:.2} km × {:.2} km\n\
         cell size   {:.3} m × {:.3} m\n\
         CRS         {}\n\
         north-west  ({}, {}) (outer corner, CRS units)\n\
         origin      ({}, {}) (the south-west sample's centre, CRS units: (0, 0) of a tree's frame)\n\
         z range     {lo:.2} .. {hi:.2} m\n\
         nodata      {nodata} samples ({:.1}%)\n\
         max slope   {:.3} (bilinear Lipschitz bound)\n",
        h.nx(),
        h.ny(),
        size.x / 1000.0,
        size.y / 1000.0,
        c.x,
        c.y,
        g.crs.describe(),
        nw[0],
        nw[1],
        g.origin[0],
        g.origin[1],
        100.0 * nodata as f64 / n as f64,
        h.lipschitz(Interpolation::Bilinear),
    )
}

fn convert(a: ConvertArgs) -> anyhow::Result<()> {
    let opts = a.read.options();
    check_outputs(
        &dem::files_read(&a.input, &opts),
        &dem::files_written(&a.output)?,
    )?;
    let mut d = dem::read(&a.input, &opts)?;
    if let Some(cell) = a.resample {
        d = d
            .resample(cell, a.interpolation.into(), a.read.budget.max_memory)
            .with_context(|| format!("resampling {}", a.input.display()))?;
    }
    print_notices(&d);
    dem::write(&d, &a.output)?;
    eprintln!(
        "wrote {} ({} × {} samples)",
        a.output.display(),
        d.heightfield.nx(),
        d.heightfield.ny()
    );
    Ok(())
}

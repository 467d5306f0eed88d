//! `karstic dem info FILE` and `karstic dem convert IN OUT`.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, Subcommand};

use crate::dem::{self, Dem, Interpolation, ReadOptions};

/// Inspect and convert DEMs (GeoTIFF, PNG + JSON sidecar, ESRI ASCII, SRTM .hgt).
#[derive(Args, Debug)]
pub struct DemArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: DemCommand,
}

/// `dem` subcommands.
#[derive(Subcommand, Debug)]
pub enum DemCommand {
    /// Print size, cell size in metres, CRS kind, elevation range and nodata count.
    Info(InfoArgs),
    /// Convert between formats (by extension: .tif, .png, .asc), optionally resampling.
    Convert(ConvertArgs),
}

/// Options shared by every command that reads a DEM.
#[derive(Args, Debug, Clone)]
pub struct ReadArgs {
    /// PNG: the JSON sidecar (default: FILE.json, or P.json for FILE = P_suffix.png).
    #[arg(long, value_name = "JSON")]
    pub sidecar: Option<PathBuf>,
    /// PNG: elevations of raw 0 and of the largest raw value, overriding the sidecar.
    #[arg(long, num_args = 2, value_names = ["LO", "HI"], allow_negative_numbers = true)]
    pub z_range: Option<Vec<f64>>,
    /// Cell size in metres for files without a georeference.
    #[arg(long, value_name = "METRES")]
    pub cell_size: Option<f64>,
    /// Refuse grids needing more memory than this (bytes; K, M, G suffixes allowed).
    #[arg(long, value_name = "BYTES", value_parser = parse_bytes, default_value = "8G")]
    pub max_memory: u64,
}

impl ReadArgs {
    /// The library's read options.
    pub fn options(&self) -> ReadOptions {
        ReadOptions {
            memory_budget: self.max_memory,
            z_range: self.z_range.as_ref().map(|v| [v[0], v[1]]),
            sidecar: self.sidecar.clone(),
            cell_size: self.cell_size,
        }
    }
}

/// `dem info`.
#[derive(Args, Debug)]
pub struct InfoArgs {
    /// The DEM file.
    pub file: PathBuf,
    /// Read options.
    #[command(flatten)]
    pub read: ReadArgs,
}

/// `dem convert`.
#[derive(Args, Debug)]
pub struct ConvertArgs {
    /// Input DEM.
    pub input: PathBuf,
    /// Output DEM (.tif float32 GeoTIFF, .png 16-bit + .json sidecar, .asc ESRI grid).
    pub output: PathBuf,
    /// Resample to square cells of this size in metres.
    #[arg(long, value_name = "METRES")]
    pub resample: Option<f64>,
    /// Interpolation used when resampling.
    #[arg(long, value_enum, default_value = "bilinear")]
    pub interpolation: InterpArg,
    /// Read options.
    #[command(flatten)]
    pub read: ReadArgs,
}

/// Interpolation names on the command line.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum InterpArg {
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

/// `"8G"` → 8 GiB; plain numbers are bytes.
pub fn parse_bytes(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let (num, mul) = match t.char_indices().last() {
        Some((i, c @ ('k' | 'K' | 'm' | 'M' | 'g' | 'G' | 't' | 'T'))) => {
            let shift = match c.to_ascii_uppercase() {
                'K' => 10,
                'M' => 20,
                'G' => 30,
                _ => 40,
            };
            (&t[..i], 1u64 << shift)
        }
        _ => (t, 1),
    };
    let v: f64 = num
        .parse()
        .map_err(|_| format!("expected a size like 512M or 8G, found {s:?}"))?;
    if !(v >= 0.0 && v.is_finite()) {
        return Err(format!("expected a non-negative size, found {s:?}"));
    }
    Ok((v * mul as f64) as u64)
}

/// Runs `karstic dem ...`.
pub fn run(args: DemArgs) -> anyhow::Result<()> {
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
pub fn describe(name: &str, d: &Dem) -> String {
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
        100.0 * nodata as f64 / n as f64,
        h.lipschitz(Interpolation::Bilinear),
    )
}

fn convert(a: ConvertArgs) -> anyhow::Result<()> {
    let mut d = dem::read(&a.input, &a.read.options())?;
    if let Some(cell) = a.resample {
        d = d
            .resample(cell, a.interpolation.into(), a.read.max_memory)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn byte_sizes() {
        assert_eq!(parse_bytes("8G"), Ok(8 << 30));
        assert_eq!(parse_bytes("512m"), Ok(512 << 20));
        assert_eq!(parse_bytes("1000"), Ok(1000));
        assert!(parse_bytes("lots").is_err());
        assert!(parse_bytes("-1K").is_err());
    }
}

//! `karstic tin SOURCE -o terrain.glb --max-error E`: an error-bounded TIN of a DEM or of
//! a tree's heightmap.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use karstic::dem::{self, ReadOptions};
use karstic::heightmap::trim_nodata_border;
use karstic::mesh::export::{self, ExportOptions};
use karstic::mesh::tin;

use super::Budget;
use super::heightmap::{GridArgs, tree_heightmap};

/// Triangulated irregular network within a vertical error of every grid point.
#[derive(Args, Debug)]
pub(super) struct TinArgs {
    /// A DEM (.tif, .png + sidecar, .asc, .hgt; the TIN is in its local frame, south-west
    /// sample at the origin) or a tree file (.ron: its heightmap is triangulated, less
    /// the nodata border where the terrain ends, in the tree's frame).
    source: PathBuf,
    /// Output mesh: .glb, .gltf (+ .bin), .obj or .ply.
    #[arg(short, long)]
    output: PathBuf,
    /// Largest vertical distance allowed between the TIN and a grid point, metres.
    #[arg(long, value_name = "METRES")]
    max_error: f64,
    /// Where a tree's heightmap samples lie (trees only).
    #[command(flatten)]
    grid: GridArgs,
    /// No summary.
    #[arg(long)]
    quiet: bool,
    /// Memory budget.
    #[command(flatten)]
    budget: Budget,
}

fn is_tree(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ron"))
}

/// Runs `karstic tin`.
pub(super) fn run(args: TinArgs) -> anyhow::Result<()> {
    let outputs = export::written_files(&args.output)?;
    let budget = args.budget.max_memory;
    let started = Instant::now();
    let dem = if is_tree(&args.source) {
        // In the tree's frame, like the meshes of `karstic build`; the ring where the
        // implicit terrain ends has no top: triangulate inside it.
        let made = tree_heightmap(&args.source, &args.grid, budget, &outputs, args.quiet)?;
        let mut dem = made.dem;
        dem.heightfield = dem.heightfield.with_origin(made.origin);
        let dem = trim_nodata_border(dem);
        super::notify(&dem.notices, args.quiet);
        dem
    } else {
        anyhow::ensure!(
            !args.grid.any(),
            "{}: --cell, --region and --tolerance place a tree's heightmap; a DEM is \
             triangulated on its own grid",
            args.source.display()
        );
        let opts = ReadOptions {
            memory_budget: budget,
            ..ReadOptions::default()
        };
        karstic::io::check_outputs(&dem::files_read(&args.source, &opts), &outputs)?;
        dem::read(&args.source, &opts)?
    };
    let read = started.elapsed();
    let t = Instant::now();
    let tin = tin::greedy(&dem.heightfield, args.max_error, budget)
        .with_context(|| format!("{}", args.source.display()))?;
    let triangulate = t.elapsed();
    export::write(&tin.to_mesh(), &args.output, &ExportOptions::default())?;
    if !args.quiet {
        let hf = &dem.heightfield;
        eprintln!(
            "wrote {}: {} vertices, {} triangles from {}×{} samples, max error {:.3} m ≤ {} m; \
             source {:.3} s, triangulation {:.3} s, total {:.3} s",
            args.output.display(),
            tin.positions.len(),
            tin.triangles.len(),
            hf.nx(),
            hf.ny(),
            tin.max_error,
            args.max_error,
            read.as_secs_f64(),
            triangulate.as_secs_f64(),
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

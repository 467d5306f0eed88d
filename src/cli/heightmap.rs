//! `karstic heightmap TREE -o top.tif`: the top surface of a tree as a georeferenced DEM.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use clap::Args;
use karstic::dem::{self, Dem};
use karstic::field::{Field, Rect};
use karstic::heightmap::{HeightmapGrid, TopOptions, heightmap};

use super::Budget;

/// The heightmap options shared by `heightmap` and `tin` (when its source is a tree).
#[derive(Args, Debug, Clone)]
pub(super) struct GridArgs {
    /// Sample spacing in metres (default: the scene's terrain DEM's cells).
    #[arg(long, value_name = "METRES")]
    cell: Option<f64>,
    /// Tree-frame rectangle to cover (default: the terrain DEM's extent, or the tree's
    /// support without one).
    #[arg(value_parser = super::finite, long, num_args = 4, value_names = ["XMIN", "YMIN", "XMAX", "YMAX"], allow_negative_numbers = true)]
    region: Option<Vec<f32>>,
    /// Locate each column's top to within this many metres (default: a thousandth of
    /// the cell).
    #[arg(value_parser = super::finite, long, value_name = "METRES")]
    tolerance: Option<f32>,
}

impl GridArgs {
    /// Whether any of the flags was given.
    pub(super) fn any(&self) -> bool {
        self.cell.is_some() || self.region.is_some() || self.tolerance.is_some()
    }
}

/// Top surface of the final 3D terrain, one elevation per column.
#[derive(Args, Debug)]
pub(super) struct HeightmapArgs {
    /// Tree file (.ron).
    tree: PathBuf,
    /// Output DEM: .tif (float32 GeoTIFF), .png (16-bit + .json sidecar) or .asc.
    #[arg(short, long)]
    output: PathBuf,
    /// Where the samples lie.
    #[command(flatten)]
    grid: GridArgs,
    /// No summary.
    #[arg(long)]
    quiet: bool,
    /// Memory budget.
    #[command(flatten)]
    budget: Budget,
}

/// A tree's heightmap and the time its stages took.
pub(super) struct TreeHeightmap {
    /// The heightmap.
    pub dem: Dem,
    /// Loading and compiling the tree (DEMs, voxel pipelines).
    pub compile: Duration,
    /// Finding the columns' tops.
    pub columns: Duration,
    /// Tree-frame position of the heightmap's sample `(0, 0)`.
    pub origin: glam::Vec2,
}

/// Loads `tree` (refusing `outputs` among its inputs) and computes its heightmap.
pub(super) fn tree_heightmap(
    tree: &Path,
    grid: &GridArgs,
    budget: u64,
    outputs: &[PathBuf],
    quiet: bool,
) -> anyhow::Result<TreeHeightmap> {
    let started = Instant::now();
    let (_, compiled) = super::load_compiled(tree, budget, outputs, quiet)?;
    let compile = started.elapsed();
    let t = &compiled.tree;
    let region = grid
        .region
        .as_deref()
        .map(|r| Rect::new(glam::Vec2::new(r[0], r[1]), glam::Vec2::new(r[2], r[3])));
    let layout = HeightmapGrid::new(
        compiled.ground.as_deref(),
        t.support().footprint(),
        grid.cell,
        region,
    )?;
    let opts = TopOptions {
        tolerance: grid
            .tolerance
            .unwrap_or(1e-3 * layout.cell[0].min(layout.cell[1]) as f32),
        direct: true,
    };
    anyhow::ensure!(
        opts.tolerance > 0.0 && opts.tolerance.is_finite(),
        "--tolerance must be > 0 metres, got {}",
        opts.tolerance
    );
    let started = Instant::now();
    let dem = heightmap(t, &layout, &opts, budget)?;
    Ok(TreeHeightmap {
        dem,
        compile,
        columns: started.elapsed(),
        origin: layout.origin,
    })
}

/// Runs `karstic heightmap`.
pub(super) fn run(args: HeightmapArgs) -> anyhow::Result<()> {
    let outputs = dem::files_written(&args.output)?;
    let started = Instant::now();
    let made = tree_heightmap(
        &args.tree,
        &args.grid,
        args.budget.max_memory,
        &outputs,
        args.quiet,
    )?;
    let dem = made.dem;
    super::notify(&dem.notices, args.quiet);
    dem::write(&dem, &args.output)?;
    if !args.quiet {
        let hf = &dem.heightfield;
        let [dx, dy] = dem.georef.cell_size_m();
        let (lo, hi) = hf.z_range().unwrap_or((f32::NAN, f32::NAN));
        eprintln!(
            "wrote {}: {}×{} samples of {dx} × {dy} m, {}, z {lo:.2} … {hi:.2} m; \
             compile {:.3} s, columns {:.3} s, total {:.3} s",
            args.output.display(),
            hf.nx(),
            hf.ny(),
            dem.georef.crs.describe(),
            made.compile.as_secs_f64(),
            made.columns.as_secs_f64(),
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

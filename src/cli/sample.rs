//! `karstic sample`: a tree's field on a dense grid, as float32 `.npy` + JSON sidecar.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use glam::Vec3;

use super::load_tree;
use crate::field::{Aabb, Field, eval_grid, slab_count};
use crate::io::{DEFAULT_MEMORY_BUDGET, check_budget, progress, write_atomic};
use crate::mesh::npy;
use crate::mesh::sample::{Sidecar, grid_spanning};

/// Sample a tree's field on a grid (float32 .npy, shape (nz, ny, nx), + .json sidecar).
#[derive(Args, Debug)]
pub struct SampleArgs {
    /// Tree file (.ron).
    pub tree: PathBuf,
    /// Box spanned by the samples, corner to corner (default: the tree's support box).
    #[arg(long = "box", num_args = 6, value_names = ["XMIN", "YMIN", "ZMIN", "XMAX", "YMAX", "ZMAX"], allow_negative_numbers = true)]
    pub bbox: Option<Vec<f32>>,
    /// Samples along x, y and z.
    #[arg(long, num_args = 3, value_names = ["NX", "NY", "NZ"], required = true)]
    pub res: Vec<usize>,
    /// Output .npy file; the sidecar goes beside it with a .json extension.
    #[arg(short, long)]
    pub output: PathBuf,
    /// No progress bar and no summary.
    #[arg(long)]
    pub quiet: bool,
    /// Memory budget in bytes for the grid.
    #[arg(long, default_value_t = DEFAULT_MEMORY_BUDGET)]
    pub max_memory: u64,
}

/// Runs `karstic sample`.
pub fn run(args: SampleArgs) -> anyhow::Result<()> {
    let field = load_tree(&args.tree)?;
    let bbox = match &args.bbox {
        Some(v) => Aabb::new(Vec3::new(v[0], v[1], v[2]), Vec3::new(v[3], v[4], v[5])),
        None => field.support(),
    };
    let spec = grid_spanning(&bbox, [args.res[0], args.res[1], args.res[2]])?;
    check_budget(
        format!("a {}×{}×{} grid", spec.dims[0], spec.dims[1], spec.dims[2]),
        spec.bytes(),
        args.max_memory,
    )?;
    let bar = progress(slab_count(&spec), "sampling", args.quiet);
    let values = eval_grid(&field, &spec, Some(&bar));
    bar.finish_and_clear();
    let sidecar = Sidecar::new(&spec);
    write_atomic(&args.output, |w| npy::write_f32(w, &sidecar.shape, &values))?;
    let side = Sidecar::path_for(&args.output);
    let text = serde_json::to_string_pretty(&sidecar).context("encoding the sidecar")?;
    write_atomic(&side, |w| writeln!(w, "{text}"))?;
    if !args.quiet {
        eprintln!("wrote {} and {}", args.output.display(), side.display());
    }
    Ok(())
}

//! `karstic sample`: a tree's field on a dense grid, as float32 `.npy` + JSON sidecar.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use super::{Budget, load_tree};
use karstic::field::{Field, slab_count};
use karstic::io::{progress, write_atomic};
use karstic::mesh::npy;
use karstic::mesh::sample::{Sidecar, grid_spanning, sample_grid};

/// Sample a tree's field on a grid (float32 .npy, shape (nz, ny, nx), + .json sidecar).
#[derive(Args, Debug)]
pub(super) struct SampleArgs {
    /// Tree file (.ron).
    tree: PathBuf,
    /// Box spanned by the samples, corner to corner (default: the tree's support box).
    #[arg(value_parser = super::finite, long = "box", num_args = 6, value_names = ["XMIN", "YMIN", "ZMIN", "XMAX", "YMAX", "ZMAX"], allow_negative_numbers = true)]
    bbox: Option<Vec<f32>>,
    /// Samples along x, y and z.
    #[arg(long, num_args = 3, value_names = ["NX", "NY", "NZ"], required = true)]
    res: Vec<usize>,
    /// Output .npy file; the sidecar goes beside it with a .json extension.
    #[arg(short, long)]
    output: PathBuf,
    /// No progress bar and no summary.
    #[arg(long)]
    quiet: bool,
    /// Memory budget.
    #[command(flatten)]
    budget: Budget,
}

/// Runs `karstic sample`.
pub(super) fn run(args: SampleArgs) -> anyhow::Result<()> {
    let side = Sidecar::path_for(&args.output);
    let outputs = [&args.output, &side];
    let field = load_tree(&args.tree, args.budget.max_memory, &outputs, args.quiet)?;
    let bbox = args
        .bbox
        .as_deref()
        .map_or_else(|| Ok(field.support()), super::corners)?;
    let spec = grid_spanning(&bbox, [args.res[0], args.res[1], args.res[2]])?;
    let bar = progress(slab_count(&spec), "sampling", args.quiet);
    let values = sample_grid(&field, &spec, args.budget.max_memory, Some(&bar))?;
    bar.finish_and_clear();
    let sidecar = Sidecar::new(&spec, &values);
    write_atomic(&args.output, |w| npy::write_f32(w, &sidecar.shape, &values))?;
    let text = serde_json::to_string_pretty(&sidecar).context("encoding the sidecar")?;
    write_atomic(&side, |w| writeln!(w, "{text}"))?;
    if !args.quiet {
        eprintln!("wrote {} and {}", args.output.display(), side.display());
    }
    Ok(())
}

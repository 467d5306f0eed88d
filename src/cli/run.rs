//! `karstic run TREE`: the main job — a mesh of the tree's region and a preview image.

use std::path::PathBuf;

use clap::Args;

use super::Budget;
use karstic::job::{self, JobOptions};
use karstic::mesh::export::Origin;

/// Arguments of `karstic run`.
#[derive(Args, Debug)]
pub(super) struct RunArgs {
    /// Tree file; its `job` section says what region, cell size and camera to use.
    tree: PathBuf,
    /// Output folder (`--out` is an older name of the flag).
    #[arg(
        short = 'o',
        long = "output",
        visible_alias = "out",
        default_value = "out"
    )]
    out: PathBuf,
    /// Mesh the whole scene at the job's coarse cell size (`full_cell`).
    #[arg(long)]
    full: bool,
    /// Skip the preview image and the feature views.
    #[arg(long)]
    no_render: bool,
    /// Skip the feature views (a close-up of each named feature and a contact sheet).
    #[arg(long)]
    no_views: bool,
    /// Also write the texture masks (slope, rock, cave, flow PNGs over the region, at the
    /// mesh's cell size; about as long as meshing on the main job).
    #[arg(long)]
    masks: bool,
    /// Where the mesh's origin lies: `dem` (the tree's frame), `center` or `min` of its
    /// box; the offset is kept as the glTF node's translation and in its extras.
    #[arg(long, value_name = "center|min|dem", default_value = "dem")]
    origin: Origin,
    /// Also print the mesher's statistics.
    #[arg(long)]
    stats: bool,
    /// No progress bars.
    #[arg(long)]
    quiet: bool,
    /// Memory budget.
    #[command(flatten)]
    budget: Budget,
}

/// Runs `karstic run`.
pub(super) fn run(args: RunArgs) -> anyhow::Result<()> {
    let opts = JobOptions {
        out_dir: args.out.clone(),
        full: args.full,
        no_render: args.no_render,
        no_views: args.no_views,
        quiet: args.quiet,
        budget: args.budget.max_memory,
        origin: args.origin,
        masks: args.masks,
    };
    let report = job::run(&args.tree, &opts)?;
    super::notify(&report.notices, args.quiet);
    let r = &report.region;
    println!(
        "region [{:.0}, {:.0}, {:.0}]..[{:.0}, {:.0}, {:.0}] at {} m cells: {} vertices, {} triangles",
        r.min.x,
        r.min.y,
        r.min.z,
        r.max.x,
        r.max.y,
        r.max.z,
        report.cell,
        report.mesh_stats.vertices,
        report.mesh_stats.triangles
    );
    println!("wrote {}", report.mesh_path.display());
    if let Some(p) = &report.image_path {
        println!("wrote {}", p.display());
    }
    for p in report
        .views
        .iter()
        .map(|(_, p)| p)
        .chain(&report.mask_paths)
    {
        println!("wrote {}", p.display());
    }
    let mut total = 0.0;
    for (stage, d) in &report.stages {
        total += d.as_secs_f64();
        println!("  {stage:<16} {:>8.2} s", d.as_secs_f64());
    }
    println!("  {:<16} {:>8.2} s", "total", total);
    if args.stats {
        println!("{}", report.mesh_stats);
    }
    Ok(())
}

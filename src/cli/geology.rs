//! `karstic geology section TREE --plane X0 Y0 X1 Y1 -o OUT.png`: a vertical cut of the
//! scene's rock resistance (pale = resistant), as in Paris et al. 2019 Fig. 4.

use std::path::PathBuf;

use clap::{Args, Subcommand};
use glam::Vec2;

use super::Budget;
use karstic::field::{Aabb, Field};
use karstic::geology::section::Section;

/// Inspect a scene's geology.
#[derive(Args, Debug)]
pub(super) struct GeologyArgs {
    #[command(subcommand)]
    command: GeologyCommand,
}

#[derive(Subcommand, Debug)]
enum GeologyCommand {
    /// Draw a vertical cut of the rock resistance ρ as a PNG: pale where the rock resists
    /// erosion, dark where it is soft.
    Section(SectionArgs),
}

#[derive(Args, Debug)]
struct SectionArgs {
    /// Tree file (.ron) with a `geology:` (a scene without one is uniform).
    tree: PathBuf,
    /// The cut's two ends on the map, metres: from (X0, Y0) to (X1, Y1).
    #[arg(value_parser = super::finite, long, num_args = 4, value_names = ["X0", "Y0", "X1", "Y1"], allow_negative_numbers = true, required = true)]
    plane: Vec<f32>,
    /// Altitude range (default: the job's region, else the tree's support).
    #[arg(value_parser = super::finite, long, num_args = 2, value_names = ["ZMIN", "ZMAX"], allow_negative_numbers = true)]
    z: Option<Vec<f32>>,
    /// Image width in pixels; the height keeps metres square unless `--height` is given.
    #[arg(long, default_value_t = 800)]
    width: u32,
    /// Image height in pixels.
    #[arg(long)]
    height: Option<u32>,
    /// Draw the terrain: its surface outline (red) and the air above it.
    #[arg(long)]
    outline: bool,
    /// Output PNG (written atomically).
    #[arg(short, long)]
    output: PathBuf,
    /// Memory budget.
    #[command(flatten)]
    budget: Budget,
}

/// Runs `karstic geology`.
pub(super) fn run(args: GeologyArgs) -> anyhow::Result<()> {
    match args.command {
        GeologyCommand::Section(a) => section(a),
    }
}

fn section(args: SectionArgs) -> anyhow::Result<()> {
    let (file, compiled) = super::load_compiled(
        &args.tree,
        args.budget.max_memory,
        std::slice::from_ref(&args.output),
        false,
    )?;
    let from = Vec2::new(args.plane[0], args.plane[1]);
    let to = Vec2::new(args.plane[2], args.plane[3]);
    let z = match &args.z {
        Some(z) => (z[0], z[1]),
        None => {
            let region = file
                .scene
                .job
                .as_ref()
                .and_then(|j| j.region)
                .map(|r| Aabb::new(r.min.0, r.max.0))
                .unwrap_or_else(|| compiled.tree.support());
            anyhow::ensure!(
                !region.is_empty() && region.size().z.is_finite(),
                "{}: the tree's altitudes are unbounded: give --z ZMIN ZMAX",
                args.tree.display()
            );
            (region.min.z, region.max.z)
        }
    };
    let height = args.height.unwrap_or_else(|| {
        let ratio = (z.1 - z.0) / from.distance(to).max(f32::MIN_POSITIVE);
        (args.width as f32 * ratio).round().clamp(1.0, 4096.0) as u32
    });
    let cut = Section::new(from, to, z, (args.width, height), args.budget.max_memory)?;
    let terrain = args.outline.then_some(&compiled.tree as &dyn Field);
    cut.write_png(&args.output, &compiled.geology, terrain)?;
    eprintln!(
        "wrote {} ({} × {} pixels, z {} .. {} m)",
        args.output.display(),
        args.width,
        height,
        z.0,
        z.1
    );
    Ok(())
}

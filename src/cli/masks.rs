//! `karstic masks TREE -o DIR`: texture masks (slope, rock, cave/overhang, flow) as PNGs
//! over the DEM frame, the rectangle the exported meshes' UVs span.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use super::Budget;
use karstic::analysis::{Masks, Raster, texture_frame};
use karstic::field::Field;

/// Write texture masks of a tree as 8-bit grey PNGs (first row north) and a JSON sidecar.
#[derive(Args, Debug)]
pub(super) struct MasksArgs {
    /// Tree file (.ron).
    tree: PathBuf,
    /// Output folder (created if needed): STEM_slope.png, STEM_rock.png, STEM_cave.png,
    /// STEM_flow.png, STEM_talus.png, STEM_deposit.png, STEM_wear.png and STEM_masks.json.
    #[arg(short, long)]
    output: PathBuf,
    /// Pixel size in metres (default: the DEM's cell, or 1/512 of the support's width).
    #[arg(value_parser = super::finite, long)]
    cell: Option<f32>,
    /// Box whose footprint the masks cover (default: the DEM's extent, or the tree's
    /// support). `karstic build --box` with the same box gives UVs over the same frame.
    #[arg(value_parser = super::finite, long = "box", num_args = 6, value_names = ["XMIN", "YMIN", "ZMIN", "XMAX", "YMAX", "ZMAX"], allow_negative_numbers = true)]
    bbox: Option<Vec<f32>>,
    /// File-name stem (default: the tree file's).
    #[arg(long)]
    stem: Option<String>,
    /// No summary.
    #[arg(long)]
    quiet: bool,
    /// Memory budget.
    #[command(flatten)]
    budget: Budget,
}

/// Runs `karstic masks`.
pub(super) fn run(args: MasksArgs) -> anyhow::Result<()> {
    let stem = args.stem.clone().unwrap_or_else(|| {
        args.tree
            .file_stem()
            .map_or("scene".into(), |s| s.to_string_lossy().into_owned())
    });
    karstic::io::check_file_name(&stem).map_err(|e| anyhow::anyhow!("--stem: {e}"))?;
    let outputs = Masks::files(&args.output, &stem);
    let (file, compiled) =
        super::load_compiled(&args.tree, args.budget.max_memory, &outputs, args.quiet)?;
    let tree = &compiled.tree;
    let support = tree.support();
    anyhow::ensure!(
        !support.is_empty(),
        "{}: the tree is empty everywhere",
        args.tree.display()
    );
    let ground = compiled.ground.as_deref();
    let bbox = args.bbox.as_deref().map(super::corners).transpose()?;
    let frame = texture_frame(bbox.as_ref(), ground, &support);
    let cell = args.cell.unwrap_or_else(|| match ground {
        Some(g) => g.heightfield().cell().min_element(),
        None => (frame.max - frame.min).max_element() / 512.0,
    });
    let raster = Raster::new(frame, cell, args.budget.max_memory)?;
    let started = Instant::now();
    let materials = karstic::picture::materials(&file.scene, tree, compiled.ground.clone());
    let masks = Masks::compute(tree, &materials, &raster);
    std::fs::create_dir_all(&args.output).map_err(|e| {
        anyhow::anyhow!(
            "cannot create the output folder {}: {e}",
            args.output.display()
        )
    })?;
    let files = masks.write(&args.output, &stem)?;
    if !args.quiet {
        eprintln!(
            "wrote {} masks of {} × {} pixels ({:.2} m) in {:.2} s:",
            files.len() - 1,
            raster.nx,
            raster.ny,
            raster.pixel().x,
            started.elapsed().as_secs_f64()
        );
        for f in &files {
            eprintln!("  {}", f.display());
        }
    }
    Ok(())
}

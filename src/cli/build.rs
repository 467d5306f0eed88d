//! `karstic build`: tree (or sampled `.npy` grid) → mesh file.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::Budget;
use anyhow::{Context, bail};
use clap::Args;
use karstic::analysis::texture_frame;
use karstic::field::{Aabb, Field};
use karstic::io::{check_outputs, progress, read_regular};
use std::sync::Arc;

use karstic::mesh::export::{self, Albedo, ExportOptions, Format, Origin};
use karstic::mesh::polygonize::progress_steps;
use karstic::mesh::sample::Sidecar;
use karstic::mesh::{DenseGrid, GridSpec, Mesh, MeshOptions, MeshStats, mc_dense, npy, polygonize};
use karstic::render::Materials;

/// Build a mesh from a tree with bound-pruned Marching Cubes.
#[derive(Args, Debug)]
pub(super) struct BuildArgs {
    /// Tree file (.ron), or a float32 .npy grid from `karstic sample` (with its .json sidecar).
    tree: PathBuf,
    /// Output mesh: .glb, .gltf (+ .bin), .obj or .ply.
    #[arg(short, long)]
    output: PathBuf,
    /// Box to mesh (default: the tree's support box).
    #[arg(value_parser = super::finite, long = "box", num_args = 6, value_names = ["XMIN", "YMIN", "ZMIN", "XMAX", "YMAX", "ZMAX"], allow_negative_numbers = true)]
    bbox: Option<Vec<f32>>,
    /// Cell size in metres.
    #[arg(value_parser = super::finite, long, conflicts_with = "res")]
    cell: Option<f32>,
    /// Cells along the box's longest axis (default 256).
    #[arg(long)]
    res: Option<usize>,
    /// Move vertices onto the true surface (regula falsi on the field).
    #[arg(long)]
    refine: bool,
    /// Visit every cell (plain Marching Cubes, for comparison).
    #[arg(long)]
    no_prune: bool,
    /// Colour the vertices with the preview's materials: rock, soil, grass (glTF COLOR_0,
    /// OBJ and PLY vertex colours).
    #[arg(long)]
    tint: bool,
    /// Where the written positions' origin lies: `dem` (the tree's frame, the DEM's
    /// south-west sample at 0), `center` or `min` of the mesh's box; the offset is kept as
    /// the glTF node's translation (and in its extras), in OBJ and PLY header comments.
    #[arg(long, value_name = "center|min|dem", default_value = "dem")]
    origin: Origin,
    /// Print extraction statistics (the columns of Table 1 of Paris et al. 2019).
    #[arg(long)]
    stats: bool,
    /// No progress bar and no summary.
    #[arg(long)]
    quiet: bool,
    /// Memory budget.
    #[command(flatten)]
    budget: Budget,
}

/// Runs `karstic build`.
pub(super) fn run(args: BuildArgs) -> anyhow::Result<()> {
    let format = Format::from_path(&args.output)?;
    let outputs = export::written_files(&args.output)?;
    let started = Instant::now();
    let (mesh, stats, export_opts) = if is_npy(&args.tree) {
        check_outputs(
            &[args.tree.clone(), Sidecar::path_for(&args.tree)],
            &outputs,
        )?;
        let (mesh, stats) = build_from_grid(&args)?;
        let albedo = args
            .tint
            .then(|| Arc::new(Materials::for_scene(&mesh.bounds(), None)) as Arc<dyn Albedo>);
        let opts = ExportOptions {
            albedo,
            origin: args.origin,
            uv_frame: None,
        };
        (mesh, stats, opts)
    } else {
        let (file, compiled) =
            super::load_compiled(&args.tree, args.budget.max_memory, &outputs, args.quiet)?;
        let (mesh, stats) = build_from_field(&compiled.tree, &args)?;
        let support = compiled.tree.support();
        let bbox = args.bbox.as_deref().map(super::corners).transpose()?;
        let opts = ExportOptions {
            albedo: args.tint.then(|| {
                Arc::new(karstic::picture::materials(
                    &file.scene,
                    &compiled.tree,
                    compiled.ground.clone(),
                )) as Arc<dyn Albedo>
            }),
            origin: args.origin,
            uv_frame: Some(texture_frame(
                bbox.as_ref(),
                compiled.ground.as_deref(),
                &support,
            )),
        };
        (mesh, stats, opts)
    };
    let write = Instant::now();
    export::write(&mesh, &args.output, &export_opts)?;
    if args.stats {
        println!("{stats}");
        println!(
            "time write        {:>12.1} ms",
            write.elapsed().as_secs_f64() * 1e3
        );
    }
    if !args.quiet {
        eprintln!(
            "wrote {} ({format:?}): {} vertices, {} triangles in {:.2} s",
            args.output.display(),
            mesh.positions.len(),
            mesh.triangles.len(),
            started.elapsed().as_secs_f64()
        );
        if mesh.triangles.is_empty() {
            eprintln!("warning: the surface does not cross the box; the mesh is empty");
        }
    }
    Ok(())
}

fn is_npy(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npy"))
}

/// The grid over `--box` (or the field's support) at `--cell` or `--res`.
fn grid_for(support: Aabb, args: &BuildArgs) -> anyhow::Result<GridSpec> {
    let bbox = args.bbox.as_deref().map_or(Ok(support), super::corners)?;
    let grid = match (args.cell, args.res) {
        (Some(c), _) => GridSpec::with_cell(&bbox, c)?,
        (None, r) => GridSpec::with_resolution(&bbox, r.unwrap_or(256))?,
    };
    Ok(grid)
}

fn build_from_field(field: &dyn Field, args: &BuildArgs) -> anyhow::Result<(Mesh, MeshStats)> {
    let grid = grid_for(field.support(), args)
        .with_context(|| format!("{}: choosing the grid", args.tree.display()))?;
    let bar = progress(progress_steps(&grid), "meshing", args.quiet);
    let opts = MeshOptions {
        prune: !args.no_prune,
        refine: args.refine,
        budget: args.budget.max_memory,
        progress: Some(bar.clone()),
        ..MeshOptions::default()
    };
    let out = polygonize(field, &grid, &opts)?;
    bar.finish_and_clear();
    Ok(out)
}

fn build_from_grid(args: &BuildArgs) -> anyhow::Result<(Mesh, MeshStats)> {
    if args.bbox.is_some()
        || args.cell.is_some()
        || args.res.is_some()
        || args.refine
        || args.no_prune
    {
        bail!(
            "{}: --box, --cell, --res, --refine and --no-prune apply to trees, not to sampled grids",
            args.tree.display()
        );
    }
    let side = Sidecar::path_for(&args.tree);
    let sidecar: Sidecar = serde_json::from_slice(&read_regular(&side, args.budget.max_memory)?)
        .with_context(|| format!("{}: not a karstic sample sidecar", side.display()))?;
    let (shape, values) = npy::read_f32(&args.tree, args.budget.max_memory)?;
    if shape != sidecar.shape {
        bail!(
            "{}: shape {shape:?} but its sidecar says {:?}",
            args.tree.display(),
            sidecar.shape
        );
    }
    if sidecar
        .values
        .as_ref()
        .is_some_and(|h| *h != Sidecar::hash(&values))
    {
        bail!(
            "{}: its sidecar {} was written for other values (a sample cut short between \
             its two files?): sample again",
            args.tree.display(),
            side.display()
        );
    }
    let spec = sidecar.spec();
    let grid = DenseGrid::new(&values, spec.dims, spec.origin, spec.step)
        .with_context(|| format!("{}", args.tree.display()))?;
    Ok(mc_dense(&grid, sidecar.iso))
}

//! `karstic build`: tree (or sampled `.npy` grid) → mesh file.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use clap::Args;
use glam::Vec3;

use crate::field::{Aabb, Field};
use crate::io::{DEFAULT_MEMORY_BUDGET, check_budget, progress};
use crate::mesh::export::{self, ExportOptions, Format};
use crate::mesh::polygonize::progress_steps;
use crate::mesh::sample::Sidecar;
use crate::mesh::{DenseGrid, GridSpec, Mesh, MeshOptions, MeshStats, mc_dense, npy, polygonize};

/// Build a mesh from a tree with bound-pruned Marching Cubes.
#[derive(Args, Debug)]
pub struct BuildArgs {
    /// Tree file (.ron), or a float32 .npy grid from `karstic sample` (with its .json sidecar).
    pub tree: PathBuf,
    /// Output mesh: .glb, .gltf (+ .bin), .obj or .ply.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Box to mesh (default: the tree's support box).
    #[arg(long = "box", num_args = 6, value_names = ["XMIN", "YMIN", "ZMIN", "XMAX", "YMAX", "ZMAX"], allow_negative_numbers = true)]
    pub bbox: Option<Vec<f32>>,
    /// Cell size in metres.
    #[arg(long, conflicts_with = "res")]
    pub cell: Option<f32>,
    /// Cells along the box's longest axis (default 256).
    #[arg(long)]
    pub res: Option<usize>,
    /// Move vertices onto the true surface (regula falsi on the field).
    #[arg(long)]
    pub refine: bool,
    /// Visit every cell (plain Marching Cubes, for comparison).
    #[arg(long)]
    pub no_prune: bool,
    /// Tint vertices by slope and altitude (glTF COLOR_0, PLY colours).
    #[arg(long)]
    pub tint: bool,
    /// Print extraction statistics (seed 002 Table 1 columns).
    #[arg(long)]
    pub stats: bool,
    /// No progress bar and no summary.
    #[arg(long)]
    pub quiet: bool,
    /// Memory budget in bytes for the sampling grid.
    #[arg(long, default_value_t = DEFAULT_MEMORY_BUDGET)]
    pub max_memory: u64,
}

/// Runs `karstic build`.
pub fn run(args: BuildArgs) -> anyhow::Result<()> {
    let format = Format::from_path(&args.output)?;
    let started = Instant::now();
    let (mesh, stats) = if is_npy(&args.tree) {
        build_from_grid(&args)?
    } else {
        let tree = super::load_tree(&args.tree)?;
        build_from_field(&tree, &args)?
    };
    let write = Instant::now();
    export::write(&mesh, &args.output, &ExportOptions { color: args.tint })?;
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
    let bbox = match &args.bbox {
        Some(v) => Aabb::new(Vec3::new(v[0], v[1], v[2]), Vec3::new(v[3], v[4], v[5])),
        None => support,
    };
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
        budget: args.max_memory,
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
    let sidecar: Sidecar = serde_json::from_slice(
        &std::fs::read(&side)
            .with_context(|| format!("{}: reading the grid's sidecar", side.display()))?,
    )
    .with_context(|| format!("{}: not a karstic sample sidecar", side.display()))?;
    let bytes = std::fs::metadata(&args.tree)
        .with_context(|| format!("cannot read {}", args.tree.display()))?
        .len();
    check_budget(
        format!("the grid {}", args.tree.display()),
        bytes,
        args.max_memory,
    )?;
    let (shape, values) = npy::read_f32(&args.tree)?;
    if shape != sidecar.shape {
        bail!(
            "{}: shape {shape:?} but its sidecar says {:?}",
            args.tree.display(),
            sidecar.shape
        );
    }
    let spec = sidecar.spec();
    let grid = DenseGrid::new(&values, spec.dims, spec.origin, spec.step)
        .with_context(|| format!("{}", args.tree.display()))?;
    Ok(mc_dense(&grid, sidecar.iso))
}

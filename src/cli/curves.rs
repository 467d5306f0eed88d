//! `karstic curves ...`: run the Feature Curve pipeline on a tree file's `FeatureVolume`
//! (or a bare `FeatureVolume(..)` file) and write its mesh or its sampled field.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::{Args, Subcommand};
use glam::{IVec3, Vec3};

use super::Budget;
use karstic::field::Grid;
use karstic::io::{check_outputs, human_bytes, write_atomic};
use karstic::mesh::MeshOptions;
use karstic::mesh::export::{self, ExportOptions, Format};
use karstic::mesh::npy;
use karstic::mesh::sample::sample_grid;
use karstic::scene::VolumeFile;
use karstic::voxel::SField;
use karstic::voxel::pipeline::Stats;

/// Feature Curves: build the S field of a tree file's `FeatureVolume`.
#[derive(Args, Debug)]
pub(super) struct CurvesArgs {
    /// What to do.
    #[command(subcommand)]
    command: CurvesCommand,
}

/// `curves` subcommands.
#[derive(Subcommand, Debug)]
pub(super) enum CurvesCommand {
    /// Run the voxel pipeline and write the S-field leaf's mesh or sampled field.
    Build(BuildArgs),
}

/// `karstic curves build FILE -o mesh.glb -o field.npy --stats`.
#[derive(Args, Debug)]
pub(super) struct BuildArgs {
    /// A tree file `(version: 1, root: ..)` holding a `FeatureVolume` node, or a RON file
    /// holding one bare `FeatureVolume(..)`.
    file: PathBuf,
    /// Outputs (repeatable): a mesh `.glb`, `.gltf`, `.obj` or `.ply` (Marching Cubes of
    /// the leaf over its domain at the voxel size, in the leaf's own frame), or `.npy` (the
    /// field f on the finest grid, float32, shape `(nz, ny, nx)`, index `[k, j, i]` at
    /// `domain.min + (i, j, k)·voxel`).
    #[arg(short, long)]
    output: Vec<PathBuf>,
    /// The `FeatureVolume` node to build, by name, when the tree has several.
    #[arg(long)]
    node: Option<String>,
    /// Mesh cell size in metres (default: the volume's voxel).
    #[arg(value_parser = super::finite, long)]
    cell: Option<f32>,
    /// Also write the proxy ribbon meshes (finest level) as OBJ.
    #[arg(long)]
    ribbons: Option<PathBuf>,
    /// Print per-stage times, iteration counts and memory (and the mesher's statistics).
    #[arg(long)]
    stats: bool,
    /// Seed of the displacement noise (default: the tree's `seed`, 0 for a bare file).
    #[arg(long)]
    seed: Option<u32>,
    /// Memory budget.
    #[command(flatten)]
    budget: Budget,
}

/// Runs `karstic curves ...`.
pub(super) fn run(args: CurvesArgs) -> anyhow::Result<()> {
    match args.command {
        CurvesCommand::Build(b) => build(b),
    }
}

fn build(args: BuildArgs) -> anyhow::Result<()> {
    for out in &args.output {
        if !is_npy(out) {
            Format::from_path(out).map_err(|_| {
                anyhow::anyhow!(
                    "{}: unknown output type (expected .glb, .gltf, .obj, .ply or .npy)",
                    out.display()
                )
            })?;
        }
    }
    let mut outputs: Vec<PathBuf> = args.ribbons.iter().cloned().collect();
    for out in &args.output {
        if is_npy(out) {
            outputs.push(out.clone());
        } else {
            outputs.extend(export::written_files(out)?);
        }
    }
    let budget = args.budget.max_memory;
    let clock = Instant::now();
    let file = VolumeFile::load(&args.file)?;
    check_outputs(&file.inputs(), &outputs)?;
    let spec = file.pick(args.node.as_deref())?;
    let field = file.build(spec, args.seed, budget)?;
    let base = file.base_dir();
    let elapsed = clock.elapsed();
    if let Some(path) = &args.ribbons {
        let features = spec.feature_set(base)?.resolve(&|_| None)?;
        let w = spec.ribbon_width();
        let mesh = features.proxy(w, w, 0.5 * spec.voxel.0, 0.0);
        write_atomic(path, |w| mesh.write_obj(w))?;
    }
    if args.stats {
        print_stats(field.stats(), elapsed.as_secs_f64() * 1e3);
        if let Some(e) = field.expanded() {
            println!(
                "expansion (§4.5): {} curves, {} control vertices, traced in {:.1} ms (the stats above are of the second run)",
                e.curves.len(),
                e.curves
                    .iter()
                    .map(|c| c.spline.control().len())
                    .sum::<usize>(),
                e.trace_time.as_secs_f64() * 1e3
            );
        }
    }
    for out in &args.output {
        if is_npy(out) {
            write_npy(&field, out, budget)?;
        } else {
            write_mesh(&field, out, &args, budget)?;
        }
    }
    Ok(())
}

fn is_npy(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npy"))
}

/// Polygonizes the leaf over its domain and writes the mesh.
fn write_mesh(field: &SField, out: &Path, args: &BuildArgs, budget: u64) -> anyhow::Result<()> {
    let opts = MeshOptions {
        budget,
        ..MeshOptions::default()
    };
    let (mesh, st) = field
        .extract(args.cell, &opts)
        .with_context(|| format!("meshing {}", args.file.display()))?;
    export::write(&mesh, out, &ExportOptions::default())?;
    if args.stats {
        println!("{st}");
    }
    eprintln!(
        "wrote {}: {} vertices, {} triangles",
        out.display(),
        mesh.positions.len(),
        mesh.triangles.len()
    );
    if mesh.triangles.is_empty() {
        eprintln!("warning: the field has no surface (no seed curve?); the mesh is empty");
    }
    Ok(())
}

/// Prints the thesis's Table 7.2 rows and the per-level iteration counts.
fn print_stats(st: &Stats, total_ms: f64) {
    let t = &st.times;
    let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
    println!("stage                 ms");
    for (name, d) in [
        ("proxy meshes", t.proxy),
        ("reset", t.reset),
        ("voxelization", t.voxelize),
        ("guidance diffusion", t.guidance),
        ("noise diffusion", t.noise),
        ("surface propagation", t.propagate),
        ("smoothing", t.smooth),
        ("field bounds", t.finish),
    ] {
        println!("{name:<20} {:>8.1}", ms(d));
    }
    println!(
        "{:<20} {:>8.1}  (build incl. cache lookup: {total_ms:.1})",
        "total",
        ms(t.total())
    );
    println!(
        "level  voxel  dims            dense  bricks  active  seeds  N-sweeps  R-sweeps  waves  relax"
    );
    for l in &st.levels {
        println!(
            "{:>5}  {:>5}  {:<14}  {:>5}  {:>6}  {:>6}  {:>5}  {:>8}  {:>8}  {:>5}  {:>5}",
            l.level,
            l.h,
            format!("{}x{}x{}", l.dims.x, l.dims.y, l.dims.z),
            if l.dense { "yes" } else { "band" },
            l.bricks,
            l.active_bricks,
            l.seeds,
            l.normal_sweeps,
            l.noise_sweeps,
            l.waves,
            l.relax_sweeps
        );
    }
    println!(
        "triangles {}  peak grid memory {}  field memory {}{}",
        st.triangles,
        human_bytes(st.peak_bytes),
        human_bytes(st.field_bytes),
        if st.empty {
            "  (no seed: empty field)"
        } else {
            ""
        }
    );
}

/// Writes the field sampled on the finest grid as a NumPy `.npy` array.
fn write_npy(field: &SField, out: &Path, budget: u64) -> anyhow::Result<()> {
    let (d, h) = (field.params().domain, field.params().voxel);
    let n = ((d.size() / h).floor().as_ivec3() + IVec3::ONE).max(IVec3::ONE);
    let grid = Grid {
        origin: d.min,
        step: Vec3::splat(h),
        dims: [n.x as usize, n.y as usize, n.z as usize],
    };
    let data = sample_grid(field, &grid, budget, None)?;
    let shape = [n.z as usize, n.y as usize, n.x as usize];
    write_atomic(out, |w| npy::write_f32(w, &shape, &data))
        .with_context(|| format!("writing {}", out.display()))?;
    Ok(())
}

//! `karstic curves ...`: run the Feature Curve pipeline on a tree file's `FeatureVolume`
//! (or a bare `FeatureVolume(..)` file) and write its mesh or its sampled field.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use glam::{IVec3, Vec3};
use rayon::prelude::*;

use crate::curves::FeatureVolumeSpec;
use crate::curves::spec::{BuildOptions, parse_ron};
use crate::field::Field;
use crate::io::{DEFAULT_MEMORY_BUDGET, check_budget, human_bytes, write_atomic};
use crate::mesh::MeshOptions;
use crate::mesh::export::{self, ExportOptions, Format};
use crate::mesh::npy;
use crate::scene::{SceneFile, parse_scene};
use crate::voxel::SField;
use crate::voxel::pipeline::Stats;

/// Feature Curves: build the S field of a tree file's `FeatureVolume`.
#[derive(Args, Debug)]
pub struct CurvesArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: CurvesCommand,
}

/// `curves` subcommands.
#[derive(Subcommand, Debug)]
pub enum CurvesCommand {
    /// Run the voxel pipeline and write the S-field leaf's mesh or sampled field.
    Build(BuildArgs),
}

/// `karstic curves build FILE -o mesh.glb -o field.npy --stats`.
#[derive(Args, Debug)]
pub struct BuildArgs {
    /// A tree file `(version: 1, root: ..)` holding a `FeatureVolume` node, or a RON file
    /// holding one bare `FeatureVolume(..)`.
    pub file: PathBuf,
    /// Outputs (repeatable): a mesh `.glb`, `.gltf`, `.obj` or `.ply` (Marching Cubes of
    /// the leaf over its domain at the voxel size, in the leaf's own frame), or `.npy` (the
    /// field f on the finest grid, float32, shape `(nz, ny, nx)`, index `[k, j, i]` at
    /// `domain.min + (i, j, k)·voxel`).
    #[arg(short, long)]
    pub output: Vec<PathBuf>,
    /// The `FeatureVolume` node to build, by name, when the tree has several.
    #[arg(long)]
    pub node: Option<String>,
    /// Mesh cell size in metres (default: the volume's voxel).
    #[arg(long)]
    pub cell: Option<f32>,
    /// Also write the proxy ribbon meshes (finest level) as OBJ.
    #[arg(long)]
    pub ribbons: Option<PathBuf>,
    /// Print per-stage times, iteration counts and memory (and the mesher's statistics).
    #[arg(long)]
    pub stats: bool,
    /// Seed of the displacement noise (default: the tree's `seed`, 0 for a bare file).
    #[arg(long)]
    pub seed: Option<u32>,
    /// Memory budget for the grids, in MiB.
    #[arg(long, default_value_t = DEFAULT_MEMORY_BUDGET >> 20)]
    pub max_memory: u64,
}

/// Runs `karstic curves ...`.
pub fn run(args: CurvesArgs) -> anyhow::Result<()> {
    match args.command {
        CurvesCommand::Build(b) => build(b),
    }
}

/// True when the first token of the RON text (after comments) is `FeatureVolume`.
fn is_bare_volume(text: &str) -> bool {
    let mut rest = text.trim_start();
    loop {
        if let Some(r) = rest.strip_prefix("//") {
            rest = r.split_once('\n').map_or("", |(_, r)| r).trim_start();
        } else if let Some(r) = rest.strip_prefix("/*") {
            rest = r.split_once("*/").map_or("", |(_, r)| r).trim_start();
        } else {
            return rest.starts_with("FeatureVolume");
        }
    }
}

/// The volume `--node` names, or the file's only one.
fn pick<'a>(file: &'a SceneFile, node: Option<&str>) -> anyhow::Result<&'a FeatureVolumeSpec> {
    let all = file.feature_volumes();
    let names = || {
        all.iter()
            .map(|f| f.name.as_deref().unwrap_or("<unnamed>"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    match (node, all.as_slice()) {
        (_, []) => bail!(
            "{}: the tree has no FeatureVolume node",
            file.path.display()
        ),
        (None, [one]) => Ok(one),
        (None, _) => bail!(
            "{}: the tree has several FeatureVolume nodes ({}): pick one with --node NAME",
            file.path.display(),
            names()
        ),
        (Some(n), _) => all
            .iter()
            .copied()
            .find(|f| f.name.as_deref() == Some(n))
            .with_context(|| {
                format!(
                    "{}: no FeatureVolume named {n:?} (there are: {})",
                    file.path.display(),
                    names()
                )
            }),
    }
}

fn build(args: BuildArgs) -> anyhow::Result<()> {
    for out in &args.output {
        let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("");
        if !ext.eq_ignore_ascii_case("npy") {
            Format::from_path(out).map_err(|_| {
                anyhow::anyhow!(
                    "{}: unknown output type (expected .glb, .gltf, .obj, .ply or .npy)",
                    out.display()
                )
            })?;
        }
    }
    let text = std::fs::read_to_string(&args.file)
        .with_context(|| format!("cannot read {}", args.file.display()))?;
    let base = args.file.parent().unwrap_or(Path::new("."));
    let budget = args.max_memory << 20;
    let clock = Instant::now();
    let (spec, field) = if is_bare_volume(&text) {
        if args.node.is_some() {
            bail!("{}: --node applies to tree files", args.file.display());
        }
        let spec: FeatureVolumeSpec = parse_ron(&text, &args.file)?;
        let opts = BuildOptions {
            seed: args.seed.unwrap_or(0),
            ground: None,
            max_memory: budget,
        };
        let field = spec.build_with(base, &opts)?;
        (spec, field)
    } else {
        let file = SceneFile {
            scene: parse_scene(&text, &args.file)?,
            path: args.file.clone(),
            base_dir: base.to_path_buf(),
        };
        let spec = pick(&file, args.node.as_deref())?.clone();
        let seed = args.seed.unwrap_or(file.scene.seed);
        let field = file.build_feature_volume(&spec, seed, budget)?;
        (spec, field)
    };
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
        if out
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("npy"))
        {
            write_npy(&field, out, budget)?;
        } else {
            write_mesh(&field, out, &args, budget)?;
        }
    }
    Ok(())
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
pub fn print_stats(st: &Stats, total_ms: f64) {
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
    let count = n.as_u64vec3().element_product();
    check_budget(
        format!("a {}x{}x{} field", n.x, n.y, n.z),
        count * 4,
        budget,
    )?;
    let mut data = vec![0f32; count as usize];
    let slab = (n.x * n.y) as usize;
    data.par_chunks_mut(slab).enumerate().for_each(|(k, out)| {
        field.eval_block(
            d.min + Vec3::new(0.0, 0.0, k as f32 * h),
            Vec3::splat(h),
            [n.x as usize, n.y as usize, 1],
            out,
        );
    });
    let shape = [n.z as usize, n.y as usize, n.x as usize];
    write_atomic(out, |w| npy::write_f32(w, &shape, &data))
        .with_context(|| format!("writing {}", out.display()))?;
    Ok(())
}

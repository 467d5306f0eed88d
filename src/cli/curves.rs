//! `karstic curves ...`: run the Feature Curve pipeline on a `FeatureVolume` file.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use glam::{IVec3, Vec3};
use rayon::prelude::*;

use crate::curves::FeatureVolumeSpec;
use crate::curves::spec::{BuildOptions, load_ron};
use crate::field::Field;
use crate::io::{DEFAULT_MEMORY_BUDGET, check_budget, human_bytes, write_atomic};
use crate::voxel::SField;
use crate::voxel::pipeline::Stats;

/// Feature Curves: build the S field of a `FeatureVolume(..)` file.
#[derive(Args, Debug)]
pub struct CurvesArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: CurvesCommand,
}

/// `curves` subcommands.
#[derive(Subcommand, Debug)]
pub enum CurvesCommand {
    /// Run the voxel pipeline and write the field.
    Build(BuildArgs),
}

/// `karstic curves build FILE -o field.npy`.
#[derive(Args, Debug)]
pub struct BuildArgs {
    /// A RON file holding one `FeatureVolume(..)`.
    pub file: PathBuf,
    /// Output: `.npy` (the field f sampled on the finest grid, float32, shape
    /// `(nz, ny, nx)`, index `[k, j, i]` at `domain.min + (i, j, k)·voxel`).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Also write the proxy ribbon meshes (finest level) as OBJ.
    #[arg(long)]
    pub ribbons: Option<PathBuf>,
    /// Print per-stage times, iteration counts and memory.
    #[arg(long)]
    pub stats: bool,
    /// Seed of the displacement noise.
    #[arg(long, default_value_t = 0)]
    pub seed: u32,
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

fn build(args: BuildArgs) -> anyhow::Result<()> {
    let spec: FeatureVolumeSpec = load_ron(&args.file)?;
    let base = args.file.parent().unwrap_or(Path::new("."));
    let budget = args.max_memory << 20;
    if let Some(path) = &args.ribbons {
        let features = spec.feature_set(base)?.resolve(&|_| None)?;
        let mesh = features.proxy(
            spec.ribbon_width(),
            spec.ribbon_width(),
            0.5 * spec.voxel.0,
            0.0,
        );
        write_atomic(path, |w| mesh.write_obj(w))?;
    }
    let clock = Instant::now();
    let field = spec.build_with(
        base,
        &BuildOptions {
            seed: args.seed,
            ground: None,
            max_memory: budget,
        },
    )?;
    let elapsed = clock.elapsed();
    if args.stats {
        print_stats(field.stats(), elapsed.as_secs_f64() * 1e3);
    }
    if let Some(out) = &args.output {
        match out.extension().and_then(|e| e.to_str()) {
            Some("npy") => write_npy(&field, &spec, out, budget)?,
            _ => bail!("{}: unknown output type (expected .npy)", out.display()),
        }
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
fn write_npy(
    field: &SField,
    spec: &FeatureVolumeSpec,
    out: &Path,
    budget: u64,
) -> anyhow::Result<()> {
    let d = field.params().domain;
    let h = spec.voxel.0;
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
    let mut header = format!(
        "{{'descr': '<f4', 'fortran_order': False, 'shape': ({}, {}, {}), }}",
        n.z, n.y, n.x
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    write_atomic(out, |w| {
        w.write_all(b"\x93NUMPY\x01\x00")?;
        w.write_all(&(header.len() as u16).to_le_bytes())?;
        w.write_all(header.as_bytes())?;
        w.write_all(bytemuck::cast_slice(&data))
    })
    .with_context(|| format!("writing {}", out.display()))?;
    Ok(())
}

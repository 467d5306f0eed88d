//! `karstic render`: a PNG preview of a tree by ray tracing its implicit surface.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use glam::Vec3;

use crate::field::Field;
use crate::io::{DEFAULT_MEMORY_BUDGET, progress};
use crate::render::gpu;
use crate::render::{Camera, Frame, Method, RenderSettings, cpu};
use crate::tape::{Tape, TapeError, tape_from_tree};

/// Arguments of `karstic render`.
#[derive(clap::Args, Debug, Clone)]
pub struct RenderArgs {
    /// The tree file (.ron) to render.
    pub tree: PathBuf,
    /// Output PNG.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Image size in pixels.
    #[arg(long, num_args = 2, value_names = ["W", "H"], default_values_t = [960, 540])]
    pub size: Vec<u32>,
    /// Step rule: `segment` (local Lipschitz bounds) or `sphere` (global bound; slow).
    #[arg(long, value_enum, default_value_t = Method::Segment)]
    pub method: Method,
    /// Also write the steps-per-pixel image to this PNG.
    #[arg(long)]
    pub cost: Option<PathBuf>,
    /// Camera eye and target (default: framed from the tree's support box, from the
    /// south-east and above).
    #[arg(long, num_args = 6, allow_negative_numbers = true,
          value_names = ["EYE_X", "EYE_Y", "EYE_Z", "TARGET_X", "TARGET_Y", "TARGET_Z"])]
    pub camera: Option<Vec<f32>>,
    /// Vertical field of view, degrees.
    #[arg(long, default_value_t = 40.0)]
    pub fov: f32,
    /// Trace on the GPU (wgpu); falls back to the CPU with a message when no adapter.
    #[arg(long)]
    pub gpu: bool,
    /// Skip the shadow rays.
    #[arg(long)]
    pub no_shadows: bool,
    /// Memory budget in bytes for the image buffers.
    #[arg(long, default_value_t = DEFAULT_MEMORY_BUDGET)]
    pub max_memory: u64,
    /// No progress bar and no summary line.
    #[arg(long)]
    pub quiet: bool,
}

/// What the renderer needs from a tree file.
pub struct LoadedTree {
    /// The compiled field (CPU tracing).
    pub field: Box<dyn Field>,
    /// When the GPU was asked for: its encoding, or why there is none (a node without an
    /// encoding). Not built for CPU renders: it copies every DEM and its slope pyramid.
    pub tape: Option<Result<Tape, TapeError>>,
}

/// Loads and compiles a tree file for rendering, with its GPU tape when `gpu` and every
/// node has an encoding ([`tape_from_tree`]).
pub fn load_tree(path: &Path, gpu: bool) -> anyhow::Result<LoadedTree> {
    let tree = super::load_tree(path)?;
    let tape = gpu.then(|| tape_from_tree(&tree));
    Ok(LoadedTree {
        field: Box::new(tree),
        tape,
    })
}

/// Runs `karstic render`.
pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    let tree = load_tree(&args.tree, args.gpu)?;
    render_tree(&args, &tree)
}

/// Renders an already loaded tree as `args` asks and writes the PNG(s).
pub fn render_tree(args: &RenderArgs, tree: &LoadedTree) -> anyhow::Result<()> {
    let (w, h) = (args.size[0], args.size[1]);
    crate::render::camera::check_size(w, h)?;
    Frame::check_budget(w, h, args.max_memory)?;
    let field = tree.field.as_ref();
    let support = field.support();
    let camera = match &args.camera {
        Some(c) => Camera::look_at(
            Vec3::new(c[0], c[1], c[2]),
            Vec3::new(c[3], c[4], c[5]),
            args.fov,
            w,
            h,
        )?,
        None => Camera::frame(&support, args.fov, w, h)?,
    };
    let mut settings = RenderSettings::for_scene(&support, &camera, args.method);
    settings.shading.shadows = !args.no_shadows;
    let start = Instant::now();
    let (frame, device) = match (args.gpu, &tree.tape) {
        (true, Some(Ok(tape))) => match gpu::render(tape, &camera, &settings) {
            Ok(frame) => (frame, "GPU"),
            Err(e) => {
                eprintln!("--gpu: {e}; rendering on the CPU instead");
                (cpu_frame(field, &camera, &settings, args.quiet), "CPU")
            }
        },
        (true, Some(Err(e))) => {
            eprintln!("--gpu: {e}; rendering on the CPU instead");
            (cpu_frame(field, &camera, &settings, args.quiet), "CPU")
        }
        _ => (cpu_frame(field, &camera, &settings, args.quiet), "CPU"),
    };
    let elapsed = start.elapsed();
    frame
        .write_png(&args.output)
        .with_context(|| format!("writing {}", args.output.display()))?;
    if let Some(cost) = &args.cost {
        frame
            .write_cost_png(cost)
            .with_context(|| format!("writing {}", cost.display()))?;
    }
    if !args.quiet {
        eprintln!(
            "rendered {w} × {h} on the {device} in {:.3} s ({:?} tracing, {} of {} pixels hit, {:.1} steps per ray) → {}",
            elapsed.as_secs_f64(),
            args.method,
            frame.hits(),
            w as usize * h as usize,
            frame.mean_steps(),
            args.output.display()
        );
    }
    Ok(())
}

fn cpu_frame(field: &dyn Field, camera: &Camera, settings: &RenderSettings, quiet: bool) -> Frame {
    let tiles = camera.width.div_ceil(cpu::TILE) * camera.height.div_ceil(cpu::TILE);
    let bar = progress(tiles as u64, "render", quiet);
    cpu::render(field, camera, settings, &bar)
}

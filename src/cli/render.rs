//! `karstic render`: a PNG preview of a tree by ray tracing its implicit surface.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use glam::Vec3;

use super::Budget;
use clap::builder::TypedValueParser;
use karstic::field::Tree;
use karstic::io::progress;
use karstic::render::{Device, Frame, Method, Renderable, cpu};

/// Arguments of `karstic render`.
#[derive(clap::Args, Debug)]
pub(super) struct RenderArgs {
    /// The tree file (.ron) to render.
    tree: PathBuf,
    /// Output PNG.
    #[arg(short, long)]
    output: PathBuf,
    /// Image size in pixels.
    #[arg(long, num_args = 2, value_names = ["W", "H"], default_values_t = [960, 540])]
    size: Vec<u32>,
    /// Step rule: `segment` (local Lipschitz bounds) or `sphere` (global bound; slow).
    #[arg(long, default_value = "segment", value_parser = method_names())]
    method: Method,
    /// Also write the steps-per-pixel image to this PNG.
    #[arg(long)]
    cost: Option<PathBuf>,
    /// Camera eye and target (default: the tree's `job` camera when it has one, else the
    /// box where the surface lies framed from the south-east and above).
    #[arg(value_parser = super::finite, long, num_args = 6, allow_negative_numbers = true,
          value_names = ["EYE_X", "EYE_Y", "EYE_Z", "TARGET_X", "TARGET_Y", "TARGET_Z"])]
    camera: Option<Vec<f32>>,
    /// Vertical field of view, degrees (default: the job's, else 40).
    #[arg(value_parser = super::finite, long)]
    fov: Option<f32>,
    /// Trace on the GPU (wgpu); falls back to the CPU with a message when no hardware
    /// adapter can.
    #[arg(long)]
    gpu: bool,
    /// With `--gpu`, use a software adapter (llvmpipe, lavapipe, WARP) too: many times
    /// slower than the CPU renderer, for tests.
    #[arg(long, requires = "gpu")]
    software_gpu: bool,
    /// Skip the shadow rays.
    #[arg(long)]
    no_shadows: bool,
    /// Draw bare ground: no trees or shrubs (the job's `vegetation`).
    #[arg(long)]
    bare: bool,
    /// Trace the whole field without first meshing the job's region to guide the rays
    /// (several times slower; draws solid thinner than the guides' cells, which the
    /// job's mesh and pictures leave out).
    #[arg(long)]
    no_guide: bool,
    /// Memory budget.
    #[command(flatten)]
    pub(super) budget: Budget,
    /// No progress bar and no summary line.
    #[arg(long)]
    quiet: bool,
}

/// `--method`'s parser: one of [`Method::NAMES`], listed in `--help`.
fn method_names() -> impl TypedValueParser<Value = Method> {
    clap::builder::PossibleValuesParser::new(Method::NAMES.map(|(n, _)| n))
        .map(|s| s.parse::<Method>().expect("a listed name"))
}

/// Runs `karstic render`.
pub(super) fn run(args: RenderArgs) -> anyhow::Result<()> {
    let outputs: Vec<&PathBuf> = std::iter::once(&args.output).chain(&args.cost).collect();
    let (w, h) = (args.size[0], args.size[1]);
    karstic::render::camera::check_size(w, h)?;
    Frame::check_budget(w, h, args.budget.max_memory)?;
    let file = karstic::scene::load(&args.tree)?;
    karstic::io::check_outputs(&file.inputs(), &outputs)?;
    let working = karstic::io::spinner("compiling", args.quiet);
    let compiled = file.compile_with(args.budget.max_memory)?;
    working.finish_and_clear();
    super::notify(&compiled.notices, args.quiet);
    let look = args
        .camera
        .as_deref()
        .map(|c| (Vec3::new(c[0], c[1], c[2]), Vec3::new(c[3], c[4], c[5])));
    let tree = &compiled.tree;
    let camera = karstic::picture::camera(&file.scene, tree, look, args.fov, w, h)
        .with_context(|| format!("{}: placing the camera", args.tree.display()))?;
    let mut settings =
        karstic::picture::settings(&file.scene, tree, compiled.ground, &camera, args.method);
    settings.shading.shadows = !args.no_shadows;
    if args.bare {
        settings.vegetation = None;
    }
    let mut subject = Renderable::from_tree(compiled.tree, args.gpu);
    subject.allow_software = args.software_gpu;
    let gpu = subject.gpu(&settings);
    let start = Instant::now();
    // On the CPU (asked for, or the GPU's fallback) the tracer follows a mesh of the job's
    // region, as `karstic run`'s pictures do: meshing it costs a fraction of the march it
    // saves.
    let tree = subject
        .field
        .as_any()
        .and_then(|a| a.downcast_ref::<Tree>());
    if let Some(tree) = tree.filter(|_| !args.no_guide && !matches!(gpu, Some(Ok(_)))) {
        settings.guides = karstic::picture::view_guides(
            tree,
            file.scene.job.as_ref(),
            &camera,
            settings.shading.shadows.then_some(settings.shading.sun),
            args.budget.max_memory,
            args.quiet,
        )
        .with_context(|| format!("{}: meshing the job's region", args.tree.display()))?;
    }
    let guided = start.elapsed();
    let tiles = w.div_ceil(cpu::TILE) * h.div_ceil(cpu::TILE);
    let bar = progress(tiles as u64, "render", args.quiet);
    let (frame, device) = subject.render_on(gpu, &camera, &settings, &bar);
    bar.finish_and_clear();
    if let Device::CpuInstead(why) = &device {
        eprintln!("--gpu: {why}; rendered on the CPU instead");
    }
    let elapsed = start.elapsed();
    frame.write_png(&args.output)?;
    if let Some(cost) = &args.cost {
        frame.write_cost_png(cost)?;
    }
    if !args.quiet {
        let guide = match settings.guides.is_empty() {
            true => String::new(),
            false => format!(
                ", guided by the job's mesh made in {:.3} s",
                guided.as_secs_f64()
            ),
        };
        eprintln!(
            "rendered {w} × {h} on the {} in {:.3} s ({:?} tracing, {} of {} pixels hit, {:.1} steps per ray{guide}) → {}",
            device.name(),
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

#[cfg(test)]
mod tests {
    use super::super::{Cli, Command};
    use super::*;
    use clap::Parser;

    fn args(extra: &[&str]) -> RenderArgs {
        let mut argv = vec!["karstic", "render", "scene.ron", "-o", "out.png"];
        argv.extend_from_slice(extra);
        match Cli::try_parse_from(argv).unwrap().command {
            Command::Render(a) => a,
            other => panic!("parsed as {other:?}"),
        }
    }

    #[test]
    fn flags_parse() {
        let a = args(&[
            "--size",
            "64",
            "48",
            "--method",
            "sphere",
            "--camera",
            "-10",
            "5",
            "3.5",
            "0",
            "0",
            "-1",
            "--fov",
            "30",
            "--gpu",
            "--software-gpu",
            "--no-guide",
            "--bare",
            "--quiet",
            "--cost",
            "c.png",
            "--max-memory",
            "1G",
        ]);
        assert_eq!(a.size, vec![64, 48]);
        assert_eq!(a.method, Method::Sphere);
        assert_eq!(a.camera, Some(vec![-10.0, 5.0, 3.5, 0.0, 0.0, -1.0]));
        assert!(a.gpu && a.software_gpu && a.no_guide && a.bare && a.quiet && a.cost.is_some());
        assert_eq!(a.fov, Some(30.0));
        assert_eq!(a.budget.max_memory, 1 << 30);
        let d = args(&[]);
        assert_eq!(d.size, vec![960, 540]);
        assert_eq!(d.method, Method::Segment);
        for bad in [
            &["--size", "5"][..],
            &["--method", "bogus"],
            &["--software-gpu"],
        ] {
            let mut argv = vec!["karstic", "render", "x.ron", "-o", "o.png"];
            argv.extend_from_slice(bad);
            assert!(Cli::try_parse_from(argv).is_err(), "{bad:?}");
        }
    }
}

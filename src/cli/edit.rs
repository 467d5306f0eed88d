//! `karstic edit`: the interactive editor, or its first settled frame as a picture.

use std::path::PathBuf;
use std::time::Duration;

use karstic::editor::{Backend, Headless};

/// Arguments of `karstic edit`.
#[derive(clap::Args, Debug)]
pub(super) struct EditArgs {
    /// The tree file (.ron) to edit.
    tree: PathBuf,
    /// Draw the editor headless, write its first settled frame (the viewport refined to
    /// full size) to this PNG and exit: no window is opened.
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// Select the node of this name (its parameters in the inspector).
    #[arg(long)]
    select: Option<String>,
    /// Show the node graph under the viewport (the toolbar's `graph` button).
    #[arg(long)]
    graph: bool,
    /// Size of the screenshot in pixels.
    #[arg(long, num_args = 2, value_names = ["W", "H"], default_values_t = [1400, 820])]
    size: Vec<u32>,
    /// Longest wait for the viewport to settle before `--screenshot` gives up, seconds.
    #[arg(long, default_value_t = 300.0)]
    timeout: f64,
    /// Refine the viewport on the GPU (wgpu) even on a software adapter such as lavapipe
    /// (by default the GPU refines only on a hardware adapter, the CPU otherwise).
    #[arg(long, conflicts_with = "cpu")]
    gpu: bool,
    /// Refine the viewport on the CPU even when a hardware GPU adapter is there.
    #[arg(long)]
    cpu: bool,
    #[command(flatten)]
    budget: super::Budget,
}

/// Runs `karstic edit`.
pub(super) fn run(args: EditArgs) -> anyhow::Result<()> {
    let file = karstic::scene::load(&args.tree)?;
    if let Some(out) = &args.screenshot {
        karstic::io::check_outputs(&file.inputs(), &[out])?;
    }
    let backend = match (args.gpu, args.cpu) {
        (true, _) => Backend::Gpu,
        (_, true) => Backend::Cpu,
        _ => Backend::Auto,
    };
    match &args.screenshot {
        Some(out) => {
            karstic::render::camera::check_size(args.size[0], args.size[1])?;
            anyhow::ensure!(
                args.timeout.is_finite() && args.timeout > 0.0,
                "--timeout must be a positive number of seconds"
            );
            let how = Headless {
                size: (args.size[0], args.size[1]),
                select: args.select.as_deref(),
                graph: args.graph,
                backend,
                timeout: Duration::from_secs_f64(args.timeout),
                budget: args.budget.max_memory,
            };
            let t = karstic::editor::screenshot(&args.tree, out, &how)?;
            eprintln!(
                "first image after {:.2} s, settled after {:.2} s (viewport {} × {}) → {}",
                t.first.as_secs_f64(),
                t.settled.as_secs_f64(),
                t.size.0,
                t.size.1,
                out.display()
            );
            Ok(())
        }
        None => {
            karstic::editor::run_window(&args.tree, args.select.as_deref(), args.graph, backend)
        }
    }
}

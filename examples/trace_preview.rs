//! Trace a preview of a tree file: segment tracing with local Lipschitz bounds, shaded
//! with sun, shadows, sky and fog, written as a PNG. With `--gpu` the tree is lowered to
//! a GPU tape and traced with wgpu when an adapter takes it; otherwise (or if it fails)
//! the CPU renders the same image and the example says why.
//!
//! ```sh
//! cargo run --release --example trace_preview -- [TREE] [OUT.png] [WIDTH HEIGHT] [--gpu]
//! ```
//!
//! Defaults: `trees/arch.ron`, `preview.png` in the system's temporary folder, 320 × 180.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use indicatif::ProgressBar;
use karstic::field::Field;
use karstic::render::{Camera, Device, Frame, Method, RenderSettings, Renderable};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let gpu = args.iter().any(|a| a == "--gpu");
    let mut args = args.into_iter().filter(|a| a != "--gpu");
    let tree_path = PathBuf::from(args.next().unwrap_or_else(|| "trees/arch.ron".into()));
    let out = args.next().map_or_else(
        || std::env::temp_dir().join("karstic-examples/preview.png"),
        PathBuf::from,
    );
    let mut size = [320u32, 180];
    for (k, s) in args.take(2).enumerate() {
        size[k] = s
            .parse()
            .with_context(|| format!("image size: expected pixels, found {s:?}"))?;
    }
    let [width, height] = size;

    // Load, validate and compile the tree file (DEMs read, Feature Volumes built).
    let tree = karstic::scene::load(&tree_path)?.compile()?.tree;

    // Refuse an image that would not fit the memory budget before allocating it, then
    // frame the tree's support box from the south-east and above.
    Frame::check_budget(width, height, karstic::io::DEFAULT_MEMORY_BUDGET)?;
    let support = tree.support();
    let camera = Camera::view(None, &support, 40.0, width, height)?;
    let settings = RenderSettings::for_scene(&support, &camera, Method::Segment);

    let start = Instant::now();
    let subject = Renderable::from_tree(tree, gpu);
    let (frame, device) = subject.render_with_fallback(&camera, &settings, &ProgressBar::hidden());
    if let Device::CpuInstead(why) = &device {
        eprintln!("--gpu: {why}; rendered on the CPU instead");
    }
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    frame.write_png(&out)?;
    println!(
        "{}: {width} × {height} on the {} in {:.2} s, {} pixels hit, {:.1} steps per ray → {}",
        tree_path.display(),
        device.name(),
        start.elapsed().as_secs_f64(),
        frame.hits(),
        frame.mean_steps(),
        out.display()
    );
    Ok(())
}

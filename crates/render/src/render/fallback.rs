//! The GPU when it can, the CPU otherwise: a field with its GPU encoding, rendered on the
//! device that can take it, saying which one did and why the GPU did not.

use indicatif::ProgressBar;

use super::camera::Camera;
use super::cpu::{self, RenderSettings};
use super::gpu::{GpuContext, GpuError};
use super::image::Frame;
use crate::field::{Field, Tree};
use crate::tape::{Tape, tape_from_tree};

/// A field to render, with its GPU encoding when the GPU is wanted.
pub struct Renderable {
    /// The field (the CPU tracer's input, and the fallback's).
    pub field: Box<dyn Field>,
    /// When the GPU is wanted: the field's encoding, or why it has none (a node without
    /// an encoding). `None` renders on the CPU.
    pub tape: Option<Result<Tape, GpuError>>,
    /// Render on a software adapter (llvmpipe, lavapipe, WARP) too. Off by default: one
    /// runs the tracer many times slower than the CPU renderer (the main job took 246 s
    /// on lavapipe against 1.5 s on the CPU), so the CPU renders instead.
    pub allow_software: bool,
}

/// Why the CPU rendered an image the GPU was asked for.
#[derive(Debug)]
pub enum Fallback<'a> {
    /// The field has no GPU encoding.
    NoTape(&'a GpuError),
    /// The GPU could not be opened or failed while rendering.
    Failed(GpuError),
    /// The only adapter is a software one (named), and software was not allowed.
    Software(String),
}

impl std::fmt::Display for Fallback<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Fallback::NoTape(e) => write!(f, "{}", crate::io::chain(*e)),
            Fallback::Failed(e) => write!(f, "{}", crate::io::chain(e)),
            Fallback::Software(name) => write!(
                f,
                "the only GPU adapter is a software one ({name}), slower than the CPU renderer (allow it with --software-gpu)"
            ),
        }
    }
}

/// The device that rendered a frame.
#[derive(Debug)]
pub enum Device<'a> {
    /// The GPU, with its adapter's name.
    Gpu(String),
    /// The CPU, as asked.
    Cpu,
    /// The CPU, because the GPU was asked for but could not be used.
    CpuInstead(Fallback<'a>),
}

impl Device<'_> {
    /// `"GPU (adapter)"` or `"CPU"`.
    pub fn name(&self) -> String {
        match self {
            Device::Gpu(adapter) => format!("GPU ({adapter})"),
            Device::Cpu | Device::CpuInstead(_) => "CPU".into(),
        }
    }
}

impl Renderable {
    /// A compiled tree, with its GPU encoding ([`tape_from_tree`]) when `gpu`. The
    /// encoding is not built otherwise: it copies every DEM and its slope pyramid.
    pub fn from_tree(tree: Tree, gpu: bool) -> Self {
        let tape = gpu.then(|| tape_from_tree(&tree).map_err(GpuError::from));
        Renderable {
            field: Box::new(tree),
            tape,
            allow_software: false,
        }
    }

    /// Renders on the GPU when a tape was built and the GPU takes it, on the CPU
    /// otherwise (`progress` advances once per CPU tile). The image is the same either
    /// way, up to the GPU's arithmetic.
    pub fn render_with_fallback(
        &self,
        camera: &Camera,
        settings: &RenderSettings,
        progress: &ProgressBar,
    ) -> (Frame, Device<'_>) {
        let cpu = || cpu::render(self.field.as_ref(), camera, settings, progress);
        match &self.tape {
            None => (cpu(), Device::Cpu),
            Some(Err(e)) => (cpu(), Device::CpuInstead(Fallback::NoTape(e))),
            Some(Ok(tape)) => {
                let ctx = match GpuContext::new() {
                    Ok(ctx) if ctx.software && !self.allow_software => {
                        let why = Fallback::Software(ctx.adapter.clone());
                        return (cpu(), Device::CpuInstead(why));
                    }
                    Ok(ctx) => ctx,
                    Err(e) => return (cpu(), Device::CpuInstead(Fallback::Failed(e))),
                };
                match ctx.render(tape, camera, settings) {
                    Ok(frame) => (frame, Device::Gpu(ctx.adapter.clone())),
                    Err(e) => (cpu(), Device::CpuInstead(Fallback::Failed(e))),
                }
            }
        }
    }
}

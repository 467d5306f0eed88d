//! The GPU when it can, the CPU otherwise: a field with its GPU encoding, rendered on the
//! device that can take it, saying which one did and why the GPU did not.

use indicatif::ProgressBar;

use super::camera::Camera;
use super::cpu::{self, RenderSettings};
use super::gpu::{GpuContext, GpuError, unsupported};
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

    /// The device this renders a picture with `settings` on, decided before anything is
    /// drawn: `None` for the CPU when the GPU was not wanted, else the GPU's context, or
    /// why the CPU renders instead (no encoding, what the shader cannot draw —
    /// [`unsupported`] —, no adapter, a software adapter not allowed). A caller that
    /// prepares the CPU's help (the mesh guides) asks this first.
    pub fn gpu(&self, settings: &RenderSettings) -> Option<Result<GpuContext, Fallback<'_>>> {
        Some(match self.tape.as_ref()? {
            Err(e) => Err(Fallback::NoTape(e)),
            Ok(_) => match unsupported(settings) {
                Some(e) => Err(Fallback::Failed(e)),
                None => match GpuContext::new() {
                    Ok(ctx) if ctx.software && !self.allow_software => {
                        Err(Fallback::Software(ctx.adapter.clone()))
                    }
                    Ok(ctx) => Ok(ctx),
                    Err(e) => Err(Fallback::Failed(e)),
                },
            },
        })
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
        self.render_on(self.gpu(settings), camera, settings, progress)
    }

    /// [`Self::render_with_fallback`] on the device [`Self::gpu`] chose.
    pub fn render_on<'s>(
        &'s self,
        gpu: Option<Result<GpuContext, Fallback<'s>>>,
        camera: &Camera,
        settings: &RenderSettings,
        progress: &ProgressBar,
    ) -> (Frame, Device<'s>) {
        let cpu = || cpu::render(self.field.as_ref(), camera, settings, progress);
        let tape = self.tape.as_ref().and_then(|t| t.as_ref().ok());
        match (gpu, tape) {
            (Some(Ok(ctx)), Some(tape)) => match ctx.render(tape, camera, settings) {
                Ok(frame) => (frame, Device::Gpu(ctx.adapter.clone())),
                Err(e) => (cpu(), Device::CpuInstead(Fallback::Failed(e))),
            },
            (Some(Err(why)), _) => (cpu(), Device::CpuInstead(why)),
            _ => (cpu(), Device::Cpu),
        }
    }
}

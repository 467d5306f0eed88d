//! The GPU when it can, the CPU otherwise: a field with its GPU encoding, rendered on the
//! device that can take it, saying which one did and why the GPU did not.

use indicatif::ProgressBar;

use super::camera::Camera;
use super::cpu::{self, RenderSettings};
use super::gpu::{self, GpuError};
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
}

/// Why the CPU rendered an image the GPU was asked for.
#[derive(Debug)]
pub enum Fallback<'a> {
    /// The field has no GPU encoding.
    NoTape(&'a GpuError),
    /// The GPU could not be opened or failed while rendering.
    Failed(GpuError),
}

impl Fallback<'_> {
    /// The GPU's error.
    pub fn error(&self) -> &GpuError {
        match self {
            Fallback::NoTape(e) => e,
            Fallback::Failed(e) => e,
        }
    }
}

/// The device that rendered a frame.
#[derive(Debug)]
pub enum Device<'a> {
    /// The GPU.
    Gpu,
    /// The CPU, as asked.
    Cpu,
    /// The CPU, because the GPU was asked for but could not be used.
    CpuInstead(Fallback<'a>),
}

impl Device<'_> {
    /// `"GPU"` or `"CPU"`.
    pub fn name(&self) -> &'static str {
        match self {
            Device::Gpu => "GPU",
            Device::Cpu | Device::CpuInstead(_) => "CPU",
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
            Some(Ok(tape)) => match gpu::render(tape, camera, settings) {
                Ok(frame) => (frame, Device::Gpu),
                Err(e) => (cpu(), Device::CpuInstead(Fallback::Failed(e))),
            },
        }
    }
}

//! Direct preview of the implicit surface `f = T` by ray tracing (Génevaux et al. 2015 §7).
//!
//! * [`camera`]: look-at pinhole camera, framed automatically from a support box.
//! * [`trace`]: segment tracing with local Lipschitz bounds (Génevaux et al. 2015 §7.2,
//!   Galin et al. 2020) and plain sphere tracing with the global bound, with per-ray step
//!   counts.
//! * [`shade`]: lighting — sun with soft shadows, sky with ambient occlusion from the
//!   field, aerial perspective, tone curve.
//! * [`cpu`]: the image renderer, tiles over rayon.
//! * [`image`]: the rendered [`Frame`] and its PNG outputs (colour and step cost).
//! * [`raycast`]: triangle-mesh ray casting (obvhs), the ground truth for the tracer.
//! * [`gpu`]: the same tracer as a wgpu compute shader over a flattened node tape.
//! * [`views`]: the box where the surface lies (automatic framing), and a close-up
//!   camera per feature.
//! * [`material`]: surface materials shared with the exported meshes.
//! * [`top_cover`]: talus at cliffs' feet and streams along the drainage, on the top
//!   surface, which the materials cover with scree and water.
//! * [`vegetation`]: trees and shrubs traced beside the field, for the pictures' scale.
//! * [`fallback`]: the GPU when it can, the CPU otherwise ([`Renderable`]).

pub mod camera;
pub mod cpu;
pub mod fallback;
pub mod gpu;
pub mod guide;
pub mod image;
pub mod material;
pub mod raycast;
pub mod shade;
pub mod top_cover;
pub mod trace;
pub mod vegetation;
pub mod views;

pub use camera::{Camera, Ray};
pub use cpu::{RenderSettings, render};
pub use fallback::{Device, Fallback, Renderable};
pub use image::Frame;
pub use material::{Cover, Materials};
pub use shade::{Shading, Water};
pub use top_cover::TopCover;
pub use trace::{Method, Trace, TraceParams, Tracer};
pub use vegetation::{Flora, Vegetation};

/// Errors of the renderer.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The image size is zero or too large.
    #[error(
        "image size {width} × {height} is invalid: both sides must be between 1 and 32768 pixels"
    )]
    BadSize {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
    },
    /// The camera cannot be built from these parameters.
    #[error("bad camera: {0}")]
    BadCamera(String),
    /// The field has an empty or non-finite support box: nothing to frame or trace.
    #[error("the field's support box is empty or not finite ({0}); nothing to render")]
    EmptySupport(String),
    /// Encoding or writing an image failed.
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
    /// The GPU path failed.
    #[error(transparent)]
    Gpu(#[from] gpu::GpuError),
}

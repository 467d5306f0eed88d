//! The tracer on the GPU: a wgpu compute shader, headless (no window), one primary ray per
//! invocation, running the same march and shading as the CPU path over a
//! [`crate::tape::Tape`] (the field lowered for the GPU, which this module uploads).
//!
//! * [`context`]: adapter, device, pipelines, buffers, dispatch and read-back.
//!
//! The WGSL lives in `crates/render/shaders/` and is assembled by [`shader_source`], starting with the
//! constant header generated from the tape's Rust definitions
//! ([`header`]); the tests validate every module with naga so shader errors
//! fail without a GPU.

pub mod context;
pub mod header;

pub use context::{GpuContext, render, unsupported};
pub use header::wgsl_header;

use crate::tape::TapeError;

/// Errors of the GPU path.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No usable adapter (no GPU and no software Vulkan such as lavapipe).
    #[error("no GPU adapter available")]
    NoAdapter(#[source] wgpu::RequestAdapterError),
    /// The device could not be created.
    #[error("cannot open the GPU device")]
    Device(#[source] wgpu::RequestDeviceError),
    /// The adapter lacks what the tracer needs.
    #[error("the GPU cannot run the tracer: {0}")]
    Unsuitable(String),
    /// The tracing shader does not compile on this device.
    #[error("the tracing shader does not compile")]
    Shader(#[source] wgpu::Error),
    /// The tree cannot be encoded for the GPU.
    #[error(transparent)]
    Tape(#[from] TapeError),
    /// The work exceeds what the device allows.
    #[error("{0}")]
    Limits(String),
    /// Running or reading back failed.
    #[error("GPU execution failed")]
    Run(#[source] Box<dyn std::error::Error + Send + Sync>),
}

/// The WGSL modules, each the concatenation of these files of `crates/render/shaders/` (WGSL has no
/// includes). The tests check that every file there belongs to some module.
pub const SHADER_MODULES: &[(&str, &[&str])] = &[(
    "trace",
    &[
        "tape_consts.wgsl",
        "noise.wgsl",
        "sfield.wgsl",
        "field.wgsl",
        "trace.wgsl",
    ],
)];

/// The source of the tracing module.
pub fn shader_source() -> String {
    [
        include_str!("../../../shaders/tape_consts.wgsl"),
        include_str!("../../../shaders/noise.wgsl"),
        include_str!("../../../shaders/sfield.wgsl"),
        include_str!("../../../shaders/field.wgsl"),
        include_str!("../../../shaders/trace.wgsl"),
    ]
    .concat()
}

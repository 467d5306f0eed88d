//! GPU tracing (wgpu compute).

/// Errors of the GPU path.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter.
    #[error("no GPU adapter: {0}")]
    NoAdapter(String),
}

//! The shared GPU context and the GPU-against-CPU probe check.

use glam::Vec3;

use super::{REQUIRE_GPU, unavailable};

/// The shared GPU context of a test binary; `None` (after a notice) when there is no
/// adapter, a failure instead where [`REQUIRE_GPU`] is set; panics when an adapter exists
/// but the tracer cannot run on it.
pub fn gpu() -> Option<&'static karstic::render::gpu::GpuContext> {
    use karstic::render::gpu::{GpuContext, GpuError};
    static CTX: std::sync::OnceLock<Option<GpuContext>> = std::sync::OnceLock::new();
    CTX.get_or_init(|| match GpuContext::new() {
        Ok(c) => Some(c),
        Err(e @ GpuError::NoAdapter(_)) => {
            unavailable(REQUIRE_GPU, &format!("GPU comparisons: {e}"));
            None
        }
        Err(e) => panic!("the GPU adapter exists but the tracer cannot run on it: {e}"),
    })
    .as_ref()
}

/// Asserts that the GPU's probes of `tape` (value and Lipschitz bound over a ball of
/// radius `r` at each point) equal the CPU tape's within float rounding.
pub fn assert_probes_match(
    ctx: &karstic::render::gpu::GpuContext,
    tape: &karstic::tape::Tape,
    pts: &[(Vec3, f32)],
) {
    let got = ctx.probe(tape, pts).unwrap();
    for (&(p, r), &(v, l)) in pts.iter().zip(&got) {
        let (cv, cl) = tape.eval(p, p, r);
        assert!(
            (v - cv).abs() <= 1e-4 * (1.0 + cv.abs()),
            "value at {p}: GPU {v}, CPU {cv}"
        );
        assert!(
            (l - cl).abs() <= 1e-3 * (1.0 + cl.abs()),
            "bound at {p}, r {r}: GPU {l}, CPU {cl}"
        );
    }
}

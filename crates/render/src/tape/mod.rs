//! The tree lowered for the GPU: a flat **tape** of instructions evaluated with a small
//! value stack, plus a parameter array and buffers of heightfield and S-field samples.
//!
//! One pass over the tape at `(p, c, r)` returns both `f(p)` and a Lipschitz bound of `f`
//! over the ball `B(c, r)` — exactly what one step of segment tracing needs (the ball
//! around a candidate segment). `r = 0` gives the value alone.
//!
//! | op | params at `param` | stack | meaning |
//! | --- | --- | --- | --- |
//! | `CONST` | [`format::constant`]: `v` | push | constant `v` (Lipschitz 0) |
//! | `PRIM` | [`format::prim`]: `R, e, shape…` | push | `e·g(max(sd, 0)/R)` (Wyvill) or `σ(−sd, R)` ([`format::flag::SIGMA`]); `sd` the signed distance to the shape ([`format::shape`]) |
//! | `HEIGHT` | [`format::height`]: `R, n, origin, cell, nx, ny, offset, level₀ … levelₙ₋₁` | push | `σ(h(x, y) − z, R)`, `h` bilinear (Catmull-Rom bicubic with [`format::flag::BICUBIC`]) in `heights[offset..]`; the ball's slope of `h` from a max pyramid of per-cell bounds of `|∇h|` ([`mod@height`]) |
//! | `NPRIM` | [`format::nprim`] | push | a noisy primitive `E·g(d̃)` on a convex shape ([`noise`]) |
//! | `SFIELD` | [`format::sfield`] | push | an S-field leaf (`flags`: its index in [`Tape::sfields`]; [`mod@sfield`]) |
//! | `BLEND` / `UNION` / `INTER` / `DIFF` | – | pop 2, push 1 | `a + b`, `max`, `min`, `min(a, 2T − b)` |
//! | `GUARD` | [`format::guard`]: `min, max` | – | when neither `p` nor the ball touches the box, push `(0, 0)` and jump to `jump` (the instruction after the guarded subtree) |
//! | `WARP` / `UNWARP` | [`format::warp`]: `M⁻¹` (3 rows of 4), `k ≥ ‖M⁻¹‖` / [`format::unwarp`]: `k` | – | `p, c ← M⁻¹p, M⁻¹c`, `r ← k·r`; on `UNWARP` restore them and scale the top bound by `k` |
//! | `TWARP` | [`format::twarp`] | – | a turbulence warp: `p ← ω⁻¹(p)`, `r ← r + reach`, closed by an `UNWARP` ([`noise`]) |
//!
//! Every subtree pushes exactly one `(value, bound)` pair and every node is 0 outside its
//! support box, so a guard may stand in for any subtree: a blend's BVH becomes nested
//! guards ([`TapeBuilder::combine_bvh`]) — a stackless BVH with escape indices. n-ary
//! nodes are emitted as chains of binary ops, which keeps the stack shallow.
//!
//! * [`mod@format`]: the instruction word, op codes, shape kinds, flags, limits and the named
//!   offset of every parameter — the definitions.
//! * [`header`]: `crates/render/shaders/tape_consts.wgsl`, the WGSL constants generated from them.
//! * [`builder`]: [`TapeBuilder`], which emits a tape and checks its balance and depth.
//! * [`from_tree`]: a compiled [`crate::field::Tree`] as a tape ([`tape_from_tree`]).
//! * [`interpreter`]: [`Tape`] and its CPU interpreter, the twin of `crates/render/shaders/field.wgsl`:
//!   the CPU tracer renders exactly what the GPU renders.
//! * [`features`]: which parts of the WGSL evaluator a tape uses.
//! * The leaves' encodings and CPU twins: [`mod@shape`] (`PRIM`), [`mod@height`]
//!   (`HEIGHT`), [`noise`] (fBm, `NPRIM`, `TWARP`), [`mod@sfield`] (`SFIELD`).
//!
//! The tape knows nothing of the GPU: the renderer's GPU path uploads it and runs the WGSL.

pub mod builder;
pub mod features;
pub mod format;
pub mod from_tree;
pub mod height;
pub mod interpreter;
pub mod noise;
pub mod sfield;
pub mod shape;

pub use builder::{Combine, Guard, TapeBuilder};
pub use features::FEATURES;
pub use format::Instr;
pub use from_tree::tape_from_tree;
pub use height::HeightGrid;
pub use interpreter::Tape;
pub use shape::{Profile, Shape};

/// Errors of encoding a field as a tape.
#[derive(Debug, thiserror::Error)]
pub enum TapeError {
    /// The builder was misused or given data it cannot encode.
    #[error("cannot encode the tree for the GPU: {0}")]
    Invalid(String),
    /// A node of the tree has no tape encoding (yet).
    #[error("{node} has no GPU encoding: {why}")]
    NoEncoding {
        /// The node, by user name or arena index, and its kind.
        node: String,
        /// What is missing.
        why: String,
    },
    /// The data exceeds what the tape can address.
    #[error("{0}")]
    Limits(String),
}

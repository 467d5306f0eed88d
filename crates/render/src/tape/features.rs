//! The parts of the WGSL evaluator a tape uses: each is a pipeline-overridable `bool` of
//! the shaders (declared in the generated header), so the GPU compiles a pipeline per set
//! without the others' code (llvmpipe runs every branch of the interpreter with masks, so
//! unused ops would cost on every step).

use super::Tape;
use super::format::{flag, op, sfield, shape};

/// The pipeline-overridable constants of the WGSL evaluator that switch parts of it on,
/// by bit of [`Tape::features`].
pub const FEATURES: [&str; 10] = [
    "USE_NPRIM",
    "USE_HEIGHT",
    "USE_BICUBIC",
    "USE_HEIGHT_DETAIL",
    "USE_SFIELD",
    "USE_SF_CUBIC",
    "USE_SF_NOISE",
    "USE_TWARP",
    "USE_CONE",
    "USE_ELLIPSOID",
];

impl Tape {
    /// The parts of the GPU evaluator this tape uses, a bit per name of [`FEATURES`].
    pub fn features(&self) -> u32 {
        let on = |name: &str| 1u32 << FEATURES.iter().position(|&f| f == name).expect("a feature");
        let mut bits = match self.ground {
            Some((flags, _)) if flags & flag::BICUBIC != 0 => on("USE_HEIGHT") | on("USE_BICUBIC"),
            Some(_) => on("USE_HEIGHT"),
            None => 0,
        };
        for ins in &self.instrs {
            let at = |k: usize| self.params[ins.param as usize + k];
            bits |= match ins.op {
                op::PRIM | op::NPRIM => {
                    let shape = match ins.flags & flag::SHAPE_MASK {
                        shape::CONE => on("USE_CONE"),
                        shape::ELLIPSOID => on("USE_ELLIPSOID"),
                        _ => 0,
                    };
                    shape
                        | if ins.op == op::NPRIM {
                            on("USE_NPRIM")
                        } else {
                            0
                        }
                }
                op::HEIGHT => {
                    let on_if = |f: u32, name: &str| if ins.flags & f != 0 { on(name) } else { 0 };
                    on("USE_HEIGHT")
                        | on_if(flag::BICUBIC, "USE_BICUBIC")
                        | on_if(flag::DETAIL, "USE_HEIGHT_DETAIL")
                }
                op::SFIELD => {
                    on("USE_SFIELD")
                        | if at(sfield::TRICUBIC) != 0.0 {
                            on("USE_SF_CUBIC")
                        } else {
                            0
                        }
                        | if at(sfield::NOISY) != 0.0 {
                            on("USE_SF_NOISE")
                        } else {
                            0
                        }
                }
                op::TWARP => on("USE_TWARP"),
                _ => 0,
            };
        }
        bits
    }

    /// The values of [`FEATURES`] for the feature bits `bits`.
    pub fn feature_constants(bits: u32) -> Vec<(&'static str, f64)> {
        FEATURES
            .iter()
            .enumerate()
            .map(|(k, &name)| (name, f64::from((bits >> k) & 1)))
            .collect()
    }
}

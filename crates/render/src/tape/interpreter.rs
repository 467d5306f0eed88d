//! The CPU interpreter of a [`Tape`]: the twin of `eval_tape` in `crates/render/shaders/field.wgsl`, with
//! the same arithmetic, so the CPU tracer renders exactly what the GPU renders (the tests
//! compare the two), and the tape is a [`Field`] like the tree it encodes.

use std::sync::Arc;

use glam::Vec3;

use super::format::{Instr, constant, get3, guard, limit, op, replace, twarp, unwarp, warp};
use super::noise::{noisy_primitive, twarp_apply};
use super::{height, sfield, shape};
use crate::field::bound::mix_lipschitz;
use crate::field::{Aabb, Fbm, Field, ISO, Interval, Transition};
use crate::voxel::SField;

/// A compiled tape: what the GPU uploads, and a [`Field`] on the CPU.
#[derive(Clone, Debug)]
pub struct Tape {
    /// Instructions in evaluation order.
    pub instrs: Vec<Instr>,
    /// Parameters of all instructions.
    pub params: Vec<f32>,
    /// Heightfield samples of all `HEIGHT` leaves.
    pub heights: Vec<f32>,
    /// The turbulences of `NPRIM` and `TWARP`, by the index in their parameters: the CPU
    /// evaluates them with these, the GPU from their encoding.
    pub noises: Vec<Fbm>,
    /// The brick tables of all `SFIELD` leaves ([`super::sfield`]).
    pub sf_table: Vec<u32>,
    /// The samples of all `SFIELD` leaves.
    pub sf_data: Vec<f32>,
    /// The `SFIELD` leaves themselves, by index: the CPU evaluates them.
    pub sfields: Vec<Arc<SField>>,
    /// The scene's terrain for the materials (the materials' ground), when
    /// given ([`Tape::with_ground`]): the `HEIGHT` flags and parameter offset of its
    /// encoding, which no instruction evaluates.
    pub ground: Option<(u32, u32)>,
    pub(super) support: Aabb,
    pub(super) lipschitz: f32,
    pub(super) grad_step: f32,
}

impl Tape {
    /// The step of the tetrahedral finite differences used for gradients (shared with
    /// the GPU so both shade with the same normals).
    pub fn grad_step(&self) -> f32 {
        self.grad_step
    }

    /// `(f(p), λ)` with `λ` a Lipschitz bound of `f` over the ball `B(c, r)`: the CPU twin
    /// of `eval_tape` in `crates/render/shaders/field.wgsl`.
    pub fn eval(&self, p: Vec3, c: Vec3, r: f32) -> (f32, f32) {
        self.run::<true>(p, c, r)
    }

    /// The tape run; `BOUND`: compute the bound (else the second component is
    /// meaningless). Where `p = c` the primitives share their distances.
    fn run<const BOUND: bool>(&self, p: Vec3, c: Vec3, r: f32) -> (f32, f32) {
        let mut stack = [(0.0f32, 0.0f32); limit::MAX_STACK];
        let mut sp = 0usize;
        let mut frames = [(Vec3::ZERO, Vec3::ZERO, 0.0f32); limit::MAX_WARPS];
        let mut fp = 0usize;
        let (mut p, mut c, mut r) = (p, c, r);
        let mut pc = 0usize;
        let prm = &self.params;
        while pc < self.instrs.len() {
            let ins = self.instrs[pc];
            let o = ins.param as usize;
            match ins.op {
                op::CONST => {
                    stack[sp] = (prm[o + constant::VALUE], 0.0);
                    sp += 1;
                }
                op::PRIM => {
                    stack[sp] = shape::primitive::<BOUND>(ins.flags, &prm[o..], p, c, r);
                    sp += 1;
                }
                op::NPRIM => {
                    stack[sp] =
                        noisy_primitive(ins.flags, &prm[o..], &self.noises, (p, c, r), BOUND);
                    sp += 1;
                }
                op::HEIGHT => {
                    stack[sp] = height::eval::<BOUND>(
                        (&self.heights, &self.noises),
                        ins.flags,
                        &prm[o..],
                        p,
                        c,
                        r,
                    );
                    sp += 1;
                }
                op::SFIELD => {
                    let sf = &self.sfields[ins.flags as usize];
                    stack[sp] = sfield::eval(sf, (p, c, r), BOUND);
                    sp += 1;
                }
                op::BLEND | op::UNION | op::INTER | op::DIFF => {
                    let (b, a) = (stack[sp - 1], stack[sp - 2]);
                    sp -= 1;
                    stack[sp - 1] = match ins.op {
                        op::BLEND => (a.0 + b.0, a.1 + b.1),
                        op::UNION => (a.0.max(b.0), a.1.max(b.1)),
                        op::INTER => (a.0.min(b.0), a.1.max(b.1)),
                        _ => (a.0.min(2.0 * ISO - b.0), a.1.max(b.1)),
                    };
                }
                op::REPLACE => {
                    let (b, a) = (stack[sp - 1], stack[sp - 2]);
                    sp -= 1;
                    stack[sp - 1] = replace(&prm[o..], a, b, (p, c, r));
                }
                op::GUARD => {
                    let bx = Aabb {
                        min: get3(prm, o + guard::MIN),
                        max: get3(prm, o + guard::MAX),
                    };
                    if !bx.contains(p) && bx.distance(c) > r {
                        stack[sp] = (0.0, 0.0);
                        sp += 1;
                        pc = ins.jump as usize;
                        continue;
                    }
                }
                op::WARP => {
                    frames[fp] = (p, c, r);
                    fp += 1;
                    p = affine(&prm[o..], p);
                    c = affine(&prm[o..], c);
                    r *= prm[o + warp::NORM];
                }
                op::TWARP => {
                    frames[fp] = (p, c, r);
                    fp += 1;
                    p = twarp_apply(&prm[o..], &self.noises, p);
                    r += prm[o + twarp::REACH];
                }
                op::UNWARP => {
                    fp -= 1;
                    (p, c, r) = frames[fp];
                    stack[sp - 1].1 *= prm[o + unwarp::SCALE];
                }
                _ => unreachable!("the builder emits only known ops"),
            }
            pc += 1;
        }
        stack[0]
    }
}

/// `REPLACE` of the entries `a` (the base) and `b` at `p`, with its bound over the ball
/// `B(c, r)`: the weight's range there comes from its depth, which is 1-Lipschitz.
fn replace(q: &[f32], a: (f32, f32), b: (f32, f32), (p, c, r): (Vec3, Vec3, f32)) -> (f32, f32) {
    let mix = Transition::new(
        Aabb {
            min: get3(q, replace::MIN),
            max: get3(q, replace::MAX),
        },
        q[replace::WIDTH],
    );
    let value = a.0 + mix.weight(p) * (b.0 - a.0);
    let dc = mix.depth(c);
    let w = Interval::new(mix.ramp(dc - r), mix.ramp(dc + r));
    // |b − a| over the ball: from the values at p and the slopes, or the ranges.
    let gap = ((b.0 - a.0).abs() + (a.1 + b.1) * (p.distance(c) + r)).min(q[replace::GAP]);
    (value, mix_lipschitz(w, a.1, b.1, gap, mix.lipschitz()))
}

/// `M⁻¹p` for the `WARP` parameters `q` ([`warp::MATRIX`]: 3 rows of 4).
fn affine(q: &[f32], p: Vec3) -> Vec3 {
    let m = &q[warp::MATRIX..];
    let p4 = |k: usize| m[k] * p.x + m[k + 1] * p.y + m[k + 2] * p.z + m[k + 3];
    Vec3::new(p4(0), p4(4), p4(8))
}

impl Field for Tape {
    fn value(&self, p: Vec3) -> f32 {
        self.run::<false>(p, p, 0.0).0
    }

    /// Tetrahedral finite differences with step [`Tape::grad_step`], as on the GPU.
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let h = self.grad_step;
        let k = [
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(1.0, 1.0, 1.0),
        ];
        let g = k
            .iter()
            .fold(Vec3::ZERO, |g, &d| g + d * self.value(p + d * h))
            / (4.0 * h);
        (self.value(p), g)
    }

    fn support(&self) -> Aabb {
        self.support
    }

    fn interval(&self, b: &Aabb) -> Interval {
        let c = b.center();
        let r = b.radius();
        let (v, l) = self.eval(c, c, r);
        Interval::new(v - l * r, v + l * r)
    }

    fn lipschitz(&self) -> f32 {
        self.lipschitz
    }

    fn lipschitz_box(&self, b: &Aabb) -> f32 {
        let c = b.center();
        self.eval(c, c, b.radius()).1
    }

    fn lipschitz_segment(&self, a: Vec3, b: Vec3) -> f32 {
        let c = 0.5 * (a + b);
        self.eval(c, c, 0.5 * a.distance(b)).1
    }
}

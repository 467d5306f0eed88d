//! [`TapeBuilder`]: emits a [`Tape`] in evaluation order (post-order: children, then the
//! combining op), tracking each stack entry's support box and range of values so that
//! guards are checked and the tape's support is known, and refusing unbalanced tapes and
//! tapes deeper than the WGSL evaluator's [`limit`]s.

use std::sync::Arc;

use glam::{Affine3A, Vec3};

use super::format::{
    Instr, constant, flag, get3, guard, limit, op, prim, replace, set3, unwarp, warp,
};
use super::height::{self, HeightGrid};
use super::noise::{nprim_head, twarp_params};
use super::shape::{Profile, Shape};
use super::{Tape, TapeError, sfield};
use crate::field::bound::gap;
use crate::field::{Aabb, Fbm, Field, ISO, Interval, Noise, Transition, Warp};
use crate::voxel::SField;

/// Ball radius standing for "everywhere" when computing the global bound.
const EVERYWHERE: f32 = 1e30;

/// Binary combination of the two top stack entries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Combine {
    /// `a + b`.
    Blend,
    /// `max(a, b)`.
    Union,
    /// `min(a, b)`.
    Intersection,
    /// `min(a, 2T − b)`: `b` carved out of `a`.
    Difference,
}

/// Where a guard opened by [`TapeBuilder::guard_begin`] sits, to close it.
#[must_use]
#[derive(Debug)]
pub struct Guard {
    at: usize,
    depth: usize,
}

/// What the builder knows of each stack entry.
#[derive(Clone, Copy, Debug)]
struct Entry {
    support: Aabb,
    range: Interval,
}

const EVERYWHERE_BOX: Aabb = Aabb {
    min: Vec3::splat(f32::NEG_INFINITY),
    max: Vec3::splat(f32::INFINITY),
};

/// A warp opened by the builder.
#[derive(Debug)]
enum OpenWarp {
    /// Affine: `M` and `M⁻¹`.
    Affine(Affine3A, Affine3A),
    /// Turbulence: how far it moves points, and its Lipschitz bound.
    Turbulence { reach: f32, lipschitz: f32 },
}

/// Builds a [`Tape`] in evaluation order (post-order: children, then the combining op).
#[derive(Debug, Default)]
pub struct TapeBuilder {
    instrs: Vec<Instr>,
    params: Vec<f32>,
    heights: Vec<f32>,
    noises: Vec<Fbm>,
    sf_table: Vec<u32>,
    sf_data: Vec<f32>,
    sfields: Vec<Arc<SField>>,
    stack: Vec<Entry>,
    max_stack: usize,
    /// Open warps: stack depth at entry, and the warp.
    warps: Vec<(usize, OpenWarp)>,
    max_warps: usize,
    guards: usize,
}

impl TapeBuilder {
    /// An empty tape.
    pub fn new() -> Self {
        Self::default()
    }

    fn emit(&mut self, op: u32, flags: u32, params: &[f32]) {
        let param = self.params.len() as u32;
        self.params.extend_from_slice(params);
        self.instrs.push(Instr {
            op,
            flags,
            jump: 0,
            param,
        });
    }

    fn push(&mut self, e: Entry) {
        self.stack.push(e);
        self.max_stack = self.max_stack.max(self.stack.len());
    }

    fn pop(&mut self, what: &str) -> Result<Entry, TapeError> {
        self.stack.pop().ok_or_else(|| {
            TapeError::Invalid(format!("{what} needs an operand but the stack is empty"))
        })
    }

    /// Pushes a constant.
    pub fn constant(&mut self, v: f32) {
        let mut q = [0.0; constant::VALUE + 1];
        q[constant::VALUE] = v;
        self.emit(op::CONST, 0, &q);
        let support = if v == 0.0 {
            Aabb::EMPTY
        } else {
            EVERYWHERE_BOX
        };
        self.push(Entry {
            support,
            range: Interval::point(v),
        });
    }

    /// Pushes a skeletal primitive.
    pub fn primitive(&mut self, shape: Shape, profile: Profile) {
        let (r, e, sigma, range) = match profile {
            Profile::Wyvill { radius, energy } => (radius, energy, 0, Interval::new(0.0, energy)),
            Profile::Sigma { radius } => (radius, 1.0, flag::SIGMA, Interval::new(0.0, 2.0 * ISO)),
        };
        let mut p = vec![0.0; prim::SHAPE];
        p[prim::RADIUS] = r;
        p[prim::ENERGY] = e;
        let kind = shape.encode(&mut p);
        self.emit(op::PRIM, kind | sigma, &p);
        self.push(Entry {
            support: shape.bounds(r),
            range,
        });
    }

    /// Pushes the noisy primitive `energy · g(d̃)` of Paris et al. 2019 §5.2 around a convex shape
    /// (not a prism), with [`crate::field::Primitive`]'s anisotropic distance `d̃`.
    pub fn noisy_primitive(
        &mut self,
        shape: Shape,
        radius: f32,
        energy: f32,
        noise: &Noise,
    ) -> Result<(), TapeError> {
        if matches!(shape, Shape::Prism { .. }) {
            return Err(TapeError::Invalid("a prism cannot carry noise".into()));
        }
        let mut p = nprim_head(radius, energy, noise, self.noises.len()).to_vec();
        self.noises.push(noise.fbm);
        let kind = shape.encode(&mut p);
        self.emit(op::NPRIM, kind, &p);
        self.push(Entry {
            support: shape.bounds((radius + noise.amplitude) * 1.000_01),
            range: Interval::new(0.0, energy),
        });
        Ok(())
    }

    /// Pushes `σ(h(x, y) − z, falloff)` for a heightfield (clamped at its edges).
    /// Solid below the surface and unbounded: intersect it with a prism (Paris et al. 2019 §5.1).
    pub fn heightfield(&mut self, grid: &HeightGrid<'_>, falloff: f32) -> Result<(), TapeError> {
        let (flags, q) = height::encode(grid, falloff, &mut self.heights, &mut self.noises)?;
        self.emit(op::HEIGHT, flags, &q);
        self.push(Entry {
            support: EVERYWHERE_BOX,
            range: Interval::new(0.0, 2.0 * ISO),
        });
        Ok(())
    }

    /// Pushes the S-field leaf `sf` (its grids go to [`Tape::sf_table`] and
    /// [`Tape::sf_data`]); `what` names it in errors. An empty field is the constant 0.
    pub fn sfield(&mut self, sf: &SField, what: &str) -> Result<(), TapeError> {
        if sf.is_empty() {
            self.constant(0.0);
            return Ok(());
        }
        let q = sfield::encode(sf, &mut self.sf_table, &mut self.sf_data, what)?;
        let index = self.sfields.len() as u32;
        self.sfields.push(Arc::new(sf.clone()));
        self.emit(op::SFIELD, index, &q);
        self.push(Entry {
            support: sf.support(),
            range: Interval::new(0.0, 2.0 * ISO),
        });
        Ok(())
    }

    /// Combines the two top entries.
    pub fn combine(&mut self, how: Combine) -> Result<(), TapeError> {
        let b = self.pop("a combination")?;
        let a = self.pop("a combination")?;
        let (code, e) = match how {
            Combine::Blend => (
                op::BLEND,
                Entry {
                    support: a.support.union(b.support),
                    range: a.range + b.range,
                },
            ),
            Combine::Union => (
                op::UNION,
                Entry {
                    support: a.support.union(b.support),
                    range: a.range.max(b.range),
                },
            ),
            Combine::Intersection => (
                op::INTER,
                Entry {
                    // Outside one support the result is min(0, other): zero unless the
                    // other can be negative.
                    support: if a.range.lo < 0.0 || b.range.lo < 0.0 {
                        a.support.union(b.support)
                    } else {
                        a.support.intersection(b.support)
                    },
                    range: a.range.min(b.range),
                },
            ),
            Combine::Difference => {
                let carved = Interval::new(2.0 * ISO - b.range.hi, 2.0 * ISO - b.range.lo);
                // Outside a's support the result is min(0, 2T − b): zero unless b > 2T.
                let support = if b.range.hi <= 2.0 * ISO {
                    a.support
                } else {
                    a.support.union(b.support)
                };
                (
                    op::DIFF,
                    Entry {
                        support,
                        range: a.range.min(carved),
                    },
                )
            }
        };
        self.emit(code, 0, &[]);
        self.push(e);
        Ok(())
    }

    /// Replaces the entry below the top (the base) by the top one (`by`) inside `mix`'s
    /// region, with its smooth transition ([`Transition`]).
    pub fn replace(&mut self, mix: &Transition) -> Result<(), TapeError> {
        let by = self.pop("a replacement")?;
        let base = self.pop("a replacement")?;
        let region = *mix.region();
        let mut q = [0.0; replace::LEN];
        set3(&mut q, replace::MIN, region.min);
        set3(&mut q, replace::MAX, region.max);
        q[replace::WIDTH] = mix.width();
        q[replace::GAP] = gap(base.range, by.range);
        self.emit(op::REPLACE, 0, &q);
        self.push(Entry {
            support: base.support.union(by.support.intersection(region)),
            range: base.range.hull(by.range),
        });
        Ok(())
    }

    /// Opens a guard: the subtree emitted until [`TapeBuilder::guard_end`] is skipped where
    /// it cannot matter. `b` must contain the subtree's support (checked at the end).
    pub fn guard_begin(&mut self, b: Aabb) -> Guard {
        let at = self.instrs.len();
        let mut q = [0.0; guard::LEN];
        set3(&mut q, guard::MIN, b.min);
        set3(&mut q, guard::MAX, b.max);
        self.emit(op::GUARD, 0, &q);
        self.guards += 1;
        Guard {
            at,
            depth: self.stack.len(),
        }
    }

    /// Closes a guard around exactly one pushed subtree.
    pub fn guard_end(&mut self, g: Guard) -> Result<(), TapeError> {
        if self.stack.len() != g.depth + 1 {
            return Err(TapeError::Invalid(format!(
                "a guard must enclose exactly one subtree, it encloses {}",
                self.stack.len() as isize - g.depth as isize
            )));
        }
        let p = self.instrs[g.at].param as usize;
        let b = Aabb {
            min: get3(&self.params, p + guard::MIN),
            max: get3(&self.params, p + guard::MAX),
        };
        let top = self.stack.last_mut().expect("checked above");
        if !top.support.is_empty() && !b.contains_box(&top.support) {
            return Err(TapeError::Invalid(format!(
                "guard box {b:?} does not contain its subtree's support {:?}",
                top.support
            )));
        }
        self.instrs[g.at].jump = self.instrs.len() as u32;
        self.guards -= 1;
        Ok(())
    }

    /// Declares that the top subtree vanishes outside `b`, when the caller knows a tighter
    /// support than the builder's own estimate (a compiled tree's cached supports): the
    /// entry's support becomes its intersection with `b`. `b` must be sound — the guards
    /// checked against it and the tape's [`Field::support`] trust it.
    pub fn assume_support(&mut self, b: Aabb) -> Result<(), TapeError> {
        let top = self
            .stack
            .last_mut()
            .ok_or_else(|| TapeError::Invalid("assume_support on an empty stack".into()))?;
        top.support = top.support.intersection(b);
        Ok(())
    }

    /// Enters an affine warp `x ↦ M x` of the subtree emitted until
    /// [`TapeBuilder::warp_end`]: the subtree is evaluated at `M⁻¹p`.
    pub fn warp_begin(&mut self, m: Affine3A) -> Result<(), TapeError> {
        self.warp_enter(m, m.inverse())
    }

    /// [`TapeBuilder::warp_begin`] given `M⁻¹` (parent to child space), as a compiled
    /// tree stores it: the tape then evaluates the subtree at exactly the tree's points.
    pub fn warp_begin_inverse(&mut self, to_child: Affine3A) -> Result<(), TapeError> {
        self.warp_enter(to_child.inverse(), to_child)
    }

    fn warp_enter(&mut self, m: Affine3A, inv: Affine3A) -> Result<(), TapeError> {
        if !(m.matrix3.determinant().abs() > 1e-12 && inv.is_finite() && m.is_finite()) {
            return Err(TapeError::Invalid(format!(
                "affine warp {m:?} is not invertible"
            )));
        }
        self.emit(op::WARP, 0, &warp_params(&inv));
        self.open_warp(OpenWarp::Affine(m, inv));
        Ok(())
    }

    fn open_warp(&mut self, w: OpenWarp) {
        self.warps.push((self.stack.len(), w));
        self.max_warps = self.max_warps.max(self.warps.len());
    }

    /// Enters the turbulence warp `w` (Paris et al. 2019 §5.3) of the subtree emitted until
    /// [`TapeBuilder::warp_end`]: the subtree is evaluated at `ω⁻¹(p)`.
    pub fn turbulence_begin(&mut self, w: &Warp) -> Result<(), TapeError> {
        if !(w.reach().is_finite() && w.lipschitz().is_finite()) {
            return Err(TapeError::Invalid(format!(
                "turbulence warp of amplitude {} is not finite",
                w.amplitude()
            )));
        }
        let q = twarp_params(w, self.noises.len());
        self.noises.extend_from_slice(w.turbulence());
        self.emit(op::TWARP, 0, &q);
        self.open_warp(OpenWarp::Turbulence {
            reach: w.reach(),
            lipschitz: w.lipschitz(),
        });
        Ok(())
    }

    /// Leaves the innermost warp; it must enclose exactly one subtree.
    pub fn warp_end(&mut self) -> Result<(), TapeError> {
        let (depth, w) = self
            .warps
            .pop()
            .ok_or_else(|| TapeError::Invalid("warp_end without warp_begin".into()))?;
        if self.stack.len() != depth + 1 {
            return Err(TapeError::Invalid(
                "a warp must enclose exactly one subtree".into(),
            ));
        }
        let mut q = [0.0; unwarp::SCALE + 1];
        q[unwarp::SCALE] = match &w {
            OpenWarp::Affine(_, inv) => warp_params(inv)[warp::NORM],
            OpenWarp::Turbulence { lipschitz, .. } => *lipschitz,
        };
        self.emit(op::UNWARP, 0, &q);
        let top = self.stack.last_mut().expect("checked above");
        if !top.support.is_empty() && top.support.min.is_finite() && top.support.max.is_finite() {
            top.support = match w {
                OpenWarp::Affine(m, _) => {
                    Aabb::from_points(top.support.corners().map(|c| m.transform_point3(c)))
                }
                OpenWarp::Turbulence { reach, .. } => top.support.dilate(reach),
            };
        }
        Ok(())
    }

    /// Emits `children` (each pushes one subtree, its support inside `boxes[i]`) combined
    /// with `how`, under a BVH of guards: a median split on the longest axis of the box
    /// centres, groups of at most 4 children at the leaves.
    pub fn combine_bvh(
        &mut self,
        how: Combine,
        boxes: &[Aabb],
        emit: &mut dyn FnMut(&mut TapeBuilder, usize) -> Result<(), TapeError>,
    ) -> Result<(), TapeError> {
        if boxes.is_empty() {
            return Err(TapeError::Invalid(
                "combine_bvh needs at least one child".into(),
            ));
        }
        let mut order: Vec<usize> = (0..boxes.len()).collect();
        self.bvh_node(how, boxes, &mut order, emit)
    }

    fn bvh_node(
        &mut self,
        how: Combine,
        boxes: &[Aabb],
        order: &mut [usize],
        emit: &mut dyn FnMut(&mut TapeBuilder, usize) -> Result<(), TapeError>,
    ) -> Result<(), TapeError> {
        let bounds = order.iter().fold(Aabb::EMPTY, |b, &i| b.union(boxes[i]));
        let g = self.guard_begin(bounds);
        if order.len() <= 4 {
            for (k, &i) in order.iter().enumerate() {
                emit(self, i)?;
                if k > 0 {
                    self.combine(how)?;
                }
            }
        } else {
            let cb = Aabb::from_points(order.iter().map(|&i| boxes[i].center()));
            let axis = cb.size().max_position();
            order.sort_by(|&a, &b| boxes[a].center()[axis].total_cmp(&boxes[b].center()[axis]));
            let mid = order.len() / 2;
            let (left, right) = order.split_at_mut(mid);
            self.bvh_node(how, boxes, left, emit)?;
            self.bvh_node(how, boxes, right, emit)?;
            self.combine(how)?;
        }
        self.guard_end(g)
    }

    /// Finishes the tape: exactly one value must be on the stack, every guard and warp
    /// closed, and the depths within the WGSL evaluator's limits.
    pub fn finish(self) -> Result<Tape, TapeError> {
        if self.stack.len() != 1 || self.guards != 0 || !self.warps.is_empty() {
            return Err(TapeError::Invalid(format!(
                "unbalanced tape: {} values on the stack, {} open guards, {} open warps",
                self.stack.len(),
                self.guards,
                self.warps.len()
            )));
        }
        if self.max_stack > limit::MAX_STACK || self.max_warps > limit::MAX_WARPS {
            return Err(TapeError::Invalid(format!(
                "tree too deep for the GPU evaluator: stack {} (max {}), warps {} (max {})",
                self.max_stack,
                limit::MAX_STACK,
                self.max_warps,
                limit::MAX_WARPS
            )));
        }
        let support = self.stack[0].support;
        let mut tape = Tape {
            instrs: self.instrs,
            params: self.params,
            heights: self.heights,
            noises: self.noises,
            sf_table: self.sf_table,
            sf_data: self.sf_data,
            sfields: self.sfields,
            ground: None,
            support,
            lipschitz: 0.0,
            grad_step: 0.0,
        };
        tape.lipschitz = tape.eval(Vec3::ZERO, Vec3::ZERO, EVERYWHERE).1;
        let size = if support.min.is_finite() && support.max.is_finite() {
            support.radius()
        } else {
            1.0
        };
        tape.grad_step = 1e-4 * size.max(1e-3);
        Ok(tape)
    }
}

/// The `WARP` parameters of `M⁻¹` ([`warp`]).
fn warp_params(inv: &Affine3A) -> [f32; warp::LEN] {
    let m = inv.matrix3;
    let t = inv.translation;
    let mut q = [0.0; warp::LEN];
    q[warp::MATRIX..warp::MATRIX + 12].copy_from_slice(&[
        m.x_axis.x, m.y_axis.x, m.z_axis.x, t.x, //
        m.x_axis.y, m.y_axis.y, m.z_axis.y, t.y, //
        m.x_axis.z, m.y_axis.z, m.z_axis.z, t.z, //
    ]);
    // ‖M⁻¹‖₂ ≤ Frobenius norm.
    q[warp::NORM] =
        (m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared()).sqrt();
    q
}

//! The GPU encoding of a field: a flat **tape** of instructions evaluated with a small
//! value stack, plus a parameter array and a buffer of heightfield samples.
//!
//! One pass over the tape at `(p, c, r)` returns both `f(p)` and a Lipschitz bound of `f`
//! over the ball `B(c, r)` — exactly what one step of segment tracing needs (the ball
//! around a candidate segment). `r = 0` gives the value alone.
//!
//! | op | params at `param` | stack | meaning |
//! | --- | --- | --- | --- |
//! | `CONST` | `v` | push | constant `v` (Lipschitz 0) |
//! | `PRIM` | `R, e, shape…` | push | `e·g(max(sd, 0)/R)` (Wyvill) or `σ(−sd, R)` (σ, `flags` bit 8); `sd` = signed distance to the shape (`flags & 0xff`: sphere `c, ρ`; capsule `a, b, ρ`; box `c, half`; heightfield prism `min, max`) |
//! | `HEIGHT` | `R, n, ox, oy, cell, nx, ny, offset, level₀ … levelₙ₋₁` | push | `σ(h(x, y) − z, R)`, `h` bilinear (Catmull-Rom bicubic with `flags` bit 0) in `heights[offset..]`; the ball's slope of `h` from a max pyramid of `n` levels of per-cell bounds of `|∇h|` at `heights[levelₖ..]` ([`slope_under`]) |
//! | `NPRIM` | see [`super::noise`] | push | a noisy primitive `E·g(d̃)` on a convex shape |
//! | `SFIELD` | see [`super::sfield`] | push | an S-field leaf (`flags`: its index in [`Tape::sfields`]) |
//! | `BLEND` / `UNION` / `INTER` / `DIFF` | – | pop 2, push 1 | `a + b`, `max`, `min`, `min(a, 2T − b)` |
//! | `GUARD` | `min.xyz, max.xyz` | – | when neither `p` nor the ball touches the box, push `(0, 0)` and jump to `jump` (the instruction after the guarded subtree) |
//! | `WARP` / `UNWARP` | `M⁻¹` (3 rows of 4), `k = ‖M⁻¹‖` / `k` | – | `p, c ← M⁻¹p, M⁻¹c`, `r ← k·r`; on `UNWARP` restore them and scale the top bound by `k` |
//! | `TWARP` | see [`super::noise`] | – | a turbulence warp: `p ← ω⁻¹(p)`, `r ← r + reach`, closed by an `UNWARP` |
//!
//! Every subtree pushes exactly one `(value, bound)` pair and every node is 0 outside its
//! support box, so a guard may stand in for any subtree: a blend's BVH becomes nested
//! guards ([`TapeBuilder::combine_bvh`]) — a stackless BVH with escape indices. n-ary
//! nodes are emitted as chains of binary ops, which keeps the stack shallow.
//!
//! [`Tape`] implements [`Field`] with the same arithmetic as `shaders/field.wgsl`, so the
//! CPU tracer renders exactly what the GPU renders; the tests compare the two.

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::{Affine3A, Vec2, Vec3, Vec3A};

use super::GpuError;
use super::noise::{noisy_primitive, nprim_head, twarp_apply, twarp_params};
use crate::dem::{Heightfield, Interpolation, MinMaxPyramid};
use crate::field::falloff::{sigma, sigma_slope, wyvill, wyvill_slope};
use crate::field::{Aabb, Fbm, Field, Interval, Noise, T, Warp};
use crate::voxel::SField;

/// One tape instruction: 16 bytes, `vec4<u32>` in WGSL.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct Instr {
    /// Operation code ([`op`]).
    pub op: u32,
    /// Operation-specific flags (shape and profile of a primitive).
    pub flags: u32,
    /// Jump target of a guard: the index just past its subtree.
    pub jump: u32,
    /// Offset of the instruction's parameters in [`Tape::params`].
    pub param: u32,
}

/// Operation codes, shared with `shaders/field.wgsl`.
pub mod op {
    /// Push a constant.
    pub const CONST: u32 = 0;
    /// Push a skeletal primitive.
    pub const PRIM: u32 = 1;
    /// Push a heightfield's `σ(h − z)`.
    pub const HEIGHT: u32 = 2;
    /// Push a noisy primitive.
    pub const NPRIM: u32 = 3;
    /// Push an S-field leaf.
    pub const SFIELD: u32 = 4;
    /// Sum of the two top entries.
    pub const BLEND: u32 = 16;
    /// Maximum.
    pub const UNION: u32 = 17;
    /// Minimum.
    pub const INTER: u32 = 18;
    /// `min(a, 2T − b)`.
    pub const DIFF: u32 = 19;
    /// Skip a subtree whose support box is out of reach.
    pub const GUARD: u32 = 32;
    /// Enter an affine warp.
    pub const WARP: u32 = 33;
    /// Leave an affine or turbulence warp.
    pub const UNWARP: u32 = 34;
    /// Enter a turbulence warp.
    pub const TWARP: u32 = 35;
}

/// Primitive shapes (`flags & 0xff`).
pub mod shape {
    /// Ball `c, ρ` (a point when `ρ = 0`).
    pub const SPHERE: u32 = 0;
    /// Capsule `a, b, ρ` (a segment when `ρ = 0`).
    pub const CAPSULE: u32 = 1;
    /// Box `centre, half-size`.
    pub const BOX: u32 = 2;
    /// A heightfield's prism `min, max` ([`super::Shape::Prism`]).
    pub const PRISM: u32 = 3;
    /// Capped cone `base, axis, height, radius` ([`super::Shape::Cone`]).
    pub const CONE: u32 = 4;
    /// Axis-aligned ellipsoid `centre, radii` ([`super::Shape::Ellipsoid`]).
    pub const ELLIPSOID: u32 = 5;
    /// Flag: σ profile instead of Wyvill.
    pub const SIGMA: u32 = 1 << 8;
}

/// `HEIGHT` flag: Catmull-Rom bicubic interpolation instead of bilinear.
pub const BICUBIC: u32 = 1;

/// Value-stack depth of the WGSL evaluator.
pub const MAX_STACK: usize = 32;
/// Nesting depth of warps in the WGSL evaluator.
pub const MAX_WARPS: usize = 8;
/// Ball radius standing for "everywhere" when computing the global bound.
const EVERYWHERE: f32 = 1e30;

/// The skeleton of a primitive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A point.
    Point(Vec3),
    /// A ball of radius `radius` (its surface is the skeleton's zero distance).
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius, metres.
        radius: f32,
    },
    /// A segment `[a, b]`.
    Segment(Vec3, Vec3),
    /// A capsule around `[a, b]`.
    Capsule {
        /// First end.
        a: Vec3,
        /// Second end.
        b: Vec3,
        /// Radius, metres.
        radius: f32,
    },
    /// An axis-aligned box.
    Box {
        /// Centre.
        center: Vec3,
        /// Half the edge lengths.
        half: Vec3,
    },
    /// A solid capped cone ([`crate::field::skeleton::Cone`]): a disc of `radius` centred
    /// on `base`, normal to the unit `axis`, and the apex at `base + height·axis`.
    Cone {
        /// Centre of the base disc.
        base: Vec3,
        /// Unit axis from the base to the apex.
        axis: Vec3,
        /// Base-to-apex distance.
        height: f32,
        /// Radius of the base.
        radius: f32,
    },
    /// A solid axis-aligned ellipsoid ([`crate::field::skeleton::Ellipsoid`]).
    Ellipsoid {
        /// Centre.
        center: Vec3,
        /// Semi-axes along x, y, z (positive).
        radii: Vec3,
    },
    /// The prism of an implicit heightfield ([`crate::dem::HeightfieldField`], seed 002
    /// §5.1): its distance is `√(d_xy² + d_z²)` with `d_xy` the largest excess of `x, y`
    /// over `[min, max]` (the leaf's `R − clearance` of its rectangle, so `min, max` is the
    /// rectangle eroded by `R`) and `d_z` the distance from `z` to `[min.z, max.z]`. Not a
    /// Euclidean distance at the corners, but 1-Lipschitz like the others.
    Prism {
        /// Lower corner (`min > max` along x or y is allowed: a domain narrower than 2R).
        min: Vec3,
        /// Upper corner.
        max: Vec3,
    },
}

impl Shape {
    fn encode(&self, out: &mut Vec<f32>) -> u32 {
        match *self {
            Shape::Point(c) => Shape::Sphere {
                center: c,
                radius: 0.0,
            }
            .encode(out),
            Shape::Segment(a, b) => Shape::Capsule { a, b, radius: 0.0 }.encode(out),
            Shape::Sphere { center, radius } => {
                out.extend([center.x, center.y, center.z, radius]);
                shape::SPHERE
            }
            Shape::Capsule { a, b, radius } => {
                out.extend([a.x, a.y, a.z, b.x, b.y, b.z, radius]);
                shape::CAPSULE
            }
            Shape::Box { center, half } => {
                out.extend([center.x, center.y, center.z, half.x, half.y, half.z]);
                shape::BOX
            }
            Shape::Prism { min, max } => {
                out.extend([min.x, min.y, min.z, max.x, max.y, max.z]);
                shape::PRISM
            }
            Shape::Cone {
                base,
                axis,
                height,
                radius,
            } => {
                out.extend([
                    base.x, base.y, base.z, axis.x, axis.y, axis.z, height, radius,
                ]);
                shape::CONE
            }
            Shape::Ellipsoid { center, radii } => {
                out.extend([center.x, center.y, center.z, radii.x, radii.y, radii.z]);
                shape::ELLIPSOID
            }
        }
    }

    /// The box where the signed distance is `≤ reach`.
    fn bounds(&self, reach: f32) -> Aabb {
        match *self {
            Shape::Point(c) => Aabb::around(c, reach),
            Shape::Sphere { center, radius } => Aabb::around(center, radius + reach),
            Shape::Segment(a, b) => Aabb::new(a, b).dilate(reach),
            Shape::Capsule { a, b, radius } => Aabb::new(a, b).dilate(radius + reach),
            Shape::Box { center, half } => Aabb::new(center - half, center + half).dilate(reach),
            Shape::Cone {
                base,
                axis,
                height,
                radius,
            } => {
                // The base disc's box (extent `radius·√(1 − aᵢ²)` along axis i) and the apex.
                let ext = (Vec3::ONE - axis * axis).max(Vec3::ZERO).powf(0.5) * radius;
                Aabb::new(base - ext, base + ext)
                    .include(base + axis * height)
                    .dilate(reach)
            }
            Shape::Ellipsoid { center, radii } => {
                Aabb::new(center - radii, center + radii).dilate(reach)
            }
            // Not `Aabb::new`: the corners are kept as given even when min > max.
            Shape::Prism { min, max } => Aabb {
                min: min - Vec3::splat(reach),
                max: max + Vec3::splat(reach),
            },
        }
    }
}

/// How a primitive turns its signed distance `sd` into a field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Profile {
    /// `energy · g(max(sd, 0) / radius)`, Wyvill's `g(x) = (1 − x²)³`.
    Wyvill {
        /// Radius of influence, metres.
        radius: f32,
        /// Energy (negative carves).
        energy: f32,
    },
    /// `σ(−sd, radius)`: `T` on the shape's surface, `2T` deep inside, 0 beyond `radius`.
    Sigma {
        /// Falloff distance, metres.
        radius: f32,
    },
}

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

/// A regular grid of elevations for [`TapeBuilder::heightfield`].
#[derive(Clone, Copy, Debug)]
pub struct HeightGrid<'a> {
    /// Position of sample `(0, 0)`, metres.
    pub origin: Vec2,
    /// Sample spacing, metres.
    pub cell: f32,
    /// Samples along x.
    pub nx: usize,
    /// Samples along y.
    pub ny: usize,
    /// Elevations, x fastest: `z[i + nx·j]` at `origin + cell·(i, j)`.
    pub z: &'a [f32],
    /// Between the samples: bilinear or Catmull-Rom bicubic, as
    /// [`crate::dem::Heightfield::sample`] interpolates.
    pub interpolation: Interpolation,
}

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
    support: Aabb,
    lipschitz: f32,
    grad_step: f32,
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

    fn pop(&mut self, what: &str) -> Result<Entry, GpuError> {
        self.stack.pop().ok_or_else(|| {
            GpuError::Tape(format!("{what} needs an operand but the stack is empty"))
        })
    }

    /// Pushes a constant.
    pub fn constant(&mut self, v: f32) {
        self.emit(op::CONST, 0, &[v]);
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
        let (r, e, flag, range) = match profile {
            Profile::Wyvill { radius, energy } => (radius, energy, 0, Interval::new(0.0, energy)),
            Profile::Sigma { radius } => (radius, 1.0, shape::SIGMA, Interval::new(0.0, 2.0 * T)),
        };
        let mut p = vec![r, e];
        let kind = shape.encode(&mut p);
        self.emit(op::PRIM, kind | flag, &p);
        self.push(Entry {
            support: shape.bounds(r),
            range,
        });
    }

    /// Pushes the noisy primitive `energy · g(d̃)` of seed 002 §5.2 around a convex shape
    /// (not a prism), with [`crate::field::Primitive`]'s anisotropic distance `d̃`.
    pub fn noisy_primitive(
        &mut self,
        shape: Shape,
        radius: f32,
        energy: f32,
        noise: &Noise,
    ) -> Result<(), GpuError> {
        if matches!(shape, Shape::Prism { .. }) {
            return Err(GpuError::Tape("a prism cannot carry noise".into()));
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
    /// Solid below the surface and unbounded: intersect it with a prism (seed 002 §5.1).
    pub fn heightfield(&mut self, grid: &HeightGrid<'_>, falloff: f32) -> Result<(), GpuError> {
        let HeightGrid {
            origin,
            cell,
            nx,
            ny,
            z,
            interpolation,
        } = *grid;
        if nx < 2
            || ny < 2
            || z.len() != nx * ny
            || cell.is_nan()
            || cell <= 0.0
            || z.iter().any(|v| !v.is_finite())
        {
            return Err(GpuError::Tape(format!(
                "heightfield: need at least 2 × 2 finite samples ({nx} × {ny} given, {} values) and a positive cell",
                z.len()
            )));
        }
        // The CPU leaf's own bounds of |∇h| per cell (from its samples or stencil), as a
        // max pyramid, so a ball's slope is that of the cells under it (seed 001 §7.3.1).
        let slopes = Heightfield::new(nx, ny, origin, Vec2::splat(cell), z.to_vec())
            .map_err(|e| GpuError::Tape(format!("heightfield: {e}")))?
            .cell_slopes(interpolation);
        let pyramid = MinMaxPyramid::new(nx - 1, ny - 1, slopes);
        let offset = self.heights.len();
        self.heights.extend_from_slice(z);
        let mut p = vec![
            falloff,
            pyramid.levels().count() as f32,
            origin.x,
            origin.y,
            cell,
            nx as f32,
            ny as f32,
            offset as f32,
        ];
        for (_, _, level) in pyramid.levels() {
            p.push(self.heights.len() as f32);
            self.heights.extend(level.iter().map(|s| s[1]));
        }
        if self.heights.len() >= 1 << 24 {
            return Err(GpuError::Tape(format!(
                "heightfield: {} samples and slopes in all exceed the 2^24 a tape indexes",
                self.heights.len()
            )));
        }
        let flags = match interpolation {
            Interpolation::Bilinear => 0,
            Interpolation::Bicubic => BICUBIC,
        };
        self.emit(op::HEIGHT, flags, &p);
        self.push(Entry {
            support: EVERYWHERE_BOX,
            range: Interval::new(0.0, 2.0 * T),
        });
        Ok(())
    }

    /// Pushes the S-field leaf `sf` (its grids go to [`Tape::sf_table`] and
    /// [`Tape::sf_data`]); `what` names it in errors. An empty field is the constant 0.
    pub fn sfield(&mut self, sf: &SField, what: &str) -> Result<(), GpuError> {
        if sf.is_empty() {
            self.constant(0.0);
            return Ok(());
        }
        let q = super::sfield::encode(sf, &mut self.sf_table, &mut self.sf_data, what)?;
        let index = self.sfields.len() as u32;
        self.sfields.push(Arc::new(sf.clone()));
        self.emit(op::SFIELD, index, &q);
        self.push(Entry {
            support: sf.support(),
            range: Interval::new(0.0, 2.0 * T),
        });
        Ok(())
    }

    /// Combines the two top entries.
    pub fn combine(&mut self, how: Combine) -> Result<(), GpuError> {
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
                let carved = Interval::new(2.0 * T - b.range.hi, 2.0 * T - b.range.lo);
                // Outside a's support the result is min(0, 2T − b): zero unless b > 2T.
                let support = if b.range.hi <= 2.0 * T {
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

    /// Opens a guard: the subtree emitted until [`TapeBuilder::guard_end`] is skipped where
    /// it cannot matter. `b` must contain the subtree's support (checked at the end).
    pub fn guard_begin(&mut self, b: Aabb) -> Guard {
        let at = self.instrs.len();
        self.emit(
            op::GUARD,
            0,
            &[b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z],
        );
        self.guards += 1;
        Guard {
            at,
            depth: self.stack.len(),
        }
    }

    /// Closes a guard around exactly one pushed subtree.
    pub fn guard_end(&mut self, g: Guard) -> Result<(), GpuError> {
        if self.stack.len() != g.depth + 1 {
            return Err(GpuError::Tape(format!(
                "a guard must enclose exactly one subtree, it encloses {}",
                self.stack.len() as isize - g.depth as isize
            )));
        }
        let p = self.instrs[g.at].param as usize;
        let b = Aabb {
            min: Vec3::new(self.params[p], self.params[p + 1], self.params[p + 2]),
            max: Vec3::new(self.params[p + 3], self.params[p + 4], self.params[p + 5]),
        };
        let top = self.stack.last_mut().expect("checked above");
        if !top.support.is_empty() && !b.contains_box(&top.support) {
            return Err(GpuError::Tape(format!(
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
    pub fn assume_support(&mut self, b: Aabb) -> Result<(), GpuError> {
        let top = self
            .stack
            .last_mut()
            .ok_or_else(|| GpuError::Tape("assume_support on an empty stack".into()))?;
        top.support = top.support.intersection(b);
        Ok(())
    }

    /// Enters an affine warp `x ↦ M x` of the subtree emitted until
    /// [`TapeBuilder::warp_end`]: the subtree is evaluated at `M⁻¹p`.
    pub fn warp_begin(&mut self, m: Affine3A) -> Result<(), GpuError> {
        self.warp_enter(m, m.inverse())
    }

    /// [`TapeBuilder::warp_begin`] given `M⁻¹` (parent to child space), as a compiled
    /// tree stores it: the tape then evaluates the subtree at exactly the tree's points.
    pub fn warp_begin_inverse(&mut self, to_child: Affine3A) -> Result<(), GpuError> {
        self.warp_enter(to_child.inverse(), to_child)
    }

    fn warp_enter(&mut self, m: Affine3A, inv: Affine3A) -> Result<(), GpuError> {
        if !(m.matrix3.determinant().abs() > 1e-12 && inv.is_finite() && m.is_finite()) {
            return Err(GpuError::Tape(format!(
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

    /// Enters the turbulence warp `w` (seed 002 §5.3) of the subtree emitted until
    /// [`TapeBuilder::warp_end`]: the subtree is evaluated at `ω⁻¹(p)`.
    pub fn turbulence_begin(&mut self, w: &Warp) -> Result<(), GpuError> {
        if !(w.reach().is_finite() && w.lipschitz().is_finite()) {
            return Err(GpuError::Tape(format!(
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
    pub fn warp_end(&mut self) -> Result<(), GpuError> {
        let (depth, w) = self
            .warps
            .pop()
            .ok_or_else(|| GpuError::Tape("warp_end without warp_begin".into()))?;
        if self.stack.len() != depth + 1 {
            return Err(GpuError::Tape(
                "a warp must enclose exactly one subtree".into(),
            ));
        }
        let k = match &w {
            OpenWarp::Affine(_, inv) => warp_params(inv)[12],
            OpenWarp::Turbulence { lipschitz, .. } => *lipschitz,
        };
        self.emit(op::UNWARP, 0, &[k]);
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
        emit: &mut dyn FnMut(&mut TapeBuilder, usize) -> Result<(), GpuError>,
    ) -> Result<(), GpuError> {
        if boxes.is_empty() {
            return Err(GpuError::Tape(
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
        emit: &mut dyn FnMut(&mut TapeBuilder, usize) -> Result<(), GpuError>,
    ) -> Result<(), GpuError> {
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
    pub fn finish(self) -> Result<Tape, GpuError> {
        if self.stack.len() != 1 || self.guards != 0 || !self.warps.is_empty() {
            return Err(GpuError::Tape(format!(
                "unbalanced tape: {} values on the stack, {} open guards, {} open warps",
                self.stack.len(),
                self.guards,
                self.warps.len()
            )));
        }
        if self.max_stack > MAX_STACK || self.max_warps > MAX_WARPS {
            return Err(GpuError::Tape(format!(
                "tree too deep for the GPU evaluator: stack {} (max {MAX_STACK}), warps {} (max {MAX_WARPS})",
                self.max_stack, self.max_warps
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

fn warp_params(inv: &Affine3A) -> [f32; 13] {
    let m = inv.matrix3;
    let t = inv.translation;
    // ‖M⁻¹‖₂ ≤ Frobenius norm.
    let k =
        (m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared()).sqrt();
    [
        m.x_axis.x, m.y_axis.x, m.z_axis.x, t.x, //
        m.x_axis.y, m.y_axis.y, m.z_axis.y, t.y, //
        m.x_axis.z, m.y_axis.z, m.z_axis.z, t.z, //
        k,
    ]
}

/// The pipeline-overridable constants of `shaders/field.wgsl` that switch parts of the
/// evaluator on, by bit of [`Tape::features`].
pub const FEATURES: [&str; 9] = [
    "USE_NPRIM",
    "USE_HEIGHT",
    "USE_BICUBIC",
    "USE_SFIELD",
    "USE_SF_CUBIC",
    "USE_SF_NOISE",
    "USE_TWARP",
    "USE_CONE",
    "USE_ELLIPSOID",
];

impl Tape {
    /// The parts of the GPU evaluator this tape uses, a bit per name of [`FEATURES`]: the
    /// GPU compiles a pipeline per set, without the others' code (llvmpipe runs every
    /// branch of the interpreter with masks, so unused ops would cost on every step).
    pub fn features(&self) -> u32 {
        let on = |name: &str| 1u32 << FEATURES.iter().position(|&f| f == name).expect("a feature");
        let mut bits = 0;
        for ins in &self.instrs {
            let at = |k: usize| self.params[ins.param as usize + k];
            bits |= match ins.op {
                op::PRIM | op::NPRIM => {
                    let shape = match ins.flags & 0xff {
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
                op::HEIGHT if ins.flags & BICUBIC != 0 => on("USE_HEIGHT") | on("USE_BICUBIC"),
                op::HEIGHT => on("USE_HEIGHT"),
                op::SFIELD => {
                    on("USE_SFIELD")
                        | if at(12) != 0.0 { on("USE_SF_CUBIC") } else { 0 }
                        | if at(9) != 0.0 { on("USE_SF_NOISE") } else { 0 }
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

    /// The step of the tetrahedral finite differences used for gradients (shared with
    /// the GPU so both shade with the same normals).
    pub fn grad_step(&self) -> f32 {
        self.grad_step
    }

    /// `(f(p), λ)` with `λ` a Lipschitz bound of `f` over the ball `B(c, r)`: the CPU twin
    /// of `eval_tape` in `shaders/field.wgsl`.
    pub fn eval(&self, p: Vec3, c: Vec3, r: f32) -> (f32, f32) {
        self.run::<true>(p, c, r)
    }

    /// The tape run; `BOUND`: compute the bound (else the second component is
    /// meaningless). Where `p = c` the primitives share their distances.
    fn run<const BOUND: bool>(&self, p: Vec3, c: Vec3, r: f32) -> (f32, f32) {
        let mut stack = [(0.0f32, 0.0f32); MAX_STACK];
        let mut sp = 0usize;
        let mut frames = [(Vec3::ZERO, Vec3::ZERO, 0.0f32); MAX_WARPS];
        let mut fp = 0usize;
        let (mut p, mut c, mut r) = (p, c, r);
        let mut pc = 0usize;
        let prm = &self.params;
        while pc < self.instrs.len() {
            let ins = self.instrs[pc];
            let o = ins.param as usize;
            match ins.op {
                op::CONST => {
                    stack[sp] = (prm[o], 0.0);
                    sp += 1;
                }
                op::PRIM => {
                    stack[sp] = primitive::<BOUND>(ins.flags, &prm[o..], p, c, r);
                    sp += 1;
                }
                op::NPRIM => {
                    stack[sp] =
                        noisy_primitive(ins.flags, &prm[o..], &self.noises, (p, c, r), BOUND);
                    sp += 1;
                }
                op::HEIGHT => {
                    stack[sp] = self.height::<BOUND>(ins.flags, &prm[o..], p, c, r);
                    sp += 1;
                }
                op::SFIELD => {
                    let sf = &self.sfields[ins.flags as usize];
                    stack[sp] = super::sfield::eval(sf, (p, c, r), BOUND);
                    sp += 1;
                }
                op::BLEND | op::UNION | op::INTER | op::DIFF => {
                    let (b, a) = (stack[sp - 1], stack[sp - 2]);
                    sp -= 1;
                    stack[sp - 1] = match ins.op {
                        op::BLEND => (a.0 + b.0, a.1 + b.1),
                        op::UNION => (a.0.max(b.0), a.1.max(b.1)),
                        op::INTER => (a.0.min(b.0), a.1.max(b.1)),
                        _ => (a.0.min(2.0 * T - b.0), a.1.max(b.1)),
                    };
                }
                op::GUARD => {
                    let lo = Vec3::new(prm[o], prm[o + 1], prm[o + 2]);
                    let hi = Vec3::new(prm[o + 3], prm[o + 4], prm[o + 5]);
                    let bx = Aabb { min: lo, max: hi };
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
                    r *= prm[o + 12];
                }
                op::TWARP => {
                    frames[fp] = (p, c, r);
                    fp += 1;
                    p = twarp_apply(&prm[o..], &self.noises, p);
                    r += prm[o + 1];
                }
                op::UNWARP => {
                    fp -= 1;
                    (p, c, r) = frames[fp];
                    stack[sp - 1].1 *= prm[o];
                }
                _ => unreachable!("the builder emits only known ops"),
            }
            pc += 1;
        }
        stack[0]
    }

    fn height<const BOUND: bool>(
        &self,
        flags: u32,
        q: &[f32],
        p: Vec3,
        c: Vec3,
        r: f32,
    ) -> (f32, f32) {
        let fall = q[0];
        let h = |x: f32, y: f32| {
            if flags & BICUBIC != 0 {
                bicubic(&self.heights, q, x, y)
            } else {
                bilinear(&self.heights, q, x, y)
            }
        };
        let hp = h(p.x, p.y);
        let value = sigma(hp - p.z, fall);
        if !BOUND {
            return (value, 0.0);
        }
        let hc = if p == c { hp } else { h(c.x, c.y) };
        let slope = slope_under(&self.heights, q, c, r);
        let v = Interval::new(hc - slope * r - c.z - r, hc + slope * r - c.z + r);
        (value, sigma_slope(v, fall) * (1.0 + slope * slope).sqrt())
    }
}

/// A bound of `|∇h|` over the disc of radius `r` around `c` (and its clamp to the grid)
/// from the slope pyramid of the heightfield `q` ([`TapeBuilder::heightfield`]): the
/// cells under the disc's square are `i0..=i1 × j0..=j1`, and at the level `k` of the
/// highest bit where `i0` and `i1` (or `j0` and `j1`) differ, they lie in at most 2 × 2
/// blocks, whose maximum is read.
fn slope_under(heights: &[f32], q: &[f32], c: Vec3, r: f32) -> f32 {
    let (ox, oy, cell, nx, ny) = (q[2], q[3], q[4], q[5], q[6]);
    let index =
        |x: f32, o: f32, n: f32| (((x - o) / cell).clamp(0.0, n - 1.0).floor()).min(n - 2.0) as u32;
    let (i0, i1) = (index(c.x - r, ox, nx), index(c.x + r, ox, nx));
    let (j0, j1) = (index(c.y - r, oy, ny), index(c.y + r, oy, ny));
    let high = |a: u32, b: u32| 31u32.saturating_sub((a ^ b).leading_zeros());
    let levels = q[1] as u32;
    let k = high(i0, i1).max(high(j0, j1)).min(levels - 1);
    let w = (nx as u32 - 1 + (1 << k) - 1) >> k;
    let at = q[8 + k as usize] as usize;
    let s = |i: u32, j: u32| heights[at + (i + w * j) as usize];
    let (i0, i1, j0, j1) = (i0 >> k, i1 >> k, j0 >> k, j1 >> k);
    s(i0, j0).max(s(i1, j0)).max(s(i0, j1)).max(s(i1, j1))
}

/// Bilinear elevation at `(x, y)` clamped to the grid `q = [.., .., ox, oy, cell, nx, ny, offset]`.
fn bilinear(heights: &[f32], q: &[f32], x: f32, y: f32) -> f32 {
    let (ox, oy, cell, nx, ny, off) = (q[2], q[3], q[4], q[5], q[6], q[7] as usize);
    let gx = ((x - ox) / cell).clamp(0.0, nx - 1.0);
    let gy = ((y - oy) / cell).clamp(0.0, ny - 1.0);
    let (i, j) = ((gx.floor()).min(nx - 2.0), (gy.floor()).min(ny - 2.0));
    let (fx, fy) = (gx - i, gy - j);
    let (i, j, w) = (i as usize, j as usize, nx as usize);
    let z = |a: usize, b: usize| heights[off + a + w * b];
    let bottom = z(i, j) + (z(i + 1, j) - z(i, j)) * fx;
    let top = z(i, j + 1) + (z(i + 1, j + 1) - z(i, j + 1)) * fx;
    bottom + (top - bottom) * fy
}

/// Bicubic (Catmull-Rom) elevation at `(x, y)` clamped to the grid, the stencil's indices
/// clamped at its edges: [`crate::dem::Heightfield::sample`]'s cell, weights and sum order.
fn bicubic(heights: &[f32], q: &[f32], x: f32, y: f32) -> f32 {
    let (ox, oy, cell, nx, ny, off) = (q[2], q[3], q[4], q[5], q[6], q[7] as usize);
    let gx = ((x - ox) / cell).clamp(0.0, nx - 1.0);
    let gy = ((y - oy) / cell).clamp(0.0, ny - 1.0);
    let (i, j) = ((gx.floor()).min(nx - 2.0), (gy.floor()).min(ny - 2.0));
    let (wx, wy) = (
        crate::dem::interp::cr_weights(gx - i),
        crate::dem::interp::cr_weights(gy - j),
    );
    let (i, j, w, h) = (i as i64, j as i64, nx as i64, ny as i64);
    let mut v = 0.0;
    for (b, wyb) in wy.iter().enumerate() {
        let jj = (j + b as i64 - 1).clamp(0, h - 1);
        let mut row = 0.0;
        for (a, wxa) in wx.iter().enumerate() {
            let ii = (i + a as i64 - 1).clamp(0, w - 1);
            row += wxa * heights[off + (ii + w * jj) as usize];
        }
        v += wyb * row;
    }
    v
}

fn affine(m: &[f32], p: Vec3) -> Vec3 {
    let p4 = |k: usize| m[k] * p.x + m[k + 1] * p.y + m[k + 2] * p.z + m[k + 3];
    Vec3::new(p4(0), p4(4), p4(8))
}

/// `(closest point, signed distance)` of the shape `kind` with parameters `q` to `p`: the
/// twin of `project` in `shaders/field.wgsl` (a prism has no closest point: `p`).
pub(super) fn project(kind: u32, q: &[f32], p: Vec3) -> (Vec3, f32) {
    let v = |k: usize| Vec3::new(q[k], q[k + 1], q[k + 2]);
    match kind {
        shape::SPHERE => {
            let c = v(0);
            let d = (p - c).length();
            let at = if d > q[3] {
                c + (p - c) * (q[3] / d)
            } else {
                p
            };
            (at, d - q[3])
        }
        shape::CAPSULE => {
            let a = v(0);
            let ab = v(3) - a;
            let ap = p - a;
            let l2 = ab.length_squared();
            let h = if l2 > 0.0 {
                (ap.dot(ab) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let s = a + ab * h;
            let d = (ap - ab * h).length();
            let at = if d > q[6] {
                s + (p - s) * (q[6] / d)
            } else {
                p
            };
            (at, d - q[6])
        }
        shape::BOX => {
            let (c, half) = (v(0), v(3));
            let d = (p - c).abs() - half;
            let sd = Vec3A::from(d).max(Vec3A::ZERO).length() + d.max_element().min(0.0);
            (c + (p - c).clamp(-half, half), sd)
        }
        shape::CONE => cone_projection(q, p),
        shape::ELLIPSOID => ellipsoid_projection(q, p),
        _ => {
            let (lo, hi) = (v(0), v(3));
            let dxy = (lo.x - p.x)
                .max(p.x - hi.x)
                .max(lo.y - p.y)
                .max(p.y - hi.y)
                .max(0.0);
            let dz = (lo.z - p.z).max(p.z - hi.z).max(0.0);
            // Signed: inside, minus the depth below the nearest face, so a ball deep
            // inside gets a zero slope (an unsigned 0 would let it reach `r` outside).
            let inside = (lo - p).max(p - hi).max_element().min(0.0);
            (p, (dxy * dxy + dz * dz).sqrt() + inside)
        }
    }
}

/// `(closest point, distance)` of the cone `q = [base, axis, height, radius]` to `p`:
/// [`crate::field::skeleton::Cone`]'s projection onto the triangle `(0, 0), (r, 0), (0, h)`
/// of the half-plane `(ρ, z)` through the axis, in f32 as `shaders/field.wgsl` computes it.
/// The distance is the 2D one (equal to the 3D one, without the cancellation of
/// `|p − s(p)|`).
fn cone_projection(q: &[f32], p: Vec3) -> (Vec3, f32) {
    let base = Vec3::new(q[0], q[1], q[2]);
    let axis = Vec3::new(q[3], q[4], q[5]);
    let (h, r) = (q[6], q[7]);
    let w = p - base;
    let z = w.dot(axis);
    let radial = w - axis * z;
    let rho = radial.length();
    if z >= 0.0 && rho * h + z * r <= r * h {
        return (p, 0.0);
    }
    let x = Vec2::new(rho, z);
    // Base edge (0, 0)–(r, 0), slant edge (r, 0)–(0, h).
    let base_at = Vec2::new(rho.clamp(0.0, r), 0.0);
    let d = Vec2::new(-r, h);
    let tau = (x - Vec2::new(r, 0.0)).dot(d) / d.length_squared();
    let slant_at = Vec2::new(r, 0.0) + d * tau.clamp(0.0, 1.0);
    let (db, ds) = (
        (x - base_at).length_squared(),
        (x - slant_at).length_squared(),
    );
    let (at, d2) = if db <= ds {
        (base_at, db)
    } else {
        (slant_at, ds)
    };
    // On the axis (ρ = 0) the closest point is on it too (at.x = 0), any e_r will do.
    let er = if rho > 0.0 { radial / rho } else { Vec3::ZERO };
    (base + axis * at.y + er * at.x, d2.sqrt())
}

/// Newton iterations at most for the ellipsoid's root (as the CPU's).
const ELLIPSOID_NEWTON: u32 = 64;

/// `(closest point, distance)` of the ellipsoid `q = [centre, radii]` to `p`:
/// [`crate::field::skeleton::Ellipsoid`]'s Newton iteration on
/// `F(t) = Σ (eᵢyᵢ/(t + eᵢ²))² − 1` from the same lower bound of the root, in f32 (WGSL has
/// no f64), stopping at the root or after a step below `10⁻⁶·(t + e²_max)` (the iterates
/// climb monotonically and converge quadratically, so what is left is far smaller), as `shaders/field.wgsl` computes it. The distance is
/// `|y·t/(t + e²)|`, the same `|y − s|` without the cancellation near the surface.
fn ellipsoid_projection(q: &[f32], p: Vec3) -> (Vec3, f32) {
    let c = Vec3::new(q[0], q[1], q[2]);
    let e = Vec3::new(q[3], q[4], q[5]);
    let y = p - c;
    if (y / e).length_squared() <= 1.0 {
        return (p, 0.0);
    }
    let e2 = e * e;
    let ey = e * y;
    let emax = e2.max_element();
    let mut t = (ey.length() - emax).max(0.0);
    for _ in 0..ELLIPSOID_NEWTON {
        let inv = (Vec3::splat(t) + e2).recip();
        let qv = ey * inv;
        let f = qv.length_squared() - 1.0;
        if f <= 0.0 {
            break;
        }
        let df = -2.0 * (qv * qv * inv).element_sum();
        let step = -f / df;
        t += step;
        if step <= 1e-6 * (t + emax) {
            break;
        }
    }
    let den = Vec3::splat(t) + e2;
    (c + e2 * y / den, (y * t / den).length())
}

/// `(value at p, Lipschitz bound over B(c, r))` of a primitive with params `q`.
fn primitive<const BOUND: bool>(flags: u32, q: &[f32], p: Vec3, c: Vec3, r: f32) -> (f32, f32) {
    let (rad, energy) = (q[0], q[1]);
    let kind = flags & 0xff;
    let sd_p = project(kind, &q[2..], p).1;
    if !BOUND {
        let v = if flags & shape::SIGMA != 0 {
            sigma(-sd_p, rad)
        } else {
            energy * wyvill(sd_p.max(0.0) / rad)
        };
        return (v, 0.0);
    }
    let sd_c = if p == c {
        sd_p
    } else {
        project(kind, &q[2..], c).1
    };
    if flags & shape::SIGMA != 0 {
        let v = sigma(-sd_p, rad);
        (v, sigma_slope(Interval::new(-sd_c - r, -sd_c + r), rad))
    } else {
        let v = energy * wyvill(sd_p.max(0.0) / rad);
        let xs = Interval::new((sd_c - r).max(0.0) / rad, (sd_c + r).max(0.0) / rad);
        (v, energy.abs() / rad * wyvill_slope(xs))
    }
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

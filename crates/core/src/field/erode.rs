//! The erosion node of Paris et al. 2019 §6: `f_e(p) = f(p) − f_D(p)·(1 − ρ(p))`, which
//! wears a subtree away where the rock is soft, over a region `D`.
//!
//! `f_D = a·w` with `a` the strength (field units) and `w` the replace operator's
//! partition of unity ([`Transition`]): 1 in the region's core, falling smoothly to 0
//! over `blend` metres inside its faces, 0 outside — compactly supported, so the node
//! is its child outside `D`.
//!
//! # Bounds
//!
//! With `e = a·w·(1 − ρ) ≥ 0`: over a box `b`, `w ∈ [w₋, w₊]` and `ρ ∈ [ρ₋, ρ₊]`
//! (both answered soundly over boxes), so `e ∈ [a w₋ (1 − ρ₊), a w₊ (1 − ρ₋)]` and
//! `f_e ∈ f(b) − e(b)`. `∇e = a((1 − ρ)∇w − w∇ρ)`, so on `b ∩ D` (outside `D`, `e = 0`)
//! `|∇e| ≤ a((1 − ρ₋)·L_w + w₊·L_ρ(b ∩ D))`, `L_w = max|g'|/blend` (0 where `w₋ = 1`),
//! and `f_e`'s bound is `L_f + |∇e|`'s. A fault inside `D` makes `ρ` jump: boxes across
//! it get `L = +∞`, which is sound (the tracers then step at their tolerance there).

use std::fmt::Debug;
use std::sync::Arc;

use glam::Vec3;

use super::bound::Bound;
use super::bounds::{Aabb, Interval};
use super::replace::Transition;

/// Rock resistance `ρ(p) ∈ [0, 1]` (Paris et al. 2019 §4): 0 the softest rock, 1 the
/// hardest, with the bounds the erosion node needs. The field defines it; a geology
/// answers it.
pub trait Resistance: Send + Sync + Debug {
    /// `ρ(p)`, in `[0, 1]`.
    fn resistance(&self, p: Vec3) -> f32;

    /// `(ρ(p), ∇ρ(p))`.
    fn resistance_grad(&self, p: Vec3) -> (f32, Vec3);

    /// A range in `[0, 1]` holding `ρ(p)` for every `p` in `b`, and a Lipschitz bound of
    /// `ρ` for pairs of points in `b` (`+∞` across a jump).
    fn resistance_bound(&self, b: &Aabb) -> Bound;
}

/// The erosion a node subtracts from its child: `e(p) = a·w(p)·(1 − ρ(p))`.
#[derive(Clone, Debug)]
pub struct Erosion {
    rock: Arc<dyn Resistance>,
    mix: Transition,
    strength: f32,
}

impl Erosion {
    /// Erosion of strength `strength ≥ 0` (field units: how much the field drops in the
    /// softest rock) over `region`, fading over `blend` metres inside its faces.
    pub fn new(rock: Arc<dyn Resistance>, region: Aabb, blend: f32, strength: f32) -> Self {
        Erosion {
            rock,
            mix: Transition::new(region, blend),
            strength: strength.max(0.0),
        }
    }

    /// The region `D`: `e = 0` outside.
    pub fn region(&self) -> &Aabb {
        self.mix.region()
    }

    /// The strength `a`: the largest `e`.
    pub fn strength(&self) -> f32 {
        self.strength
    }

    /// `e(p)`.
    #[inline]
    pub fn amount(&self, p: Vec3) -> f32 {
        let w = self.mix.weight(p);
        if w <= 0.0 {
            return 0.0;
        }
        self.strength * w * (1.0 - self.rock.resistance(p))
    }

    /// `(e(p), ∇e(p))`.
    pub fn amount_grad(&self, p: Vec3) -> (f32, Vec3) {
        let (w, gw) = self.mix.weight_grad(p);
        if w <= 0.0 {
            return (0.0, Vec3::ZERO);
        }
        let (rho, grho) = self.rock.resistance_grad(p);
        let a = self.strength;
        (a * w * (1.0 - rho), a * ((1.0 - rho) * gw - w * grho))
    }

    /// A range holding `e(p)` for every `p` in `b`, and a Lipschitz bound of `e` for pairs
    /// of points in `b` (`+∞` across a fault in `D`): `a · w · (1 − ρ)` by the product
    /// rule.
    pub fn bound(&self, b: &Aabb) -> Bound {
        let w = self.mix.interval(b);
        if w.hi <= 0.0 || self.strength == 0.0 {
            return Bound::ZERO;
        }
        let lw = if w.lo >= 1.0 {
            0.0
        } else {
            self.mix.lipschitz()
        };
        let rho = self.rock.resistance_bound(&b.intersection(*self.region()));
        let w = Bound::new(Interval::new(w.lo.max(0.0), w.hi), lw);
        w.product(rho.scale(-1.0).shift(1.0)).scale(self.strength)
    }

    /// A range holding `e(p)` for every `p` in `b`.
    pub fn interval(&self, b: &Aabb) -> Interval {
        self.bound(b).range
    }

    /// A Lipschitz bound of `e` for pairs of points in `b` (`+∞` across a fault in `D`).
    pub fn lipschitz_box(&self, b: &Aabb) -> f32 {
        self.bound(b).lipschitz
    }

    /// [`Erosion::lipschitz_box`] over the whole region: the global bound.
    pub fn lipschitz(&self) -> f32 {
        self.lipschitz_box(self.region())
    }
}

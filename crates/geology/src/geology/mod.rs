//! Geology: the rock's resistance to erosion, `ρ: R³ → [0, 1]` (1 = hard), as a
//! construction tree of its own (Paris et al. 2019 §4).
//!
//! Leaves are strata (a profile of the distance to a plane plus turbulence, §4.1–4.2),
//! 3D turbulence, and skeletal primitives that harden or soften rock locally (§4.2);
//! operators blend (the clamped sum), fold and taper (warps, §4.3) and fault (a
//! translation strictly inside a domain, a discontinuity on its boundary, §4.4). A tree
//! file carries it as a top-level `geology:` beside the terrain tree
//! ([`GeologySpec`]); compiling the scene builds it once
//! (`compile::Compiler::resistance`), and the erosion node (`field::Erosion`) and
//! the landform generators read it. `docs/geology.md` shows each node in section.

mod rock;
pub mod section;
pub mod spec;

use glam::Vec3;

pub use spec::{
    FaultSpec, FoldSpec, GeologySpec, LayerSpec, ProfileSpec, RockSpec, StrataSpec, TaperSpec,
    TurbulenceSpec,
};

use crate::field::{Aabb, Bound, Interval, Resistance};
use rock::Rock;

/// The resistance a scene without a geology has everywhere.
pub const DEFAULT_RESISTANCE: f32 = 0.5;

/// A compiled geology tree, with the bounds the erosion node needs.
#[derive(Clone, Debug)]
pub struct Geology {
    root: Rock,
}

impl Geology {
    /// Compiles a tree-file geology; `scene_seed` is the scene's global seed (every noise
    /// derives from it and the nodes' `seed_offset`s: the same file gives the same rock).
    pub fn from_spec(spec: &GeologySpec, scene_seed: u32) -> Self {
        Geology {
            root: Rock::new(&spec.root, scene_seed),
        }
    }

    /// The same resistance `rho` everywhere (clamped to `[0, 1]`).
    pub fn uniform(rho: f32) -> Self {
        Geology {
            root: Rock::Constant(rho.clamp(0.0, 1.0)),
        }
    }

    /// `ρ(p)`, clamped to `[0, 1]`.
    #[inline]
    pub fn value(&self, p: Vec3) -> f32 {
        self.root.value(p).clamp(0.0, 1.0)
    }

    /// `(ρ(p), ∇ρ(p))`; the gradient is 0 where the clamp is active.
    pub fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let (v, g) = self.root.value_grad(p);
        if (0.0..=1.0).contains(&v) {
            (v, g)
        } else {
            (v.clamp(0.0, 1.0), Vec3::ZERO)
        }
    }

    /// A range in `[0, 1]` holding `ρ(p)` for every `p` in `b`, and a Lipschitz bound of
    /// `ρ` for pairs of points in `b`: `+∞` when `b` crosses a fault (the resistance
    /// jumps there, Paris et al. 2019 §4.4).
    pub fn bound(&self, b: &Aabb) -> Bound {
        if b.is_empty() {
            return Bound::new(Interval::new(0.0, 1.0), 0.0);
        }
        self.root.bound(b).clamp(0.0, 1.0)
    }
}

impl Default for Geology {
    /// [`DEFAULT_RESISTANCE`] everywhere.
    fn default() -> Self {
        Geology::uniform(DEFAULT_RESISTANCE)
    }
}

impl Resistance for Geology {
    #[inline]
    fn resistance(&self, p: Vec3) -> f32 {
        self.value(p)
    }

    fn resistance_grad(&self, p: Vec3) -> (f32, Vec3) {
        self.value_grad(p)
    }

    fn resistance_bound(&self, b: &Aabb) -> Bound {
        self.bound(b)
    }
}

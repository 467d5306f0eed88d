//! The tape's format: the instruction word, the op codes, shape kinds and flags, the
//! evaluator's limits, and the named offset of every parameter of every op.
//!
//! These are the definitions: the CPU interpreter reads parameters through them and
//! `crates/render/shaders/tape_consts.wgsl`, generated from them (`render::gpu::header`),
//! gives the shaders the same names (`PRIM_RADIUS`, `HEIGHT_PYRAMID`, …). Each module
//! below becomes one block of WGSL constants named `PREFIX_NAME`.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// One tape instruction: 16 bytes, `vec4<u32>` in WGSL.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct Instr {
    /// Operation code ([`op`]).
    pub op: u32,
    /// Operation-specific flags ([`flag`]; an S-field leaf's index).
    pub flags: u32,
    /// Jump target of a guard: the index just past its subtree.
    pub jump: u32,
    /// Offset of the instruction's parameters in [`super::Tape::params`].
    pub param: u32,
}

/// Defines modules of integer constants and [`GROUPS`], the list of them with their WGSL
/// prefixes and docs, so that every constant defined here reaches the shaders' header.
macro_rules! layout {
    ($(
        $(#[doc = $doc:literal])*
        pub mod $m:ident: $t:ty = $prefix:literal {
            $($(#[doc = $d:literal])* $name:ident = $v:expr;)*
        }
    )*) => {
        $(
            $(#[doc = $doc])*
            pub mod $m {
                #[allow(unused_imports)]
                use super::*;
                $($(#[doc = $d])* pub const $name: $t = $v;)*
            }
        )*
        /// Every module of this file: the WGSL header declares `PREFIX_NAME` as a `u32`
        /// for each of its constants.
        pub const GROUPS: &[Group] = &[$(
            Group {
                prefix: $prefix,
                doc: concat!($($doc),*),
                items: &[$(Item {
                    name: stringify!($name),
                    value: $m::$name as u64,
                    doc: concat!($($d),*),
                }),*],
            },
        )*];
    };
}

/// A module of constants of this file, as the WGSL header declares them.
#[derive(Clone, Copy, Debug)]
pub struct Group {
    /// What the WGSL names start with (`OP_`; empty for the limits).
    pub prefix: &'static str,
    /// The module's documentation, its lines joined.
    pub doc: &'static str,
    /// Its constants.
    pub items: &'static [Item],
}

/// One constant of a [`Group`].
#[derive(Clone, Copy, Debug)]
pub struct Item {
    /// Its Rust name (the WGSL one without the prefix).
    pub name: &'static str,
    /// Its value.
    pub value: u64,
    /// Its documentation, its lines joined.
    pub doc: &'static str,
}

layout! {
    /// Evaluator limits.
    pub mod limit: usize = "" {
        /// Value-stack depth of the WGSL evaluator.
        MAX_STACK = 32;
        /// Nesting depth of warps in the WGSL evaluator.
        MAX_WARPS = 8;
        /// `vec4` slots of the WGSL evaluator's warp frames: two per warp, `(p, r)` and
        /// `(c, 0)`.
        WARP_FRAMES = 2 * MAX_WARPS;
        /// Newton iterations at most for an ellipsoid's closest point.
        ELLIPSOID_NEWTON = 64;
        /// Offsets and indices travel as f32 parameters, exact up to this.
        MAX_OFFSET = 1 << 24;
    }

    /// Operation codes.
    pub mod op: u32 = "OP_" {
        /// Push a constant ([`constant`]).
        CONST = 0;
        /// Push a skeletal primitive ([`prim`]).
        PRIM = 1;
        /// Push a heightfield's `σ(h − z)` ([`height`]).
        HEIGHT = 2;
        /// Push a noisy primitive ([`nprim`]).
        NPRIM = 3;
        /// Push an S-field leaf ([`sfield`]).
        SFIELD = 4;
        /// Sum of the two top entries.
        BLEND = 16;
        /// Maximum.
        UNION = 17;
        /// Minimum.
        INTER = 18;
        /// `min(a, 2T − b)`.
        DIFF = 19;
        /// `a + w·(b − a)`, `w` the partition of unity of a region ([`replace`]).
        REPLACE = 20;
        /// Skip a subtree whose support box is out of reach ([`guard`]).
        GUARD = 32;
        /// Enter an affine warp ([`warp`]).
        WARP = 33;
        /// Leave an affine or turbulence warp ([`unwarp`]).
        UNWARP = 34;
        /// Enter a turbulence warp ([`twarp`]).
        TWARP = 35;
    }

    /// Primitive shapes: `flags & SHAPE_MASK` of `PRIM` and `NPRIM`.
    pub mod shape: u32 = "SHAPE_" {
        /// Ball ([`sphere`]; a point when its radius is 0).
        SPHERE = 0;
        /// Capsule ([`capsule`]; a segment when its radius is 0).
        CAPSULE = 1;
        /// Axis-aligned box ([`cuboid`]).
        BOX = 2;
        /// A heightfield's prism ([`prism`]).
        PRISM = 3;
        /// Capped cone ([`cone`]).
        CONE = 4;
        /// Axis-aligned ellipsoid ([`ellipsoid`]).
        ELLIPSOID = 5;
    }

    /// Instruction flags.
    pub mod flag: u32 = "FLAG_" {
        /// The bits of `PRIM` and `NPRIM` flags holding the [`shape`].
        SHAPE_MASK = 0xff;
        /// `PRIM`: σ profile instead of Wyvill.
        SIGMA = 1 << 8;
        /// `HEIGHT`: Catmull-Rom bicubic interpolation instead of bilinear.
        BICUBIC = 1;
        /// `HEIGHT`: detail amplification `h + A·m·t(p)` ([`height::DETAIL_AMPLITUDE`]).
        DETAIL = 2;
    }

    /// `CONST` parameters.
    pub mod constant: usize = "CONST_" {
        /// The value.
        VALUE = 0;
    }

    /// `PRIM` parameters: `e·g(max(sd, 0)/R)` (Wyvill) or `σ(−sd, R)` ([`flag::SIGMA`]),
    /// `sd` the signed distance to the shape.
    pub mod prim: usize = "PRIM_" {
        /// `R`, the radius of influence or σ's width.
        RADIUS = 0;
        /// `e`, the energy (1 with σ).
        ENERGY = 1;
        /// Where the shape's parameters start.
        SHAPE = 2;
    }

    /// [`shape::SPHERE`] parameters.
    pub mod sphere: usize = "SPHERE_" {
        /// Centre (3 floats).
        CENTER = 0;
        /// Radius `ρ`.
        RADIUS = 3;
        /// Floats in all.
        LEN = 4;
    }

    /// [`shape::CAPSULE`] parameters.
    pub mod capsule: usize = "CAPSULE_" {
        /// First end (3 floats).
        A = 0;
        /// Second end (3 floats).
        B = 3;
        /// Radius `ρ`.
        RADIUS = 6;
        /// Floats in all.
        LEN = 7;
    }

    /// [`shape::BOX`] parameters.
    pub mod cuboid: usize = "CUBOID_" {
        /// Centre (3 floats).
        CENTER = 0;
        /// Half the edge lengths (3 floats).
        HALF = 3;
        /// Floats in all.
        LEN = 6;
    }

    /// [`shape::PRISM`] parameters.
    pub mod prism: usize = "PRISM_" {
        /// Lower corner (3 floats).
        MIN = 0;
        /// Upper corner (3 floats).
        MAX = 3;
        /// Floats in all.
        LEN = 6;
    }

    /// [`shape::CONE`] parameters.
    pub mod cone: usize = "CONE_" {
        /// Centre of the base disc (3 floats).
        BASE = 0;
        /// Unit axis from the base to the apex (3 floats).
        AXIS = 3;
        /// Base-to-apex distance.
        HEIGHT = 6;
        /// Radius of the base.
        RADIUS = 7;
        /// Floats in all.
        LEN = 8;
    }

    /// [`shape::ELLIPSOID`] parameters.
    pub mod ellipsoid: usize = "ELLIPSOID_" {
        /// Centre (3 floats).
        CENTER = 0;
        /// Semi-axes (3 floats).
        RADII = 3;
        /// Floats in all.
        LEN = 6;
    }

    /// `HEIGHT` parameters ([`super::height`]).
    pub mod height: usize = "HEIGHT_" {
        /// σ's width `R`.
        FALLOFF = 0;
        /// Levels `n` of the slope pyramid.
        LEVELS = 1;
        /// Position of sample `(0, 0)` (2 floats).
        ORIGIN = 2;
        /// Sample spacing.
        CELL = 4;
        /// Samples along x.
        NX = 5;
        /// Samples along y.
        NY = 6;
        /// Offset of the samples in `heights`.
        OFFSET = 7;
        /// With [`flag::DETAIL`]: the detail's amplitude `A` (Frasson et al. §5).
        DETAIL_AMPLITUDE = 8;
        /// A bound of the detail's slope `|∇d| ≤ A·(L_m + L_t)`.
        DETAIL_SLOPE = 9;
        /// Offset in `heights` of the roughness `m` (one per sample, bilinear).
        DETAIL_ROUGH = 10;
        /// The detail's fBm `t` ([`fbm`], `fbm::LEN` floats).
        DETAIL_FBM = 11;
        /// Offsets in `heights` of the pyramid's levels `0 … n − 1` (`n` floats).
        PYRAMID = 11 + fbm::LEN;
    }

    /// An encoded fBm ([`super::noise::encode_fbm`]), inside `NPRIM`, `TWARP` and
    /// `SFIELD` parameters.
    pub mod fbm: usize = "FBM_" {
        /// Its index in [`super::super::Tape::noises`].
        INDEX = 0;
        /// `seed & 0xffff`.
        SEED_LO = 1;
        /// `seed >> 16`.
        SEED_HI = 2;
        /// `1/λ`.
        INV_WAVELENGTH = 3;
        /// Octaves.
        OCTAVES = 4;
        /// Normalisation factor.
        NORM = 5;
        /// Lipschitz bound `L_t`.
        LIPSCHITZ = 6;
        /// Floats in all.
        LEN = 7;
    }

    /// `NPRIM` parameters ([`super::noise`]).
    pub mod nprim: usize = "NPRIM_" {
        /// `R`.
        RADIUS = 0;
        /// `E`.
        ENERGY = 1;
        /// `A`, the noise amplitude.
        AMPLITUDE = 2;
        /// `λ_d̃`, the global bound of `|∇d̃|`.
        SLOPE = 3;
        /// The turbulence ([`fbm`]).
        FBM = 4;
        /// Where the shape's parameters start.
        SHAPE = FBM + fbm::LEN;
    }

    /// `GUARD` parameters.
    pub mod guard: usize = "GUARD_" {
        /// Lower corner of the box (3 floats).
        MIN = 0;
        /// Upper corner (3 floats).
        MAX = 3;
        /// Floats in all.
        LEN = 6;
    }

    /// `REPLACE` parameters: the region, its transition width and a bound of
    /// `|b − a|` (from the children's ranges).
    pub mod replace: usize = "REPLACE_" {
        /// Lower corner of the region (3 floats).
        MIN = 0;
        /// Upper corner (3 floats).
        MAX = 3;
        /// Transition width.
        WIDTH = 6;
        /// `max |b − a|` anywhere.
        GAP = 7;
        /// Floats in all.
        LEN = 8;
    }

    /// `WARP` parameters.
    pub mod warp: usize = "WARP_" {
        /// `M⁻¹`, 3 rows of 4 (12 floats).
        MATRIX = 0;
        /// `k ≥ ‖M⁻¹‖`, which scales the ball's radius.
        NORM = 12;
        /// Floats in all.
        LEN = 13;
    }

    /// `UNWARP` parameters.
    pub mod unwarp: usize = "UNWARP_" {
        /// The factor of the top bound.
        SCALE = 0;
    }

    /// `TWARP` parameters ([`super::noise`]).
    pub mod twarp: usize = "TWARP_" {
        /// `A`.
        AMPLITUDE = 0;
        /// How far a point moves at most, added to the ball's radius.
        REACH = 1;
        /// `L_ω`.
        LIPSCHITZ = 2;
        /// 1 when the warp is localized to a region, else 0.
        HAS_REGION = 3;
        /// Lower corner of the region (3 floats).
        REGION_MIN = 4;
        /// Upper corner (3 floats).
        REGION_MAX = 7;
        /// Width of the falloff around the region.
        FALLOFF = 10;
        /// The three turbulences ([`fbm`], one after the other).
        TURBULENCE = 11;
        /// Floats in all.
        LEN = TURBULENCE + 3 * fbm::LEN;
    }

    /// `SFIELD` parameters before the levels ([`super::sfield`]).
    pub mod sfield: usize = "SF_" {
        /// Lower corner of the domain (3 floats).
        MIN = 0;
        /// Upper corner (3 floats).
        MAX = 3;
        /// σ's width `R`.
        TRANSITION = 6;
        /// The face falloff `R_f`.
        FALLOFF = 7;
        /// `−1` for a solid, `+1` for an air orientation.
        SIGN = 8;
        /// 1 with displacement noise, else 0.
        NOISY = 9;
        /// Level count.
        LEVELS = 10;
        /// The global Lipschitz bound of `S'`.
        S_LIPSCHITZ = 11;
        /// 1 with the tricubic blend, else 0.
        TRICUBIC = 12;
        /// Offset of the blend weights in `sf_data`.
        WEIGHTS = 13;
        /// The displacement noise ([`fbm`]).
        FBM = 14;
        /// Where the levels start ([`sf_level`], one after the other).
        HEAD = FBM + fbm::LEN;
    }

    /// The parameters of one level of an `SFIELD`.
    pub mod sf_level: usize = "SF_LEVEL_" {
        /// Position of node `(0, 0, 0)` (3 floats).
        ORIGIN = 0;
        /// Node spacing.
        H = 3;
        /// Nodes along x, y, z (3 floats).
        DIMS = 4;
        /// Offset of its brick table in `sf_table`.
        TABLE = 7;
        /// Offset of its S samples in `sf_data`.
        S = 8;
        /// Offset of its α samples.
        ALPHA = 9;
        /// Offset of its β samples.
        BETA = 10;
        /// Floats in all.
        LEN = 11;
    }
}

/// The 3 floats of `q` at offset `at` as a vector.
pub(crate) fn get3(q: &[f32], at: usize) -> Vec3 {
    Vec3::new(q[at], q[at + 1], q[at + 2])
}

/// Writes `v` into the 3 floats of `q` at offset `at`.
pub(crate) fn set3(q: &mut [f32], at: usize, v: Vec3) {
    q[at..at + 3].copy_from_slice(&v.to_array());
}

/// Appends `len` zeros to `out` and returns them, to be written at named offsets.
pub(crate) fn tail(out: &mut Vec<f32>, len: usize) -> &mut [f32] {
    let start = out.len();
    out.resize(start + len, 0.0);
    &mut out[start..]
}

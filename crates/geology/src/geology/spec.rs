//! The geology of a tree file: a top-level `geology: (root: ...)` beside the terrain tree.
//!
//! ```text
//! geology: (
//!     root: Blend([
//!         Turbulence(base: 0.6, noise: (amplitude: 0.2, wavelength: 30)),
//!         Strata(profile: Band(half_width: 2.0, resistance: -0.5), point: (0, 0, 12)),
//!         Fault(
//!             point: (40, 0, 0), normal: (1, 0, 0.3), slip: (0, 0, -6),
//!             child: Strata(profile: Layers(layers: [(thickness: 4, resistance: 0.9),
//!                                                    (thickness: 1.5, resistance: 0.1)])),
//!         ),
//!     ]),
//! )
//! ```
//!
//! Every number checks itself while parsing, and the checks across fields run in
//! `try_from`, so a bad geology is reported with its line and column like the rest of the
//! file. `docs/geology.md` describes each node.

use serde::{Deserialize, Serialize};

use crate::field::{NoiseSpec, PrimitiveSpec};
use crate::value::{BoxSpec, Region};
use crate::value::{Dir3, Finite, P3, Positive, Unit};

/// The geology of a scene: the root of its resistance tree (Paris et al. 2019 §4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GeologySpec {
    /// The resistance tree; its value is clamped to `[0, 1]`.
    pub root: RockSpec,
}

/// One node of a geology tree. Leaves give a resistance, operators combine or deform
/// their children's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum RockSpec {
    /// The same resistance everywhere.
    Constant(Unit),
    /// A profile of the signed distance to a plane plus turbulence:
    /// `ρ = g(d(p)) + A·t(p/λ₀)` (Paris et al. 2019 §4.1, §4.2).
    Strata(StrataSpec),
    /// 3D turbulence: `ρ = base + A·t(p/λ₀)` (Paris et al. 2019 §4.1).
    Turbulence(TurbulenceSpec),
    /// A skeletal primitive (sphere, curve, …) adding its energy `E·g(d/R)`: positive
    /// hardens, negative softens (Paris et al. 2019 §4.2, "local").
    Local(PrimitiveSpec),
    /// The clamped sum of the children (Paris et al. 2019 §4.2: `ρ_{A+B} = ρ_A + ρ_B`).
    Blend(Vec<RockSpec>),
    /// A fold: the child seen through a turbulence warp (Paris et al. 2019 §4.3).
    Fold(FoldSpec),
    /// A taper: strata compressed along z by a factor varying across the map
    /// (Paris et al. 2019 §4.3).
    Taper(TaperSpec),
    /// A fault: the child translated strictly inside a domain, so the resistance jumps on
    /// the domain's boundary (Paris et al. 2019 §4.4).
    Fault(FaultSpec),
}

/// A strata leaf: a 1D profile of the distance to a plane, plus optional turbulence.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrataSpec {
    /// A point of the plane (default the origin).
    #[serde(default)]
    pub point: P3,
    /// The plane's normal (default up): the distance grows along it.
    #[serde(default = "up")]
    pub normal: Dir3,
    /// The profile `g` of the signed distance `d`.
    pub profile: ProfileSpec,
    /// Added turbulence `A·t(p/λ₀)` (joints and fractures); `amplitude` in resistance units.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub turbulence: Option<NoiseSpec>,
}

fn up() -> Dir3 {
    Dir3(glam::Vec3::Z)
}

/// The 1D profile of a strata leaf.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawProfile")]
pub enum ProfileSpec {
    /// One layer around the plane: `resistance · g(d / half_width)` with Wyvill's falloff
    /// (the plane primitive of Paris et al. 2019 §4.2); a negative resistance softens
    /// what it is blended with.
    Band {
        /// Half thickness, metres.
        half_width: Positive,
        /// Value on the plane.
        resistance: Finite,
    },
    /// Layers repeated along the normal from the plane: `(thickness, resistance)` each,
    /// with smooth transitions `transition` metres wide between neighbours (default a
    /// fifth of the thinnest layer, at most the thinnest layer).
    Layers {
        /// The layers, bottom to top.
        layers: Vec<LayerSpec>,
        /// Width of the ramp between two layers, metres.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        transition: Option<Positive>,
    },
    /// Noise of the distance only, `base + A·t(d/λ₀)`: the altitude strata of
    /// Paris et al. 2019 §4.1 (`ρ = t(p_z/λ₀)`) when the normal is up.
    Noise {
        /// The mean resistance.
        base: Finite,
        /// `amplitude` in resistance units, `wavelength` λ₀ in metres.
        noise: NoiseSpec,
    },
}

#[derive(Deserialize)]
#[serde(rename = "ProfileSpec", deny_unknown_fields)]
enum RawProfile {
    Band {
        half_width: Positive,
        resistance: Finite,
    },
    Layers {
        layers: Vec<LayerSpec>,
        #[serde(default)]
        transition: Option<Positive>,
    },
    Noise {
        base: Finite,
        noise: NoiseSpec,
    },
}

impl TryFrom<RawProfile> for ProfileSpec {
    type Error = String;
    fn try_from(r: RawProfile) -> Result<Self, String> {
        Ok(match r {
            RawProfile::Band {
                half_width,
                resistance,
            } => ProfileSpec::Band {
                half_width,
                resistance,
            },
            RawProfile::Noise { base, noise } => ProfileSpec::Noise { base, noise },
            RawProfile::Layers { layers, transition } => {
                let thinnest = layers
                    .iter()
                    .map(|l| l.thickness.get())
                    .fold(f32::INFINITY, f32::min);
                if layers.len() < 2 {
                    return Err(format!(
                        "Layers needs at least two layers, found {}",
                        layers.len()
                    ));
                }
                if let Some(t) = transition
                    && t.get() > thinnest
                {
                    return Err(format!(
                        "transition {t} is wider than the thinnest layer ({thinnest} m)"
                    ));
                }
                ProfileSpec::Layers { layers, transition }
            }
        })
    }
}

/// One layer of a `Layers` profile.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayerSpec {
    /// Thickness along the normal, metres.
    pub thickness: Positive,
    /// Its resistance.
    pub resistance: Unit,
}

/// A turbulence leaf: `base + A·t(p/λ₀)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TurbulenceSpec {
    /// The mean resistance.
    pub base: Finite,
    /// `amplitude` in resistance units, `wavelength` λ₀ in metres.
    pub noise: NoiseSpec,
}

/// A fold: `ρ(p + δ(p)·f_D(p))` with `δ` an fBm displacement of `amplitude` metres.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FoldSpec {
    /// The displacement; `amplitude` in metres.
    pub turbulence: NoiseSpec,
    /// Where it applies (everywhere when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<Region>,
    /// The folded subtree.
    pub child: Box<RockSpec>,
}

/// A taper: the child read at `z' = z₀ + (z − z₀)·s`, `s` going linearly from
/// `factor.0` to `factor.1` as `axis · p` goes from `from` to `to` (constant beyond):
/// strata appear `s` times thinner.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, try_from = "RawTaper")]
pub struct TaperSpec {
    /// Horizontal direction along which the factor changes (its z is ignored).
    pub axis: Dir3,
    /// Where along `axis` the factor is `factor.0`, metres.
    pub from: Finite,
    /// Where along `axis` the factor is `factor.1`, metres.
    pub to: Finite,
    /// The compression factors at `from` and `to`, `> 0`.
    pub factor: (Positive, Positive),
    /// The altitude `z₀` that stays in place (default 0).
    #[serde(default)]
    pub z0: Finite,
    /// The tapered subtree.
    pub child: Box<RockSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "TaperSpec")]
struct RawTaper {
    axis: Dir3,
    from: Finite,
    to: Finite,
    factor: (Positive, Positive),
    #[serde(default)]
    z0: Finite,
    child: Box<RockSpec>,
}

impl TryFrom<RawTaper> for TaperSpec {
    type Error = String;
    fn try_from(r: RawTaper) -> Result<Self, String> {
        if r.axis.0.truncate().length() < 1e-6 {
            return Err("the taper's axis must be horizontal, not vertical".into());
        }
        if r.from.get() == r.to.get() {
            return Err(format!("`from` and `to` must differ, both are {}", r.from));
        }
        Ok(TaperSpec {
            axis: r.axis,
            from: r.from,
            to: r.to,
            factor: r.factor,
            z0: r.z0,
            child: r.child,
        })
    }
}

/// A fault: inside the domain (the open half-space on the normal's side of the plane,
/// within `region` when given) the child is read at `p − slip`; outside, at `p`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaultSpec {
    /// A point of the fault plane.
    pub point: P3,
    /// The fault plane's normal, pointing into the moved block.
    pub normal: Dir3,
    /// How far the moved block slides, metres.
    pub slip: P3,
    /// Bounds the moved block (everywhere on the normal's side when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<BoxSpec>,
    /// The faulted subtree.
    pub child: Box<RockSpec>,
}

impl RockSpec {
    /// The node's kind as written in the file.
    pub fn kind(&self) -> &'static str {
        match self {
            RockSpec::Constant(_) => "Constant",
            RockSpec::Strata(_) => "Strata",
            RockSpec::Turbulence(_) => "Turbulence",
            RockSpec::Local(_) => "Local",
            RockSpec::Blend(_) => "Blend",
            RockSpec::Fold(_) => "Fold",
            RockSpec::Taper(_) => "Taper",
            RockSpec::Fault(_) => "Fault",
        }
    }
}

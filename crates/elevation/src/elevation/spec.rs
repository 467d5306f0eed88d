//! The `Elevation(...)` leaf of tree files and the elevation tree inside it.
//!
//! ```ron
//! Elevation(
//!     name: "terrain",
//!     extent: ((0, 0), (2000, 2000)), // the leaf's domain, tree frame (metres)
//!     falloff: 20,                    // R of the implicitization, metres
//!     base_depth: 150,                // prism floor below the lowest elevation (default R)
//!     detail: 2,                      // LoD: cut details smaller than this (default: none)
//!     tree: Replace(
//!         base: Blend(base: 120, children: [
//!             Disc(centre: (600, 900), radius: 700,
//!                  elevation: Ridged(base: 150, amplitude: 450, wavelength: 700, octaves: 6)),
//!         ]),
//!         by: Curve(points: [(0, 400, 110), (2000, 600, 95)], width: 120,
//!                   profile: [(0, -6), (15, -6), (40, 0), (120, 8)]),
//!     ),
//! )
//! ```

use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::multifractal::{ElevationFn, Kind, Multifractal};
use super::node::Node;
use super::primitive::{Contour, Curve, Disc, Image, Primitive};
use super::profile::Profile;
use super::{ElevationError, ElevationParams, ElevationTree, Lod};
use crate::dem::{Heightfield, Interpolation, ReadOptions};
use crate::field::noise::Octaves;
use crate::field::{Fbm, NoiseSpec, Rect, Warp};
use crate::value::{Finite, NonNegative, P2, P3, Positive};

fn one() -> Finite {
    Finite(1.0)
}

/// The `Elevation` leaf: an elevation tree implicitized over a rectangle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ElevationSpec {
    /// Unique node name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The domain `(min, max)` corners in the tree frame.
    pub extent: (P2, P2),
    /// Falloff distance `R` of the implicitization, metres.
    pub falloff: Positive,
    /// Depth of the prism's floor below the lowest elevation (default: `falloff`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base_depth: Option<NonNegative>,
    /// Continuous LoD: details smaller than this many metres are cut (default: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub detail: Option<Positive>,
    /// The elevation tree.
    pub tree: ENodeSpec,
}

/// A node of an elevation tree.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ENodeSpec {
    /// A disc with an elevation function (Génevaux et al. 2015 §4.1).
    Disc(DiscSpec),
    /// A polyline with a cross-section profile: rivers, ridges, roads.
    Curve(CurveSpec),
    /// A polygon with a profile of the distance to it: lakes, plateaus.
    Contour(ContourSpec),
    /// A raster patch (a DEM file) (Génevaux et al. 2015 §4.2).
    Image(ImageSpec),
    /// The weighted blend of the children (Génevaux et al. 2015 §5.1).
    Blend(BlendSpec),
    /// `detail` added onto `base` where it weighs (Génevaux et al. 2015 §5.3).
    Add(AddSpec),
    /// `by` replaces `base` where it weighs (Génevaux et al. 2015 §5.2).
    Replace(ReplaceSpec),
    /// A turbulence warp of the plane (Génevaux et al. 2015 §5.4).
    Warp(WarpSpec),
}

/// A disc primitive.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiscSpec {
    /// Centre.
    pub centre: P2,
    /// Radius of its influence, metres.
    pub radius: Positive,
    /// Its elevation.
    pub elevation: ElevationFnSpec,
}

/// An elevation function.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ElevationFnSpec {
    /// A constant elevation, metres.
    Constant(Finite),
    /// fBm: rolling hills.
    Fbm(FractalSpec),
    /// Ridged multifractal: mountains.
    Ridged(FractalSpec),
    /// Hybrid multifractal: smooth valleys, rough heights.
    Hybrid(FractalSpec),
}

/// A multifractal's parameters: elevations in `[base, base + amplitude]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FractalSpec {
    /// Lowest elevation, metres.
    pub base: Finite,
    /// Elevation span, metres.
    pub amplitude: NonNegative,
    /// Wavelength of the first octave, metres.
    pub wavelength: Positive,
    /// Octave count (1 to 12, default 4).
    #[serde(default)]
    pub octaves: Octaves,
    /// Added to the scene seed.
    #[serde(default)]
    pub seed_offset: u32,
}

/// A curve primitive.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurveSpec {
    /// The skeleton's points `(x, y, z)`, at least 2.
    pub points: Vec<P3>,
    /// How far from the curve its weight reaches, metres.
    pub width: Positive,
    /// The cross-section: `(distance, elevation offset)` keys.
    pub profile: Profile,
}

/// A contour primitive.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContourSpec {
    /// The closed polygon, at least 3 points.
    pub polygon: Vec<P2>,
    /// Elevation the profile is added to, metres.
    pub elevation: Finite,
    /// `(signed distance to the contour, negative inside; elevation offset)` keys.
    pub profile: Profile,
    /// How far outside the contour its weight reaches, metres.
    pub falloff: Positive,
}

/// An image primitive.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImageSpec {
    /// The DEM file, relative to the tree file's folder.
    pub source: PathBuf,
    /// Tree-frame position of its south-west sample (default the origin).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub placement: Option<P2>,
    /// Multiplies elevations (default 1).
    #[serde(default = "one")]
    pub vertical_scale: Finite,
    /// Added after scaling, metres (default 0).
    #[serde(default)]
    pub vertical_offset: Finite,
    /// Width of the weight's fall to 0 inside the border, metres.
    pub falloff: Positive,
    /// Resample to cells of this size first, metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cell_size: Option<Positive>,
}

/// A blend node.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlendSpec {
    /// Elevation where the children weigh less than ½ (default 0).
    #[serde(default)]
    pub base: Finite,
    /// The children.
    pub children: Vec<ENodeSpec>,
}

/// An add node.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AddSpec {
    /// The terrain.
    pub base: Box<ENodeSpec>,
    /// The detail added to it.
    pub detail: Box<ENodeSpec>,
    /// The detail's size, metres: LoD cuts it where it is smaller than a pixel or cell.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<Positive>,
}

/// A replace node.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReplaceSpec {
    /// The terrain.
    pub base: Box<ENodeSpec>,
    /// What stands in for it where it weighs.
    pub by: Box<ENodeSpec>,
}

/// A warp node.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WarpSpec {
    /// The displacement: `amplitude` metres per axis, fBm of `wavelength` and `octaves`.
    pub turbulence: NoiseSpec,
    /// The warped subtree.
    pub child: Box<ENodeSpec>,
}

/// What building an elevation tree needs: the tree file's folder (image sources), the
/// scene seed and the memory budget of rasters.
pub struct BuildContext<'a> {
    /// Folder image sources are relative to.
    pub base_dir: &'a Path,
    /// The scene's seed.
    pub seed: u32,
    /// Largest raster, bytes.
    pub budget: u64,
}

/// The noise seed of `seed_offset` under the scene seed, derived as every noise of the
/// scene is ([`Fbm::new`]).
fn seed_of(scene_seed: u32, seed_offset: u32) -> u32 {
    let spec = NoiseSpec {
        amplitude: NonNegative(0.0),
        wavelength: Positive(1.0),
        octaves: Octaves::default(),
        seed_offset,
    };
    Fbm::new(&spec, scene_seed).seed()
}

impl ENodeSpec {
    /// The node's kind as written in the file.
    pub fn kind(&self) -> &'static str {
        match self {
            ENodeSpec::Disc(_) => "Disc",
            ENodeSpec::Curve(_) => "Curve",
            ENodeSpec::Contour(_) => "Contour",
            ENodeSpec::Image(_) => "Image",
            ENodeSpec::Blend(_) => "Blend",
            ENodeSpec::Add(_) => "Add",
            ENodeSpec::Replace(_) => "Replace",
            ENodeSpec::Warp(_) => "Warp",
        }
    }

    /// Image files this node and its descendants read, relative to the tree file.
    pub fn sources(&self) -> Vec<&Path> {
        match self {
            ENodeSpec::Image(i) => vec![i.source.as_path()],
            ENodeSpec::Blend(b) => b.children.iter().flat_map(|c| c.sources()).collect(),
            ENodeSpec::Add(a) => [a.base.sources(), a.detail.sources()].concat(),
            ENodeSpec::Replace(r) => [r.base.sources(), r.by.sources()].concat(),
            ENodeSpec::Warp(w) => w.child.sources(),
            ENodeSpec::Disc(_) | ENodeSpec::Curve(_) | ENodeSpec::Contour(_) => Vec::new(),
        }
    }

    /// Builds the node; `at` is its path in the tree for error messages (`tree.children[2]`).
    pub fn build(&self, cx: &BuildContext, at: &str) -> Result<Node, ElevationError> {
        let err = |what: String| ElevationError::Node {
            at: format!("{at} ({})", self.kind()),
            what,
        };
        Ok(match self {
            ENodeSpec::Disc(d) => Node::primitive(Primitive::Disc(Disc {
                centre: d.centre.0,
                radius: d.radius.get(),
                elevation: d.elevation.build(cx.seed),
            })),
            ENodeSpec::Curve(c) => Node::primitive(Primitive::Curve(
                Curve::new(
                    c.points.iter().map(|p| p.0).collect(),
                    c.width.get(),
                    c.profile.clone(),
                )
                .map_err(err)?,
            )),
            ENodeSpec::Contour(c) => {
                if c.polygon.len() < 3 {
                    return Err(err(format!(
                        "`polygon` needs at least 3 points, found {}",
                        c.polygon.len()
                    )));
                }
                Node::primitive(Primitive::Contour(Contour {
                    polygon: c.polygon.iter().map(|p| p.0).collect(),
                    elevation: c.elevation.get(),
                    profile: c.profile.clone(),
                    falloff: c.falloff.get(),
                }))
            }
            ENodeSpec::Image(i) => {
                let hf = i
                    .load(cx)
                    .map_err(|e| err(format!("`source` {}: {e}", i.source.display())))?;
                Node::primitive(Primitive::Image(
                    Image::new(Arc::new(hf), i.falloff.get()).map_err(err)?,
                ))
            }
            ENodeSpec::Blend(b) => {
                let children = b
                    .children
                    .iter()
                    .enumerate()
                    .map(|(k, c)| c.build(cx, &format!("{at}.children[{k}]")))
                    .collect::<Result<Vec<_>, _>>()?;
                Node::blend(b.base.get(), children)
            }
            ENodeSpec::Add(a) => Node::add(
                a.base.build(cx, &format!("{at}.base"))?,
                a.detail.build(cx, &format!("{at}.detail"))?,
                a.size.map(Positive::get),
            ),
            ENodeSpec::Replace(r) => Node::replace(
                r.base.build(cx, &format!("{at}.base"))?,
                r.by.build(cx, &format!("{at}.by"))?,
            ),
            ENodeSpec::Warp(w) => {
                let noise = Fbm::new(&w.turbulence, cx.seed);
                let seed = cx.seed ^ w.turbulence.seed_offset.rotate_left(16);
                Node::warp(
                    w.child.build(cx, &format!("{at}.child"))?,
                    Warp::new(noise, seed, w.turbulence.amplitude.get(), None),
                )
            }
        })
    }
}

impl ElevationFnSpec {
    fn build(&self, scene_seed: u32) -> ElevationFn {
        let (kind, f) = match self {
            ElevationFnSpec::Constant(c) => return ElevationFn::Constant(c.get()),
            ElevationFnSpec::Fbm(f) => (Kind::Fbm, f),
            ElevationFnSpec::Ridged(f) => (Kind::Ridged, f),
            ElevationFnSpec::Hybrid(f) => (Kind::Hybrid, f),
        };
        ElevationFn::Fractal(Multifractal::new(
            kind,
            f.base.get(),
            f.amplitude.get(),
            f.wavelength.get(),
            f.octaves.get(),
            seed_of(scene_seed, f.seed_offset),
        ))
    }
}

impl ImageSpec {
    fn load(&self, cx: &BuildContext) -> Result<Heightfield, crate::dem::DemError> {
        let opts = ReadOptions {
            memory_budget: cx.budget,
            ..ReadOptions::default()
        };
        let mut dem = crate::dem::read(&cx.base_dir.join(&self.source), &opts)?;
        if let Some(c) = self.cell_size {
            dem = dem.resample(c.get().into(), Interpolation::Bilinear, cx.budget)?;
        }
        let hf = &dem.heightfield;
        let (s, o) = (self.vertical_scale.get(), self.vertical_offset.get());
        let z = hf.samples().iter().map(|&v| v * s + o).collect();
        let at = self.placement.map_or(glam::Vec2::ZERO, |p| p.0);
        Heightfield::new(hf.nx(), hf.ny(), hf.origin() + at, hf.cell(), z)
    }
}

impl ElevationSpec {
    /// The implicitization parameters this spec asks for.
    pub fn params(&self) -> ElevationParams {
        let r = self.falloff.get();
        ElevationParams {
            extent: Rect::new(self.extent.0.0, self.extent.1.0),
            falloff: r,
            base_depth: self.base_depth.map_or(r, NonNegative::get),
            lod: self.detail.map_or(Lod::FULL, |d| Lod::new(d.get())),
        }
    }

    /// Builds the elevation tree (not yet implicitized).
    pub fn build_tree(&self, cx: &BuildContext) -> Result<ElevationTree, ElevationError> {
        Ok(ElevationTree::new(self.tree.build(cx, "tree")?))
    }
}

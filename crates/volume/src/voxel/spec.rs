//! The RON format of Feature Curves: a [`FeatureSet`] (curves, shapes, tunnels, arches)
//! and the [`FeatureVolumeSpec`] tree node that runs the voxel pipeline on one.
//!
//! ```ron
//! FeatureVolume(
//!     curves: Inline(
//!         curves: [(
//!             points: [Abs(0, 32, 40), Abs(64, 40, 44), Abs(127, 32, 40)],
//!             constraints: [(t: 0, left: Slope(35), right: Slope(35))],
//!         )],
//!     ),
//!     domain: ((0, 0, 0), (127, 63, 63)),
//!     voxel: 1.0,
//! )
//! ```
//!
//! Points are `Abs(x, y, z)` or `Ground(x, y, offset)` (`offset` metres above the ground
//! given to [`FeatureVolumeSpec::build_with_ground`]). Bitangents are `Slope(degrees)` (see
//! [`slope_bitangent`]) or `Dir(x, y, z)`.

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

use super::{Expansion, FieldParams, Interpolation, Params, SField, expand, run_cached};
use crate::curves::compound::{Arch, Profile, Tube};
use crate::curves::constraint::{ConstraintPoint, FeatureCurve, reproject, slope_bitangent};
use crate::curves::shapes::{Disc, Quad};
use crate::curves::terrain::TerrainSurface;
use crate::curves::{BSpline, CurveError, Features, Orientation, Propagation};
use crate::field::Aabb;
use crate::field::Fbm;
use crate::field::noise::{Octaves, mix32};
use crate::value::{Dir3, Finite, NonNegative, P3, Positive, Unit};

/// A point: absolute, or anchored to the ground.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Point {
    /// `(x, y, z)` in metres.
    Abs(Finite, Finite, Finite),
    /// `offset` metres above the ground at `(x, y)` (negative: below).
    Ground(Finite, Finite, Finite),
}

/// A bitangent of a Constraint Point.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Bitangent {
    /// Degrees below the horizontal, on this side of the curve (see [`slope_bitangent`]).
    Slope(Finite),
    /// An explicit direction, projected onto the plane normal to the tangent.
    Dir(Finite, Finite, Finite),
}

fn zero() -> NonNegative {
    NonNegative(0.0)
}

/// Whether `v` is the default 0 (not written back).
fn is_zero(v: &NonNegative) -> bool {
    v.0 == 0.0
}

/// A Constraint Point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConstraintSpec {
    /// Position on the curve, in `[0, 1]`.
    pub t: Unit,
    /// Left-hand bitangent.
    pub left: Bitangent,
    /// Right-hand bitangent.
    pub right: Bitangent,
    /// Noise amplitude α (metres).
    #[serde(default = "zero", skip_serializing_if = "is_zero")]
    pub amplitude: NonNegative,
    /// Noise roughness β: base frequency of the noise (1/m).
    #[serde(default = "zero", skip_serializing_if = "is_zero")]
    pub roughness: NonNegative,
}

fn yes() -> bool {
    true
}

/// Whether `v` is the default `true` (not written back).
fn is_yes(v: &bool) -> bool {
    *v
}

/// A Feature Curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurveSpec {
    /// A name for messages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Control vertices (at least two; the curve interpolates the first and the last).
    pub points: Vec<Point>,
    /// Constraint Points (at least one), sorted by `t`.
    pub constraints: Vec<ConstraintSpec>,
    /// Seed (the surface passes through it) or guidance (it only steers normals).
    #[serde(default = "yes", skip_serializing_if = "is_yes")]
    pub seed: bool,
    /// Ribbon width in metres (default: the volume's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ribbon: Option<Positive>,
}

/// A quad; the normal follows the corners' winding (counter-clockwise seen from the air).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QuadSpec {
    /// Corners in order.
    pub corners: [Point; 4],
    /// Seed or guidance.
    #[serde(default = "yes", skip_serializing_if = "is_yes")]
    pub seed: bool,
    /// Noise amplitude.
    #[serde(default = "zero", skip_serializing_if = "is_zero")]
    pub amplitude: NonNegative,
    /// Noise roughness.
    #[serde(default = "zero", skip_serializing_if = "is_zero")]
    pub roughness: NonNegative,
}

/// A disc.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiscSpec {
    /// Centre.
    pub center: Point,
    /// Normal (into the air).
    pub normal: Dir3,
    /// Radius.
    pub radius: Positive,
    /// Seed or guidance.
    #[serde(default = "yes", skip_serializing_if = "is_yes")]
    pub seed: bool,
    /// Noise amplitude.
    #[serde(default = "zero", skip_serializing_if = "is_zero")]
    pub amplitude: NonNegative,
    /// Noise roughness.
    #[serde(default = "zero", skip_serializing_if = "is_zero")]
    pub roughness: NonNegative,
}

/// A profile along a path.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ProfileSpec {
    /// The same everywhere.
    Const(Positive),
    /// `(t, value)` keys, sorted by `t`, linear in between.
    Keys(Vec<(Unit, Positive)>),
}

/// A tunnel (an elliptic tube around `path`); tunnels sharing a point branch.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TunnelSpec {
    /// A name for messages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The axis' control vertices.
    pub path: Vec<Point>,
    /// Full width.
    pub width: ProfileSpec,
    /// Full height.
    pub height: ProfileSpec,
    /// Noise amplitude.
    #[serde(default = "zero", skip_serializing_if = "is_zero")]
    pub amplitude: NonNegative,
    /// Noise roughness.
    #[serde(default = "zero", skip_serializing_if = "is_zero")]
    pub roughness: NonNegative,
}

/// A natural arch: a rock slab from foot to foot, thinnest at the crown.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArchSpec {
    /// One foot (the centre of the slab where it meets the ground).
    pub from: Point,
    /// The other foot.
    pub to: Point,
    /// Apex height of the top above the feet.
    pub height: Positive,
    /// Thickness of the slab at the crown.
    pub thickness: Positive,
    /// Width of the slab at the crown, across the span (default: twice the thickness).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<Positive>,
    /// Thickness at the feet (default: three times the crown's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub abutment: Option<Positive>,
    /// Version-1 files: the slope in degrees of the flanks of the old two-curve beam. When
    /// `width` is absent it sets it: `thickness / tan(flank)`, the width at which flanks
    /// of that slope close the beam.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flank: Option<Finite>,
    /// Half-length of a ground curve under the apex, across the span (none by default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground: Option<Positive>,
    /// Noise amplitude.
    #[serde(default = "zero", skip_serializing_if = "is_zero")]
    pub amplitude: NonNegative,
    /// Noise roughness.
    #[serde(default = "zero", skip_serializing_if = "is_zero")]
    pub roughness: NonNegative,
}

/// The modelling primitives of a curve file.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeatureSet {
    /// Feature Curves.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub curves: Vec<CurveSpec>,
    /// Quads.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub quads: Vec<QuadSpec>,
    /// Discs.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub discs: Vec<DiscSpec>,
    /// Tunnels.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tunnels: Vec<TunnelSpec>,
    /// Arches.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub arches: Vec<ArchSpec>,
}

/// Where the curves of a volume come from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum CurveSource {
    /// Written in the tree file.
    Inline(FeatureSet),
    /// A `FeatureSet` RON file, relative to the tree file's folder.
    Path(PathBuf),
}

/// Solver settings of the pipeline (all have defaults).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SolverSpec {
    /// Perona–Malik edge parameter `k` (§4.3.1).
    pub k: Positive,
    /// Jacobi iterations per level below the coarsest (the coarse-to-fine cascade).
    pub iterations: u32,
    /// Half-width of the fine band around the surface, in voxels of each level.
    pub band: Positive,
    /// Largest node count per axis of the dense base level.
    pub base: u32,
    /// Gaussian smoothing passes on S (§4.6.3).
    pub smoothing: u32,
}

impl Default for SolverSpec {
    fn default() -> Self {
        SolverSpec {
            k: Positive(0.01),
            iterations: 8,
            band: Positive(6.0),
            base: 32,
            smoothing: 1,
        }
    }
}

/// Settings of the surface noise `S − α·fbm(β·q)`: the shared simplex fBm
/// ([`crate::field::Fbm`], gain ½, lacunarity 2, `|fbm| ≤ 1`); α and β come from the
/// Constraint Points. Written `noise: (octaves: 4, seed_offset: 0)`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SurfaceNoiseSpec {
    /// Octaves, `1..=12` (default 4).
    pub octaves: Octaves,
    /// Added to the scene's seed, as for every other noise of a tree (default 0).
    pub seed_offset: u32,
}

impl SurfaceNoiseSpec {
    /// The fBm of this volume for the scene seed `scene_seed`, in units where β is the
    /// first octave's frequency (wavelength 1 in `β·q`).
    pub fn fbm(&self, scene_seed: u32) -> Fbm {
        let seed = mix32(scene_seed ^ mix32(self.seed_offset.wrapping_add(0x9e37_79b9)));
        Fbm::with(seed, 1.0, self.octaves.get())
    }
}

/// Feature Curve expansion (Becher 2016 §4.5): `expansion: (length: 40)`. Each end of every
/// seed Feature Curve is continued along the surface of a first run, for at most `length`
/// metres or until it comes within `stop` of another curve; the pipeline then runs again
/// with the continuations as seed curves.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExpansionSpec {
    /// Longest continuation of each end (metres).
    pub length: Positive,
    /// Spacing of the continuation's control vertices (default 2 voxels).
    #[serde(default)]
    pub step: Option<Positive>,
    /// Distance to another curve at which a continuation stops (default 4 voxels).
    #[serde(default)]
    pub stop: Option<Positive>,
}

/// A tree node: Feature Curves compiled by the voxel pipeline into an S-field primitive.
/// Written `FeatureVolume(..)` in RON.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "FeatureVolume", deny_unknown_fields)]
pub struct FeatureVolumeSpec {
    /// A name for messages.
    #[serde(default)]
    pub name: Option<String>,
    /// The primitives.
    pub curves: CurveSource,
    /// The domain box `(min, max)`; the field's support.
    pub domain: (P3, P3),
    /// Voxel size (metres).
    pub voxel: Positive,
    /// Solid side.
    #[serde(default)]
    pub orientation: Orientation,
    /// Width `R` of the sigmoid `σ_R` turning S into the field (default 2 voxels).
    #[serde(default)]
    pub transition: Option<Positive>,
    /// Width of the fade to 0 inside the domain's faces (default 4 voxels).
    #[serde(default)]
    pub falloff: Option<Positive>,
    /// Surface propagation method.
    #[serde(default)]
    pub propagation: Propagation,
    /// Default ribbon width (default 2 voxels).
    #[serde(default)]
    pub ribbon: Option<Positive>,
    /// Solver settings.
    #[serde(default)]
    pub solver: SolverSpec,
    /// Noise settings.
    #[serde(default)]
    pub noise: SurfaceNoiseSpec,
    /// Feature Curve expansion (none by default).
    #[serde(default)]
    pub expansion: Option<ExpansionSpec>,
    /// Interpolation of S between the voxel nodes (trilinear by default).
    #[serde(default)]
    pub interpolation: Interpolation,
    /// The scene's terrain as boundary conditions: it is sampled over the domain (every
    /// voxel) and its surface enters the pipeline as seed triangles (see
    /// [`super::terrain`]), so S reproduces the ground away from the features. Put the
    /// volume in a `Replace` node over the terrain. Off by default.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub on_terrain: bool,
    /// With `on_terrain`, the room left to the features: the terrain's samples give way
    /// within this many metres of a curve's ribbon or a tube's section (default: 4
    /// voxels).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clearance: Option<Positive>,
}

/// Reads a RON file with the tree files' options (`Some` implicit, newtype variants
/// unwrapped: `Inline(curves: [..])`, a UTF-8 byte-order mark skipped), reporting parse
/// errors with the path, line and column.
pub fn parse_ron<T: serde::de::DeserializeOwned>(text: &str, path: &Path) -> Result<T, CurveError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    crate::value::ron_options()
        .from_str(text)
        .map_err(|e| CurveError::Parse {
            path: path.to_path_buf(),
            line: e.span.start.line,
            col: e.span.start.col,
            msg: crate::value::ron_message(&e, text, "a karstic RON file"),
        })
}

/// The largest curves file read, in bytes: far above any hand-written or generated set of
/// curves, and a bound on what a mistaken path (a disk image, a log) costs.
pub const MAX_CURVES_FILE: u64 = 256 << 20;

/// Reads and parses a RON file: a regular file (a FIFO would block, `/dev/zero` never
/// ends) of at most [`MAX_CURVES_FILE`] bytes, in UTF-8.
pub fn load_ron<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, CurveError> {
    let bytes = crate::io::read_regular(path, MAX_CURVES_FILE)?;
    let text = String::from_utf8(bytes).map_err(|e| CurveError::Read {
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, e.utf8_error()),
    })?;
    parse_ron(&text, path)
}

/// The ground callback: terrain height at `(x, y)`, `None` outside the terrain.
pub type Ground<'a> = &'a dyn Fn(Vec2) -> Option<f32>;

struct Resolver<'a> {
    ground: Ground<'a>,
}

impl Resolver<'_> {
    fn point(&self, p: &Point, what: &dyn Fn() -> String) -> Result<Vec3, CurveError> {
        match *p {
            Point::Abs(x, y, z) => Ok(Vec3::new(x.0, y.0, z.0)),
            Point::Ground(x, y, off) => {
                let xy = Vec2::new(x.0, y.0);
                match (self.ground)(xy) {
                    Some(h) if h.is_finite() => Ok(xy.extend(h + off.0)),
                    _ => Err(CurveError::invalid(
                        what(),
                        format!(
                            "Ground({}, {}, {}) has no ground height there (no terrain given, or outside it)",
                            x, y, off
                        ),
                    )),
                }
            }
        }
    }

    fn points(&self, ps: &[Point], what: &dyn Fn() -> String) -> Result<Vec<Vec3>, CurveError> {
        ps.iter()
            .enumerate()
            .map(|(i, p)| self.point(p, &|| format!("{} point {i}", what())))
            .collect()
    }
}

fn label(kind: &str, i: usize, name: &Option<String>) -> String {
    match name {
        Some(n) => format!("{kind} {i} \"{n}\""),
        None => format!("{kind} {i}"),
    }
}

fn bitangent(
    b: &Bitangent,
    tangent: Vec3,
    left: bool,
    what: &dyn Fn() -> String,
) -> Result<Vec3, CurveError> {
    let v = match *b {
        Bitangent::Slope(deg) => slope_bitangent(tangent, left, deg.0).ok_or_else(|| {
            CurveError::invalid(
                what(),
                "Slope(..) needs a non-vertical curve here; use Dir(x, y, z)",
            )
        })?,
        Bitangent::Dir(x, y, z) => Vec3::new(x.0, y.0, z.0),
    };
    let p = v.reject_from_normalized(tangent);
    if p.length() < 1e-3 * v.length().max(1e-12) {
        return Err(CurveError::invalid(
            what(),
            "bitangent is zero or parallel to the curve",
        ));
    }
    Ok(reproject(p, tangent))
}

fn profile(p: &ProfileSpec, what: &dyn Fn() -> String) -> Result<Profile, CurveError> {
    match p {
        ProfileSpec::Const(v) => Ok(Profile::constant(v.0)),
        ProfileSpec::Keys(k) if k.is_empty() => Err(CurveError::invalid(
            what(),
            "a profile needs at least one key",
        )),
        ProfileSpec::Keys(k) => {
            if k.windows(2).any(|w| w[1].0.0 < w[0].0.0) {
                return Err(CurveError::invalid(
                    what(),
                    "profile keys must be sorted by t",
                ));
            }
            Ok(Profile(k.iter().map(|(t, v)| (t.0, v.0)).collect()))
        }
    }
}

fn spline(points: Vec<Vec3>, what: &dyn Fn() -> String) -> Result<BSpline, CurveError> {
    if points.windows(2).all(|w| w[0].distance(w[1]) < 1e-6) {
        return Err(CurveError::invalid(
            what(),
            "needs at least two distinct points",
        ));
    }
    BSpline::new(points).ok_or_else(|| CurveError::invalid(what(), "needs at least two points"))
}

impl FeatureSet {
    /// Resolves the file into world-space primitives; `ground` answers `Ground(..)`
    /// points.
    pub fn resolve(&self, ground: Ground<'_>) -> Result<Features, CurveError> {
        let r = Resolver { ground };
        let mut out = Features::default();
        for (i, c) in self.curves.iter().enumerate() {
            let what = || label("curve", i, &c.name);
            let spline = spline(r.points(&c.points, &what)?, &what)?;
            if c.constraints.is_empty() {
                return Err(CurveError::invalid(
                    what(),
                    "needs at least one Constraint Point",
                ));
            }
            let mut constraints = Vec::with_capacity(c.constraints.len());
            for (k, cs) in c.constraints.iter().enumerate() {
                let cwhat = || format!("{} constraint {k}", what());
                if k > 0 && cs.t.0 < c.constraints[k - 1].t.0 {
                    return Err(CurveError::invalid(
                        cwhat(),
                        "Constraint Points must be sorted by t",
                    ));
                }
                let v = spline.tangent(cs.t.0);
                constraints.push(ConstraintPoint {
                    t: cs.t.0,
                    left: bitangent(&cs.left, v, true, &|| format!("{} left", cwhat()))?,
                    right: bitangent(&cs.right, v, false, &|| format!("{} right", cwhat()))?,
                    amplitude: cs.amplitude.0,
                    roughness: cs.roughness.0,
                });
            }
            out.curves.push(FeatureCurve {
                spline,
                constraints,
                seed: c.seed,
                ribbon: c.ribbon.map(|w| w.0),
            });
        }
        for (i, q) in self.quads.iter().enumerate() {
            let what = || format!("quad {i}");
            let pts = r.points(&q.corners, &what)?;
            let quad = Quad {
                corners: [pts[0], pts[1], pts[2], pts[3]],
                seed: q.seed,
                noise: Vec2::new(q.amplitude.0, q.roughness.0),
            };
            if quad.normal() == Vec3::ZERO {
                return Err(CurveError::invalid(
                    what(),
                    "the corners are degenerate (no normal)",
                ));
            }
            out.quads.push(quad);
        }
        for (i, d) in self.discs.iter().enumerate() {
            let what = || format!("disc {i}");
            out.discs.push(Disc {
                center: r.point(&d.center, &what)?,
                normal: d.normal.unit(),
                radius: d.radius.0,
                seed: d.seed,
                noise: Vec2::new(d.amplitude.0, d.roughness.0),
            });
        }
        for (i, t) in self.tunnels.iter().enumerate() {
            let what = || label("tunnel", i, &t.name);
            out.tunnels.push(Tube {
                path: spline(r.points(&t.path, &what)?, &what)?,
                width: profile(&t.width, &|| format!("{} width", what()))?,
                height: profile(&t.height, &|| format!("{} height", what()))?,
                noise: Vec2::new(t.amplitude.0, t.roughness.0),
                inward: true,
            });
        }
        for (i, a) in self.arches.iter().enumerate() {
            let what = || format!("arch {i}");
            let (from, to) = (r.point(&a.from, &what)?, r.point(&a.to, &what)?);
            if Vec2::new(to.x - from.x, to.y - from.y).length() < 1e-3 {
                return Err(CurveError::invalid(
                    what(),
                    "the feet must be apart horizontally",
                ));
            }
            if a.thickness.0 >= a.height.0 {
                return Err(CurveError::invalid(
                    what(),
                    "thickness must be less than height",
                ));
            }
            let thickness = a.thickness.0;
            let width = match (a.width, a.flank) {
                (Some(w), _) => w.0,
                (None, Some(f)) if f.0 > 1.0 && f.0 < 89.0 => thickness / f.0.to_radians().tan(),
                (None, Some(f)) => {
                    return Err(CurveError::invalid(
                        format!("{} flank", what()),
                        format!("{f} degrees: must lie between 1 and 89 (or give `width`)"),
                    ));
                }
                (None, None) => 2.0 * thickness,
            };
            out.arches.push(Arch {
                from,
                to,
                height: a.height.0,
                thickness,
                width,
                abutment: a.abutment.map_or(3.0 * thickness, |b| b.0),
                ground: a.ground.map(|g| g.0),
                noise: Vec2::new(a.amplitude.0, a.roughness.0),
            });
        }
        Ok(out)
    }
}

impl FeatureVolumeSpec {
    /// The feature set, read from its file when given by path (relative to `base_dir`).
    pub fn feature_set(&self, base_dir: &Path) -> Result<FeatureSet, CurveError> {
        match &self.curves {
            CurveSource::Inline(set) => Ok(set.clone()),
            CurveSource::Path(p) => load_ron(&base_dir.join(p)),
        }
    }

    /// A label for messages.
    pub fn label(&self) -> String {
        match &self.name {
            Some(n) => format!("feature volume \"{n}\""),
            None => "feature volume".to_string(),
        }
    }
}

/// Options of [`FeatureVolumeSpec::build_with`].
#[derive(Clone, Copy)]
pub struct BuildOptions<'a> {
    /// Seed of the displacement noise.
    pub seed: u32,
    /// Answers `Ground(..)` points (`None`: such points are an error).
    pub ground: Option<Ground<'a>>,
    /// Memory budget of the grids (bytes).
    pub max_memory: u64,
}

impl Default for BuildOptions<'_> {
    fn default() -> Self {
        BuildOptions {
            seed: 0,
            ground: None,
            max_memory: crate::io::DEFAULT_MEMORY_BUDGET,
        }
    }
}

impl FeatureVolumeSpec {
    /// The pipeline's and the field's parameters.
    pub fn params(&self, seed: u32, max_memory: u64) -> (Params, FieldParams) {
        let h = self.voxel.0;
        let (a, b) = (self.domain.0.0, self.domain.1.0);
        let domain = Aabb::new(a, b);
        let transition = self.transition.map_or(2.0 * h, |t| t.0);
        let p = Params {
            domain,
            voxel: h,
            k: self.solver.k.0,
            iterations: self.solver.iterations,
            band: self.solver.band.0,
            base: self.solver.base,
            smoothing: self.solver.smoothing,
            propagation: self.propagation,
            max_memory,
            ribbon: self.ribbon_width(),
            keep_normals: false,
            transition,
        };
        let f = FieldParams {
            domain,
            voxel: h,
            orientation: self.orientation,
            transition,
            falloff: self.falloff.map_or(4.0 * h, |t| t.0),
            fbm: self.noise.fbm(seed),
            interpolation: self.interpolation,
        };
        (p, f)
    }

    /// Default ribbon width: 2 voxels.
    pub fn ribbon_width(&self) -> f32 {
        self.ribbon.map_or(2.0 * self.voxel.0, |r| r.0)
    }

    /// Runs the pipeline (or takes its cached result) and returns the S-field primitive.
    /// Curve files are found relative to `base_dir`.
    pub fn build(&self, base_dir: &Path, seed: u32) -> Result<SField, CurveError> {
        self.build_with(
            base_dir,
            &BuildOptions {
                seed,
                ..Default::default()
            },
        )
    }

    /// [`FeatureVolumeSpec::build`] with a ground callback and a memory budget.
    pub fn build_with(
        &self,
        base_dir: &Path,
        opts: &BuildOptions<'_>,
    ) -> Result<SField, CurveError> {
        let features = self.resolve(base_dir, opts)?;
        self.build_features(&features, opts.seed, opts.max_memory)
    }

    /// The volume's primitives in world coordinates, `Ground(..)` points resolved on
    /// `opts.ground`, and with `on_terrain` the terrain sampled over the domain: what
    /// [`FeatureVolumeSpec::build_with`] runs the pipeline on.
    pub fn resolve(
        &self,
        base_dir: &Path,
        opts: &BuildOptions<'_>,
    ) -> Result<Features, CurveError> {
        let no_ground = |_: Vec2| None;
        let set = self.feature_set(base_dir)?;
        let mut features = set
            .resolve(opts.ground.unwrap_or(&no_ground))
            .map_err(|e| match e {
                CurveError::Invalid { what, msg } => CurveError::Invalid {
                    what: format!("{}: {what}", self.label()),
                    msg,
                },
                e => e,
            })?;
        self.check_inside(&set, &features)?;
        if self.on_terrain {
            if self.orientation != Orientation::Solid {
                return Err(CurveError::invalid(
                    format!("{} on_terrain", self.label()),
                    "terrain boundary conditions need `orientation: Solid` (the volume stands in for the ground)",
                ));
            }
            let ground = opts.ground.ok_or_else(|| {
                CurveError::invalid(
                    format!("{} on_terrain", self.label()),
                    "terrain boundary conditions need a terrain: the scene has no Heightfield",
                )
            })?;
            features.terrain = Some(self.terrain_surface(&features, ground));
        }
        Ok(features)
    }

    /// Errors when a primitive lies wholly outside the domain: the pipeline would draw
    /// nothing of it, and the feature the user placed would be silently missing. A
    /// curve lies in the hull of its control points, a tube within its largest section
    /// of them; a primitive that leaves the domain in part (a tunnel opening out of it)
    /// is what the domain's faces fade, and is kept.
    fn check_inside(&self, set: &FeatureSet, features: &Features) -> Result<(), CurveError> {
        let domain = Aabb::new(self.domain.0.0, self.domain.1.0);
        let reach = |points: &[Vec3], pad: f32| {
            let b = Aabb::from_points(points.iter().copied());
            Aabb::new(b.min - Vec3::splat(pad), b.max + Vec3::splat(pad))
        };
        let tube = |t: &Tube| reach(t.path.control(), 0.5 * t.width.max().max(t.height.max()));
        let reaches = features
            .curves
            .iter()
            .zip(&set.curves)
            .enumerate()
            .map(|(i, (c, spec))| {
                let pad = c.ribbon.unwrap_or(0.0);
                (
                    label("curve", i, &spec.name),
                    reach(c.spline.control(), pad),
                )
            })
            .chain(
                features
                    .quads
                    .iter()
                    .enumerate()
                    .map(|(i, q)| (format!("quad {i}"), reach(&q.corners, 0.0))),
            )
            .chain(
                features
                    .discs
                    .iter()
                    .enumerate()
                    .map(|(i, d)| (format!("disc {i}"), reach(&[d.center], d.radius))),
            )
            .chain(
                features
                    .tunnels
                    .iter()
                    .zip(&set.tunnels)
                    .enumerate()
                    .map(|(i, (t, spec))| (label("tunnel", i, &spec.name), tube(t))),
            )
            .chain(
                features
                    .arches
                    .iter()
                    .enumerate()
                    .map(|(i, a)| (format!("arch {i}"), tube(&a.beam()))),
            );
        for (what, b) in reaches {
            if !b.overlaps(&domain) {
                return Err(CurveError::invalid(
                    format!("{}: {what}", self.label()),
                    format!(
                        "lies wholly outside the volume's domain {:?} .. {:?}: nothing of it \
                         would be drawn (move it, or widen `domain`)",
                        domain.min.to_array(),
                        domain.max.to_array()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The terrain under the volume, sampled over its domain, with room made for the
    /// features.
    fn terrain_surface(&self, features: &Features, ground: Ground<'_>) -> TerrainSurface {
        let h = self.voxel.0;
        let (a, b) = (self.domain.0.0, self.domain.1.0);
        let clearance = self.clearance.map_or(4.0 * h, |c| c.0);
        let beta = features.max_roughness();
        let mut surface = TerrainSurface::new(ground, &Aabb::new(a, b), h, clearance, beta);
        // The compounds' sides of the ground are read off the surface itself.
        let on = Features {
            terrain: Some(surface.clone()),
            ..features.clone()
        };
        surface.make_room(&on.room(0.5 * h, self.ribbon_width(), clearance));
        surface
    }

    /// Runs the pipeline on resolved primitives.
    pub fn build_features(
        &self,
        features: &Features,
        seed: u32,
        max_memory: u64,
    ) -> Result<SField, CurveError> {
        let (p, f) = self.params(seed, max_memory);
        let Some(e) = &self.expansion else {
            let (vol, _) = run_cached(features, &p)?;
            return Ok(SField::new(vol, f));
        };
        // The first run keeps its guidance normals for tracing.
        let first = Params {
            keep_normals: true,
            ..p.clone()
        };
        let (vol, _) = run_cached(features, &first)?;
        let field = SField::new(vol, f);
        let h = self.voxel.0;
        let expansion = Expansion {
            length: e.length.0,
            step: e.step.map_or(2.0 * h, |s| s.0),
            stop: e.stop.map_or(4.0 * h, |s| s.0),
        };
        let grown = expand(features, &field, &expansion);
        if grown.curves.is_empty() {
            return Ok(field.with_expansion(grown));
        }
        let mut all = features.clone();
        all.curves.extend(grown.curves.iter().cloned());
        let (vol, _) = run_cached(&all, &p)?;
        Ok(SField::new(vol, f).with_expansion(grown))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPEC: &str = r#"
        FeatureVolume(
            name: "cliff",
            curves: Inline(
                curves: [(
                    points: [Abs(0, 32, 40), Ground(64, 40, -2), Abs(127, 32, 40)],
                    constraints: [
                        (t: 0, left: Slope(0), right: Slope(90)),
                        (t: 1, left: Dir(0, 1, 0), right: Slope(100), amplitude: 1.5, roughness: 0.1),
                    ],
                )],
                tunnels: [(path: [Abs(0, 0, 0), Abs(10, 0, 0)], width: Const(4), height: Keys([(0, 3), (1, 5)]))],
            ),
            domain: ((0, 0, 0), (127, 63, 63)),
            voxel: 1.0,
        )
    "#;

    #[test]
    fn parses_resolves_and_anchors_to_the_ground() {
        let spec: FeatureVolumeSpec = parse_ron(SPEC, Path::new("<test>")).unwrap();
        assert_eq!(spec.solver, SolverSpec::default());
        let set = spec.feature_set(Path::new(".")).unwrap();
        let ground = |xy: Vec2| Some(0.5 * xy.x);
        let f = set.resolve(&ground).unwrap();
        assert_eq!(f.curves[0].spline.control()[1], Vec3::new(64.0, 40.0, 30.0));
        assert_eq!(f.curves[0].constraints[1].amplitude, 1.5);
        assert_eq!(f.tunnels.len(), 1);
        let none = |_: Vec2| None;
        let e = set.resolve(&none).unwrap_err().to_string();
        assert!(
            e.contains("curve 0 point 1") && e.contains("Ground(64, 40, -2)"),
            "{e}"
        );
    }

    #[test]
    fn bad_values_are_reported_with_position_or_field() {
        let bad = SPEC.replace("voxel: 1.0", "voxel: -1.0");
        let e = parse_ron::<FeatureVolumeSpec>(&bad, Path::new("x.ron"))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("x.ron:") && e.contains("expected a number > 0"),
            "{e}"
        );
        let bad = SPEC.replace("Dir(0, 1, 0)", "Dir(0, 0, 0)");
        let spec: FeatureVolumeSpec = parse_ron(&bad, Path::new("x.ron")).unwrap();
        let e = spec
            .feature_set(Path::new("."))
            .unwrap()
            .resolve(&|_| Some(0.0))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("curve 0 constraint 1 left") && e.contains("zero or parallel"),
            "{e}"
        );
        let missing = CurveSource::Path("does/not/exist.ron".into());
        let spec = FeatureVolumeSpec {
            curves: missing,
            ..spec
        };
        assert!(
            spec.feature_set(Path::new("/tmp"))
                .unwrap_err()
                .to_string()
                .contains("does/not/exist.ron")
        );
    }
}

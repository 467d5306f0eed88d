//! The serde types of a tree file: the scene and its node kinds.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::landform::{
    ArchSpec, CanyonSpec, CaprockSpec, HoodooSpec, KarstSpec, SeaCliffSpec, SeaSpec,
};
use crate::elevation::ElevationSpec;
use crate::field::{NoiseSpec, PrimitiveSpec};
use crate::scene::HeightfieldSpec;
use crate::value::{BoxSpec, Dir3, Finite, NonNegative, P2, P3, Positive, Region, Scale3, Unit};
use crate::voxel::FeatureVolumeSpec;

/// The tree-file format version this build reads and writes.
pub const FORMAT_VERSION: u32 = 1;

/// A whole tree file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Format version; must be [`FORMAT_VERSION`].
    pub version: u32,
    /// Optional scene name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Global seed: every noise of the scene derives from it.
    #[serde(default)]
    pub seed: u32,
    /// The `Heightfield` node that terrain anchors (`Anchor` nodes, `Ground(x, y, offset)`
    /// curve points) resolve against. Default: the scene's only heightfield.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub terrain: Option<String>,
    /// What `karstic run` makes of the scene: mesh region, cell size, preview camera.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub job: Option<JobSpec>,
    /// The rock's resistance to erosion (Paris et al. 2019 §4), read by `Erode` nodes and
    /// the landform generators; uniform when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub geology: Option<crate::geology::GeologySpec>,
    /// Named subtrees that are not drawn themselves but can be instanced.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub defs: Vec<NodeSpec>,
    /// The tree.
    pub root: NodeSpec,
}

/// One node of a tree file. In RON: `Blend(name: "root", children: [...])`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum NodeSpec {
    /// A skeletal primitive (Paris et al. 2019 §5.2): `energy · g(d̃ / R)` around a skeleton.
    Primitive(PrimitiveSpec),
    /// A DEM as an implicit terrain (Paris et al. 2019 §5.1): solid below the elevation.
    Heightfield(HeightfieldSpec),
    /// An elevation tree (Génevaux et al. 2015) implicitized like a DEM: solid below it.
    Elevation(ElevationSpec),
    /// Feature Curves compiled by the voxel pipeline into an S-field primitive (Becher 2016).
    FeatureVolume(FeatureVolumeSpec),
    /// A subtree placed on the terrain: its origin moved to `(x, y, h(x, y) + offset)`.
    Anchor(AnchorSpec),
    /// Sum of the children (Wyvill blend).
    Blend(Nary),
    /// Max of the children.
    Union(Nary),
    /// Min of the children.
    Intersection(Nary),
    /// The base with the carves removed: `min(f_base, 2T − f_carve, …)`.
    Difference(DifferenceSpec),
    /// Affine placement of a subtree: scale, then rotate, then translate.
    Transform(TransformSpec),
    /// A reference to a named node (in `defs` or the tree), so it can be reused.
    Instance(InstanceSpec),
    /// Localized turbulence warp of a subtree (Paris et al. 2019 §5.3).
    Warp(WarpSpec),
    /// `by` stands in for `base` inside a region, with a smooth transition near the
    /// region's faces: how a terrain-aware Feature Volume goes into its terrain.
    Replace(ReplaceSpec),
    /// The child worn away where the scene's geology is soft, inside a region:
    /// `f − a·w·(1 − ρ)` (Paris et al. 2019 §6).
    Erode(ErodeSpec),
    /// A landform generator (Paris et al. 2019 §6) over a base terrain: expanded into
    /// plain primitives when the tree compiles (`karstic tree expand` writes them out).
    Landform(LandformSpec),
}

/// An erosion node: `f_child(p) − strength · w(p) · (1 − ρ(p))`, `ρ` the scene's
/// `geology`, `w` 1 inside the region and falling to 0 over `blend` metres inside its
/// faces.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ErodeSpec {
    /// Unique node name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// How much the field drops where the rock is softest (`ρ = 0`), in field units
    /// (the iso-value is 0.5): 0.2 to 0.45 recess soft layers, more cuts through.
    pub strength: NonNegative,
    /// Where erosion acts.
    pub region: BoxSpec,
    /// Width of the fade inside the region's faces, metres (default: an eighth of the
    /// region's smaller horizontal side).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blend: Option<Positive>,
    /// The eroded subtree.
    pub child: Box<NodeSpec>,
}

/// A replace node: `f_base + w·(f_by − f_base)` with `w` a partition of unity of the
/// region (1 inside, falling to 0 over `blend` metres inside its faces, 0 outside).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReplaceSpec {
    /// Unique node name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// What is replaced (the terrain).
    pub base: Box<NodeSpec>,
    /// What stands in for it: typically a `FeatureVolume` with `terrain: Some(())`.
    pub by: Box<NodeSpec>,
    /// The region (default: `by`'s support box; a Feature Volume's domain inside its face
    /// falloff).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<BoxSpec>,
    /// Width of the transition inside the region's faces, in metres (default: an eighth
    /// of the region's smaller horizontal side).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blend: Option<Positive>,
}

/// An n-ary operator node.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Nary {
    /// Unique node name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Children.
    pub children: Vec<NodeSpec>,
}

/// A difference (carve) node.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DifferenceSpec {
    /// Unique node name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// What is carved.
    pub base: Box<NodeSpec>,
    /// What carves it away.
    pub carves: Vec<NodeSpec>,
}

/// A rotation by `degrees` about `axis` (right-handed).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rotation {
    /// Rotation axis.
    pub axis: Dir3,
    /// Angle in degrees.
    pub degrees: Finite,
}

/// An affine placement node.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransformSpec {
    /// Unique node name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Translation in metres.
    #[serde(default)]
    pub translate: P3,
    /// Rotation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotate: Option<Rotation>,
    /// Per-axis scale; a negative factor mirrors (e.g. `(1, 1, -1)` turns a terrain upside
    /// down). No factor may be 0.
    #[serde(default)]
    pub scale: Scale3,
    /// The placed subtree.
    pub child: Box<NodeSpec>,
}

/// A look-at camera.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// Eye position.
    pub eye: P3,
    /// Point looked at.
    pub target: P3,
}

/// The default job of a scene (`karstic run`): a fine mesh and a preview of a region, and
/// a coarse mesh of the whole scene with `--full`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JobSpec {
    /// Region meshed and framed (default: the scene's support box).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<BoxSpec>,
    /// Marching Cubes cell size in metres for the region.
    pub cell: Positive,
    /// Preview size in pixels `(width, height)`.
    #[serde(default = "default_image")]
    pub image: (u32, u32),
    /// Preview camera (default: framed from the region).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera: Option<CameraSpec>,
    /// Vertical field of view in degrees.
    #[serde(default = "default_fov")]
    pub fov: Positive,
    /// Cell size of the whole-scene mesh made with `--full` (default: 4 × `cell`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub full_cell: Option<Positive>,
    /// Cameras of the close-ups, by name: a feature's name fixes that feature's view where
    /// the automatic close-up does not suit; any other name adds a view of its own (a part
    /// of a landform: an arch, a shelter). `karstic run` writes a view of each named feature,
    /// then of each other name, in the order of the names.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub views: std::collections::BTreeMap<String, CameraSpec>,
    /// Size of the feature views in pixels (default: half the preview's on each side).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub view_image: Option<(u32, u32)>,
    /// Altitude (metres) above which flats turn to snow (default: no snow).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub snow_line: Option<Finite>,
    /// Altitude (metres) of a water surface the pictures draw: a sea or a lake, with
    /// shallows showing their floor (default: no water; meshes are not affected).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub water_level: Option<Finite>,
    /// Where the sun stands in the pictures (default: in the south-west, 38° up). Light a
    /// cliff from the side it faces, low, as a photographer waits for, and its ledges,
    /// joints and recesses read.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sun: Option<SunSpec>,
    /// What covers the ground that is not rock in the pictures and the meshes' colours
    /// (default `Temperate`: grass, patches of dry grass, soil on the slopes).
    #[serde(default, skip_serializing_if = "Climate::is_temperate")]
    pub climate: Climate,
    /// How much of the ground fit for plants the pictures' trees and shrubs cover, in
    /// `[0, 1]` (default: the climate's, [`Climate::vegetation`]; 0: bare ground). They
    /// grow on soil and grass, not on rock, scree or features, in stands with clearings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vegetation: Option<Unit>,
}

/// The ground cover of a scene: what grows, or does not, between the rocks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Climate {
    /// Grass, patches of dry grass, soil on the slopes: a humid hill country.
    #[default]
    Temperate,
    /// Red sand between the rocks, patches of dark desert scrub, redder soil on the
    /// slopes: the plateau deserts where arches, fins and hoodoos stand (hoodoos on a
    /// lawn read as a set to blind judges).
    Arid,
}

impl Climate {
    fn is_temperate(&self) -> bool {
        *self == Climate::Temperate
    }

    /// The plants of the climate and the share of the fit ground they cover by default:
    /// a woodland of stands and clearings (0.55), or scattered desert scrub (0.2).
    pub fn vegetation(self) -> (crate::render::Flora, f32) {
        match self {
            Climate::Temperate => (crate::render::Flora::Woodland, 0.55),
            Climate::Arid => (crate::render::Flora::Scrub, 0.2),
        }
    }
}

/// The sun of a scene's pictures.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SunSpec {
    /// Compass bearing, degrees clockwise from north (+y): 90 is east, 180 south.
    pub azimuth: Finite,
    /// Height above the horizon, degrees, above 0 and at most 90.
    pub elevation: Finite,
}

impl SunSpec {
    /// The unit vector towards the sun.
    pub fn direction(&self) -> Vec3 {
        let (az, el) = (self.azimuth.0.to_radians(), self.elevation.0.to_radians());
        Vec3::new(az.sin() * el.cos(), az.cos() * el.cos(), el.sin())
    }
}

fn default_image() -> (u32, u32) {
    (1280, 720)
}

fn default_fov() -> Positive {
    Positive(crate::render::camera::DEFAULT_FOV)
}

/// A turbulence warp node: `child` evaluated at `p + δ(p)·f_D(p)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WarpSpec {
    /// Unique node name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The displacement: `amplitude` metres per axis, fBm of `wavelength` and `octaves`.
    pub turbulence: NoiseSpec,
    /// Where the warp applies (full strength inside the box); everywhere when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<Region>,
    /// The warped subtree.
    pub child: Box<NodeSpec>,
}

/// A subtree anchored to the terrain.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnchorSpec {
    /// Unique node name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Where on the terrain, in the terrain's frame (metres).
    pub at: P2,
    /// Height above (positive) or depth below (negative) the terrain surface there.
    #[serde(default)]
    pub offset: Finite,
    /// The anchored subtree, built around its own origin.
    pub child: Box<NodeSpec>,
}

/// A reference to another named node.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InstanceSpec {
    /// Unique node name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Name of the referenced node.
    pub of: String,
}

impl NodeSpec {
    /// The node's kind as written in the file.
    pub fn kind(&self) -> &'static str {
        match self {
            NodeSpec::Primitive(_) => "Primitive",
            NodeSpec::Heightfield(_) => "Heightfield",
            NodeSpec::Elevation(_) => "Elevation",
            NodeSpec::FeatureVolume(_) => "FeatureVolume",
            NodeSpec::Anchor(_) => "Anchor",
            NodeSpec::Blend(_) => "Blend",
            NodeSpec::Union(_) => "Union",
            NodeSpec::Intersection(_) => "Intersection",
            NodeSpec::Difference(_) => "Difference",
            NodeSpec::Transform(_) => "Transform",
            NodeSpec::Instance(_) => "Instance",
            NodeSpec::Warp(_) => "Warp",
            NodeSpec::Replace(_) => "Replace",
            NodeSpec::Landform(_) => "Landform",
            NodeSpec::Erode(_) => "Erode",
        }
    }

    /// The node's name.
    pub fn name(&self) -> Option<&str> {
        match self {
            NodeSpec::Primitive(n) => n.name.as_deref(),
            NodeSpec::Heightfield(n) => n.name.as_deref(),
            NodeSpec::Elevation(n) => n.name.as_deref(),
            NodeSpec::FeatureVolume(n) => n.name.as_deref(),
            NodeSpec::Anchor(n) => n.name.as_deref(),
            NodeSpec::Blend(n) | NodeSpec::Union(n) | NodeSpec::Intersection(n) => {
                n.name.as_deref()
            }
            NodeSpec::Difference(n) => n.name.as_deref(),
            NodeSpec::Transform(n) => n.name.as_deref(),
            NodeSpec::Instance(n) => n.name.as_deref(),
            NodeSpec::Warp(n) => n.name.as_deref(),
            NodeSpec::Replace(n) => n.name.as_deref(),
            NodeSpec::Landform(n) => n.name.as_deref(),
            NodeSpec::Erode(n) => n.name.as_deref(),
        }
    }

    /// Mutable access to the node's name.
    pub fn name_mut(&mut self) -> &mut Option<String> {
        match self {
            NodeSpec::Primitive(n) => &mut n.name,
            NodeSpec::Heightfield(n) => &mut n.name,
            NodeSpec::Elevation(n) => &mut n.name,
            NodeSpec::FeatureVolume(n) => &mut n.name,
            NodeSpec::Anchor(n) => &mut n.name,
            NodeSpec::Blend(n) | NodeSpec::Union(n) | NodeSpec::Intersection(n) => &mut n.name,
            NodeSpec::Difference(n) => &mut n.name,
            NodeSpec::Transform(n) => &mut n.name,
            NodeSpec::Instance(n) => &mut n.name,
            NodeSpec::Warp(n) => &mut n.name,
            NodeSpec::Replace(n) => &mut n.name,
            NodeSpec::Landform(n) => &mut n.name,
            NodeSpec::Erode(n) => &mut n.name,
        }
    }

    /// Children, in order (the base of a difference first).
    pub fn children(&self) -> Vec<&NodeSpec> {
        match self {
            NodeSpec::Blend(n) | NodeSpec::Union(n) | NodeSpec::Intersection(n) => {
                n.children.iter().collect()
            }
            NodeSpec::Difference(d) => std::iter::once(&*d.base).chain(&d.carves).collect(),
            NodeSpec::Replace(r) => vec![&*r.base, &*r.by],
            NodeSpec::Transform(t) => vec![&*t.child],
            NodeSpec::Warp(w) => vec![&*w.child],
            NodeSpec::Erode(e) => vec![&*e.child],
            NodeSpec::Anchor(a) => vec![&*a.child],
            NodeSpec::Landform(l) => vec![&*l.base],
            NodeSpec::Instance(_)
            | NodeSpec::Primitive(_)
            | NodeSpec::Heightfield(_)
            | NodeSpec::Elevation(_)
            | NodeSpec::FeatureVolume(_) => Vec::new(),
        }
    }

    /// Whether the node has a list a new child can be appended to (`tree add`).
    pub fn takes_children(&self) -> bool {
        matches!(
            self,
            NodeSpec::Blend(_)
                | NodeSpec::Union(_)
                | NodeSpec::Intersection(_)
                | NodeSpec::Difference(_)
        )
    }

    /// Mutable access to the list a new child is appended to, if the node has one.
    pub fn child_list_mut(&mut self) -> Option<&mut Vec<NodeSpec>> {
        match self {
            NodeSpec::Blend(n) | NodeSpec::Union(n) | NodeSpec::Intersection(n) => {
                Some(&mut n.children)
            }
            NodeSpec::Difference(d) => Some(&mut d.carves),
            _ => None,
        }
    }

    /// Mutable children, in the order of [`NodeSpec::children`].
    pub fn children_mut(&mut self) -> Vec<&mut NodeSpec> {
        match self {
            NodeSpec::Blend(n) | NodeSpec::Union(n) | NodeSpec::Intersection(n) => {
                n.children.iter_mut().collect()
            }
            NodeSpec::Difference(d) => std::iter::once(&mut *d.base)
                .chain(d.carves.iter_mut())
                .collect(),
            NodeSpec::Replace(r) => vec![&mut *r.base, &mut *r.by],
            NodeSpec::Transform(t) => vec![&mut *t.child],
            NodeSpec::Warp(w) => vec![&mut *w.child],
            NodeSpec::Erode(e) => vec![&mut *e.child],
            NodeSpec::Anchor(a) => vec![&mut *a.child],
            NodeSpec::Landform(l) => vec![&mut *l.base],
            NodeSpec::Instance(_)
            | NodeSpec::Primitive(_)
            | NodeSpec::Heightfield(_)
            | NodeSpec::Elevation(_)
            | NodeSpec::FeatureVolume(_) => Vec::new(),
        }
    }

    /// Visits this node and its descendants, parents first.
    pub fn walk<'a>(&'a self, visit: &mut impl FnMut(&'a NodeSpec, usize)) {
        fn rec<'a>(n: &'a NodeSpec, depth: usize, visit: &mut impl FnMut(&'a NodeSpec, usize)) {
            visit(n, depth);
            for c in n.children() {
                rec(c, depth + 1, visit);
            }
        }
        rec(self, 0, visit)
    }
}

/// A landform node of a tree file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LandformSpec {
    /// Unique node name; the expansion keeps it, its primitives' blend is `NAME-carves`
    /// (or `NAME-rocks`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Seed of the generator's random choices (mixed with the scene's seed).
    #[serde(default)]
    pub seed: u32,
    /// The terrain the landforms are generated on (any subtree; often a `Heightfield`,
    /// or an earlier `Landform` for repeated steps).
    pub base: Box<NodeSpec>,
    /// Where the generator works (default: the base's support box).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<BoxSpec>,
    /// Cell of the analysis grid (top surface, drainage, accessibility), metres.
    pub cell: Positive,
    /// What to generate.
    pub generator: GeneratorSpec,
}

/// The generators.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum GeneratorSpec {
    /// Caves by invasion percolation from the sinks (Paris et al. 2019 §6.2).
    Karst(KarstSpec),
    /// Undercuts, arches and sea caves around sea level (Paris et al. 2019 §6.1).
    SeaErosion(SeaSpec),
    /// Hoodoos and goblins grown by an open grammar (Paris et al. 2019 §6.3).
    Hoodoos(HoodooSpec),
    /// River canyons whose walls the stream erodes (Paris et al. 2019 §6.1).
    Canyon(CanyonSpec),
    /// A natural arch: a fin of rock with an opening under its hard bed.
    Arch(ArchSpec),
    /// A caprock cliff line: a hard bed cropping out as a cliff of joint blocks.
    Caprock(CaprockSpec),
    /// A sea cliff of joint blocks: notch, platform, sea caves, arches, stacks, boulders.
    SeaCliff(SeaCliffSpec),
}

impl Scene {
    /// The file's geology, compiled with the scene's seed; `None` when it has none.
    pub fn geology(&self) -> Option<crate::geology::Geology> {
        self.geology
            .as_ref()
            .map(|g| crate::geology::Geology::from_spec(g, self.seed))
    }

    /// The names of the scene's features, in the tree's order: named Feature Volumes,
    /// anchored nodes, landforms, and named carves of a `Difference` — what `karstic run`
    /// makes a close-up of.
    pub fn feature_names(&self) -> Vec<&str> {
        let mut names = Vec::new();
        for n in self.all_nodes() {
            if let NodeSpec::Difference(d) = n {
                names.extend(d.carves.iter().filter_map(NodeSpec::name));
            }
            if matches!(
                n,
                NodeSpec::FeatureVolume(_) | NodeSpec::Anchor(_) | NodeSpec::Landform(_)
            ) && let Some(name) = n.name()
            {
                names.push(name);
            }
        }
        let mut seen = std::collections::HashSet::new();
        names.retain(|n| seen.insert(*n));
        names
    }

    /// Every node of the scene, `defs` first, parents before children.
    pub fn all_nodes(&self) -> Vec<&NodeSpec> {
        let mut v = Vec::new();
        for d in &self.defs {
            d.walk(&mut |n, _| v.push(n));
        }
        self.root.walk(&mut |n, _| v.push(n));
        v
    }
}

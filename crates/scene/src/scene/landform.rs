//! The parameters of the landform generators as tree files write them (Paris et al. 2019
//! §6, and the natural arch of `docs/landforms.md`): plain data, checked while the file is
//! parsed. The landform generators read them.

use serde::{Deserialize, Serialize};

use crate::value::{Finite, NonNegative, P2, Positive, Unit};

/// The effect below which the erosion generators drop a sample (`min_effect`'s default).
fn default_min_effect() -> Unit {
    Unit(0.1)
}

fn arch_default_weathering() -> NonNegative {
    NonNegative(0.4)
}

fn arch_default_talus() -> bool {
    true
}

/// Parameters of a natural arch.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArchSpec {
    /// One foot of the opening on the ground (tree frame, x and y).
    pub from: P2,
    /// The other foot: the span is the distance between the two.
    pub to: P2,
    /// Height of the opening's ceiling above the ground at mid-span, metres (default: the
    /// base of the hard bed the geology puts there, else 45% of the span).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<Positive>,
    /// Thickness of the lintel at mid-span, metres (default 30% of the opening's height,
    /// at least 3 m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lintel: Option<Positive>,
    /// Mean width of the fin, metres (default 22% of the span, between 4 and 20 m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<Positive>,
    /// How far the fin runs on beyond each foot, metres (default 70% of the span).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reach: Option<Positive>,
    /// Strength of the erosion node over the fin (Paris et al. 2019 §6): how far its soft
    /// beds recess, in field units (default 0.4; 0 leaves the fin unweathered).
    #[serde(default = "arch_default_weathering")]
    pub weathering: NonNegative,
    /// Whether blocks fallen from the fin lie on the ground beside it (default true).
    #[serde(default = "arch_default_talus")]
    pub talus: bool,
    /// Fins of the same joint set beside the arch's, without an opening, on its left
    /// looking from `from` to `to` (default 0: the arch's fin alone): a fin field, as the
    /// parallel joints of a sandstone leave one.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub fins: u32,
}

fn is_zero(n: &u32) -> bool {
    *n == 0
}

fn caprock_default_joints() -> Positive {
    Positive(12.0)
}

fn caprock_default_talus() -> NonNegative {
    NonNegative(0.15)
}

fn caprock_default_apron() -> NonNegative {
    NonNegative(0.3)
}

/// Parameters of a caprock cliff line: a hard bed cropping out across the slopes as a
/// cliff of joint blocks, with recesses in its foot and fallen blocks below it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaprockSpec {
    /// Height of the hard bed's top, metres.
    pub top: Finite,
    /// Thickness of the hard bed, metres: the cliff's height where it stands whole.
    pub thickness: Positive,
    /// Mean spacing of the joints, metres (default 12).
    #[serde(default = "caprock_default_joints")]
    pub joints: Positive,
    /// Strike of the first joint set, degrees counter-clockwise from east (default 0); the
    /// second set runs at right angles to it. The GPU tape encodes boxes turned by quarter
    /// turns only: a multiple of 90° keeps a scene on the GPU.
    #[serde(default)]
    pub strike: Finite,
    /// Recesses in the cliff's foot: rock shelters (long and shallow) and cave mouths
    /// (narrow and deep), each under a lip of the hard bed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub recesses: Vec<RecessSpec>,
    /// Spurs of the bed left standing out from the cliff, each with an optional window
    /// through it (a natural arch whose lintel is the bed's top layer).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub spurs: Vec<SpurSpec>,
    /// Fallen blocks per metre of cliff face (default 0.15; 0 for none).
    #[serde(default = "caprock_default_talus")]
    pub talus: NonNegative,
    /// Height of the talus apron banked against the cliff's foot, as a fraction of the
    /// bed's thickness (default 0.3; 0 for none): cones of scree at the angle of repose
    /// under each stretch of face, merging into an apron.
    #[serde(default = "caprock_default_apron")]
    pub apron: NonNegative,
}

/// A spur of a caprock cliff: a narrow run of the bed's blocks standing out from the face.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpurSpec {
    /// Where it leaves the cliff (tree frame, x and y).
    pub from: P2,
    /// Where it ends.
    pub to: P2,
    /// Its width, metres.
    pub width: Positive,
    /// The span of a window through its middle, metres: the opening's floor is the ground,
    /// its roof the base of the bed's top layer, which stands over it as the lintel.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub window: Option<Positive>,
}

/// A recess in the foot of a caprock cliff: a rock shelter or a cave mouth.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecessSpec {
    /// A point near the cliff (tree frame, x and y): the recess opens in the face nearest
    /// to it.
    pub at: P2,
    /// Length along the face, metres.
    pub length: Positive,
    /// How far it runs back under the hard bed, metres.
    pub depth: Positive,
    /// Height of its mouth above its floor, metres: less than the bed's thickness, the
    /// rest stands over it as a lip.
    pub height: Positive,
}

fn canyon_default_retreat() -> Unit {
    Unit(0.5)
}

fn canyon_default_beta() -> Unit {
    Unit(0.3)
}

/// Parameters of canyon erosion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CanyonSpec {
    /// Stream power (m, `√m²` times slope) above which a sample is riverbed.
    pub threshold: Positive,
    /// The riverbed's stress reaches this far onto the banks, metres: the gorge is at most
    /// twice this wide at its rim.
    pub banks: Positive,
    /// Incision below the bed where the stream power is twice the threshold or more,
    /// metres (proportionally less on weaker streams).
    pub depth: Positive,
    /// Falloff radius of the spheres, metres: how far the carving field is smoothed
    /// (smaller keeps the steps of thin beds sharper).
    pub radius: Positive,
    /// Pitch of the sphere lattice, metres; at most half the radius, so the spheres
    /// overlap into one field.
    pub spacing: Positive,
    /// β of the erosion effect (the effect on the hardest rock).
    #[serde(default = "canyon_default_beta")]
    pub beta: Unit,
    /// How far the walls step back per metre of height, times `2(1 − ρ)²` (default 0.5; 0:
    /// vertical walls): at 1 a slope of about 35° in the softest beds, cliffs in the hard
    /// ones.
    #[serde(default = "canyon_default_retreat")]
    pub retreat: Unit,
    /// Samples with a smaller effect make no sphere.
    #[serde(default = "default_min_effect")]
    pub min_effect: Unit,
    /// Drainage area below which no sample is riverbed, m² (default 0): a steep gully high
    /// on a hillside has the stream power of a river and a fraction of its water, and
    /// cuts no gorge.
    #[serde(default)]
    pub min_area: NonNegative,
}

fn hoodoo_default_lambda() -> Unit {
    Unit(0.8)
}

fn hoodoo_default_depth() -> u32 {
    6
}

/// Parameters of a field of hoodoos.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HoodooSpec {
    /// Poisson spacing of the hoodoos, metres.
    pub spacing: Positive,
    /// Height of the first symbol, metres.
    pub size: Positive,
    /// λ: each symbol is this fraction of the one below.
    #[serde(default = "hoodoo_default_lambda")]
    pub lambda: Unit,
    /// Most symbols in one hoodoo.
    #[serde(default = "hoodoo_default_depth")]
    pub max_depth: u32,
    /// Slopes (rise over run) where hoodoos grow best, `(lo, hi)`.
    pub slope: (Finite, Finite),
    /// Drainage area (m²) at and above which nothing grows (rivers wash them away).
    pub max_area: Positive,
    /// Only inside this polygon (tree frame), when given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mask: Option<Vec<P2>>,
}

fn karst_default_directions() -> u32 {
    6
}

fn karst_default_beta() -> Unit {
    Unit(0.5)
}

fn karst_default_epsilon() -> Unit {
    Unit(0.1)
}

/// Parameters of a karst network.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KarstSpec {
    /// Sinks given by hand, `(x, y)`: water enters the ground there.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sinks: Vec<P2>,
    /// Also seed at the terrain's own sinks: pits of its depressions at least this many
    /// metres deep (Barnes et al. 2014's pits, see `analysis::relief::sinks`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub auto_sinks: Option<Positive>,
    /// Cavity radius of one carving sphere in the softest rock, metres.
    pub radius: Positive,
    /// Poisson spacing of the candidates (and the step of the percolation), metres.
    pub spacing: Positive,
    /// ρ₀: no carving where the resistance is at least this.
    pub threshold: Unit,
    /// ε: the range of the random perturbation of the queue's order.
    #[serde(default = "karst_default_epsilon")]
    pub epsilon: Unit,
    /// β of the erosion effect (the effect on the hardest rock).
    #[serde(default = "karst_default_beta")]
    pub beta: Unit,
    /// Candidate directions drawn around each carved point.
    #[serde(default = "karst_default_directions")]
    pub directions: u32,
    /// At most this many spheres.
    pub max_spheres: u32,
}

fn sea_default_beta() -> Unit {
    Unit(0.5)
}

/// Parameters of one step of sea erosion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SeaSpec {
    /// Mean sea level, metres.
    pub sea_level: Finite,
    /// The waves act within this many metres above and below sea level.
    pub band: Positive,
    /// Cavity radius of one sphere at full effect, metres.
    pub radius: Positive,
    /// Poisson spacing of the surface samples, metres.
    pub spacing: Positive,
    /// How far the accessibility looks for open sea, metres.
    pub reach: Positive,
    /// β of the erosion effect (the effect on the hardest rock).
    #[serde(default = "sea_default_beta")]
    pub beta: Unit,
    /// Samples with a smaller effect make no sphere.
    #[serde(default = "default_min_effect")]
    pub min_effect: Unit,
}

fn sea_cliff_default_joints() -> Positive {
    Positive(10.0)
}

fn sea_cliff_default_platform() -> NonNegative {
    NonNegative(24.0)
}

fn sea_cliff_default_notch() -> NonNegative {
    NonNegative(3.0)
}

fn sea_cliff_default_caves() -> Unit {
    Unit(0.55)
}

fn sea_cliff_default_stacks() -> Unit {
    Unit(0.35)
}

fn sea_cliff_default_talus() -> NonNegative {
    NonNegative(0.3)
}

fn sea_cliff_default_reach() -> Positive {
    Positive(40.0)
}

/// Parameters of a sea cliff of jointed, bedded rock: the base's coast rebuilt as a face
/// of joint blocks with a wave-cut notch, a platform before it, sea caves, arches and
/// stacks where the waves find the rock soft, and boulders at its foot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SeaCliffSpec {
    /// Sea level, metres (default 0).
    #[serde(default)]
    pub sea_level: Finite,
    /// Mean spacing of the joints, metres (default 10).
    #[serde(default = "sea_cliff_default_joints")]
    pub joints: Positive,
    /// Strike of the first joint set, degrees counter-clockwise from east (default 0).
    #[serde(default)]
    pub strike: Finite,
    /// Width of the wave-cut platform the cliff left as it retreated, metres (default 24;
    /// 0 for none).
    #[serde(default = "sea_cliff_default_platform")]
    pub platform: NonNegative,
    /// Depth of the wave-cut notch where the waves' erosion effect is full, metres
    /// (default 3; 0 for none).
    #[serde(default = "sea_cliff_default_notch")]
    pub notch: NonNegative,
    /// The erosion effect at the waterline from which the sea opens a cave (default
    /// 0.55); through a headland one block wide, the cave is an arch.
    #[serde(default = "sea_cliff_default_caves")]
    pub caves: Unit,
    /// The chance that a block off an exposed headland is left standing as a stack
    /// (default 0.35; 0 for none).
    #[serde(default = "sea_cliff_default_stacks")]
    pub stacks: Unit,
    /// Boulders fallen from the face per metre of it (default 0.3; 0 for none).
    #[serde(default = "sea_cliff_default_talus")]
    pub talus: NonNegative,
    /// The effect's share left on the hardest rock, `β` of Paris et al. 2019 §6.1
    /// (default 0.5).
    #[serde(default = "sea_default_beta")]
    pub beta: Unit,
    /// How far the coastal accessibility looks out to sea, metres (default 40).
    #[serde(default = "sea_cliff_default_reach")]
    pub reach: Positive,
}

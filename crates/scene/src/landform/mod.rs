//! Landform generators (Paris et al. 2019 §6): tree-file nodes that read the terrain
//! below them (its top surface, drainage, the rock's resistance ρ) and emit plain
//! skeletal primitives — negative spheres that carve caves, sea undercuts and canyon
//! walls, positive blocks and cones that stand as hoodoos, arches and caprock cliff lines
//! (whose recesses are hollows cut into both the blocks and the ground).
//!
//! A `Landform(base: …, generator: …)` node is *expanded* when its tree compiles: the
//! base is compiled on its own, the generator runs on it, and the node becomes
//! `Blend([base, Blend(carves)])` (erosion) or `Union([base, Blend(rocks)])` (accretion)
//! of ordinary primitives, so bounds, BVH pruning, meshing and rendering need nothing new.
//! `karstic tree expand` writes that plain tree out for hand editing. Generators are
//! sequential and seeded from the node's `seed`: the same file gives the same primitives,
//! byte for byte, on any number of threads.

mod arch;
mod canyon;
mod caprock;
mod coast;
mod hoodoo;
mod joints;
mod karst;
mod scale;
mod sea;

use std::collections::HashMap;

use glam::{IVec3, Vec2, Vec3};
use rayon::prelude::*;

pub use arch::{ArchShape, Block as FinBlock, Fin};
pub use caprock::{Apron, CliffLine, Fallen, JointBlock, REPOSE, Recess, Window};
pub use coast::{Bed, Clear, CoastBlock, Notch, SeaCliff, Slab};
pub use hoodoo::{Hoodoo, Terminal};
pub use joints::JointGrid;

use crate::dem::{Heightfield, Interpolation};
use crate::field::noise::Octaves;
use crate::field::{Aabb, Field, ISO, NodeId, NoiseSpec, PrimitiveSpec, SkeletonSpec, Tree};
use crate::heightmap::{Columns, TopOptions};
use crate::rng::Rng;
use crate::scene::NodeSpec;
use crate::scene::spec::{DifferenceSpec, GeneratorSpec, LandformSpec, Nary};
use crate::value::{Finite, NonNegative, P3, Positive};

/// Errors of a generator: bad parameters for the terrain it meets.
#[derive(Debug, thiserror::Error)]
pub enum LandformError {
    /// The region or the analysis grid cannot be built.
    #[error("{0}")]
    Invalid(String),
}

/// What a generator reads: the base compiled, its top surface, the rock, a seed.
pub struct Ground<'a> {
    /// The base subtree, compiled.
    pub tree: &'a Tree,
    /// The region the generator works in.
    pub region: Aabb,
    /// The top surface of the base over the region's footprint, sample `(0, 0)` at the
    /// region's south-west corner (NaN where a column holds no solid).
    pub top: Heightfield,
    /// Rock resistance ρ(p) ∈ [0, 1] (1 = hard).
    pub resistance: &'a (dyn Fn(Vec3) -> f32 + Sync),
    /// The generator's seed.
    pub seed: u64,
}

impl<'a> Ground<'a> {
    /// Reads the top surface of `tree` over `region` on a grid of `cell` metres.
    pub fn new(
        tree: &'a Tree,
        region: Aabb,
        cell: f32,
        resistance: &'a (dyn Fn(Vec3) -> f32 + Sync),
        seed: u64,
    ) -> Result<Ground<'a>, LandformError> {
        let size = region.size();
        if region.is_empty() || !size.is_finite() || size.x <= 0.0 || size.y <= 0.0 {
            return Err(LandformError::Invalid(format!(
                "the landform region {:?} .. {:?} is empty or unbounded: give `region`",
                region.min, region.max
            )));
        }
        let (nx, ny) = (
            (size.x / cell).floor() as usize + 1,
            (size.y / cell).floor() as usize + 1,
        );
        if nx < 3 || ny < 3 || nx * ny > 64 << 20 {
            return Err(LandformError::Invalid(format!(
                "a {nx}×{ny} analysis grid: choose a `cell` giving between 3×3 and 64 M samples"
            )));
        }
        let origin = Vec2::new(region.min.x, region.min.y);
        let opts = TopOptions {
            tolerance: 0.01 * cell,
            direct: true,
        };
        let mut z = vec![f32::NAN; nx * ny];
        z.par_chunks_mut(nx).enumerate().for_each_init(
            || Columns::new(tree, &opts),
            |columns, (j, row)| {
                for (i, out) in row.iter_mut().enumerate() {
                    let xy = origin + Vec2::new(i as f32, j as f32) * cell;
                    *out = columns
                        .top(xy)
                        .filter(|&h| h <= region.max.z)
                        .unwrap_or(f32::NAN);
                }
            },
        );
        let top = Heightfield::new(nx, ny, origin, Vec2::splat(cell), z)
            .map_err(|e| LandformError::Invalid(e.to_string()))?;
        Ok(Ground {
            tree,
            region,
            top,
            resistance,
            seed,
        })
    }

    /// The top surface's height at `xy` (bilinear), NaN outside or over nodata.
    pub fn height(&self, xy: Vec2) -> f32 {
        self.top.sample(xy, Interpolation::Bilinear)
    }

    /// The height of the base's surface over `xy` within `reach` of `guess` (bisection
    /// along the vertical to a millimetre), where the column is solid at `guess − reach`
    /// and empty at `guess + reach`: the exact surface where [`Ground::height`]
    /// interpolates the analysis grid.
    pub fn surface_near(&self, xy: Vec2, guess: f32, reach: f32) -> Option<f32> {
        let (mut lo, mut hi) = (guess - reach, guess + reach);
        if !self.solid(xy.extend(lo)) || self.solid(xy.extend(hi)) {
            return None;
        }
        while hi - lo > 1e-3 {
            let mid = 0.5 * (lo + hi);
            match self.solid(xy.extend(mid)) {
                true => lo = mid,
                false => hi = mid,
            }
        }
        Some(0.5 * (lo + hi))
    }

    /// Whether `p` is in the base's solid.
    pub fn solid(&self, p: Vec3) -> bool {
        self.tree.value(p) > ISO
    }

    /// The highest air in the column over `xy` from `from` down to `to`, probed every
    /// half metre: a cave of the base under the ground, `None` when the column is solid.
    pub fn cavity_under(&self, xy: Vec2, from: f32, to: f32) -> Option<f32> {
        let mut z = from;
        while z > to {
            if !self.solid(xy.extend(z)) {
                return Some(z);
            }
            z -= 0.5;
        }
        None
    }

    /// How far `xy` lies inside the region's nearest side, in plan (negative outside).
    pub fn side_room(&self, xy: Vec2) -> f32 {
        let r = &self.region;
        (xy - r.min.truncate())
            .min(r.max.truncate() - xy)
            .min_element()
    }

    /// The lowest of the ground's heights at `xy` and at eight points `reach` around it
    /// (points off the region's ground are skipped; NaN when all are): what a rock of that
    /// reach must go under to lie in a slope without its downhill edge in the air.
    pub fn lowest_around(&self, xy: Vec2, reach: f32) -> f32 {
        (0..8)
            .map(|k| xy + reach * Vec2::from_angle(k as f32 * std::f32::consts::FRAC_PI_4))
            .chain([xy])
            .map(|q| self.height(q))
            .filter(|z| z.is_finite())
            .fold(f32::NAN, f32::min)
    }

    /// The tree-frame position of sample `k` of [`Ground::top`], at its height.
    pub fn sample_point(&self, k: usize) -> Vec3 {
        let nx = self.top.nx();
        let xy = self.top.origin() + Vec2::new((k % nx) as f32, (k / nx) as f32) * self.top.cell();
        xy.extend(self.top.samples()[k])
    }

    /// The top grid's sample nearest `xy`, if inside.
    pub fn nearest_sample(&self, xy: Vec2) -> Option<usize> {
        let q = ((xy - self.top.origin()) / self.top.cell()).round();
        let (nx, ny) = (self.top.nx(), self.top.ny());
        (q.x >= 0.0 && q.y >= 0.0 && (q.x as usize) < nx && (q.y as usize) < ny)
            .then(|| q.x as usize + nx * q.y as usize)
    }
}

/// The erosion effect `e(ρ, σ) = σ(1 − ρ)(1 − β) + σβ` of Paris et al. 2019 §6.1: no
/// effect without stress, `β` at full stress on the hardest rock, `σ` on the softest.
pub fn effect(rho: f32, sigma: f32, beta: f32) -> f32 {
    sigma * (1.0 - rho) * (1.0 - beta) + sigma * beta
}

/// The falloff radius of a carving sphere whose cavity, at full effect `e = 1`, has
/// radius `r` inside saturated solid: a sphere `−2e·g(d/R)` carves where
/// `1 − 2e·g > T`, i.e. `g(d/R) > 1/4` at `e = 1`, `d < 0.61 R`.
const CAVITY_FRACTION: f32 = 0.61;

/// A carving sphere of cavity radius `radius` (at full effect) and effect `e`: a point
/// primitive of energy `−2e` (coordinates rounded to the millimetre, so expanded files
/// read well).
pub fn carving_sphere(center: Vec3, radius: f32, e: f32) -> NodeSpec {
    point(center, radius / CAVITY_FRACTION, -2.0 * e)
}

/// Rounds to the millimetre, so expanded files read well.
fn round3(v: f32) -> f32 {
    (v * 1000.0).round() / 1000.0
}

/// A point rounded to the millimetre, so expanded files read well.
pub(crate) fn p3(v: Vec3) -> P3 {
    P3(v.to_array().map(round3).into())
}

/// A noise of the given amplitude and wavelength (rounded to the millimetre), octaves and
/// seed offset, for a generated primitive.
pub(crate) fn noise(
    amplitude: f32,
    wavelength: f32,
    octaves: u32,
    seed_offset: u32,
) -> Option<NoiseSpec> {
    Some(NoiseSpec {
        amplitude: NonNegative(round3(amplitude)),
        wavelength: Positive(round3(wavelength).max(0.01)),
        octaves: Octaves::new(octaves).unwrap_or_default(),
        seed_offset,
    })
}

/// A solid primitive (energy 1) of `shape`, falloff `falloff` and optional noise: the
/// rock the accreting generators stand on the terrain.
pub fn solid(shape: SkeletonSpec, falloff: f32, noise: Option<NoiseSpec>) -> NodeSpec {
    NodeSpec::Primitive(PrimitiveSpec {
        name: None,
        shape,
        falloff: Positive(falloff),
        energy: Finite(1.0),
        noise,
    })
}

/// A point primitive (a blob) of falloff `falloff` and energy `energy`.
pub fn point(center: Vec3, falloff: f32, energy: f32) -> NodeSpec {
    NodeSpec::Primitive(PrimitiveSpec {
        name: None,
        shape: SkeletonSpec::Point {
            center: P3(center.to_array().map(round3).into()),
        },
        falloff: Positive(round3(falloff).max(0.001)),
        energy: Finite(round3(energy)),
        noise: None,
    })
}

/// The base of a hard bed over `xy`, as a height above `g` within `range` of it: where the
/// resistance rises most steeply going up, probed every `step` (a soft bed under a hard
/// one, Paris et al. 2019 §6.1); `None` where it rises by less than 0.05 over two steps
/// anywhere in the range (noise, not a bed).
pub(crate) fn hard_bed_base(
    ground: &Ground,
    xy: Vec2,
    g: f32,
    range: (f32, f32),
    step: f32,
) -> Option<f32> {
    let rho = |dz: f32| (ground.resistance)(xy.extend(g + dz));
    let mut best = (0.0, range.0);
    let mut dz = range.0;
    while dz <= range.1 {
        let rise = rho(dz + step) - rho(dz - step);
        if rise > best.0 {
            best = (rise, dz);
        }
        dz += step;
    }
    (best.0 >= 0.05).then_some(best.1)
}

/// Hermite step from 0 at `a` to 1 at `b`.
pub(crate) fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The band inside a landform region's faces over which its carving fades in: four cells
/// of its analysis grid, and at least 8% of the region's smaller horizontal side.
pub fn fade_width(region: &Aabb, cell: f32) -> f32 {
    let size = region.size();
    (4.0 * cell).max(0.08 * size.x.min(size.y))
}

/// Carving spheres faded at the region's faces: a sphere whose centre lies `d` inside the
/// nearest face keeps `smoothstep(0, width, d)` of its energy and a falloff of at most
/// `d`, so the carving fades over `width` and nothing reaches beyond the faces (a sea
/// notch or a canyon no longer stops dead at the region's side). Spheres left with less
/// than a thousandth of their energy, or a falloff under a millimetre, are dropped;
/// those wholly inside and past the band are kept as they were.
pub fn fade_at_faces(primitives: Vec<NodeSpec>, region: &Aabb, width: f32) -> Vec<NodeSpec> {
    primitives
        .into_iter()
        .filter_map(|n| {
            let NodeSpec::Primitive(p) = &n else {
                return Some(n);
            };
            let SkeletonSpec::Point { center } = p.shape else {
                return Some(n);
            };
            let c = center.0;
            let inside = (c - region.min).min(region.max - c).min_element();
            let (falloff, energy) = (p.falloff.0, p.energy.0);
            let w = smoothstep(0.0, width, inside);
            if w >= 1.0 && falloff <= inside {
                return Some(n);
            }
            let (falloff, energy) = (falloff.min(inside), energy * w);
            (energy.abs() >= 1e-3 * p.energy.0.abs() && falloff >= 1e-3)
                .then(|| point(c, falloff, energy))
        })
        .collect()
}

/// Poisson-disk acceptance in 3D: a point is taken only if no taken point lies closer
/// than the spacing (a hash grid of cells of the spacing's side).
pub struct Poisson {
    spacing: f32,
    cells: HashMap<IVec3, Vec<Vec3>>,
}

impl Poisson {
    /// An empty set with minimum distance `spacing`.
    pub fn new(spacing: f32) -> Poisson {
        Poisson {
            spacing,
            cells: HashMap::new(),
        }
    }

    fn cell(&self, p: Vec3) -> IVec3 {
        (p / self.spacing).floor().as_ivec3()
    }

    /// Whether `p` keeps its distance from every point taken so far.
    pub fn free(&self, p: Vec3) -> bool {
        let c = self.cell(p);
        let r2 = self.spacing * self.spacing;
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    if let Some(v) = self.cells.get(&(c + IVec3::new(dx, dy, dz)))
                        && v.iter().any(|q| q.distance_squared(p) < r2)
                    {
                        return false;
                    }
                }
            }
        }
        true
    }

    /// Takes `p` if it is free; says whether it was.
    pub fn take(&mut self, p: Vec3) -> bool {
        if !self.free(p) {
            return false;
        }
        self.cells.entry(self.cell(p)).or_default().push(p);
        true
    }
}

/// How a generator's primitives join the base.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Joining {
    /// `Blend([base, Blend(carves)])`: negative spheres summed into the terrain.
    Carve,
    /// `Union([base, Blend(rocks)])`: new rock standing on the terrain.
    Accrete,
    /// `Difference(Union([base, Blend(rocks)]), [Union(hollows)])`: rock standing on the
    /// terrain, then hollows cut into both; with clears, the base is
    /// `Difference(base, [Union(clears)])`.
    Sculpt,
}

impl Joining {
    /// What names the blend of the generated primitives: `NAME-carves` or `NAME-rocks`.
    fn suffix(&self) -> &'static str {
        match self {
            Joining::Carve => "carves",
            Joining::Accrete | Joining::Sculpt => "rocks",
        }
    }
}

/// The node of a compiled `tree` that stands for the feature `name` (one of
/// [`crate::scene::Scene::feature_names`]): for a landform, the blend of what it generated
/// (`NAME-carves` or `NAME-rocks`; the node `NAME` is the terrain under it too), else the
/// node of that name.
pub fn feature_node(tree: &Tree, name: &str) -> Option<NodeId> {
    [Joining::Carve, Joining::Accrete]
        .iter()
        .find_map(|j| tree.find(&format!("{name}-{}", j.suffix())))
        .or_else(|| tree.find(name))
}

/// What a generator made: its primitives and how they join the base.
pub struct Generated {
    /// The primitives.
    pub primitives: Vec<NodeSpec>,
    /// How they join the base.
    pub joining: Joining,
    /// What is cut out of the base and the primitives afterwards ([`Joining::Sculpt`]).
    pub hollows: Vec<NodeSpec>,
    /// What is cut out of the base alone before the primitives join it
    /// ([`Joining::Sculpt`]): ground the rocks rebuild (a sea cliff's face).
    pub clears: Vec<NodeSpec>,
}

impl Generated {
    /// `primitives` joining the base by `joining`, with no hollows.
    fn plain(primitives: Vec<NodeSpec>, joining: Joining) -> Generated {
        Generated {
            primitives,
            joining,
            hollows: Vec::new(),
            clears: Vec::new(),
        }
    }
}

impl LandformSpec {
    /// Runs the generator on `ground`.
    pub fn generate(&self, ground: &Ground) -> Result<Generated, LandformError> {
        scale::check(&self.generator, &ground.region)?;
        let mut generated = match &self.generator {
            GeneratorSpec::Karst(k) => Generated::plain(k.generate(ground)?, Joining::Carve),
            GeneratorSpec::SeaErosion(s) => Generated::plain(s.generate(ground)?, Joining::Carve),
            GeneratorSpec::Canyon(c) => Generated::plain(c.generate(ground)?, Joining::Carve),
            GeneratorSpec::Hoodoos(h) => Generated::plain(h.generate(ground)?, Joining::Accrete),
            GeneratorSpec::Arch(a) => Generated::plain(a.generate(ground)?, Joining::Accrete),
            GeneratorSpec::Caprock(c) => {
                let (primitives, hollows) = c.generate(ground)?;
                Generated {
                    primitives,
                    joining: Joining::Sculpt,
                    hollows,
                    clears: Vec::new(),
                }
            }
            GeneratorSpec::SeaCliff(c) => c.generate(ground)?,
        };
        if generated.joining == Joining::Carve {
            let width = fade_width(&ground.region, self.cell.0);
            generated.primitives = fade_at_faces(generated.primitives, &ground.region, width);
        }
        Ok(generated)
    }

    /// The seed of the generator: the node's, mixed with the scene's.
    pub fn full_seed(&self, scene_seed: u32) -> u64 {
        (u64::from(scene_seed) << 32) | u64::from(self.seed)
    }

    /// The plain node this landform expands into (its base already expanded).
    pub fn expansion(self, generated: Generated) -> NodeSpec {
        let suffix = generated.joining.suffix();
        let base = match generated.clears.is_empty() {
            true => *self.base,
            false => NodeSpec::Difference(DifferenceSpec {
                name: None,
                base: self.base,
                carves: vec![NodeSpec::Union(Nary {
                    name: self.name.as_ref().map(|n| format!("{n}-clears")),
                    children: generated.clears,
                })],
            }),
        };
        let mut children = vec![base];
        // An empty blend is refused by the tree file's checks: nothing generated, nothing
        // added.
        if !generated.primitives.is_empty() {
            let rocks = Nary {
                name: self.name.as_ref().map(|n| format!("{n}-{suffix}")),
                children: generated.primitives,
            };
            children.push(NodeSpec::Blend(rocks));
        }
        let node = Nary {
            name: self.name,
            children,
        };
        match generated.joining {
            Joining::Carve => NodeSpec::Blend(node),
            Joining::Accrete => NodeSpec::Union(node),
            Joining::Sculpt if generated.hollows.is_empty() => NodeSpec::Union(node),
            Joining::Sculpt => {
                let name = node.name.clone();
                NodeSpec::Difference(DifferenceSpec {
                    name: name.clone(),
                    base: Box::new(NodeSpec::Union(Nary {
                        name: None,
                        children: node.children,
                    })),
                    carves: vec![NodeSpec::Union(Nary {
                        name: name.map(|n| format!("{n}-hollows")),
                        children: generated.hollows,
                    })],
                })
            }
        }
    }
}

/// A dart thrown in the grid cell of size `cell` centred on `xy`, at height `z(u)` for a
/// uniform `u ∈ [0, 1)`, then moved onto the surface ([`project`], within 5% of the
/// Poisson `spacing`): the erosion generators' surface samples.
pub fn throw_dart(
    ground: &Ground,
    rng: &mut Rng,
    xy: Vec2,
    cell: Vec2,
    spacing: f32,
    z: impl Fn(f32) -> f32,
) -> Option<Vec3> {
    let jitter = Vec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit());
    let dart = Vec3::new(
        xy.x + jitter.x * cell.x,
        xy.y + jitter.y * cell.y,
        z(jitter.z),
    );
    project(ground, dart, 0.05 * spacing, 2.0 * cell.max_element())
}

/// Newton steps that bring a dart onto the surface.
const PROJECTION_STEPS: usize = 6;

/// `p` moved onto the surface `f = T` by Newton steps along the gradient; `None` when it
/// does not settle within `tolerance` metres or wanders more than `wander` metres.
pub fn project(ground: &Ground, p: Vec3, tolerance: f32, wander: f32) -> Option<Vec3> {
    let mut q = p;
    for _ in 0..PROJECTION_STEPS {
        let (f, g) = ground.tree.value_grad(q);
        let g2 = g.length_squared();
        if g2 < 1e-12 {
            return None;
        }
        let dq = g * ((ISO - f) / g2);
        q += dq;
        if dq.length() < tolerance {
            return ((q - p).length() < wander).then_some(q);
        }
    }
    None
}

//! Sea cliffs of jointed, bedded rock.
//!
//! A coast of bedded rock does not wear back as a smooth wall: the waves work at its foot,
//! around sea level and a metre or two above it, and cut a notch there; the rock above,
//! undermined, falls away block by block along its joints, so the face is a wall of joint
//! blocks whose beds recede where they are soft; what the cliff left behind as it
//! retreated is a wave-cut platform at about sea level, its joints open; where the rock is
//! softer, or a headland takes the waves from both sides, the sea follows the weakness
//! into a cave, through a narrow headland into an arch, and leaves stacks standing off the
//! exposed points when the arches fall; boulders from the face lie at its foot (Trenhaile
//! 1987; Sunamura 1992). Paris et al. 2019 §6.1 weigh the sea's work by the erosion effect
//! `e(ρ, σ)` of the rock's resistance ρ and the wave stress σ, the coastal accessibility;
//! so does this generator, but it builds the cliff from the rock's structure:
//!
//! * **The face.** The base's coast is rebuilt as joint blocks (two sets of vertical
//!   joints, [`super::joints`]): the ground of the two rows of blocks behind the coast and
//!   of the sea before it is cleared (the base's cliff, a heightfield stretched up a wall,
//!   goes), and each block stands from below sea level to the ground's top over it, sliced
//!   into the scene geology's beds, each weathered back on the block's seaward sides by
//!   its softness, so the face steps in and out at the joints and ledges run along the
//!   hard beds.
//! * **The notch.** Along every seaward side, the waves cut a notch at sea level as deep
//!   as `notch` times the erosion effect of the rock there under the side's exposure.
//! * **Caves and arches.** Where the effect passes `caves`, a cave runs into the block
//!   under a roof at the base of a hard bed; a block with the sea on two opposite sides is
//!   a narrow headland, and its cave goes through it as an arch.
//! * **Stacks.** Off exposed headlands, a block two rows out stands on in the sea, lower
//!   than the cliff, narrower than its joints, notched all round; no two side by side.
//! * **A broken edge.** One face block in four has lost beds off its top.
//! * **The platform.** Before the face, the rock is planed off at about sea level (a few
//!   decimetres above it at the foot, sloping gently seaward, rough enough that it goes
//!   awash in patches) as slabs parted by the joints.
//! * **Boulders** fallen from the face lie on the platform at its foot, many small and few
//!   large, the larger thrown farther.

use glam::{Vec2, Vec3};

use super::caprock::{Fallen, Recess, Window};
use super::joints::{JointGrid, block_falloff, boxed, fallen_half};
use super::sea::section;
use super::{Generated, Ground, Joining, LandformError, effect, hard_bed_base, noise, p3, solid};
use crate::analysis::relief::coastal_accessibility;
use crate::field::SkeletonSpec;
use crate::field::skeleton::Size3;
use crate::rng::Rng;
use crate::scene::NodeSpec;
use crate::scene::landform::SeaCliffSpec;
use crate::scene::spec::{Nary, Rotation, TransformSpec, WarpSpec};
use crate::value::{Dir3, Finite};

/// Joint spacings the generator accepts, metres.
const JOINTS: (f32, f32) = (3.0, 100.0);

/// The warp of the blocks (amplitude and wavelength in joint spacings): gentler than a
/// caprock's, so the cliff's top stays level with the ground behind it.
const WARP: (f32, f32) = (0.1, 2.0);

/// The roughness of the blocks' faces, in joint spacings (at a third of a spacing).
const ROUGH: f32 = 0.06;

/// The rounding of a bed's edges, metres: sharp enough that a bed reads as a slab of
/// rock, not a cushion.
const BED_FALLOFF: f32 = 0.5;

/// How far the softest bed weathers back from a seaward side, in joint spacings.
const RECESSION: f32 = 0.12;

/// The half height of the wave-cut notch, metres: the tidal range and the splash.
const NOTCH_HALF_HEIGHT: f32 = 1.6;

/// The roughness of the platform, metres: its rock stands out of the sea and goes under
/// it in patches.
const PLATFORM_ROUGH: f32 = 0.35;

/// The rounding of the platform's pieces, metres: small, so the blend of two pieces
/// raises no seam between them.
const PLATFORM_FALLOFF: f32 = 0.5;

/// The platform's fall seaward, metres a metre (about 2°): its outer edge goes under the
/// sea where its roughness lets it.
const PLATFORM_SLOPE: f32 = 0.04;

/// Rows of blocks behind the coast rebuilt as joint blocks.
const ROWS: u32 = 2;

/// How far a block's surface can stand beyond its box, for joints `spacing` apart.
fn reach(spacing: f32) -> f32 {
    (3f32.sqrt() * WARP.0 + ROUGH) * spacing + block_falloff(spacing)
}

/// How much narrower a stack's top is than its foot: from the first to the second (worn
/// from every side, a stack tapers; 10–35% read to blind judges as "the same width top
/// to bottom", "stacked boxes").
pub const STACK_TAPER: (f32, f32) = (0.3, 0.55);

/// How far each bed of a stack sits off the one below it, in joint spacings: its beds
/// wore back unevenly from every side.
const STACK_SHIFT: f32 = 0.14;

/// The falloff that rounds a stack's vertical edges, in joint spacings: the waves and the
/// weather attack a corner from two sides, so a stack's beds wear to rounded plans
/// (Trenhaile 1987), where a box's square corners read to blind judges as "stacked
/// cuboids". Its rounding radius is 0.454 of it (where Wyvill's falloff crosses the
/// iso-value): a twelfth of a spacing.
const STACK_CORNER: f32 = 0.18;

/// A joint block of the cliff or a stack, in the tree frame.
#[derive(Clone, Debug, PartialEq)]
pub struct CoastBlock {
    /// Middle of its footprint.
    pub center: Vec2,
    /// Half extents along the joint frame's two axes.
    pub half: Vec2,
    /// Its beds from the root up.
    pub beds: Vec<Bed>,
    /// Which sides face the sea: `+u`, `−u`, `+v`, `−v` of the joint frame.
    pub seaward: [bool; 4],
    /// Whether it stands off the coast.
    pub stack: bool,
    /// How much narrower its top bed is than its foot, as a fraction (a stack tapers as
    /// the weather works on it from every side; 0 for the cliff's blocks).
    pub taper: f32,
}

/// A side of a block that faces the sea.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Side {
    /// Which: `+u`, `−u`, `+v`, `−v` of the joint frame.
    index: usize,
    /// Horizontal direction out of it, unit.
    out: Vec2,
    /// Its middle.
    face: Vec2,
    /// Its length.
    length: f32,
}

impl CoastBlock {
    /// Its sides that face the sea, in a joint frame of first axis `axis`.
    fn seaward_sides(&self, axis: Vec2) -> impl Iterator<Item = Side> + '_ {
        let axes = [axis, -axis, axis.perp(), -axis.perp()];
        (0..4).filter(|&n| self.seaward[n]).map(move |n| {
            let (depth, length) = match n < 2 {
                true => (self.half.x, 2.0 * self.half.y),
                false => (self.half.y, 2.0 * self.half.x),
            };
            Side {
                index: n,
                out: axes[n],
                face: self.center + axes[n] * depth,
                length,
            }
        })
    }

    /// Its root's height.
    pub fn root(&self) -> f32 {
        self.beds.first().map_or(0.0, |b| b.z.x)
    }

    /// Its top's height.
    pub fn top(&self) -> f32 {
        self.beds.last().map_or(0.0, |b| b.z.y)
    }
}

/// A bed of a block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bed {
    /// Its bottom and top heights.
    pub z: Vec2,
    /// How far it is weathered back from the block's seaward sides.
    pub inset: f32,
    /// How far it stands off the block's axis, along the joint frame's axes: no bed lies
    /// exactly over the one below.
    pub shift: Vec2,
}

/// A slab of the wave-cut platform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slab {
    /// Middle of its footprint.
    pub center: Vec2,
    /// Half extents along the joint frame's axes.
    pub half: Vec2,
    /// Bottom and top heights.
    pub z: Vec2,
}

/// A stretch of wave-cut notch along a seaward side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Notch {
    /// Its middle on the face, at the height of its deepest cut.
    pub center: Vec3,
    /// Horizontal direction out of the face, unit.
    pub out: Vec2,
    /// Its length along the face.
    pub length: f32,
    /// How deep it cuts into the face.
    pub depth: f32,
}

/// Ground the blocks rebuild: a joint cell cleared from `z.x` to `z.y`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clear {
    /// Middle of the cell.
    pub center: Vec2,
    /// Half extents along the joint frame's axes (joint to joint).
    pub half: Vec2,
    /// Bottom and top of the cleared box.
    pub z: Vec2,
}

/// The sea cliff the generator settled on.
#[derive(Clone, Debug, PartialEq)]
pub struct SeaCliff {
    /// Sea level.
    pub sea: f32,
    /// The joints.
    pub grid: JointGrid,
    /// The cliff's blocks and the stacks.
    pub blocks: Vec<CoastBlock>,
    /// The platform's slabs.
    pub slabs: Vec<Slab>,
    /// The base's ground cleared for the blocks.
    pub clears: Vec<Clear>,
    /// The notch, side by side.
    pub notches: Vec<Notch>,
    /// The sea caves.
    pub caves: Vec<Recess>,
    /// The arches through narrow headlands.
    pub arches: Vec<Window>,
    /// The boulders at the foot.
    pub fallen: Vec<Fallen>,
}

/// What a joint cell of the region is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// Too near the region's sides, or off its ground.
    Out,
    /// Ground above sea level at its middle.
    Land,
    /// Sea at its middle.
    Sea,
}

/// The four sides of a joint cell, as steps on the grid: `+u`, `−u`, `+v`, `−v`.
const SIDES: [(isize, isize); 4] = [(1, 0), (-1, 0), (0, 1), (0, -1)];

impl SeaCliffSpec {
    /// The sea cliff on `ground`.
    pub fn shape(&self, ground: &Ground) -> Result<SeaCliff, LandformError> {
        let s = self.joints.0;
        if !(JOINTS.0..=JOINTS.1).contains(&s) {
            return Err(LandformError::Invalid(format!(
                "sea cliff joints {s} m apart: give between {} and {} m",
                JOINTS.0, JOINTS.1
            )));
        }
        let sea = self.sea_level.0;
        let cell = ground.top.cell().max_element();
        let mut rng = Rng::new(ground.seed ^ 0x5ea_c11f);
        let grid = JointGrid::new(
            &mut rng,
            &ground.region,
            self.strike.0,
            s,
            cell,
            "sea cliff",
        )?;
        let alpha = coastal_accessibility(&section(ground, sea, 1.0)?, sea, 0.5, self.reach.0);
        let exposure = |xy: Vec2| ground.nearest_sample(xy).map_or(0.0, |k| alpha[k]);
        let (nu, nv) = grid.dims();
        let index = |i: isize, j: isize| {
            (i >= 0 && j >= 0 && (i as usize) < nu && (j as usize) < nv)
                .then(|| i as usize + nu * j as usize)
        };
        let middle = |i: usize, j: usize| {
            let (q0, q1) = grid.footprint(i, j);
            (grid.to_world(0.5 * (q0 + q1)), 0.5 * (q1 - q0))
        };
        let kinds: Vec<Kind> = (0..nu * nv)
            .map(|k| {
                let (c, half) = middle(k % nu, k / nu);
                let h = ground.height(c);
                if !h.is_finite() || ground.side_room(c) < half.length() + reach(s) {
                    Kind::Out
                } else if h > sea {
                    Kind::Land
                } else {
                    Kind::Sea
                }
            })
            .collect();
        // Rows from the coast: land counted from the sea, sea from the land (1 beside
        // the coast), by steps across the grid's sides.
        let rows = |from: Kind, through: Kind| {
            let mut d = vec![u32::MAX; nu * nv];
            let mut queue = std::collections::VecDeque::new();
            for (k, kind) in kinds.iter().enumerate() {
                if *kind == from {
                    d[k] = 0;
                    queue.push_back(k);
                }
            }
            while let Some(k) = queue.pop_front() {
                let (i, j) = ((k % nu) as isize, (k / nu) as isize);
                for (di, dj) in SIDES {
                    if let Some(n) = index(i + di, j + dj)
                        && kinds[n] == through
                        && d[n] == u32::MAX
                    {
                        d[n] = d[k] + 1;
                        queue.push_back(n);
                    }
                }
            }
            d
        };
        let inland = rows(Kind::Sea, Kind::Land);
        let offshore = rows(Kind::Land, Kind::Sea);
        let platform_rows = (1.3 * self.platform.0 / s).ceil() as u32;
        let shore = shore_distance(ground, sea);
        let falloff = block_falloff(s);

        // The cliff's blocks: the rows behind the coast, from below the notch to the
        // ground's top over them.
        let heights = |i: usize, j: usize| {
            let (q0, q1) = grid.footprint(i, j);
            let mid = 0.5 * (q0 + q1);
            [mid, q0, q1, Vec2::new(q0.x, q1.y), Vec2::new(q1.x, q0.y)]
                .map(|q| ground.height(grid.to_world(q)))
        };
        let mut blocks = Vec::new();
        let mut clears = Vec::new();
        let mut cliff = vec![false; nu * nv];
        for k in 0..nu * nv {
            let (i, j) = (k % nu, k / nu);
            if kinds[k] != Kind::Land || inland[k] > ROWS {
                continue;
            }
            let (center, half) = middle(i, j);
            let h = heights(i, j);
            let top = h.iter().filter(|&&z| z > sea).fold(sea, |a, &z| a.max(z));
            let lowest = h.iter().copied().fold(f32::INFINITY, f32::min);
            let root = (lowest - 2.0).min(sea - 4.0);
            let seaward = SIDES.map(|(di, dj)| {
                index(i as isize + di, j as isize + dj).is_some_and(|n| kinds[n] == Kind::Sea)
            });
            let mut beds = beds(ground, center, (root, top), sea, (s, 0.03), &mut rng);
            // A broken edge: one face block in four has lost a bed or a few off its top.
            if seaward.contains(&true) && rng.unit() < 0.25 {
                let lost = 1 + (3.0 * rng.unit()) as usize;
                beds.truncate(beds.len().saturating_sub(lost).max(3));
            }
            blocks.push(CoastBlock {
                center,
                half,
                beds,
                seaward,
                stack: false,
                taper: 0.0,
            });
            cliff[k] = true;
            clears.push(clear(&grid, i, j, Vec2::new(sea - 3.0, top + 5.0), falloff));
        }
        let cliff_top = median(blocks.iter().map(CoastBlock::top).collect()).unwrap_or(sea);

        // The sea before it: slabs of the platform, stacks off the exposed headlands.
        let mut slabs = Vec::new();
        let mut stacks = vec![false; nu * nv];
        for k in 0..nu * nv {
            let (i, j) = (k % nu, k / nu);
            let row = offshore[k];
            if kinds[k] != Kind::Sea || row > platform_rows + 1 {
                continue;
            }
            let (center, half) = middle(i, j);
            let h = heights(i, j);
            let ceiling = h.iter().copied().fold(sea, f32::max) + 5.0;
            let lowest = h.iter().copied().fold(f32::INFINITY, f32::min);
            // The platform: pieces on a lattice of a third of the joints, kept within its
            // width of the coast (a ragged edge: each piece's reach drawn), so its edge
            // follows the shore, not the joints; blended, they join into one sheet.
            let (q0, q1) = grid.cell(i, j);
            let n = (q1 - q0) / (s / 3.0);
            let (n_u, n_v) = (n.x.ceil().max(1.0) as usize, n.y.ceil().max(1.0) as usize);
            let piece = 0.5 * (q1 - q0) / Vec2::new(n_u as f32, n_v as f32);
            for (a, b) in (0..n_v).flat_map(|b| (0..n_u).map(move |a| (a, b))) {
                let q = q0 + piece * Vec2::new(2.0 * a as f32 + 1.0, 2.0 * b as f32 + 1.0);
                let xy = grid.to_world(q);
                let d = ground
                    .nearest_sample(xy)
                    .map_or(f32::INFINITY, |k| shore[k]);
                let reach = self.platform.0 * (0.7 + 0.6 * rng.unit());
                if d > reach {
                    continue;
                }
                // Falling faster over its outer third, so its edge goes under the sea
                // instead of stopping at a step.
                let top = sea + 0.2 - PLATFORM_SLOPE * d - 0.3 * (d - 0.7 * reach).max(0.0);
                // Each piece a little off the lattice and of its own size, so the edge is
                // ragged, not a staircase.
                let jitter = Vec2::new(rng.unit() - 0.5, rng.unit() - 0.5) * 0.5;
                let size = 1.0 + 0.3 * rng.unit();
                slabs.push(Slab {
                    center: xy + grid.to_world(jitter * piece),
                    half: piece * size,
                    z: Vec2::new(lowest.min(sea - 4.0) - 1.0, top),
                });
            }
            clears.push(clear(&grid, i, j, Vec2::new(sea - 4.0, ceiling), falloff));
            // Stacks: two rows out or more, off a headland the waves reach from most
            // sides, standing on the platform.
            let open = (0..9)
                .map(|n| {
                    let d = Vec2::from_angle(n as f32 * std::f32::consts::TAU / 9.0);
                    exposure(center + d * (2.0 * s))
                })
                .fold(0.0, f32::max);
            let stack_chance = self.stacks.0 * super::smoothstep(0.45, 0.7, open);
            let draw = rng.unit();
            let beside_stack = SIDES.iter().any(|&(di, dj)| {
                index(i as isize + di, j as isize + dj).is_some_and(|n| stacks[n])
            });
            if (2..=platform_rows.max(2)).contains(&row) && !beside_stack && draw < stack_chance {
                // What the waves left of a block: narrower than its joints, off their
                // middle, lower than the cliff.
                let shrink = Vec2::new(0.6 + 0.3 * rng.unit(), 0.6 + 0.3 * rng.unit());
                let room = half * (Vec2::ONE - shrink);
                let shift = room * Vec2::new(2.0 * rng.unit() - 1.0, 2.0 * rng.unit() - 1.0);
                let center = center + grid.to_world(shift);
                let half = half * shrink;
                let top = sea + (cliff_top - sea) * (0.5 + 0.45 * rng.unit());
                let mut beds = beds(
                    ground,
                    center,
                    (lowest - 2.0, top),
                    sea,
                    (s, STACK_SHIFT),
                    &mut rng,
                );
                // Its top beds worn narrower than the rest: what is left of a cap.
                let n = beds.len();
                for bed in beds.iter_mut().skip(n.saturating_sub(2)) {
                    bed.inset += (0.1 + 0.2 * rng.unit()) * half.min_element();
                }
                blocks.push(CoastBlock {
                    center,
                    half,
                    beds,
                    seaward: [true; 4],
                    stack: true,
                    taper: STACK_TAPER.0 + (STACK_TAPER.1 - STACK_TAPER.0) * rng.unit(),
                });
                stacks[k] = true;
            }
        }

        // The sea's work on every seaward side: the notch, caves, arches.
        let mut notches = Vec::new();
        let mut caves = Vec::new();
        let mut arches = Vec::new();
        let axes = [grid.axis, -grid.axis, grid.axis.perp(), -grid.axis.perp()];
        for b in &blocks {
            let height = b.top() - sea;
            let mut effects = [0.0f32; 4];
            for Side {
                index: side,
                out,
                face,
                length,
            } in b.seaward_sides(grid.axis)
            {
                let probe = face - out * 0.5;
                let open = if b.stack { 1.0 } else { exposure(face - out) };
                let rho = (ground.resistance)(probe.extend(sea + 0.5));
                let e = effect(rho, open, self.beta.0);
                effects[side] = e;
                let pieces = (length / 4.0).ceil().max(1.0) as usize;
                for p in 0..pieces {
                    let along = length * ((p as f32 + 0.5) / pieces as f32 - 0.5);
                    // No deeper than a sixth of the block's width: the waves cut a
                    // narrow stack no further before it falls.
                    // A stack, narrow, stands only while its notch is shallow.
                    let share = if b.stack { 0.5 } else { 1.0 };
                    let d = (share * self.notch.0 * e * (0.75 + 0.5 * rng.unit()))
                        .min(b.half.min_element() / 3.0);
                    if d < 0.3 {
                        continue;
                    }
                    notches.push(Notch {
                        center: (face + out.perp() * along).extend(sea + 0.4),
                        out,
                        length: length / pieces as f32,
                        depth: d,
                    });
                }
            }
            if b.stack || height < 6.0 {
                continue;
            }
            // A narrow headland: the sea on two opposite sides; its cave goes through.
            let through = [(0, 1), (2, 3)]
                .into_iter()
                .filter(|&(a, c)| b.seaward[a] && b.seaward[c])
                .find(|&(a, c)| effects[a].max(effects[c]) >= self.caves.0 - 0.15);
            let floor = sea - 0.8;
            // The roof at the base of a hard bed, from 3 m over the sea up to half the
            // cliff's height and not much over the opening's span.
            let roof = |span: f32| {
                let range = (3.0, (0.5 * height).min((1.2 * span).max(6.0)));
                sea + hard_bed_base(ground, b.center, sea, range, 0.25)
                    .unwrap_or(0.5 * (range.0 + range.1))
            };
            if let Some((a, _)) = through {
                let along = axes[a].perp();
                let (span, width) = match a < 2 {
                    true => (2.0 * b.half.y, 2.0 * b.half.x),
                    false => (2.0 * b.half.x, 2.0 * b.half.y),
                };
                let span = 0.75 * span;
                arches.push(Window {
                    floor: b.center.extend(floor),
                    along,
                    span,
                    width,
                    roof: roof(span),
                });
                continue;
            }
            for side in b.seaward_sides(grid.axis) {
                let Side {
                    out, face, length, ..
                } = side;
                if effects[side.index] < self.caves.0 || length < 5.0 {
                    continue;
                }
                let width = 0.55 * length;
                caves.push(Recess {
                    mouth: face.extend(floor),
                    out,
                    size: Vec3::new(width, (1.5 * s).clamp(6.0, 30.0), roof(width) - floor),
                    faces: vec![face],
                });
            }
        }

        // Boulders on the platform at the foot of the cliff's seaward sides, and a few
        // about each stack's foot.
        let notch_depth = self.notch.0 * 1.25;
        // Where a boulder of `size` at `xy` comes to rest: on the platform, or on the sea
        // floor (cleared to 4 m under the sea where the base's cliff stood) clear of the
        // platform's edge; none in the cliff or a stack, where a cave's or an arch's
        // hollow reaching out of the face would cut it, or near the region's sides.
        let rest = |xy: Vec2, size: f32| -> Option<f32> {
            let off_cliff = grid.block_at(xy).is_some_and(|(i, j)| !cliff[i + nu * j]);
            let reach_of =
                |sl: &Slab| (grid.to_frame(xy - sl.center).abs() - sl.half).max_element();
            let under = slabs.iter().filter(|sl| reach_of(sl) < 0.0);
            let beside = slabs.iter().any(|sl| reach_of(sl) < 0.5 * size + 2.0);
            let base = match under.map(|sl| sl.z.y).reduce(f32::max) {
                Some(top) => top,
                None if beside => return None,
                None => ground.height(xy).min(sea - 4.0),
            };
            let in_stack = blocks.iter().any(|o| {
                o.stack
                    && (grid.to_frame(xy - o.center).abs() - o.half)
                        .cmplt(Vec2::splat(0.5 * size))
                        .all()
            });
            let by_cave = caves.iter().any(|r| {
                let d = xy - r.mouth.truncate();
                d.dot(r.out.perp()).abs() < 0.5 * r.size.x + size
                    && d.dot(r.out) < 0.25 * r.size.y + size + 2.0
            }) || arches
                .iter()
                .any(|a| a.floor.truncate().distance(xy) < 0.5 * a.span + a.width + size);
            let fits = base.is_finite()
                && off_cliff
                && !in_stack
                && !by_cave
                && size >= cell
                && ground.side_room(xy) >= 1.5 * size + reach(s);
            fits.then_some(base)
        };
        let mut fallen = Vec::new();
        let mut lay = |xy: Vec2, size: f32, rng: &mut Rng| {
            let Some(base) = rest(xy, size) else { return };
            let half = fallen_half(rng, size);
            let sunk = 0.2 + 0.5 * rng.unit();
            fallen.push(Fallen {
                center: xy.extend(base - sunk * half.z),
                half,
            });
        };
        for b in &blocks {
            if b.stack {
                let n = 2 + (3.0 * rng.unit()) as usize;
                for _ in 0..n {
                    let d = Vec2::from_angle(rng.unit() * std::f32::consts::TAU);
                    let size = s * (0.15 + 0.3 * rng.unit().powi(3));
                    let off = b.half.length() + 0.5 * size + 2.0 * rng.unit();
                    lay(b.center + d * off, size, &mut rng);
                }
                continue;
            }
            let height = b.top() - sea;
            for Side {
                out, face, length, ..
            } in b.seaward_sides(grid.axis)
            {
                let expected = self.talus.0 * length;
                let n = expected.floor() as usize + usize::from(rng.unit() < expected.fract());
                for _ in 0..n {
                    let far = rng.unit();
                    let size = s * (0.2 + 0.5 * rng.unit().powi(3)) * (0.7 + 0.6 * far);
                    let off = notch_depth + 0.5 * size + (0.05 + 0.9 * far * far) * 0.35 * height;
                    let xy = face + out * off + out.perp() * (length * (rng.unit() - 0.5));
                    lay(xy, size, &mut rng);
                }
            }
        }
        Ok(SeaCliff {
            sea,
            grid,
            blocks,
            slabs,
            clears,
            notches,
            caves,
            arches,
            fallen,
        })
    }

    /// The generated cliff: its rocks (blocks warped as one, slabs and boulders), its
    /// hollows (notch, caves, arches, in the blocks' warp) and the base's ground it clears.
    pub fn generate(&self, ground: &Ground) -> Result<Generated, LandformError> {
        let cliff = self.shape(ground)?;
        let s = self.joints.0;
        let warp = |children: Vec<NodeSpec>, blend: bool| {
            let nary = Nary {
                name: None,
                children,
            };
            NodeSpec::Warp(WarpSpec {
                name: None,
                turbulence: noise(WARP.0 * s, WARP.1 * s, 4, 17)
                    .expect("a noise of positive wavelength"),
                region: None,
                child: Box::new(match blend {
                    true => NodeSpec::Blend(nary),
                    false => NodeSpec::Union(nary),
                }),
            })
        };
        let yaw = cliff.grid.yaw();
        let mut primitives = Vec::new();
        if !cliff.blocks.is_empty() {
            primitives.push(warp(cliff.block_rocks(s), true));
        }
        primitives.extend(cliff.slabs.iter().enumerate().map(|(k, sl)| {
            boxed(
                sl.center.extend(0.5 * (sl.z.x + sl.z.y)),
                sl.half.extend(0.5 * (sl.z.y - sl.z.x)),
                yaw,
                PLATFORM_FALLOFF,
                noise(PLATFORM_ROUGH, 3.0, 3, 400 + k as u32),
            )
        }));
        primitives.extend(cliff.fallen.iter().enumerate().map(|(k, f)| f.rock(k)));
        let hollows: Vec<NodeSpec> = cliff
            .notches
            .iter()
            .enumerate()
            .map(|(k, n)| n.hollow(k))
            .chain(cliff.caves.iter().enumerate().map(|(k, c)| c.hollow(k)))
            .chain(cliff.arches.iter().map(Window::hollow))
            .collect();
        let clears: Vec<NodeSpec> = cliff
            .clears
            .iter()
            .map(|c| {
                boxed(
                    c.center.extend(0.5 * (c.z.x + c.z.y)),
                    c.half.extend(0.5 * (c.z.y - c.z.x)),
                    yaw,
                    BED_FALLOFF,
                    None,
                )
            })
            .collect();
        Ok(Generated {
            primitives,
            joining: Joining::Sculpt,
            hollows: match hollows.is_empty() {
                true => hollows,
                false => vec![warp(hollows, false)],
            },
            clears: match clears.is_empty() {
                true => clears,
                false => vec![warp(clears, false)],
            },
        })
    }
}

/// Each sample's distance from the shore (the nearest sample of `ground` whose top stands
/// over `sea`), metres, 0 on land: the exact Euclidean distance transform the DEM's
/// domain uses ([`crate::dem::edt`]).
fn shore_distance(ground: &Ground, sea: f32) -> Vec<f32> {
    let top = &ground.top;
    let c = top.cell();
    let land: Vec<bool> = top.samples().iter().map(|&h| h > sea).collect();
    crate::dem::edt(&land, top.nx(), top.ny(), f64::from(c.x), f64::from(c.y))
        .into_iter()
        .map(|d2| d2.sqrt() as f32)
        .collect()
}

/// The cleared box of cell `(i, j)`, joint to joint and a falloff beyond, over `z`.
fn clear(grid: &JointGrid, i: usize, j: usize, z: Vec2, falloff: f32) -> Clear {
    let (q0, q1) = grid.cell(i, j);
    Clear {
        center: grid.to_world(0.5 * (q0 + q1)),
        half: 0.5 * (q1 - q0) + Vec2::splat(falloff),
        z,
    }
}

/// The median of `v`, `None` when empty.
fn median(mut v: Vec<f32>) -> Option<f32> {
    v.sort_by(f32::total_cmp);
    v.get(v.len() / 2).copied()
}

/// The beds of a block over `xy` from `root` to `top`: one from the root to 2 m under sea
/// level, then a new bed wherever the resistance up the column departs from its bed's
/// mean by 0.2 (from 1.5 m to 9 m thick: the geology's beds, not every ripple of its
/// noise); each weathered back by
/// [`RECESSION`] joint spacings times twice its softness squared, ±15% (a bed recedes
/// alike from block to block, so its ledge runs along the face), and set off the block's
/// axis by up to `shift` joint spacings.
fn beds(
    ground: &Ground,
    xy: Vec2,
    (root, top): (f32, f32),
    sea: f32,
    (spacing, shift): (f32, f32),
    rng: &mut Rng,
) -> Vec<Bed> {
    let rho = |z: f32| (ground.resistance)(xy.extend(z));
    let start = (sea - 2.0).max(root + 1.0).min(top - 1.0);
    let mut bed = |lo: f32, hi: f32, mean: f32| Bed {
        z: Vec2::new(lo, hi),
        inset: RECESSION * spacing * 2.0 * (1.0 - mean).powi(2) * (0.85 + 0.3 * rng.unit()),
        shift: shift * spacing * Vec2::new(2.0 * rng.unit() - 1.0, 2.0 * rng.unit() - 1.0),
    };
    let mut out = vec![Bed {
        z: Vec2::new(root, start),
        inset: 0.0,
        shift: Vec2::ZERO,
    }];
    let step = 0.5;
    let (mut lo, mut sum, mut n) = (start, 0.0, 0);
    let mut z = start;
    while z + step < top {
        let r = rho(z + 0.5 * step);
        let mean = if n > 0 { sum / n as f32 } else { r };
        if n > 0 && z - lo >= 1.5 && ((r - mean).abs() > 0.2 || z - lo >= 9.0) {
            out.push(bed(lo, z, mean));
            (lo, sum, n) = (z, 0.0, 0);
        }
        sum += r;
        n += 1;
        z += step;
    }
    let mean = if n > 0 { sum / n as f32 } else { rho(lo) };
    out.push(bed(lo, top, mean));
    out
}

impl Notch {
    /// The notch's hollow: an ellipsoid along the face, as deep into it as the notch and
    /// [`NOTCH_HALF_HEIGHT`] high each way, roughened.
    fn hollow(&self, k: usize) -> NodeSpec {
        let along = self.out.perp();
        // Set into the face, so it cuts `depth` into the rock and little of the platform
        // before it.
        let ellipsoid = solid(
            SkeletonSpec::Ellipsoid {
                center: p3(Vec3::new(0.0, 0.4 * self.depth, 0.0)),
                radii: Size3(Vec3::new(
                    0.5 * self.length + 0.8,
                    0.6 * self.depth,
                    NOTCH_HALF_HEIGHT,
                )),
            },
            (0.3 * self.depth).clamp(0.2, 1.0),
            noise(0.15 * self.depth, 2.0, 2, 500 + k as u32),
        );
        NodeSpec::Transform(TransformSpec {
            name: None,
            translate: p3(self.center),
            rotate: Some(Rotation {
                axis: Dir3(Vec3::Z),
                degrees: Finite(along.y.atan2(along.x).to_degrees()),
            }),
            scale: Default::default(),
            child: Box::new(ellipsoid),
        })
    }
}

impl SeaCliff {
    /// The blocks' beds as boxes turned to the joint frame, each weathered back from the
    /// seaward sides.
    pub fn block_rocks(&self, joints: f32) -> Vec<NodeSpec> {
        let yaw = self.grid.yaw();
        let axis = self.grid.axis;
        let falloff = BED_FALLOFF.min(block_falloff(joints));
        let mut out = Vec::new();
        for (k, b) in self.blocks.iter().enumerate() {
            for (l, bed) in b.beds.iter().enumerate() {
                let cut = |side: usize| if b.seaward[side] { bed.inset } else { 0.0 };
                // Set off the axis toward the sea only: a landward side stays flush with
                // the block behind it.
                let shift = |side: usize, v: f32| if b.seaward[side] { v } else { 0.0 };
                let (q0, q1) = (
                    -b.half + Vec2::new(cut(1), cut(3))
                        - Vec2::new(
                            shift(1, bed.shift.x.max(0.0)),
                            shift(3, bed.shift.y.max(0.0)),
                        ),
                    b.half - Vec2::new(cut(0), cut(2))
                        + Vec2::new(
                            shift(0, (-bed.shift.x).max(0.0)),
                            shift(2, (-bed.shift.y).max(0.0)),
                        ),
                );
                // Narrower up the block by its taper.
                let up = ((bed.z.y - self.sea) / (b.top() - self.sea).max(1.0)).clamp(0.0, 1.0);
                let (q0, q1) = (q0 * (1.0 - b.taper * up), q1 * (1.0 - b.taper * up));
                let mid = 0.5 * (q0 + q1);
                let center = (b.center + axis * mid.x + axis.perp() * mid.y)
                    .extend(0.5 * (bed.z.x + bed.z.y));
                let half = (0.5 * (q1 - q0))
                    .max(Vec2::splat(0.5))
                    .extend(0.5 * (bed.z.y - bed.z.x));
                let rough = || {
                    noise(
                        ROUGH * joints,
                        0.35 * joints,
                        4,
                        600 + 7 * k as u32 + l as u32,
                    )
                };
                let slab = boxed(center, half, yaw, falloff, rough());
                if !b.stack {
                    out.push(slab);
                    continue;
                }
                // A stack's bed: the slab, its vertical edges rounded by a box of a wide
                // falloff, shrunk by its reach and standing through the slab's top and
                // foot (so that the bed's own edges stay sharp).
                let corner = STACK_CORNER * joints;
                let reach = crate::field::falloff::iso_reach() * corner;
                let inner = (half.truncate() - Vec2::splat(reach))
                    .max(Vec2::splat(0.25))
                    .extend(half.z + corner);
                out.push(NodeSpec::Intersection(Nary {
                    name: None,
                    children: vec![boxed(center, inner, yaw, corner, rough()), slab],
                }));
            }
        }
        out
    }
}

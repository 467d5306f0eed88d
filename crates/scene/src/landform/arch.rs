//! Natural arches as remnants of a fin of bedded rock.
//!
//! A natural arch is what weathering left of a narrow wall of rock — a fin, a spur or a
//! cliff line — after a soft bed under a harder one gave way right through it (the
//! sandstone arches of the Colorado Plateau and of the Cumberland Plateau's caprock;
//! Paris et al. 2019 §6.1 and Fig. 11 carve theirs where the geology is less durable).
//! So the generator does not bend a tube over the ground: it stands up the fin and cuts
//! the opening out of it.
//!
//! * **The fin** is a run of joint blocks rooted well below the ground, each a little
//!   wider or narrower than its neighbours and set off to either side (the faces break
//!   along vertical joints, the section varies along the span), narrowing toward the
//!   ends; a dome over them brings the crest down toward both ends, as fins wear from
//!   their ends.
//! * **The opening** is an upright ellipsoid through the fin, its top cut off level by a
//!   bedding plane: the ceiling is the base of the hard bed that holds the lintel up. When
//!   `height` is not given, the ceiling is found in the scene's geology: the height, in
//!   the upper part of the span's range, where the rock turns hardest from below to above
//!   (the contact of a soft bed under a hard one). Without geology it lies at 45% of the
//!   span.
//! * Both carry a weathering noise scaled by the fin's width.
//!
//! The node expands to `Union([base, Erode(Transform(Difference(fin, opening)))])`: the
//! erosion node over the fin alone reads the scene's geology, so its soft beds recess and
//! its hard ones stand out on its faces while the ground around it is left as it was. Spans default to what nature holds (tens of metres; the longest known spans
//! are about 90 to 120 m).

use glam::{Vec2, Vec3};

use super::joints::boulder;
use super::{Ground, LandformError, noise, p3, round3, solid};
use crate::field::skeleton::Size3;
use crate::field::{NoiseSpec, SkeletonSpec};
use crate::rng::Rng;
use crate::scene::NodeSpec;
use crate::scene::landform::ArchSpec;
use crate::scene::spec::{DifferenceSpec, ErodeSpec, Nary, Rotation, TransformSpec};
use crate::value::BoxSpec;
use crate::value::{Dir3, Finite, NonNegative, Positive};

/// Spans the generator accepts, metres: a metre-wide window is a pothole, not an arch,
/// and no known arch spans more than about 120 m.
const SPANS: (f32, f32) = (4.0, 300.0);

/// How far from the arch's middle the fins beside it begin, as a fraction of its fin's
/// half length: the fins stand en échelon off its ends, so the sky shows through its
/// opening from either side.
const OPEN: f32 = 0.45;

/// How far the blocks' tops step down toward a fin's ends, as a fraction of its height:
/// a fin's end breaks back block by block along its joints, so its crest comes down in
/// steps (a dome alone drew one smooth half-lens, every fin alike).
const STEP_DOWN: f32 = 0.6;

/// Height of the dome that rounds a fin's crest at its ends, as a fraction of the fin's
/// height: it takes the stepped blocks' outer corners off.
const DOME_END: f32 = 0.35;

/// How far below the lowest ground under the fin it is rooted, as a fraction of its
/// height above that ground.
const ROOT: f32 = 0.3;

/// The geometry the generator settled on, in the arch's frame (x along the span from its
/// middle, z absolute).
#[derive(Clone, Debug, PartialEq)]
pub struct ArchShape {
    /// Middle of the span (tree frame, x and y).
    pub center: Vec2,
    /// Direction of the span, from `from` to `to`.
    pub axis: Vec2,
    /// Span between the feet, metres.
    pub span: f32,
    /// Ground height at mid-span.
    pub ground: f32,
    /// Height of the opening's ceiling (the base of the lintel's bed).
    pub ceiling: f32,
    /// Height of the crest at mid-span.
    pub crest: f32,
    /// The fin's joint blocks in the arch's frame, from `from`'s side to `to`'s.
    pub blocks: Vec<Block>,
    /// Fallen blocks on the ground beside the fins, in the arch's frame.
    pub talus: Vec<Talus>,
    /// Bottom of the fin.
    pub root: f32,
    /// The fins of the same joint set beside the arch's, in the arch's frame.
    pub fins: Vec<Fin>,
}

/// A fin beside the arch's, without an opening: its joint blocks (in the arch's frame),
/// the middle of its footprint, the ground there, its crest and its root.
#[derive(Clone, Debug, PartialEq)]
pub struct Fin {
    /// Joint blocks, from one end to the other.
    pub blocks: Vec<Block>,
    /// Middle of the footprint, arch frame.
    pub center: Vec2,
    /// Ground height at its middle.
    pub ground: f32,
    /// Height of its crest.
    pub crest: f32,
    /// Bottom of the fin.
    pub root: f32,
}

/// A joint block of the fin: its x and y ranges in the arch's frame and its top (the
/// dome trims it further).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Block {
    /// Range along the span.
    pub x: Vec2,
    /// Range across it.
    pub y: Vec2,
    /// Height of its top.
    pub top: f32,
}

/// A block fallen from the fin: its centre (x and y in the arch's frame, z absolute),
/// half extents and turn about the vertical, degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Talus {
    /// Centre.
    pub center: Vec3,
    /// Half extents.
    pub half: Vec3,
}

impl ArchSpec {
    /// The arch's geometry on `ground`.
    pub fn shape(&self, ground: &Ground) -> Result<ArchShape, LandformError> {
        let (a, b) = (self.from.0, self.to.0);
        let span = a.distance(b);
        if !(SPANS.0..=SPANS.1).contains(&span) {
            return Err(LandformError::Invalid(format!(
                "an arch spans {span:.1} m between `from` and `to`: give between {} and {} m",
                SPANS.0, SPANS.1
            )));
        }
        let axis = (b - a) / span;
        let center = 0.5 * (a + b);
        let heights = [a, center, b].map(|p| ground.height(p));
        if heights.iter().any(|h| !h.is_finite()) {
            return Err(LandformError::Invalid(
                "an arch's feet and middle must stand on the landform region's ground".into(),
            ));
        }
        let g = heights[1];
        let ceiling = g + self
            .height
            .map_or_else(|| hard_bed(ground, center, g, span), |h| h.0);
        let rise = ceiling - g;
        let lintel = self.lintel.map_or((0.3 * rise).max(3.0), |t| t.0);
        let crest = ceiling + lintel;
        let width = self.width.map_or((0.22 * span).clamp(4.0, 20.0), |w| w.0);
        let reach = self.reach.map_or(0.7 * span, |r| r.0);
        let half = 0.5 * span + reach;
        let low = lowest_ground(ground, center, axis, half, width).min(g);
        let mut rng = Rng::new(ground.seed ^ 0xa5c4_0ac4);
        // Where the lintel has weathered thinnest: a waist somewhere over the opening.
        let waist = span * (rng.unit() - 0.5) * 0.5;
        let blocks = blocks(
            &mut rng,
            half,
            width,
            (crest, rise + lintel),
            (waist, 0.2 * span),
        );
        let frame = |p: Vec2| center + axis * p.x + axis.perp() * p.y;
        let fins = fins(
            &mut rng,
            self.fins,
            (half, width, crest - g),
            ground,
            &frame,
            axis,
        );
        let on_ground = |p: Vec2| {
            let xy = frame(p);
            ground.surface_near(xy, ground.height(xy), 0.5 * width)
        };
        let talus = match self.talus {
            true => std::iter::once(&blocks)
                .chain(fins.iter().map(|f| &f.blocks))
                .flat_map(|b| talus(&mut rng, b, width, on_ground))
                .collect(),
            false => Vec::new(),
        };
        Ok(ArchShape {
            center,
            axis,
            span,
            ground: g,
            ceiling,
            crest,
            blocks,
            talus,
            root: low - ROOT * (crest - low),
            fins,
        })
    }

    /// The arch's nodes: one transform holding the fin less its opening.
    pub fn generate(&self, ground: &Ground) -> Result<Vec<NodeSpec>, LandformError> {
        let s = self.shape(ground)?;
        Ok(vec![s.node(self.weathering.0)])
    }
}

/// The lowest ground under a fin of half-length `half` and width `width` along `axis`
/// from `center` (on a slope its downhill end stands far below its feet), sampled every
/// half width along its axis and both sides; samples off the region's ground are skipped.
fn lowest_ground(ground: &Ground, center: Vec2, axis: Vec2, half: f32, width: f32) -> f32 {
    let across = axis.perp();
    let n = (2.0 * half / (0.5 * width)).ceil() as usize;
    (0..=n)
        .flat_map(|i| {
            let along = center + axis * (-half + 2.0 * half * i as f32 / n as f32);
            [-0.5, 0.0, 0.5].map(|k| along + across * (k * width))
        })
        .map(|xy| ground.height(xy))
        .filter(|h| h.is_finite())
        .fold(f32::INFINITY, f32::min)
}

/// `n` fins beside the arch's (of half length, width and height `arch`), on its left
/// (+y, looking from `from` to `to`), so the arch's fin stands in front of the field seen
/// from its right: each a joint spacing from the last — its own width plus a slot of 0.6
/// to 1.6 widths weathered open along the joint between them — from 35% to 80% of the
/// arch fin's length, off its ends by turns (from [`OPEN`] of its half length out), 70% to
/// 120% as wide, waisted as the arch's fin is, from 80% to 130% as high above its own
/// ground, rooted as the arch's fin is ([`lowest_ground`]); a fin whose ends or middle are
/// off the region's ground is left out. `frame` takes a point of the arch's frame to the
/// tree's, whose x runs along `axis`.
fn fins(
    rng: &mut Rng,
    n: u32,
    arch: (f32, f32, f32),
    ground: &Ground,
    frame: &dyn Fn(Vec2) -> Vec2,
    axis: Vec2,
) -> Vec<Fin> {
    let (half, width, rise) = arch;
    let mut edge = 0.5 * width;
    (0..n)
        .filter_map(|k| {
            let w = width * (0.7 + 0.5 * rng.unit());
            let across = edge + width * (0.6 + rng.unit()) + 0.5 * w;
            edge = across + 0.5 * w;
            let h = half * (0.35 + 0.45 * rng.unit());
            let end = [-1.0, 1.0][k as usize % 2];
            let along = end * (OPEN * half + h);
            let center = Vec2::new(along, across);
            let [a, middle, b] = [-h, 0.0, h].map(|x| ground.height(frame(center + Vec2::X * x)));
            if !(a.is_finite() && middle.is_finite() && b.is_finite()) {
                return None;
            }
            let lowest = lowest_ground(ground, frame(center), axis, h, w).min(middle);
            let crest = middle + rise * (0.8 + 0.5 * rng.unit());
            let waist = (h * (rng.unit() - 0.5), 0.3 * h);
            let blocks = blocks(rng, h, w, (crest, crest - middle), waist)
                .into_iter()
                .map(|b| Block {
                    x: b.x + Vec2::splat(center.x),
                    y: b.y + Vec2::splat(center.y),
                    ..b
                })
                .collect();
            Some(Fin {
                blocks,
                center,
                ground: middle,
                crest,
                root: lowest - ROOT * (crest - lowest),
            })
        })
        .collect()
}

/// The ceiling's height above `g` at `xy`: where, between 30% and 70% of the span above
/// the ground, the resistance rises most steeply going up (a soft bed under a hard one);
/// 45% of the span when the rock is the same all the way up.
fn hard_bed(ground: &Ground, xy: Vec2, g: f32, span: f32) -> f32 {
    let step = (0.01 * span).max(0.1);
    super::hard_bed_base(ground, xy, g, (0.3 * span, 0.7 * span), step).unwrap_or(0.45 * span)
}

/// A fin's joint blocks over `[-half, half]`, mean width `width`, under `crest`: joints
/// half a width to two and a half widths apart; each side set in or out by up to 45%,
/// or (two times in five) flush with its neighbour, so not every joint shows on both
/// faces; narrowing to 60% at both ends and by up to 40% at the `waist` (its position
/// and reach along the span), where the lintel weathered thinnest; tops from a sixth of a
/// width below the crest to half a width above it, less [`STEP_DOWN`] of the fin's
/// `height` (`crest` is the crest and that height) toward the ends, so the crest steps at
/// the joints and comes down block by block to the ends (the dome trims the corners).
fn blocks(
    rng: &mut Rng,
    half: f32,
    width: f32,
    crest: (f32, f32),
    waist: (f32, f32),
) -> Vec<Block> {
    let (crest, height) = crest;
    let mut joints = vec![-half];
    while let Some(&x) = joints.last()
        && x < half
    {
        let next = x + width * (0.5 + 2.0 * rng.unit());
        // No sliver of a block at the end.
        joints.push(if next > half - 0.5 * width {
            half
        } else {
            next
        });
    }
    let mut sides = (0.0f32, 0.0f32);
    joints
        .windows(2)
        .enumerate()
        .map(|(k, j)| {
            let mid = 0.5 * (j[0] + j[1]);
            let thinning = 0.4 * (-((mid - waist.0) / waist.1).powi(2)).exp();
            let taper = (1.0 - 0.4 * (mid / half).powi(2)) * (1.0 - thinning);
            let mut side = |previous: f32| match k > 0 && rng.unit() < 0.4 {
                true => previous,
                false => 0.5 * width * taper * (0.55 + 0.9 * rng.unit()),
            };
            sides = (side(sides.0), side(sides.1));
            Block {
                x: Vec2::new(j[0], j[1]),
                y: Vec2::new(-sides.0, sides.1),
                top: crest - STEP_DOWN * height * (mid / half).abs().powf(2.5)
                    + width * (-1.0 / 6.0 + (2.0 / 3.0) * rng.unit()),
            }
        })
        .collect()
}

/// Blocks fallen from the fin onto the ground beside it (`ground`: the surface's height
/// at a point of the arch's frame, `None` where it cannot be found): about three every
/// width along each face, many small and few large (a cubed draw: from a twelfth to half
/// the width across), most near the foot and a few rolled farther (up to five of their
/// sizes off the face), sunk into the ground by a tenth to a third of their height, turned
/// and tilted at random ([`boulder`]). An even scatter of like blocks read as "pebbles in a neat
/// line".
fn talus(
    rng: &mut Rng,
    blocks: &[Block],
    width: f32,
    ground: impl Fn(Vec2) -> Option<f32>,
) -> Vec<Talus> {
    let (lo, hi) = match (blocks.first(), blocks.last()) {
        (Some(a), Some(b)) => (a.x.x, b.x.y),
        _ => return Vec::new(),
    };
    let n = ((hi - lo) / (0.35 * width)).ceil() as usize;
    let mut out = Vec::with_capacity(2 * n);
    for side in [-1.0f32, 1.0] {
        for _ in 0..n {
            let x = lo + (hi - lo) * rng.unit();
            let Some(b) = blocks.iter().find(|b| b.x.x <= x && x <= b.x.y) else {
                continue;
            };
            let face = if side < 0.0 { -b.y.x } else { b.y.y };
            let size = width * (0.08 + 0.42 * rng.unit().powi(3));
            let off = 0.6 + 4.4 * rng.unit().powi(2);
            let xy = Vec2::new(x, side * (face + size * off));
            let Some(h) = ground(xy) else {
                continue;
            };
            let half = 0.5
                * size
                * Vec3::new(
                    0.7 + 0.6 * rng.unit(),
                    0.6 + 0.6 * rng.unit(),
                    0.55 + 0.5 * rng.unit(),
                );
            // Sunk by a tenth to a third of its height: a block resting on a slope settles
            // into it, and one only touching the ground would leave slivers of air under
            // its tilted edge.
            let sunk = 0.1 + 0.25 * rng.unit();
            out.push(Talus {
                center: xy.extend(h + half.z * (1.0 - 2.0 * sunk)),
                half,
            });
        }
    }
    out
}

/// The mean width of a fin of `blocks`.
fn mean_width(blocks: &[Block]) -> f32 {
    blocks.iter().map(|b| b.y.y - b.y.x).sum::<f32>() / blocks.len().max(1) as f32
}

fn primitive(shape: SkeletonSpec, falloff: f32, noise: Option<NoiseSpec>) -> NodeSpec {
    solid(shape, round3(falloff).max(0.01), noise)
}

impl Fin {
    /// The fin's rock: its blocks, standing from the root to their tops, trimmed by a
    /// dome — an ellipsoid centred at the root, its top at the crest mid-fin and
    /// [`DOME_END`] of the fin's height above the middle's ground at the ends, so it
    /// rounds the crest's outer corners, never the root (a downhill end stays in the
    /// ground). `k` picks its noises.
    fn node(&self, falloff: f32, k: u32) -> NodeSpec {
        let w = mean_width(&self.blocks);
        let half = 0.5
            * self
                .blocks
                .last()
                .zip(self.blocks.first())
                .map_or(0.0, |(b, a)| b.x.y - a.x.x);
        let blocks = self
            .blocks
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let (lo, hi) = (self.root, b.top);
                primitive(
                    SkeletonSpec::Box {
                        center: p3(Vec3::new(
                            0.5 * (b.x.x + b.x.y),
                            0.5 * (b.y.x + b.y.y),
                            0.5 * (lo + hi),
                        )),
                        half_size: Size3(
                            Vec3::new(
                                0.5 * (b.x.y - b.x.x),
                                0.5 * (b.y.y - b.y.x),
                                0.5 * (hi - lo),
                            )
                            .map(round3),
                        ),
                        yaw: Finite(0.0),
                    },
                    falloff,
                    noise(0.12 * w, 0.8 * w, 4, 71 + 97 * k + i as u32),
                )
            })
            .collect();
        let height = self.crest - self.ground;
        let rz = self.crest - self.root;
        let end = (self.ground + DOME_END * height - self.root) / rz;
        let rx = half / (1.0 - end * end).sqrt();
        let dome = primitive(
            SkeletonSpec::Ellipsoid {
                center: p3(self.center.extend(self.root)),
                radii: Size3(Vec3::new(rx, 4.0 * w, rz).map(round3)),
            },
            falloff,
            noise(0.06 * height, 0.5 * height, 3, 61 + 97 * k),
        );
        NodeSpec::Intersection(Nary {
            name: None,
            children: vec![
                NodeSpec::Union(Nary {
                    name: None,
                    children: blocks,
                }),
                dome,
            ],
        })
    }
}

impl ArchShape {
    /// The fin's mean width.
    fn width(&self) -> f32 {
        mean_width(&self.blocks)
    }

    /// The plain node: the fin less its opening, and the fins beside it, placed on the
    /// span, weathered by an erosion node of strength `weathering` over their box (none
    /// at 0).
    pub fn node(&self, weathering: f32) -> NodeSpec {
        let w = self.width();
        let half = self.blocks.last().map_or(0.0, |b| b.x.y);
        let falloff = (0.25 * w).clamp(1.0, 4.0);
        let arch_fin = Fin {
            blocks: self.blocks.clone(),
            center: Vec2::ZERO,
            ground: self.ground,
            crest: self.crest,
            root: self.root,
        };
        let fin = arch_fin.node(falloff, 0);
        // The opening: an upright ellipsoid whose section at the ground spans the feet,
        // cut level at the ceiling.
        let rise = self.ceiling - self.ground;
        let (cz, oz) = (self.ground - 0.25 * rise, 1.35 * rise);
        let ox = 0.5 * self.span / (1.0 - ((self.ground - cz) / oz).powi(2)).sqrt();
        let vault = primitive(
            SkeletonSpec::Ellipsoid {
                center: p3(Vec3::new(0.0, 0.0, cz)),
                radii: Size3(Vec3::new(ox, 3.0 * w, oz).map(round3)),
            },
            falloff,
            noise(0.03 * self.span, 0.25 * self.span, 3, 62),
        );
        let deep = self.ceiling - self.root + 10.0;
        let bed = primitive(
            SkeletonSpec::Box {
                center: p3(Vec3::new(0.0, 0.0, self.ceiling - 0.5 * deep)),
                half_size: Size3(Vec3::new(self.span, 3.0 * w, 0.5 * deep).map(round3)),
                yaw: Finite(0.0),
            },
            0.5 * falloff,
            noise(0.02 * self.span, 0.15 * self.span, 3, 63),
        );
        let arch = NodeSpec::Difference(DifferenceSpec {
            name: None,
            base: Box::new(fin),
            carves: vec![NodeSpec::Intersection(Nary {
                name: None,
                children: vec![vault, bed],
            })],
        });
        // Boulders: blocks fallen from the fins, their corners broken off.
        let fallen =
            (self.talus.iter().enumerate()).map(|(k, t)| boulder(t.center, t.half, k as u32));
        let others = (self.fins.iter().enumerate()).map(|(k, f)| f.node(falloff, 1 + k as u32));
        let arch = NodeSpec::Union(Nary {
            name: None,
            children: std::iter::once(arch).chain(others).chain(fallen).collect(),
        });
        let placed = NodeSpec::Transform(TransformSpec {
            name: None,
            translate: p3(self.center.extend(0.0)),
            rotate: Some(Rotation {
                axis: Dir3(Vec3::Z),
                degrees: Finite(round3(self.axis.y.atan2(self.axis.x).to_degrees())),
            }),
            scale: Default::default(),
            child: Box::new(arch),
        });
        if weathering <= 0.0 {
            return placed;
        }
        // The fins' footprint turned onto the tree frame, with room for their talus.
        let extent = (self.fins.iter().flat_map(|f| &f.blocks))
            .map(|b| b.x.abs().max(b.y.abs()).max_element())
            .fold(half, f32::max);
        let reach = Vec2::splat(extent + 2.5 * w);
        let (lo, hi) = (self.center - reach, self.center + reach);
        NodeSpec::Erode(ErodeSpec {
            name: None,
            strength: NonNegative(weathering),
            region: BoxSpec {
                min: p3(lo.extend(self.root)),
                max: p3(hi.extend(self.fins.iter().fold(self.crest, |c, f| c.max(f.crest)) + w)),
            },
            blend: Some(Positive(round3(0.5 * w).max(0.5))),
            child: Box::new(placed),
        })
    }
}

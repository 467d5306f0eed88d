//! Joint blocks: the two sets of vertical joints at right angles that part a bed of rock
//! into blocks, shared by the generators that build cliffs of them (caprock cliff lines,
//! sea cliffs). Each joint is a straight line across the region at an irregular spacing;
//! a third of them weathered open into a crack, the others tight.

use glam::{Vec2, Vec3};

use super::{LandformError, noise, p3, round3, solid};
use crate::field::skeleton::Size3;
use crate::field::{Aabb, NoiseSpec, SkeletonSpec};
use crate::rng::Rng;
use crate::scene::NodeSpec;
use crate::scene::spec::{Nary, Rotation, TransformSpec};
use crate::value::{Dir3, Finite};

/// At most this many joint blocks: beyond, the joints are too close for the region.
pub const MAX_BLOCKS: usize = 20_000;

/// The joints over a region: the frame they run in and where each one lies.
#[derive(Clone, Debug, PartialEq)]
pub struct JointGrid {
    /// The first set's direction (unit, along the strike); the second runs along its
    /// perpendicular.
    pub axis: Vec2,
    /// The first set's joints across the frame's `u` axis: position and open width.
    pub u: Vec<(f32, f32)>,
    /// The second set's, across `v`.
    pub v: Vec<(f32, f32)>,
}

impl JointGrid {
    /// Joints `spacing` apart on average over `region`, the first set striking `strike`
    /// degrees from east; open cracks at least `cell` of air wide. `what` names the
    /// generator in the error when the blocks would pass [`MAX_BLOCKS`].
    pub fn new(
        rng: &mut Rng,
        region: &Aabb,
        strike: f32,
        spacing: f32,
        cell: f32,
        what: &str,
    ) -> Result<JointGrid, LandformError> {
        let axis = Vec2::from_angle(strike.to_radians());
        let frame = |p: Vec2| Vec2::new(p.dot(axis), p.dot(axis.perp()));
        let corners = [
            Vec2::new(region.min.x, region.min.y),
            Vec2::new(region.max.x, region.min.y),
            Vec2::new(region.min.x, region.max.y),
            Vec2::new(region.max.x, region.max.y),
        ]
        .map(frame);
        let lo = corners.iter().fold(Vec2::INFINITY, |a, &c| a.min(c));
        let hi = corners.iter().fold(Vec2::NEG_INFINITY, |a, &c| a.max(c));
        let u = joint_set(rng, lo.x, hi.x, spacing, cell);
        let v = joint_set(rng, lo.y, hi.y, spacing, cell);
        let grid = JointGrid { axis, u, v };
        let (nu, nv) = grid.dims();
        if nu * nv > MAX_BLOCKS {
            return Err(LandformError::Invalid(format!(
                "{what} joints {spacing} m apart make {} blocks over the region (at most \
                 {MAX_BLOCKS}): space them wider or shrink the region",
                nu * nv
            )));
        }
        Ok(grid)
    }

    /// The number of blocks across `u` and `v`.
    pub fn dims(&self) -> (usize, usize) {
        (self.u.len() - 1, self.v.len() - 1)
    }

    /// Frame coordinates of a tree-frame point.
    pub fn to_frame(&self, p: Vec2) -> Vec2 {
        Vec2::new(p.dot(self.axis), p.dot(self.axis.perp()))
    }

    /// The tree-frame point of frame coordinates `q`.
    pub fn to_world(&self, q: Vec2) -> Vec2 {
        self.axis * q.x + self.axis.perp() * q.y
    }

    /// Block `(i, j)`'s footprint in frame coordinates, inside the open joints' cracks:
    /// its lower and upper corners.
    pub fn footprint(&self, i: usize, j: usize) -> (Vec2, Vec2) {
        let (a, b) = (self.u[i], self.u[i + 1]);
        let (c, d) = (self.v[j], self.v[j + 1]);
        (
            Vec2::new(a.0 + 0.5 * a.1, c.0 + 0.5 * c.1),
            Vec2::new(b.0 - 0.5 * b.1, d.0 - 0.5 * d.1),
        )
    }

    /// Block `(i, j)`'s cell from joint to joint (cracks included), frame coordinates.
    pub fn cell(&self, i: usize, j: usize) -> (Vec2, Vec2) {
        (
            Vec2::new(self.u[i].0, self.v[j].0),
            Vec2::new(self.u[i + 1].0, self.v[j + 1].0),
        )
    }

    /// The widths of the joints on block `(i, j)`'s sides `+u`, `−u`, `+v`, `−v`.
    pub fn widths(&self, i: usize, j: usize) -> [f32; 4] {
        [self.u[i + 1].1, self.u[i].1, self.v[j + 1].1, self.v[j].1]
    }

    /// The block whose cell holds the tree-frame point `p`, if any.
    pub fn block_at(&self, p: Vec2) -> Option<(usize, usize)> {
        let q = self.to_frame(p);
        let find = |set: &[(f32, f32)], x: f32| {
            let k = set.partition_point(|&(j, _)| j <= x);
            (k >= 1 && k < set.len()).then(|| k - 1)
        };
        Some((find(&self.u, q.x)?, find(&self.v, q.y)?))
    }

    /// The strike of the first set, degrees counter-clockwise from east.
    pub fn yaw(&self) -> f32 {
        self.axis.y.atan2(self.axis.x).to_degrees()
    }
}

/// The falloff of the blocks for joints `spacing` apart: rounded edges, and small enough
/// that the blocks' fields do not meet across a joint ([`joint_set`]'s narrowest crack,
/// 1.4 falloffs, is wider than the 1.2 falloffs over which two blended fields close it).
pub fn block_falloff(spacing: f32) -> f32 {
    (0.06 * spacing).clamp(0.3, 1.5)
}

/// Joint positions across `[lo, hi]`: a joint before `lo`, then steps of 50% to 160% of
/// `spacing` until past `hi`; each with the width its weathering opened: for a third of
/// them 1.4 to 2.8 block falloffs and at least one `cell` of air between the blocks'
/// surfaces (a narrower crack falls between the samples of a mesh at that cell and leaves
/// specks of air sealed in the rock), none (a tight joint) for the others.
fn joint_set(rng: &mut Rng, lo: f32, hi: f32, spacing: f32, cell: f32) -> Vec<(f32, f32)> {
    let falloff = block_falloff(spacing);
    let mut out = Vec::new();
    let mut x = lo - spacing * rng.unit();
    loop {
        let open = rng.unit() < 1.0 / 3.0;
        let width = (falloff * (1.4 + 1.4 * rng.unit())).max(cell + falloff);
        let gap = if open { width } else { 0.0 };
        out.push((x, gap));
        if x > hi {
            return out;
        }
        x += spacing * (0.5 + 1.1 * rng.unit());
    }
}

/// A box of rock: `half` extents about `center`, turned `yaw` degrees about the vertical.
pub fn boxed(
    center: Vec3,
    half: Vec3,
    yaw: f32,
    falloff: f32,
    noise: Option<NoiseSpec>,
) -> NodeSpec {
    solid(
        SkeletonSpec::Box {
            center: p3(center),
            half_size: Size3(half.map(round3)),
            yaw: Finite(round3(yaw)),
        },
        round3(falloff).max(0.01),
        noise,
    )
}

/// The half extents of a block of `size` fallen from a bedded face: slabs and blocks, as a
/// bed's joints part it into pieces from flat to near cubic.
pub fn fallen_half(rng: &mut Rng, size: f32) -> Vec3 {
    0.5 * size
        * Vec3::new(
            0.7 + 0.6 * rng.unit(),
            0.45 + 0.55 * rng.unit(),
            0.3 + 0.6 * rng.unit(),
        )
}

/// How far a boulder's corners reach past its box, as a multiple of its half extents: the
/// box is cut by an ellipsoid this much larger, which takes its corners and edges off and
/// leaves its faces.
const CORNERS: f32 = 1.15;

/// Fallen block `k`: a joint block of half extents `half` about `center`, its corners and
/// edges broken off (a box cut by an ellipsoid [`CORNERS`] times its extents, both
/// roughened, the ellipsoid more), lying at a turn and a tilt drawn from `k`. Blocks fallen
/// from a bedded face keep their joint and bedding faces and lose their corners first
/// (spheroidal weathering rounds the corners, which weather from three sides, fastest);
/// a rounded ellipsoid with the same noise reads as a sponge.
pub fn boulder(center: Vec3, half: Vec3, k: u32) -> NodeSpec {
    let size = 2.0 * half.max_element();
    let mut rng = Rng::new(0xb01d_e125 ^ u64::from(k));
    let block = solid(
        SkeletonSpec::Box {
            center: p3(Vec3::ZERO),
            half_size: Size3(half.map(round3)),
            yaw: Finite(0.0),
        },
        round3((0.08 * size).max(0.1)),
        noise(0.03 * size, 0.6 * size, 2, 100 + k),
    );
    let corners = solid(
        SkeletonSpec::Ellipsoid {
            center: p3(Vec3::ZERO),
            radii: Size3((CORNERS * half).map(round3)),
        },
        round3((0.08 * size).max(0.1)),
        noise(0.06 * size, 0.35 * size, 2, 200 + k),
    );
    // A turn about an axis up to 9° off the vertical: the block turned any way about the
    // vertical and tilted by up to twice that, as it came to rest.
    let (tilt, azimuth) = (0.15 * rng.unit(), std::f32::consts::TAU * rng.unit());
    let axis = Vec3::new(
        tilt.sin() * azimuth.cos(),
        tilt.sin() * azimuth.sin(),
        tilt.cos(),
    );
    NodeSpec::Transform(TransformSpec {
        name: None,
        translate: p3(center),
        rotate: Some(Rotation {
            axis: Dir3(axis.map(round3).normalize()),
            degrees: Finite(round3(360.0 * rng.unit())),
        }),
        scale: Default::default(),
        child: Box::new(NodeSpec::Intersection(Nary {
            name: None,
            children: vec![block, corners],
        })),
    })
}

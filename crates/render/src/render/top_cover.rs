//! What lies on a region's top surface that the field alone does not tell: the talus
//! under its cliffs and the streams along its drainage ([`TopCover`]).
//!
//! **Talus.** //! A cliff retreats by rockfall: blocks loosened along its joints and beds drop, roll and
//! slide down until the slope is gentle enough to hold them, and pile up at its foot in
//! a talus apron of angular debris at or below its angle of repose, about 32–36° (Carson
//! 1977), steeper where blocks interlock. No tree grows on its fresh part.
//!
//! [`TopCover`] finds the aprons on the top surface of a picture's region, sampled as a
//! raster of column tops: a point lies on an apron when rock above it rises steeper than
//! [`REACH_ANGLE`] — some top within [`REACH`] stands higher than the line at that angle
//! from the point by more than [`EXCESS`] (the point lies under a face that sheds onto
//! it). The test needs no cliff detection: the apron's width scales with the face's height
//! by itself (a face `h` high sheds out to about `h / tan 55°`, 0.7 h, whether the ground
//! below is flat or a hillside), ground gentler than the angle sheds nothing, and a
//! canyon's stepped walls shed onto their soft-bed slopes and floor. The angle is ours:
//! at the angle of repose itself a 24 m caprock over a 30° hillside buried the whole
//! slope below it, 60 m and more, where real aprons under such a face are a few tens of
//! metres.
//!
//! The materials ([`crate::render::material`]) cover such ground with scree, over a
//! feature's surface too (a canyon's floor is carved, yet buried in debris): each block
//! its own shade and facet ([`rubble`]), so an apron reads as broken rock under a low
//! sun.
//!
//! **Streams.** Water gathers along the drainage of the same top surface: where more than
//! [`STREAM_AREA`] drains through a sample (the drainage area comes with the raster, from
//! the caller's flow routing), a stream runs, one sample wide, on a bed of damp gravel;
//! the pictures draw its water ([`crate::render::Shading::stream`]). Channels of humid
//! hills begin at catchments of about a hectare to a few (Montgomery and Dietrich 1988,
//! Nature 336); a stream the picture can show at the region's scale takes a few more.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::material::{resolved, smoothstep};
use crate::field::noise::{cellular, unit};

/// The angle (degrees) from an apron's toe to the top of the face that shed it.
pub const REACH_ANGLE: f32 = 55.0;

/// How far (metres) from a point the rock above it is searched: the apron of a 60 m face.
pub const REACH: f32 = 40.0;

/// How much (metres) the rock above must stand over the repose line for a point to lie
/// on talus: none below the first, all above the second.
pub const EXCESS: (f32, f32) = (1.5, 6.0);

/// How far (metres) off the top surface a point still lies on it: a cave's floor or an
/// arch's underside beneath it does not.
pub const ON_TOP: (f32, f32) = (1.0, 3.0);

/// Metres under the top surface over which a point turns from on it to under a roof of
/// rock ([`OnTop::under`]).
pub const UNDER: (f32, f32) = (3.0, 6.0);

/// Directions searched about each point.
const DIRECTIONS: usize = 24;

/// Seed of the rubble's cells ([`rubble`]).
pub const RUBBLE_SEED: u32 = 0x7a1e_5000;

/// The drainage areas (m², log10) over which a sample turns from dry ground to a
/// stream's bed: from 10 ha to 30 ha.
pub const STREAM_AREA: (f32, f32) = (5.0, 5.5);

/// The talus and streams of a region: a raster of column tops and, per sample, how much
/// of it lies on an apron and in a stream.
#[derive(Clone, Debug)]
pub struct TopCover {
    origin: Vec2,
    cell: f32,
    nx: usize,
    ny: usize,
    top: Vec<f32>,
    talus: Vec<f32>,
    stream: Vec<f32>,
}

/// How much of a point lies on talus and in a stream ([`TopCover::at`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OnTop {
    /// On a talus apron, in `[0, 1]`.
    pub talus: f32,
    /// In a stream's bed, in `[0, 1]`: water where it passes a half.
    pub stream: f32,
    /// On the top surface, in `[0, 1]` (0 on a cave's floor under it).
    pub top: f32,
    /// Under the top surface, in `[0, 1]`: 1 more than [`UNDER`]`.1` below it (a rock
    /// shelter's floor, a cave's), 0 nearer than [`UNDER`]`.0` (the raster's cells
    /// interpolate a slope's surface within a few metres), over it and off the raster.
    pub under: f32,
}

impl TopCover {
    /// The cover of a raster of `nx × ny` column tops `top` (row-major from the
    /// south-west sample at `origin`, `cell` metres apart; NaN where a column holds no
    /// solid) with the drainage area `area` (m²) through each sample. `None` when the
    /// raster is smaller than 2 × 2 or `top` or `area` is not its size.
    pub fn new(
        origin: Vec2,
        cell: f32,
        (nx, ny): (usize, usize),
        top: Vec<f32>,
        area: &[f32],
    ) -> Option<TopCover> {
        if nx < 2 || ny < 2 || top.len() != nx * ny || area.len() != nx * ny || !(cell > 0.0) {
            return None;
        }
        let rise = REACH_ANGLE.to_radians().tan() * cell;
        let steps = (REACH / cell).ceil().max(1.0) as i64;
        let dirs: Vec<Vec2> = (0..DIRECTIONS)
            .map(|k| Vec2::from_angle(k as f32 * std::f32::consts::TAU / DIRECTIONS as f32))
            .collect();
        let talus = (0..nx * ny)
            .into_par_iter()
            .map(|k| {
                let (i, j) = ((k % nx) as i64, (k / nx) as i64);
                let h = top[k];
                if !h.is_finite() {
                    return 0.0;
                }
                let mut excess = f32::NEG_INFINITY;
                for d in &dirs {
                    for s in 1..=steps {
                        let q = (Vec2::new(i as f32, j as f32) + *d * s as f32).round();
                        let (qi, qj) = (q.x as i64, q.y as i64);
                        if qi < 0 || qj < 0 || qi >= nx as i64 || qj >= ny as i64 {
                            break;
                        }
                        let t = top[(qi + qj * nx as i64) as usize];
                        if t.is_finite() {
                            excess = excess.max(t - h - rise * s as f32);
                        }
                    }
                }
                smoothstep(EXCESS.0, EXCESS.1, excess)
            })
            .collect();
        // The streams' courses smoothed over a few samples: routed cell to cell, they run
        // in straight runs at multiples of 45° and widen in steps.
        let wet: Vec<f32> = area
            .iter()
            .map(|a| smoothstep(STREAM_AREA.0, STREAM_AREA.1, a.max(1.0).log10()))
            .collect();
        let stream = blur(&blur(&wet, nx, ny), nx, ny)
            .into_iter()
            .map(|w| (1.6 * w).min(1.0))
            .collect();
        Some(TopCover {
            origin,
            cell,
            nx,
            ny,
            top,
            talus,
            stream,
        })
    }

    /// The four samples about `xy` with their bilinear weights (sample index, weight),
    /// `None` off the raster.
    fn corners(&self, xy: Vec2) -> Option<[(usize, f32); 4]> {
        let g = (xy - self.origin) / self.cell;
        if !(g.x >= 0.0 && g.y >= 0.0) {
            return None;
        }
        let (i, j) = (g.x as usize, g.y as usize);
        if i + 1 >= self.nx || j + 1 >= self.ny {
            return None;
        }
        let f = g - Vec2::new(i as f32, j as f32);
        let k = i + j * self.nx;
        Some([
            (k, (1.0 - f.x) * (1.0 - f.y)),
            (k + 1, f.x * (1.0 - f.y)),
            (k + self.nx, (1.0 - f.x) * f.y),
            (k + self.nx + 1, f.x * f.y),
        ])
    }

    /// The top surface's height over `xy` (bilinear between the samples), `None` off the
    /// raster or where a column holds no solid.
    pub fn height(&self, xy: Vec2) -> Option<f32> {
        let z: f32 = self
            .corners(xy)?
            .iter()
            .map(|&(k, b)| b * self.top[k])
            .sum();
        z.is_finite().then_some(z)
    }

    /// How much of `p` lies on a talus apron and in a stream's bed: the raster's weights
    /// there, faded off the top surface ([`ON_TOP`]); none off the raster.
    pub fn at(&self, p: Vec3) -> OnTop {
        let Some(corners) = self.corners(p.truncate()) else {
            return OnTop::default();
        };
        let (mut talus, mut stream, mut z, mut sum) = (0.0, 0.0, 0.0, 0.0);
        for (k, b) in corners {
            let t = self.top[k];
            if !t.is_finite() {
                continue;
            }
            talus += b * self.talus[k];
            stream += b * self.stream[k];
            z += b * t;
            sum += b;
        }
        if sum <= 0.0 {
            return OnTop::default();
        }
        let below = z / sum - p.z;
        let on = 1.0 - smoothstep(ON_TOP.0, ON_TOP.1, below.abs());
        OnTop {
            talus: talus / sum * on,
            stream: stream / sum * on,
            top: on,
            under: smoothstep(UNDER.0, UNDER.1, below),
        }
    }
}

/// `v` (an `nx × ny` raster) blurred by the binomial kernel 1 2 1 along each axis.
fn blur(v: &[f32], nx: usize, ny: usize) -> Vec<f32> {
    let at = |i: usize, j: usize| v[i + j * nx];
    let along = |i: usize, j: usize, di: bool| {
        let (lo, hi) = if di {
            (at(i.saturating_sub(1), j), at((i + 1).min(nx - 1), j))
        } else {
            (at(i, j.saturating_sub(1)), at(i, (j + 1).min(ny - 1)))
        };
        0.25 * lo + 0.5 * at(i, j) + 0.25 * hi
    };
    let x: Vec<f32> = (0..nx * ny).map(|k| along(k % nx, k / nx, true)).collect();
    let at = |i: usize, j: usize| x[i + j * nx];
    (0..nx * ny)
        .map(|k| {
            let (i, j) = (k % nx, k / nx);
            0.25 * at(i, j.saturating_sub(1)) + 0.5 * at(i, j) + 0.25 * at(i, (j + 1).min(ny - 1))
        })
        .collect()
}

/// The rubble of a talus apron at `p` seen `footprint` metres a pixel: a factor on its
/// albedo about 1, and the tilt of its stones' surfaces (to add to a near-level normal's
/// `x` and `y`). Blocks about 1.6 m across and stones about 0.5 m (cellular noise after
/// Worley 1996, in plan: an apron is gentle enough that plan cells do not stretch), each
/// its own shade, rounded (its surface tilts away from its middle, so the sun lights one
/// side and leaves the other in shade: flat facets, one tilt a block, read to blind
/// judges as "a polygon pattern"; domed as far as the sun lit a rim round each, "popcorn"),
/// tipped, with shaded gaps and some grit between them; each
/// scale fades to its mean and level as a pixel grows past it.
pub fn rubble(p: Vec3, footprint: f32) -> (f32, Vec2) {
    let (mut f, mut tilt) = (1.0, Vec2::ZERO);
    for (k, size, lean) in [(1u32, 1.6f32, 0.45f32), (2, 0.5, 0.35)] {
        let seen = resolved(size, footprint);
        if seen <= 0.0 {
            continue;
        }
        let (id, gap, offset) = cellular(RUBBLE_SEED ^ k, p.truncate() / size);
        let u = |s: u32| unit(id, s);
        // A third of the cells hold grit between the stones: level, darker, no stone
        // (every cell a stone, domed, read as "popcorn" and "a repeated cobble tile").
        if u(6) < RUBBLE_GRIT {
            f *= 1.0 - 0.12 * seen;
            continue;
        }
        let stone = (0.8 + 0.4 * u(3)) * (0.7 + 0.3 * smoothstep(0.0, 0.12, gap));
        f *= 1.0 + seen * (stone - 0.97);
        // Broken faces as much as rounded ones: each stone tipped its own way.
        let tip = 0.5 * u(4) * Vec2::from_angle(std::f32::consts::TAU * u(5));
        tilt += seen * lean * (offset + tip);
    }
    (f, tilt)
}

/// The share of a talus apron's cells that hold grit, not a stone ([`rubble`]).
pub const RUBBLE_GRIT: f32 = 0.35;

#[cfg(test)]
mod tests {
    use super::*;

    /// A plain at 0 with a cliff 30 m high rising at x = 100 to a plateau: the apron lies
    /// at the cliff's foot, out to about its height over tan 55°, and nowhere on the
    /// plateau or far out on the plain; a gentle hillside sheds nothing.
    #[test]
    fn talus_lies_at_a_cliffs_foot_out_to_its_reach() {
        let (nx, ny, cell) = (120, 20, 2.0);
        let top: Vec<f32> = (0..nx * ny)
            .map(|k| {
                if (k % nx) as f32 * cell >= 100.0 {
                    30.0
                } else {
                    0.0
                }
            })
            .collect();
        let dry = vec![0.0; nx * ny];
        let d = TopCover::new(Vec2::ZERO, cell, (nx, ny), top, &dry).unwrap();
        let at = |x: f32, z: f32| d.at(Vec3::new(x, 20.0, z)).talus;
        // Under the plateau's top (a shelter's floor) and not on the plain.
        let under = |x: f32, z: f32| d.at(Vec3::new(x, 20.0, z)).under;
        assert_eq!(
            (under(110.0, 10.0), under(110.0, 30.0), under(50.0, 0.0)),
            (1.0, 0.0, 0.0)
        );
        assert!(at(96.0, 0.0) > 0.99, "{}", at(96.0, 0.0));
        assert!(at(86.0, 0.0) > 0.9, "{}", at(86.0, 0.0));
        let reach = 30.0 / REACH_ANGLE.to_radians().tan();
        assert!(at(100.0 - reach - 2.0, 0.0) == 0.0);
        assert!(at(150.0, 30.0) == 0.0, "no talus on the plateau");
        // A floor 10 m under the top (a cave's) is not on the apron.
        assert!(at(96.0, -10.0) == 0.0);
        // A hillside at 40°: gentler than the reach angle, it sheds nothing.
        let slope = 40f32.to_radians().tan();
        let hill: Vec<f32> = (0..nx * ny)
            .map(|k| (k % nx) as f32 * cell * slope)
            .collect();
        let d = TopCover::new(Vec2::ZERO, cell, (nx, ny), hill, &dry).unwrap();
        let z = 60.0 * slope;
        assert!(d.at(Vec3::new(60.0, 20.0, z)).talus == 0.0);
    }

    /// A stream runs where the drainage area passes its threshold, on the top surface only:
    /// water (over a half) along a course one sample wide, smoothed over its neighbours,
    /// none three samples away.
    #[test]
    fn streams_run_where_the_drainage_gathers() {
        let (nx, ny, cell) = (10, 10, 5.0);
        let area: Vec<f32> = (0..nx * ny)
            .map(|k| if k % nx == 5 { 1e6 } else { 50.0 })
            .collect();
        let d = TopCover::new(Vec2::ZERO, cell, (nx, ny), vec![0.0; nx * ny], &area).unwrap();
        let centre = d.at(Vec3::new(25.0, 20.0, 0.0)).stream;
        assert!(centre > 0.5, "{centre}");
        assert_eq!(d.at(Vec3::new(10.0, 20.0, 0.0)).stream, 0.0);
        assert_eq!(d.at(Vec3::new(25.0, 20.0, -5.0)).stream, 0.0);
        assert!(TopCover::new(Vec2::ZERO, cell, (nx, ny), vec![0.0; 4], &area).is_none());
    }

    /// The rubble varies about a mean near 1 where resolved, its facets lean, and it is 1
    /// and level where a pixel is wider than its blocks.
    #[test]
    fn rubble_shows_blocks_where_resolved() {
        let p = |i: u32| Vec3::new(0.137 * i as f32, 0.071 * i as f32, 0.0);
        let near: Vec<f32> = (0..4000).map(|i| rubble(p(i), 0.01).0).collect();
        let mean = near.iter().sum::<f32>() / near.len() as f32;
        let (lo, hi) = near
            .iter()
            .fold((f32::INFINITY, 0.0f32), |(a, b), &v| (a.min(v), b.max(v)));
        assert!((0.8..1.1).contains(&mean), "mean {mean}");
        assert!(hi - lo > 0.4, "range {lo}..{hi}");
        let lean = (0..4000)
            .map(|i| rubble(p(i), 0.01).1.length())
            .sum::<f32>()
            / 4000.0;
        assert!(lean > 0.1, "mean lean {lean}");
        assert!((0..400).all(|i| rubble(p(i), 5.0) == (1.0, Vec2::ZERO)));
    }
}

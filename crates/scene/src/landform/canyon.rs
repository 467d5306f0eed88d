//! River canyons and gorges (Paris et al. 2019 §6.1): the riverbed is where the stream
//! power `σ = A^½·s` of the terrain (drainage by Freeman 1991 over a depression-filled
//! grid, Barnes et al. 2014), with at least `min_area` of drainage and carried on down the
//! river, exceeds a threshold; a convolution spreads its stress over the banks. The gorge is then carved as a volume:
//! negative spheres on a jittered lattice fill the rock from the incised floor — `depth`
//! metres below the bed where the stream is strongest, less up the tributaries — to the
//! surface, each of energy the erosion effect `e(ρ, σ)` of the rock at its centre. The
//! spheres overlap (several per radius) and their energies are scaled by the lattice's
//! density, so together they sum to a smooth carving field `2e` with no scallops of single
//! spheres: the rock goes where `2e` exceeds what holds it, which happens farther from the
//! stream in soft rock than in hard. Walls step back going up, by `2·retreat·(1 − ρ)²`
//! metres per metre of height, so the gorge opens upwards in steps: cliffs in the hard
//! beds, talus slopes in the soft ones (the profile of the Grand Canyon's walls), and the
//! effect all the way up a column is that of the softest rock the river cut through there,
//! so no bed overhangs the one beneath.

use glam::{Vec2, Vec3};

use super::{Ground, LandformError, effect, point};
use crate::analysis::flow::{NEIGHBOURS, drainage_area, fill_depressions};
use crate::analysis::relief::slope;
use crate::dem::Heightfield;
use crate::field::ISO;
use crate::scene::NodeSpec;
use crate::scene::landform::CanyonSpec;

/// `∫ g(|x|) dx` over the unit ball for Wyvill's `g(x) = (1 − x²)³`: `4π · 16/315`. A
/// lattice of pitch `s` of such spheres of radius `R` sums to about this times `(R/s)³`.
const WYVILL_VOLUME: f32 = 4.0 * std::f32::consts::PI * 16.0 / 315.0;

/// How far from its bed a river's stress is mapped, in `banks`: as far as its walls can
/// step back going up.
const WALL_REACH: f32 = 2.0;

/// What the river does at one sample of the top grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stress {
    /// Strength of the bed the sample is under the influence of, in `[0, 1]`: 1 where
    /// its stream power is twice the threshold or more.
    pub strength: f32,
    /// The elevation of that bed (NaN where no river reaches).
    pub bed: f32,
    /// Horizontal distance to that bed, metres.
    pub distance: f32,
}

impl Stress {
    const NONE: Stress = Stress {
        strength: 0.0,
        bed: f32::NAN,
        distance: f32::INFINITY,
    };
}

impl CanyonSpec {
    /// Per sample of the top grid: the bed that stresses it most (its strength falling
    /// linearly to 0 across the banks), or [`Stress::NONE`]-like values where no river
    /// reaches.
    pub fn stress(&self, ground: &Ground) -> Vec<Stress> {
        let top = &ground.top;
        let (nx, ny) = (top.nx(), top.ny());
        let sp = self.river_power(top);
        let z = top.samples();
        let t = self.threshold.0;
        let cell = top.cell();
        // Out to twice the banks: the walls step back past them as they rise.
        let far = WALL_REACH * self.banks.0;
        let reach = (far / cell.x.min(cell.y)).ceil() as isize;
        let lateral = |s: &Stress| s.strength * (1.0 - s.distance / far).max(0.0);
        let mut out = vec![Stress::NONE; nx * ny];
        for k in 0..nx * ny {
            if sp[k] <= t || z[k].is_nan() {
                continue;
            }
            let strength = ((sp[k] - t) / t).min(1.0);
            let (i, j) = ((k % nx) as isize, (k / nx) as isize);
            for dj in -reach..=reach {
                for di in -reach..=reach {
                    let (a, b) = (i + di, j + dj);
                    if a < 0 || b < 0 || a as usize >= nx || b as usize >= ny {
                        continue;
                    }
                    let s = Stress {
                        strength,
                        bed: z[k],
                        distance: (Vec2::new(di as f32, dj as f32) * cell).length(),
                    };
                    let m = a as usize + nx * b as usize;
                    let (new, old) = (lateral(&s), lateral(&out[m]));
                    // The strongest bed wins; ties to the lower bed (fixed order).
                    if new > old || (new == old && new > 0.0 && s.bed < out[m].bed) {
                        out[m] = s;
                    }
                }
            }
        }
        out
    }

    /// The stream power of the river at each sample of `top`: `A^½·s` where the drainage
    /// area reaches `min_area` (0 elsewhere), then carried down the river — each sample
    /// passes its power on to its steepest receiver on the depression-filled grid, which
    /// keeps the larger — so a gorge once cut runs on down its river through the flatter
    /// reaches, where the local power would fall under the threshold and leave the gorge
    /// as closed bowls.
    fn river_power(&self, top: &Heightfield) -> Vec<f32> {
        let filled = fill_depressions(top);
        let area = drainage_area(&filled);
        let mut power: Vec<f32> = slope(top)
            .iter()
            .zip(&area)
            .map(|(s, a)| {
                if *a >= self.min_area.0 {
                    a.sqrt() * s
                } else {
                    0.0
                }
            })
            .collect();
        let (nx, ny) = (top.nx(), top.ny());
        let f = filled.samples();
        let mut order: Vec<usize> = (0..nx * ny).filter(|&k| f[k].is_finite()).collect();
        order.sort_by(|&a, &b| f[b].total_cmp(&f[a]).then(a.cmp(&b)));
        for k in order {
            let (i, j) = ((k % nx) as isize, (k / nx) as isize);
            let receiver = NEIGHBOURS
                .iter()
                .filter_map(|&(di, dj)| {
                    let (a, b) = (i + di, j + dj);
                    let inside = a >= 0 && b >= 0 && (a as usize) < nx && (b as usize) < ny;
                    let n = inside.then(|| a as usize + nx * b as usize)?;
                    let drop = (f[k] - f[n]) / ((di * di + dj * dj) as f32).sqrt();
                    (drop > 0.0).then_some((n, drop))
                })
                .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)));
            if let Some((n, _)) = receiver {
                power[n] = power[n].max(power[k]);
            }
        }
        power
    }

    /// The river's stress over a sample stressed by `s`, at a height where the wall has
    /// stepped back `recession` metres from where it stands at the floor: the bed's
    /// strength over the inner half of the banks, falling linearly to 0 across the outer
    /// half.
    fn sigma(&self, s: &Stress, recession: f32) -> f32 {
        let d = (s.distance - recession).max(0.0);
        s.strength * (2.0 * (1.0 - d / self.banks.0)).clamp(0.0, 1.0)
    }

    /// How far a wall steps back per metre of height in rock of resistance `rho`:
    /// `2·retreat·(1 − ρ)²` — a talus slope in the soft beds (about 35° at `retreat` 1
    /// in the softest), a cliff in the hard ones (a fiftieth of that at ρ = 0.9).
    fn step_back(&self, rho: f32) -> f32 {
        2.0 * self.retreat.0 * (1.0 - rho.clamp(0.0, 1.0)).powi(2)
    }

    /// The sphere centres and their weighted effects: a regular lattice of pitch
    /// `spacing` in the columns the river stresses, from the incised floor up to the
    /// surface. The lowest sphere of a column is weighted by how much of its layer lies
    /// above the floor, so the floor follows the bed smoothly rather than in steps of the
    /// lattice.
    pub fn samples(&self, ground: &Ground) -> Vec<(Vec3, f32)> {
        let stress = self.stress(ground);
        let top = &ground.top;
        let h = self.spacing.0;
        let (nx, ny) = (top.nx(), top.ny());
        let size = top.cell() * Vec2::new((nx - 1) as f32, (ny - 1) as f32);
        let (mx, my) = ((size.x / h) as usize + 1, (size.y / h) as usize + 1);
        let mut out = Vec::new();
        let mut rocks = Vec::new();
        for j in 0..my {
            for i in 0..mx {
                let xy = top.origin() + Vec2::new(i as f32, j as f32) * h;
                let Some(k) = ground.nearest_sample(xy) else {
                    continue;
                };
                let s = stress[k];
                let surface = ground.height(xy);
                if s.strength <= 0.0 || !surface.is_finite() {
                    continue;
                }
                let floor = s.bed - self.depth.0 * s.strength;
                let (lo, hi) = ((floor / h).floor() as i32, (surface / h).ceil() as i32);
                // The rock up the column from the floor, a metre at a time. The wall steps
                // back going up (cliffs in hard beds, slopes in soft ones), less up the
                // weaker tributaries; the effect all the way up is that of the softest
                // rock the river cut through there. Neither lets a bed overhang the one
                // below it: a soft bed under a hard one is a slope the cliff above stands
                // back from, as the talus shed from the cliff keeps it.
                rocks.clear();
                let mut z = floor;
                while z < surface {
                    let dz = (surface - z).min(1.0);
                    rocks.push((dz, (ground.resistance)(xy.extend(z + 0.5 * dz))));
                    z += dz;
                }
                let softest = rocks.iter().fold(1.0f32, |m, r| m.min(r.1));
                let (mut z, mut recession, mut next) = (floor, 0.0f32, rocks.iter());
                for l in lo..=hi {
                    let p = xy.extend(l as f32 * h);
                    while z < p.z
                        && let Some(&(dz, rho)) = next.next()
                    {
                        recession += s.strength * self.step_back(rho) * dz;
                        z += dz;
                    }
                    let weight = ((p.z + 0.5 * h - floor) / h).clamp(0.0, 1.0);
                    if !ground.region.contains(p) {
                        continue;
                    }
                    let e = weight * effect(softest, self.sigma(&s, recession), self.beta.0);
                    if e >= self.min_effect.0 {
                        out.push((p, e));
                    }
                }
            }
        }
        out
    }

    /// The carving spheres: energies scaled so the lattice sums to `2e`, which carves
    /// saturated rock (`f = 2T`) where `e > T/2`.
    pub fn generate(&self, ground: &Ground) -> Result<Vec<NodeSpec>, LandformError> {
        let r = self.radius.0;
        if self.spacing.0 > 0.5 * r {
            return Err(LandformError::Invalid(format!(
                "canyon spacing {} m over half the radius {r} m: the spheres would show",
                self.spacing.0
            )));
        }
        let density = (self.spacing.0 / r).powi(3) / WYVILL_VOLUME;
        Ok(self
            .samples(ground)
            .into_iter()
            .map(|(p, e)| point(p, r, -4.0 * ISO * e * density))
            .collect())
    }
}

//! River canyons and gorges (Paris et al. 2019 §6.1): the riverbed is where the stream
//! power `σ = A^½·s` of the terrain (`analysis::relief::stream_power`, drainage by
//! Freeman 1991 over a depression-filled grid, Barnes et al. 2014) exceeds a threshold;
//! a small convolution widens its influence to the banks (floods). Points sampled on the
//! surface of the walls, from the bed up to `depth` metres above it, get negative
//! spheres whose energy is the erosion effect `e(ρ, σ)`, strongest at the water: walls
//! are undercut where the rock is soft.

use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

use super::{Ground, LandformError, Poisson, Rng, carving_sphere, effect, throw_dart};
use crate::analysis::relief::stream_power;
use crate::scene::{NodeSpec, Positive, Unit};

fn default_beta() -> Unit {
    Unit(0.3)
}

/// Parameters of canyon erosion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CanyonSpec {
    /// Stream power (m, `√m²` times slope) above which a sample is riverbed.
    pub threshold: Positive,
    /// The riverbed's influence reaches this far onto the banks, metres.
    pub banks: Positive,
    /// The walls are eroded up to this height above the bed, metres.
    pub depth: Positive,
    /// Cavity radius of one sphere at full effect, metres.
    pub radius: Positive,
    /// Poisson spacing of the wall samples, metres.
    pub spacing: Positive,
    /// β of the erosion effect (the effect on the hardest rock).
    #[serde(default = "default_beta")]
    pub beta: Unit,
    /// Samples with a smaller effect make no sphere.
    #[serde(default = "super::default_min_effect")]
    pub min_effect: Unit,
}

impl CanyonSpec {
    /// Per sample of the top grid: the river's stress in `[0, 1]` (1 on a bed of twice
    /// the threshold, falling linearly to 0 across the banks) and the elevation of the bed
    /// it comes from (NaN where no river reaches).
    pub fn stress(&self, ground: &Ground) -> Vec<(f32, f32)> {
        let top = &ground.top;
        let (nx, ny) = (top.nx(), top.ny());
        let sp = stream_power(top);
        let z = top.samples();
        let t = self.threshold.0;
        let cell = top.cell();
        let reach = (self.banks.0 / cell.x.min(cell.y)).ceil() as isize;
        let mut out = vec![(0.0f32, f32::NAN); nx * ny];
        for k in 0..nx * ny {
            if sp[k] <= t || z[k].is_nan() {
                continue;
            }
            let bed = ((sp[k] - t) / t).min(1.0);
            let (i, j) = ((k % nx) as isize, (k / nx) as isize);
            for dj in -reach..=reach {
                for di in -reach..=reach {
                    let (a, b) = (i + di, j + dj);
                    if a < 0 || b < 0 || a as usize >= nx || b as usize >= ny {
                        continue;
                    }
                    let d = (Vec2::new(di as f32, dj as f32) * cell).length();
                    let s = bed * (1.0 - d / (self.banks.0 + cell.x)).max(0.0);
                    let m = a as usize + nx * b as usize;
                    // The strongest bed wins; ties to the lower bed (fixed order).
                    if s > out[m].0 || (s == out[m].0 && s > 0.0 && z[k] < out[m].1) {
                        out[m] = (s, z[k]);
                    }
                }
            }
        }
        out
    }

    /// The wall samples and their effects.
    pub fn samples(&self, ground: &Ground) -> Vec<(Vec3, f32)> {
        let stress = self.stress(ground);
        let top = &ground.top;
        let cell = top.cell();
        let levels = ((self.depth.0 / self.spacing.0).ceil() as usize).max(1);
        let mut rng = Rng::new(ground.seed);
        let mut poisson = Poisson::new(self.spacing.0);
        let mut out = Vec::new();
        for (k, &(s, bed)) in stress.iter().enumerate() {
            if s <= 0.0 {
                continue;
            }
            let xy = ground.sample_point(k).truncate();
            for l in 0..levels {
                let z = |u: f32| bed + self.depth.0 * (l as f32 + u) / levels as f32;
                let Some(p) = throw_dart(ground, &mut rng, xy, cell, self.spacing.0, z) else {
                    continue;
                };
                let above = (p.z - bed) / self.depth.0;
                if !(-0.2..=1.0).contains(&above) || !ground.region.contains(p) {
                    continue;
                }
                let sigma = s * (1.0 - above.max(0.0));
                let e = effect((ground.resistance)(p), sigma, self.beta.0);
                if e >= self.min_effect.0 && poisson.take(p) {
                    out.push((p, e));
                }
            }
        }
        out
    }

    /// The carving spheres.
    pub fn generate(&self, ground: &Ground) -> Result<Vec<NodeSpec>, LandformError> {
        Ok(self
            .samples(ground)
            .into_iter()
            .map(|(p, e)| carving_sphere(p, self.radius.0, e))
            .collect())
    }
}

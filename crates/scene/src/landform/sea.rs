//! Sea erosion (Paris et al. 2019 §6.1): points sampled on the terrain's surface around
//! sea level (Poisson spacing) each get a negative sphere whose energy follows the
//! erosion effect `e(ρ, σ)`, with the wave stress `σ = w·α`: `w` falls from 1 at sea
//! level to 0 at the band's edges, `α` is the coastal accessibility of the point
//! (`analysis::relief::coastal_accessibility`, on the terrain's section at sea level, so
//! earlier undercuts count as sea). Points whose effect is below `min_effect` are dropped.
//! Repeated steps are nested `Landform` nodes, each on the one before.

use glam::{Vec2, Vec3};

use super::{Ground, LandformError, Poisson, carving_sphere, effect, throw_dart};
use crate::analysis::relief::coastal_accessibility;
use crate::dem::Heightfield;
use crate::rng::Rng;
use crate::scene::NodeSpec;
use crate::scene::landform::SeaSpec;

impl SeaSpec {
    /// The wave stress's falloff `w(z)`: 1 at sea level, 0 at and beyond the band.
    pub fn falloff(&self, z: f32) -> f32 {
        let t = ((z - self.sea_level.0) / self.band.0).abs();
        if t >= 1.0 { 0.0 } else { (1.0 - t * t).powi(2) }
    }

    /// The carving spheres of one step.
    pub fn generate(&self, ground: &Ground) -> Result<Vec<NodeSpec>, LandformError> {
        Ok(self
            .samples(ground)?
            .into_iter()
            .map(|(p, e)| carving_sphere(p, self.radius.0, e))
            .collect())
    }

    /// The surface samples and their effects.
    pub fn samples(&self, ground: &Ground) -> Result<Vec<(Vec3, f32)>, LandformError> {
        let sea = self.sea_level.0;
        let band = self.band.0;
        let section = section(ground, sea, band)?;
        let alpha = coastal_accessibility(&section, sea, 0.5, self.reach.0);
        let top = &ground.top;
        let (nx, ny) = (top.nx(), top.ny());
        let cell = top.cell();
        // Columns near where the surface crosses the band: the top or the section changes
        // within a few cells (undercuts from earlier steps hide under the top).
        let window = ((2.0 * self.radius.0 / cell.x.min(cell.y)).ceil() as isize).max(1);
        let z = top.samples();
        let s = section.samples();
        let near = |i: usize, j: usize| {
            let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
            let mut mixed = (false, false);
            for dj in -window..=window {
                for di in -window..=window {
                    let (a, b) = (i as isize + di, j as isize + dj);
                    if a < 0 || b < 0 || a as usize >= nx || b as usize >= ny {
                        continue;
                    }
                    let k = a as usize + nx * b as usize;
                    if !z[k].is_nan() {
                        lo = lo.min(z[k]);
                        hi = hi.max(z[k]);
                    }
                    if s[k] < sea {
                        mixed.0 = true;
                    } else {
                        mixed.1 = true;
                    }
                }
            }
            (lo <= sea + band && hi >= sea - band) || (mixed.0 && mixed.1)
        };
        let mut rng = Rng::new(ground.seed);
        let mut poisson = Poisson::new(self.spacing.0);
        let levels = ((2.0 * band / self.spacing.0).ceil() as usize).max(1);
        let mut out = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                if !near(i, j) {
                    continue;
                }
                let xy = top.origin() + Vec2::new(i as f32, j as f32) * cell;
                for l in 0..levels {
                    let z = |u: f32| sea - band + 2.0 * band * (l as f32 + u) / levels as f32;
                    let Some(p) = throw_dart(ground, &mut rng, xy, cell, self.spacing.0, z) else {
                        continue;
                    };
                    let w = self.falloff(p.z);
                    if w <= 0.0 || !ground.region.contains(p) {
                        continue;
                    }
                    let a = ground
                        .nearest_sample(p.truncate())
                        .map_or(0.0, |k| alpha[k]);
                    let e = effect((ground.resistance)(p), w * a, self.beta.0);
                    if e >= self.min_effect.0 && poisson.take(p) {
                        out.push((p, e));
                    }
                }
            }
        }
        Ok(out)
    }
}

/// The section of `ground` at `sea` level as a heightfield: 1 m below sea level where the
/// base is air there (sea), `above` metres over it where it is rock, so an undercut counts
/// as sea.
pub(super) fn section(ground: &Ground, sea: f32, above: f32) -> Result<Heightfield, LandformError> {
    let top = &ground.top;
    let (nx, ny) = (top.nx(), top.ny());
    let z = (0..nx * ny)
        .map(|k| {
            let p = ground.sample_point(k).truncate().extend(sea);
            if ground.solid(p) {
                sea + 1.0 + above
            } else {
                sea - 1.0
            }
        })
        .collect();
    Heightfield::new(nx, ny, Vec2::ZERO, top.cell(), z)
        .map_err(|e| LandformError::Invalid(e.to_string()))
}

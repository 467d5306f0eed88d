//! Karst networks by invasion percolation (Paris et al. 2019 §6.2, after Wilkinson and
//! Willemsen 1983): from the sinks of the terrain, water advances into the least
//! resistant rock first. A queue holds candidate points ordered by their resistance ρ
//! perturbed by up to ε; the least resistant is taken, carved by a negative sphere whose
//! energy follows the erosion effect `e(ρ, 1)`, and new candidates are drawn on the lower
//! hemisphere around it, kept only where their Poisson sphere is free. Rock at least as
//! hard as `threshold` (ρ₀) is never carved nor percolated through.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::Vec3;

use super::{Ground, LandformError, Poisson, carving_sphere, effect};
use crate::analysis::relief::sinks;
use crate::rng::Rng;
use crate::scene::NodeSpec;
use crate::scene::landform::KarstSpec;

/// A candidate: perturbed resistance (as ordered bits), arrival number, position.
type Candidate = Reverse<(u32, u64, [u32; 3])>;

fn candidate(key: f32, seq: u64, p: Vec3) -> Candidate {
    Reverse((key.to_bits(), seq, p.to_array().map(f32::to_bits)))
}

impl KarstSpec {
    /// The carving spheres of the network (their centres via [`KarstSpec::network`]).
    pub fn generate(&self, ground: &Ground) -> Result<Vec<NodeSpec>, LandformError> {
        Ok(self
            .network(ground)?
            .into_iter()
            .map(|(p, e)| carving_sphere(p, self.radius.0, e))
            .collect())
    }

    /// The seeds: hand-given sinks, then the terrain's, each just below the surface.
    pub fn seeds(&self, ground: &Ground) -> Vec<Vec3> {
        let mut seeds: Vec<Vec3> = self
            .sinks
            .iter()
            .map(|s| s.0.extend(ground.height(s.0)))
            .collect();
        if let Some(depth) = self.auto_sinks {
            seeds.extend(
                sinks(&ground.top, depth.0)
                    .into_iter()
                    .map(|k| ground.sample_point(k)),
            );
        }
        seeds
            .into_iter()
            .filter(|p| p.z.is_finite())
            .map(|p| p - Vec3::Z * (0.5 * self.radius.0))
            .collect()
    }

    /// The carved points, in the order they were carved, with their erosion effect.
    pub fn network(&self, ground: &Ground) -> Result<Vec<(Vec3, f32)>, LandformError> {
        if self.directions == 0 {
            return Err(LandformError::Invalid(
                "karst `directions` must be at least 1".into(),
            ));
        }
        let rho0 = self.threshold.0;
        let eps = self.epsilon.0;
        let step = self.spacing.0;
        let mut rng = Rng::new(ground.seed);
        let mut poisson = Poisson::new(0.95 * step);
        let mut queue = BinaryHeap::new();
        let mut seq = 0u64;
        let inside = |p: Vec3| {
            let r = &ground.region;
            p.cmpge(r.min).all() && p.cmple(r.max).all()
        };
        // Queues `p` if its rock is soft and its Poisson sphere free (hard candidates
        // take no room: a softer one may come close later).
        let mut push = |queue: &mut BinaryHeap<Candidate>, rng: &mut Rng, p: Vec3| {
            let rho = (ground.resistance)(p);
            if rho >= rho0 || !poisson.take(p) {
                return;
            }
            let key = (rho + eps * rng.unit()).max(0.0);
            queue.push(candidate(key, seq, p));
            seq += 1;
        };
        for s in self.seeds(ground) {
            if inside(s) {
                push(&mut queue, &mut rng, s);
            }
        }
        let mut carved = Vec::new();
        while let Some(Reverse((_, _, bits))) = queue.pop() {
            if carved.len() >= self.max_spheres as usize {
                break;
            }
            let p = Vec3::from_array(bits.map(f32::from_bits));
            let rho = (ground.resistance)(p);
            carved.push((p, effect(rho, 1.0, self.beta.0)));
            for _ in 0..self.directions {
                let q = p + rng.lower_hemisphere() * step;
                if inside(q) && ground.solid(q) {
                    push(&mut queue, &mut rng, q);
                }
            }
        }
        Ok(carved)
    }
}

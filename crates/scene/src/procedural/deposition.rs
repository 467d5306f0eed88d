//! Particle deposition (the survey of basic terrain generation, "Particle Deposition"):
//! particles dropped around a vent roll to a lower neighbour while there is one, for a
//! bounded number of moves, and settle there; the vent moves between series, building
//! volcanic ranges. Sequential, drawing from one seeded generator in a fixed order.

use serde::{Deserialize, Serialize};

use super::unit_hash;

fn default_series() -> u32 {
    5
}

fn default_particles() -> u32 {
    20_000
}

fn default_radius() -> u32 {
    8
}

/// `(series: 5, particles: 20000, radius: 8)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DepositionSpec {
    /// Vents, one after another (default 5).
    #[serde(default = "default_series")]
    pub series: u32,
    /// Particles per vent (default 20,000).
    #[serde(default = "default_particles")]
    pub particles: u32,
    /// Particles land within this many cells of the vent (default 8).
    #[serde(default = "default_radius")]
    pub radius: u32,
}

/// Most particles in all: `series × particles` is capped here.
pub const MAX_PARTICLES: u64 = 100_000_000;

/// Moves a particle may make before it settles.
const MAX_MOVES: u32 = 64;

/// The samples of an `nx × ny` grid: particle counts (each particle one unit high).
pub fn generate(s: &DepositionSpec, nx: usize, ny: usize, seed: u32) -> Vec<f32> {
    let mut z = vec![0.0f32; nx * ny];
    let mut draw = 0u32;
    let mut next = || {
        draw = draw.wrapping_add(1);
        unit_hash(seed, draw, draw >> 16)
    };
    let mut dropped = 0u64;
    for _ in 0..s.series {
        let (vx, vy) = (next() * nx as f32, next() * ny as f32);
        for _ in 0..s.particles {
            if dropped >= MAX_PARTICLES {
                return z;
            }
            dropped += 1;
            let r = s.radius as f32;
            let i = (vx + (2.0 * next() - 1.0) * r).clamp(0.0, (nx - 1) as f32) as usize;
            let j = (vy + (2.0 * next() - 1.0) * r).clamp(0.0, (ny - 1) as f32) as usize;
            let mut k = i + nx * j;
            for _ in 0..MAX_MOVES {
                let (ci, cj) = (k % nx, k / nx);
                let mut lowest = k;
                for (di, dj) in crate::analysis::flow::NEIGHBOURS {
                    let (a, b) = (ci as isize + di, cj as isize + dj);
                    if a < 0 || b < 0 || a as usize >= nx || b as usize >= ny {
                        continue;
                    }
                    let n = a as usize + nx * b as usize;
                    if z[n] < z[lowest] {
                        lowest = n;
                    }
                }
                if lowest == k {
                    break;
                }
                k = lowest;
            }
            z[k] += 1.0;
        }
    }
    z
}

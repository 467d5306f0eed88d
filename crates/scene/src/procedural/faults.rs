//! Fault lines (the survey of basic terrain generation, "Fault Line Algorithm"): each
//! fault is the line through two random points of the grid; samples on one side rise and
//! those on the other sink, by an offset that shrinks from one fault to the next. The
//! step is softened over `width` metres with a cosine ("Variations to the Fault Line
//! Algorithm"), which also stands in for the low-pass filter the survey recommends.

use glam::Vec2;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::unit_hash;
use crate::value::NonNegative;

fn default_faults() -> u32 {
    200
}

/// `(count: 200, width: 50)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaultSpec {
    /// Number of faults (default 200, at most 100,000).
    #[serde(default = "default_faults")]
    pub count: u32,
    /// Width of the cosine step across a fault, metres (0: a sharp step).
    #[serde(default)]
    pub width: NonNegative,
}

/// Most faults a spec may ask for.
pub const MAX_FAULTS: u32 = 100_000;

/// The samples of an `nx × ny` grid of `cell`-metre cells: the sum of every fault's
/// signed offset (1 for the first fault, falling linearly towards 0 for the last).
pub fn generate(s: &FaultSpec, nx: usize, ny: usize, cell: f32, seed: u32) -> Vec<f32> {
    let count = s.count;
    // Faults in grid units: a point and a unit normal, with their offsets.
    let faults: Vec<(Vec2, Vec2, f32)> = (0..count)
        .map(|f| {
            let p = |a: u32| {
                Vec2::new(
                    unit_hash(seed, f, 4 * a) * (nx - 1) as f32,
                    unit_hash(seed, f, 4 * a + 1) * (ny - 1) as f32,
                )
            };
            let (a, b) = (p(0), p(1));
            let d = (b - a).try_normalize().unwrap_or(Vec2::X);
            let offset = 1.0 - f as f32 / count.max(1) as f32;
            (a, d.perp(), offset)
        })
        .collect();
    let width = s.width.get() / cell;
    let mut z = vec![0.0f32; nx * ny];
    z.par_chunks_mut(nx).enumerate().for_each(|(j, row)| {
        for (i, v) in row.iter_mut().enumerate() {
            let q = Vec2::new(i as f32, j as f32);
            *v = faults
                .iter()
                .map(|&(a, n, off)| off * step((q - a).dot(n), width))
                .sum();
        }
    });
    z
}

/// `±1` on either side of a fault, a cosine ramp within `width / 2` of it.
fn step(d: f32, width: f32) -> f32 {
    if d.abs() * 2.0 >= width {
        d.signum()
    } else {
        (d / width * std::f32::consts::PI).sin()
    }
}

//! Diamond–square midpoint displacement: on a `(2^k + 1)²` grid, each square's centre
//! (the diamond step) and then each diamond's centre (the square step) takes the mean of
//! its corners plus a random offset whose range shrinks by `2^{−H}` per level (Fournier,
//! Fussell and Carpenter 1982, §3 on stochastic subdivision; the diamond–square order of
//! Miller 1986). The grid asked for is the south-west corner of the smallest such grid.

use serde::{Deserialize, Serialize};

use super::unit_hash;
use crate::dem::DemError;
use crate::value::Unit;

fn default_roughness() -> Unit {
    Unit(0.8)
}

/// `(roughness: 0.8)`: the Hurst exponent `H` in `[0, 1]` (1 smooth, 0 rough).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiamondSquareSpec {
    /// `H`: offsets shrink by `2^{−H}` per level.
    #[serde(default = "default_roughness")]
    pub roughness: Unit,
}

/// The samples of an `nx × ny` grid. Each sample's offset hashes the seed with its
/// position, so the result does not depend on evaluation order.
pub fn generate(
    s: &DiamondSquareSpec,
    nx: usize,
    ny: usize,
    seed: u32,
    budget: u64,
) -> Result<Vec<f32>, DemError> {
    let side = nx.max(ny).saturating_sub(1).next_power_of_two() + 1;
    crate::io::check_budget(
        format!("generate.size: diamond-square on a {side}×{side} grid"),
        (side as u64).pow(2) * 4,
        budget,
    )?;
    let rnd = |i: usize, j: usize| 2.0 * unit_hash(seed, i as u32, j as u32) - 1.0;
    let mut z = vec![0.0f32; side * side];
    let at = |i: usize, j: usize| i + side * j;
    for (i, j) in [(0, 0), (side - 1, 0), (0, side - 1), (side - 1, side - 1)] {
        z[at(i, j)] = rnd(i, j);
    }
    let decay = 2f32.powf(-s.roughness.get());
    let mut range = decay;
    let mut step = side - 1;
    while step > 1 {
        let half = step / 2;
        // Diamond step: centres of squares.
        for j in (half..side).step_by(step) {
            for i in (half..side).step_by(step) {
                let mean = (z[at(i - half, j - half)]
                    + z[at(i + half, j - half)]
                    + z[at(i - half, j + half)]
                    + z[at(i + half, j + half)])
                    / 4.0;
                z[at(i, j)] = mean + range * rnd(i, j);
            }
        }
        // Square step: centres of diamonds (edges of the squares), 3 neighbours on the rim.
        for j in (0..side).step_by(half) {
            let first = if (j / half).is_multiple_of(2) {
                half
            } else {
                0
            };
            for i in (first..side).step_by(step) {
                let (mut sum, mut count) = (0.0f32, 0.0f32);
                if i >= half {
                    sum += z[at(i - half, j)];
                    count += 1.0;
                }
                if i + half < side {
                    sum += z[at(i + half, j)];
                    count += 1.0;
                }
                if j >= half {
                    sum += z[at(i, j - half)];
                    count += 1.0;
                }
                if j + half < side {
                    sum += z[at(i, j + half)];
                    count += 1.0;
                }
                z[at(i, j)] = sum / count + range * rnd(i, j);
            }
        }
        range *= decay;
        step = half;
    }
    Ok((0..nx * ny).map(|k| z[at(k % nx, k / nx)]).collect())
}

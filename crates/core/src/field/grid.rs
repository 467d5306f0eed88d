//! Batch evaluation of a field on a regular grid, in parallel over z-slabs of bricks.

use glam::Vec3;
use rayon::prelude::*;

use super::block::BRICK;
use super::contract::Field;

/// A regular grid of sample points: `origin + (i, j, k)·step`, `dims = [nx, ny, nz]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    /// Position of sample (0, 0, 0).
    pub origin: Vec3,
    /// Spacing along each axis.
    pub step: Vec3,
    /// Number of samples along each axis.
    pub dims: [usize; 3],
}

impl Grid {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.dims.iter().product()
    }

    /// True when the grid has no sample.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bytes needed for its values as f32 (saturating: a grid too large to count is
    /// too large for any budget).
    pub fn bytes(&self) -> u64 {
        self.dims
            .iter()
            .fold(4u64, |b, &d| b.saturating_mul(d as u64))
    }

    /// Position of sample `(i, j, k)`.
    pub fn point(&self, i: usize, j: usize, k: usize) -> Vec3 {
        self.origin + Vec3::new(i as f32, j as f32, k as f32) * self.step
    }
}

/// Number of z-slabs [`eval_grid`] reports progress for.
pub fn slab_count(grid: &Grid) -> u64 {
    grid.dims[2].div_ceil(BRICK) as u64
}

/// Values of `field` on `grid` (x fastest, then y, then z), pruned per brick through
/// [`Field::eval_block`], in parallel. The result does not depend on the thread count.
/// `progress` advances once per slab of [`BRICK`] layers ([`slab_count`] in all).
pub fn eval_grid(
    field: &dyn Field,
    grid: &Grid,
    progress: Option<&indicatif::ProgressBar>,
) -> Vec<f32> {
    let [nx, ny, nz] = grid.dims;
    let mut out = vec![0.0f32; grid.len()];
    let slab = nx * ny * BRICK;
    if slab == 0 {
        return out;
    }
    out.par_chunks_mut(slab).enumerate().for_each(|(s, chunk)| {
        let k0 = s * BRICK;
        let dims = [nx, ny, (nz - k0).min(BRICK)];
        field.eval_block(grid.point(0, 0, k0), grid.step, dims, chunk);
        if let Some(p) = progress {
            p.inc(1);
        }
    });
    out
}

/// The same values by one [`Field::value`] per point, with no pruning: the baseline.
pub fn eval_grid_naive(field: &dyn Field, grid: &Grid) -> Vec<f32> {
    let [nx, ny, _] = grid.dims;
    let mut out = vec![0.0f32; grid.len()];
    out.par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(k, layer)| {
            for j in 0..ny {
                for i in 0..nx {
                    layer[i + nx * j] = field.value(grid.point(i, j, k));
                }
            }
        });
    out
}

//! The [`Heightfield`]: a regular grid of f32 elevations in a local metric frame.

use glam::{Vec2, Vec4};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::DemError;
use super::interp::{BICUBIC_OVERSHOOT, BICUBIC_SLOPE, cr_weights, cr_weights_d};
use crate::field::Rect;

/// How elevations between samples are interpolated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Interpolation {
    /// Bilinear in each cell: C⁰, never overshoots the samples.
    #[default]
    Bilinear,
    /// Catmull-Rom bicubic (samples clamped at the grid border): C¹, may overshoot slightly.
    Bicubic,
}

/// A grid of elevations: sample `(i, j)` (i east, j north) sits at
/// `origin + (i·dx, j·dy)` and holds `z[i + nx·j]` metres, NaN for nodata.
///
/// The surface `h(x, y)` is defined on the *valid cells*: cells whose interpolation stencil
/// (the 4 corners for bilinear, the 4×4 samples around them for bicubic) has no nodata.
/// Elsewhere [`Heightfield::sample`] returns NaN.
#[derive(Clone, Debug, PartialEq)]
pub struct Heightfield {
    nx: usize,
    ny: usize,
    origin: Vec2,
    cell: Vec2,
    z: Vec<f32>,
}

/// The rows of a bicubic stencil weighed by `w` across them: `Σ_b w[b]·rows[b]`.
#[inline]
fn weigh(rows: &[Vec4; 4], w: [f32; 4]) -> Vec4 {
    rows[0] * w[0] + rows[1] * w[1] + rows[2] * w[2] + rows[3] * w[3]
}

impl Heightfield {
    /// A grid of `nx × ny` samples (row `j = 0` is the southern one).
    ///
    /// Fails when sizes disagree, the grid is smaller than 2×2, the cell size is not
    /// positive, or a sample is infinite (use NaN for nodata).
    pub fn new(
        nx: usize,
        ny: usize,
        origin: Vec2,
        cell: Vec2,
        z: Vec<f32>,
    ) -> Result<Heightfield, DemError> {
        let invalid = |what: String| Err(DemError::Invalid { what });
        if nx < 2 || ny < 2 {
            return invalid(format!(
                "a heightfield needs at least 2×2 samples, got {nx}×{ny}"
            ));
        }
        if nx.checked_mul(ny) != Some(z.len()) {
            return invalid(format!("{nx}×{ny} samples expected, got {}", z.len()));
        }
        if !(cell.x > 0.0 && cell.y > 0.0 && cell.is_finite()) {
            return invalid(format!("cell size must be finite and > 0, got {cell}"));
        }
        if !origin.is_finite() {
            return invalid(format!("origin must be finite, got {origin}"));
        }
        if let Some(k) = z.iter().position(|v| v.is_infinite()) {
            return invalid(format!("sample ({}, {}) is infinite", k % nx, k / nx));
        }
        Ok(Heightfield {
            nx,
            ny,
            origin,
            cell,
            z,
        })
    }

    /// Samples along x.
    pub fn nx(&self) -> usize {
        self.nx
    }

    /// Samples along y.
    pub fn ny(&self) -> usize {
        self.ny
    }

    /// Position of sample `(0, 0)`.
    pub fn origin(&self) -> Vec2 {
        self.origin
    }

    /// Cell size `(dx, dy)` in metres.
    pub fn cell(&self) -> Vec2 {
        self.cell
    }

    /// All samples, row-major from the south (`z[i + nx·j]`).
    pub fn samples(&self) -> &[f32] {
        &self.z
    }

    /// Sample `(i, j)` (NaN = nodata).
    #[inline]
    pub fn at(&self, i: usize, j: usize) -> f32 {
        self.z[i + self.nx * j]
    }

    /// The same grid moved so that sample `(0, 0)` sits at `origin`.
    pub fn with_origin(mut self, origin: Vec2) -> Heightfield {
        self.origin = origin;
        self
    }

    /// The rectangle spanned by the samples.
    pub fn extent(&self) -> Rect {
        let size = Vec2::new((self.nx - 1) as f32, (self.ny - 1) as f32) * self.cell;
        Rect::new(self.origin, self.origin + size)
    }

    /// Number of nodata samples.
    pub fn nodata_count(&self) -> usize {
        self.z.iter().filter(|v| v.is_nan()).count()
    }

    /// `(min, max)` of the valid samples, `None` when every sample is nodata.
    pub fn z_range(&self) -> Option<(f32, f32)> {
        let (lo, hi) = self
            .z
            .iter()
            .filter(|v| !v.is_nan())
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        (lo <= hi).then_some((lo, hi))
    }

    /// Number of cells along x and y: `(nx − 1, ny − 1)`.
    pub fn cells(&self) -> (usize, usize) {
        (self.nx - 1, self.ny - 1)
    }

    /// The cell holding `xy` and the position inside it, `None` outside the extent.
    #[inline]
    fn locate(&self, xy: Vec2) -> Option<(usize, usize, f32, f32)> {
        let u = (xy - self.origin) / self.cell;
        let (cx, cy) = ((self.nx - 1) as f32, (self.ny - 1) as f32);
        if !(u.x >= 0.0 && u.y >= 0.0 && u.x <= cx && u.y <= cy) {
            return None;
        }
        let i = (u.x as usize).min(self.nx - 2);
        let j = (u.y as usize).min(self.ny - 2);
        Some((i, j, u.x - i as f32, u.y - j as f32))
    }

    /// The cell range `(i0, i1, j0, j1)` (inclusive) of cells touching `r`, `None` when `r`
    /// misses the grid.
    pub fn cells_overlapping(&self, r: &Rect) -> Option<(usize, usize, usize, usize)> {
        let a = (r.min - self.origin) / self.cell;
        let b = (r.max - self.origin) / self.cell;
        let (cx, cy) = ((self.nx - 1) as f32, (self.ny - 1) as f32);
        if !(b.x >= 0.0 && b.y >= 0.0 && a.x <= cx && a.y <= cy) {
            return None;
        }
        // Truncation is the floor here: negative values clamp to 0 either way.
        let clampi = |v: f32, n: usize| (v.max(0.0) as usize).min(n - 2);
        Some((
            clampi(a.x, self.nx),
            clampi(b.x, self.nx),
            clampi(a.y, self.ny),
            clampi(b.y, self.ny),
        ))
    }

    /// The bicubic stencil of cell `(i, j)`: its 4 × 4 samples around the cell as rows of
    /// increasing `y`, indices clamped to the grid.
    #[inline]
    fn stencil_rows(&self, i: usize, j: usize) -> [Vec4; 4] {
        if i >= 1 && j >= 1 && i + 2 < self.nx && j + 2 < self.ny {
            std::array::from_fn(|b| {
                let at = i - 1 + self.nx * (j - 1 + b);
                Vec4::from_slice(&self.z[at..at + 4])
            })
        } else {
            let clamp = |v: isize, n: usize| v.clamp(0, n as isize - 1) as usize;
            std::array::from_fn(|b| {
                let jj = clamp(j as isize + b as isize - 1, self.ny);
                Vec4::from_array(std::array::from_fn(|a| {
                    self.at(clamp(i as isize + a as isize - 1, self.nx), jj)
                }))
            })
        }
    }

    /// `h(xy)`; NaN outside the valid cells.
    #[inline]
    pub fn sample(&self, xy: Vec2, interp: Interpolation) -> f32 {
        let Some((i, j, t, s)) = self.locate(xy) else {
            return f32::NAN;
        };
        match interp {
            Interpolation::Bilinear => {
                let k = i + self.nx * j;
                let (a, b) = (self.z[k], self.z[k + 1]);
                let (c, d) = (self.z[k + self.nx], self.z[k + self.nx + 1]);
                let lo = a + (b - a) * t;
                let hi = c + (d - c) * t;
                lo + (hi - lo) * s
            }
            // The rows weighed along `y` first, four lanes at a time, then along `x`.
            Interpolation::Bicubic => {
                weigh(&self.stencil_rows(i, j), cr_weights(s)).dot(Vec4::from(cr_weights(t)))
            }
        }
    }

    /// `(h(xy), ∇h(xy))`; NaN outside the valid cells. Inside a cell the gradient is exact;
    /// on cell edges it is the one of the cell [`Heightfield::sample`] uses.
    #[inline]
    pub fn sample_grad(&self, xy: Vec2, interp: Interpolation) -> (f32, Vec2) {
        let Some((i, j, t, s)) = self.locate(xy) else {
            return (f32::NAN, Vec2::NAN);
        };
        let (v, dt, ds) = match interp {
            Interpolation::Bilinear => {
                let k = i + self.nx * j;
                let (a, b) = (self.z[k], self.z[k + 1]);
                let (c, d) = (self.z[k + self.nx], self.z[k + self.nx + 1]);
                let lo = a + (b - a) * t;
                let hi = c + (d - c) * t;
                let dt = (b - a) + ((d - c) - (b - a)) * s;
                (lo + (hi - lo) * s, dt, hi - lo)
            }
            Interpolation::Bicubic => {
                let rows = self.stencil_rows(i, j);
                let (wx, dwx) = (Vec4::from(cr_weights(t)), Vec4::from(cr_weights_d(t)));
                let across = weigh(&rows, cr_weights(s));
                let d_across = weigh(&rows, cr_weights_d(s));
                (across.dot(wx), across.dot(dwx), d_across.dot(wx))
            }
        };
        (v, Vec2::new(dt, ds) / self.cell)
    }

    /// The samples a cell's interpolation reads: its corners (bilinear) or its clamped 4×4
    /// stencil (bicubic), as an index window `(i0, i1, j0, j1)` inclusive.
    #[inline]
    fn stencil(&self, i: usize, j: usize, interp: Interpolation) -> (usize, usize, usize, usize) {
        match interp {
            Interpolation::Bilinear => (i, i + 1, j, j + 1),
            Interpolation::Bicubic => (
                i.saturating_sub(1),
                (i + 2).min(self.nx - 1),
                j.saturating_sub(1),
                (j + 2).min(self.ny - 1),
            ),
        }
    }

    /// Per cell (row-major, `(nx − 1)·(ny − 1)`): a sound range `[lo, hi]` of `h` over the
    /// cell, `[+∞, −∞]` for invalid cells.
    pub fn cell_ranges(&self, interp: Interpolation) -> Vec<[f32; 2]> {
        self.per_cell(|i, j| {
            let (i0, i1, j0, j1) = self.stencil(i, j, interp);
            let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
            for jj in j0..=j1 {
                for &v in &self.z[i0 + self.nx * jj..=i1 + self.nx * jj] {
                    if v.is_nan() {
                        return [f32::INFINITY, f32::NEG_INFINITY];
                    }
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
            match interp {
                Interpolation::Bilinear => [lo, hi],
                Interpolation::Bicubic => {
                    let o = BICUBIC_OVERSHOOT * (hi - lo);
                    [lo - o, hi + o]
                }
            }
        })
    }

    /// Per cell: a bound on `|∇h|` over the cell (`[s, s]`; `[+∞, −∞]` for invalid cells).
    ///
    /// Génevaux et al. 2015 §7.3.1, sharpened per axis: inside a bilinear cell `∂h/∂x` is a convex
    /// combination of the two x-edge differences over `dx` (likewise y), so
    /// `|∇h| ≤ √(Lx² + Ly²)`. Bicubic cells use the Catmull-Rom bound over their stencil.
    pub fn cell_slopes(&self, interp: Interpolation) -> Vec<[f32; 2]> {
        self.per_cell(|i, j| {
            let (i0, i1, j0, j1) = self.stencil(i, j, interp);
            let (mut gx, mut gy) = (0.0f32, 0.0f32);
            for jj in j0..=j1 {
                for ii in i0..=i1 {
                    let v = self.at(ii, jj);
                    if v.is_nan() {
                        return [f32::INFINITY, f32::NEG_INFINITY];
                    }
                    if ii < i1 {
                        gx = gx.max((self.at(ii + 1, jj) - v).abs());
                    }
                    if jj < j1 {
                        gy = gy.max((self.at(ii, jj + 1) - v).abs());
                    }
                }
            }
            let k = match interp {
                Interpolation::Bilinear => 1.0,
                Interpolation::Bicubic => BICUBIC_SLOPE,
            };
            let s = k * Vec2::new(gx / self.cell.x, gy / self.cell.y).length() * (1.0 + 1e-6);
            [s, s]
        })
    }

    /// A global Lipschitz bound of `h` over its valid cells (0 when there is none).
    pub fn lipschitz(&self, interp: Interpolation) -> f32 {
        self.cell_slopes(interp)
            .iter()
            .map(|c| c[1])
            .fold(0.0, f32::max)
    }

    fn per_cell(&self, f: impl Fn(usize, usize) -> [f32; 2] + Sync) -> Vec<[f32; 2]> {
        let (cx, cy) = self.cells();
        let mut out = vec![[0.0; 2]; cx * cy];
        out.par_chunks_mut(cx).enumerate().for_each(|(j, row)| {
            for (i, o) in row.iter_mut().enumerate() {
                *o = f(i, j);
            }
        });
        out
    }

    /// True when the cell `(i, j)` has a defined surface.
    pub fn cell_valid(&self, i: usize, j: usize, interp: Interpolation) -> bool {
        let (i0, i1, j0, j1) = self.stencil(i, j, interp);
        (j0..=j1).all(|jj| {
            self.z[i0 + self.nx * jj..=i1 + self.nx * jj]
                .iter()
                .all(|v| !v.is_nan())
        })
    }

    /// The grid resampled to cells of `dx × dy` metres over the same extent (the last
    /// row/column is dropped where the extent is not a whole number of new cells).
    /// Samples falling outside the valid cells become nodata.
    pub fn resample(
        &self,
        dx: f32,
        dy: f32,
        interp: Interpolation,
        budget: u64,
    ) -> Result<Heightfield, DemError> {
        if !(dx > 0.0 && dy > 0.0 && dx.is_finite() && dy.is_finite()) {
            return Err(DemError::Invalid {
                what: format!("resampling needs a cell size > 0, got {dx} × {dy}"),
            });
        }
        let size = self.extent();
        let w = (size.max - size.min) / Vec2::new(dx, dy);
        // tolerate rounding: 1000 m / 10 m must give 101 samples, not 100
        let n = |v: f32| (v * (1.0 + 1e-6) + 1e-4).floor() as u64 + 1;
        let (nx, ny) = (n(w.x), n(w.y));
        let need = nx.saturating_mul(ny).saturating_mul(4 + 8);
        crate::io::check_budget(format!("a resampled {nx}×{ny} grid"), need, budget).map_err(
            |e| DemError::Invalid {
                what: e.to_string(),
            },
        )?;
        let (nx, ny) = (nx as usize, ny as usize);
        let mut z = vec![0.0f32; nx * ny];
        z.par_chunks_mut(nx).enumerate().for_each(|(j, row)| {
            for (i, v) in row.iter_mut().enumerate() {
                let mut p = self.origin + Vec2::new(i as f32 * dx, j as f32 * dy);
                p = p.min(size.max);
                *v = self.sample(p, interp);
            }
        });
        Heightfield::new(nx, ny, self.origin, Vec2::new(dx, dy), z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wavy(nx: usize, ny: usize) -> Heightfield {
        let z = (0..nx * ny)
            .map(|k| {
                let (i, j) = ((k % nx) as f32, (k / nx) as f32);
                10.0 * (0.7 * i).sin() + 5.0 * (0.4 * j).cos() + 0.3 * i * j
            })
            .collect();
        Heightfield::new(nx, ny, Vec2::new(-3.0, 2.0), Vec2::new(2.0, 3.0), z).unwrap()
    }

    fn rng(seed: &mut u64) -> f32 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*seed >> 40) as f32 / (1u64 << 24) as f32
    }

    #[test]
    fn interpolation_hits_samples_and_gradients_match_fd() {
        let h = wavy(12, 9);
        for interp in [Interpolation::Bilinear, Interpolation::Bicubic] {
            for (i, j) in [(0, 0), (3, 4), (11, 8), (5, 8)] {
                let p = h.origin() + Vec2::new(i as f32, j as f32) * h.cell();
                assert!(
                    (h.sample(p, interp) - h.at(i, j)).abs() < 1e-4,
                    "{interp:?} {i} {j}"
                );
            }
            let mut seed = 7;
            for _ in 0..500 {
                let p = h.origin()
                    + Vec2::new(0.05 + rng(&mut seed) * 21.8, 0.05 + rng(&mut seed) * 23.8);
                let (v, g) = h.sample_grad(p, interp);
                assert!((v - h.sample(p, interp)).abs() < 1e-5);
                let e = 1e-2;
                let fx = (h.sample(p + Vec2::X * e, interp) - h.sample(p - Vec2::X * e, interp))
                    / (2.0 * e);
                let fy = (h.sample(p + Vec2::Y * e, interp) - h.sample(p - Vec2::Y * e, interp))
                    / (2.0 * e);
                // FD straddling a bilinear cell edge differs; skip those
                let u = (p - h.origin()) / h.cell();
                let near_edge =
                    (u.x - u.x.round()).abs() < 0.01 || (u.y - u.y.round()).abs() < 0.01;
                if interp == Interpolation::Bicubic || !near_edge {
                    assert!(
                        (fx - g.x).abs() < 2e-2 && (fy - g.y).abs() < 2e-2,
                        "{interp:?} {p}: {g} vs {fx},{fy}"
                    );
                }
            }
        }
        assert!(
            h.sample(Vec2::new(-3.1, 2.0), Interpolation::Bilinear)
                .is_nan()
        );
    }

    #[test]
    fn lipschitz_and_cell_ranges_are_sound() {
        let h = wavy(15, 11);
        for interp in [Interpolation::Bilinear, Interpolation::Bicubic] {
            let l = h.lipschitz(interp);
            let ranges = h.cell_ranges(interp);
            let slopes = h.cell_slopes(interp);
            let mut seed = 3;
            let ext = h.extent();
            let mut worst = 0.0f32;
            for _ in 0..4000 {
                let a = ext.min + (ext.max - ext.min) * Vec2::new(rng(&mut seed), rng(&mut seed));
                let b = a + Vec2::new(rng(&mut seed) - 0.5, rng(&mut seed) - 0.5) * 4.0;
                let b = b.clamp(ext.min, ext.max);
                let (ha, hb) = (h.sample(a, interp), h.sample(b, interp));
                if a.distance(b) > 1e-3 {
                    worst = worst.max((ha - hb).abs() / a.distance(b));
                }
                let (i, j, _, _) = h.locate(a).unwrap();
                let [lo, hi] = ranges[i + (h.nx() - 1) * j];
                assert!(
                    lo - 1e-4 <= ha && ha <= hi + 1e-4,
                    "{interp:?} {ha} not in [{lo}, {hi}]"
                );
                let (_, g) = h.sample_grad(a, interp);
                assert!(g.length() <= slopes[i + (h.nx() - 1) * j][1] * 1.0001 + 1e-4);
            }
            assert!(worst <= l * 1.0001, "{interp:?}: {worst} > {l}");
            assert!(
                worst > 0.3 * l,
                "{interp:?}: bound {l} is too loose ({worst})"
            );
        }
    }

    #[test]
    fn nodata_masks_cells() {
        let mut h = wavy(6, 5);
        h.z[2 + 6 * 2] = f32::NAN;
        assert!(!h.cell_valid(1, 1, Interpolation::Bilinear));
        assert!(!h.cell_valid(2, 2, Interpolation::Bilinear));
        assert!(h.cell_valid(3, 3, Interpolation::Bilinear));
        assert!(!h.cell_valid(3, 3, Interpolation::Bicubic));
        assert!(h.cell_valid(0, 0, Interpolation::Bilinear));
        let p = h.origin() + Vec2::new(1.5, 1.5) * h.cell();
        assert!(h.sample(p, Interpolation::Bilinear).is_nan());
        assert_eq!(h.nodata_count(), 1);
        assert_eq!(
            h.cell_ranges(Interpolation::Bilinear)[1 + 5],
            [f32::INFINITY, f32::NEG_INFINITY]
        );
    }

    #[test]
    fn resampling_keeps_the_extent_and_values() {
        let h = wavy(21, 16);
        let r = h
            .resample(1.0, 1.0, Interpolation::Bilinear, 1 << 30)
            .unwrap();
        assert_eq!((r.nx(), r.ny()), (41, 46));
        assert_eq!(r.extent(), h.extent());
        for (i, j) in [(0, 0), (20, 15), (7, 3)] {
            assert!((r.at(2 * i, 3 * j) - h.at(i, j)).abs() < 1e-4);
        }
        assert!(
            h.resample(0.0, 1.0, Interpolation::Bilinear, 1 << 30)
                .is_err()
        );
        assert!(
            h.resample(1e-4, 1e-4, Interpolation::Bilinear, 1 << 30)
                .is_err()
        );
    }
}

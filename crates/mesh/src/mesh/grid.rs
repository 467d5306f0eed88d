//! The virtual sampling grid of an extraction: a box cut into cells.

use glam::Vec3;

use super::MeshError;
use crate::field::Aabb;

/// A regular grid of `cells[0] × cells[1] × cells[2]` cells, with samples at
/// `origin + (offset[0] + i, offset[1] + j, k)·spacing` for `i ≤ cells[0]`, etc.
///
/// A grid with a non-zero `offset` is a window of a larger grid (see [`GridSpec::window`]):
/// its samples are computed from the larger grid's integer indices, so two windows place a
/// sample they share at bit-identical positions (the tiles of `karstic tile`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridSpec {
    /// Position of the sample with global indices `(0, 0, 0)` (sample `(0, 0, 0)` of the
    /// grid when `offset` is zero).
    pub origin: Vec3,
    /// Cell size along each axis.
    pub spacing: Vec3,
    /// Number of cells along each axis.
    pub cells: [usize; 3],
    /// Global x and y indices of the grid's sample `(0, 0, ·)`.
    pub offset: [usize; 2],
}

/// Errors unless `b` is a finite box with positive size on every axis; an empty box (the
/// support of a field that is zero everywhere) is told as such.
pub(crate) fn check_box(b: &Aabb) -> Result<(), MeshError> {
    if b.is_empty() {
        return Err(MeshError::GridShape(
            "the box is empty: the field is zero everywhere (its support box is empty), \
             or the box's minimum exceeds its maximum"
                .into(),
        ));
    }
    let size = b.size();
    if !size.is_finite() || size.min_element() <= 0.0 {
        return Err(MeshError::GridShape(format!(
            "box {} .. {}: expected a finite box with positive size on every axis",
            b.min, b.max
        )));
    }
    Ok(())
}

/// Largest sample count along one axis (indices are stored as `u32`).
const MAX_AXIS: usize = 1 << 24;

impl GridSpec {
    /// A grid with the given origin, spacing and cell counts; errors on a non-positive or
    /// non-finite spacing or an axis with no cell.
    pub fn new(origin: Vec3, spacing: Vec3, cells: [usize; 3]) -> Result<Self, MeshError> {
        if !(origin.is_finite() && spacing.is_finite() && spacing.cmpgt(Vec3::ZERO).all()) {
            return Err(MeshError::GridShape(format!(
                "origin {origin}, spacing {spacing}: the spacing must be positive and finite"
            )));
        }
        if cells.iter().any(|&c| c == 0 || c >= MAX_AXIS) {
            return Err(MeshError::GridShape(format!(
                "{}×{}×{} cells: each axis needs between 1 and {} cells",
                cells[0],
                cells[1],
                cells[2],
                MAX_AXIS - 1
            )));
        }
        Ok(GridSpec {
            origin,
            spacing,
            cells,
            offset: [0, 0],
        })
    }

    /// The window of this grid whose x and y cells are `lo[a] .. lo[a] + cells[a]` (all its
    /// z cells): same origin and spacing, samples at the same positions. Errors when the
    /// window has no cell or leaves the grid.
    pub fn window(&self, lo: [usize; 2], cells: [usize; 2]) -> Result<Self, MeshError> {
        for a in 0..2 {
            if cells[a] == 0 || lo[a] + cells[a] > self.cells[a] {
                return Err(MeshError::GridShape(format!(
                    "window of cells {}..{} along axis {a}: the grid has {} cells",
                    lo[a],
                    lo[a] + cells[a],
                    self.cells[a]
                )));
            }
        }
        Ok(GridSpec {
            cells: [cells[0], cells[1], self.cells[2]],
            offset: [self.offset[0] + lo[0], self.offset[1] + lo[1]],
            ..*self
        })
    }

    /// Covers `b` with cells of about `cell` metres: `ceil(size / cell)` cells per axis,
    /// shrunk to fit the box exactly.
    pub fn with_cell(b: &Aabb, cell: f32) -> Result<Self, MeshError> {
        if !(cell > 0.0 && cell.is_finite()) {
            return Err(MeshError::GridShape(format!(
                "cell size {cell}: expected a positive number"
            )));
        }
        Self::fit(b, |size| (size / cell).ceil())
    }

    /// Covers `b` with `n` cells along its longest axis and cubic cells elsewhere (rounded
    /// up, then shrunk to fit the box exactly).
    pub fn with_resolution(b: &Aabb, n: usize) -> Result<Self, MeshError> {
        if n == 0 {
            return Err(MeshError::GridShape(
                "resolution 0: expected at least 1 cell".into(),
            ));
        }
        let longest = b.size().max_element();
        Self::fit(b, |size| (size / longest * n as f32).ceil())
    }

    fn fit(b: &Aabb, cells_for: impl Fn(f32) -> f32) -> Result<Self, MeshError> {
        check_box(b)?;
        let size = b.size();
        let mut cells = [0usize; 3];
        for (k, c) in cells.iter_mut().enumerate() {
            let n = cells_for(size[k]).max(1.0);
            *c = if n < MAX_AXIS as f32 {
                n as usize
            } else {
                MAX_AXIS
            };
        }
        let spacing = size / Vec3::new(cells[0] as f32, cells[1] as f32, cells[2] as f32);
        Self::new(b.min, spacing, cells)
    }

    /// Samples per axis (`cells + 1`).
    pub fn points(&self) -> [usize; 3] {
        self.cells.map(|c| c + 1)
    }

    /// Total number of samples: what plain Marching Cubes evaluates (#C0).
    pub fn point_count(&self) -> u64 {
        self.points().iter().map(|&n| n as u64).product()
    }

    /// Total number of cells.
    pub fn cell_count(&self) -> u64 {
        self.cells.iter().map(|&n| n as u64).product()
    }

    /// Sample `(i, j, k)`.
    #[inline]
    pub fn point(&self, i: usize, j: usize, k: usize) -> Vec3 {
        let [oi, oj] = self.offset;
        self.origin + Vec3::new((oi + i) as f32, (oj + j) as f32, k as f32) * self.spacing
    }

    /// The box the grid covers.
    pub fn bounds(&self) -> Aabb {
        Aabb::new(
            self.point(0, 0, 0),
            self.point(self.cells[0], self.cells[1], self.cells[2]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_the_box() {
        let b = Aabb::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::new(9.0, 5.0, 2.5));
        let g = GridSpec::with_cell(&b, 2.0).unwrap();
        assert_eq!(g.cells, [5, 3, 2]);
        assert!((g.bounds().max - b.max).abs().max_element() < 1e-5);
        let g = GridSpec::with_resolution(&b, 100).unwrap();
        assert_eq!(g.cells, [100, 50, 25]);
        assert!(GridSpec::with_cell(&b, 0.0).is_err());
        assert!(
            GridSpec::with_cell(&Aabb::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)), 0.1).is_err()
        );
    }

    #[test]
    fn windows_share_the_grid_samples() {
        let b = Aabb::new(Vec3::new(0.1, -7.3, 0.0), Vec3::new(100.7, 40.0, 3.0));
        let g = GridSpec::with_cell(&b, 0.37).unwrap();
        let w = g.window([100, 31], [50, 20]).unwrap();
        assert_eq!(w.cells, [50, 20, g.cells[2]]);
        for (i, j, k) in [(0, 0, 0), (50, 20, 3), (17, 3, 1)] {
            // Bit-identical, not merely close: a window is the same grid.
            assert_eq!(w.point(i, j, k), g.point(100 + i, 31 + j, k));
        }
        let ww = w.window([10, 10], [5, 5]).unwrap();
        assert_eq!(ww.point(1, 2, 0), g.point(111, 43, 0));
        assert_eq!(ww.bounds().min, g.point(110, 41, 0));
        assert!(g.window([0, 0], [0, 1]).is_err());
        assert!(g.window([g.cells[0] - 1, 0], [2, 1]).is_err());
    }
}

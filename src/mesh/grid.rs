//! The virtual sampling grid of an extraction: a box cut into cells.

use glam::Vec3;

use super::MeshError;
use crate::field::Aabb;

/// A regular grid of `cells[0] × cells[1] × cells[2]` cells starting at `origin`, with
/// samples at `origin + (i, j, k)·spacing` for `i ≤ cells[0]`, etc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridSpec {
    /// Position of sample `(0, 0, 0)`.
    pub origin: Vec3,
    /// Cell size along each axis.
    pub spacing: Vec3,
    /// Number of cells along each axis.
    pub cells: [usize; 3],
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
        self.origin + Vec3::new(i as f32, j as f32, k as f32) * self.spacing
    }

    /// The box the grid covers.
    pub fn bounds(&self) -> Aabb {
        Aabb::new(
            self.origin,
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
}

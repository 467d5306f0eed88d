//! Extraction statistics: the columns of Table 1 of Paris et al. 2019 (#C, #C0, times per stage).

use std::fmt;
use std::time::Duration;

/// What an extraction did. `field_evaluations` is #C in Table 1 of Paris et al. 2019 and
/// `grid_points` is #C0, what plain Marching Cubes evaluates on the same grid.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshStats {
    /// Samples of the whole grid (#C0).
    pub grid_points: u64,
    /// Cells of the whole grid.
    pub cells: u64,
    /// Cells classified (inside the pruning bands).
    pub cells_visited: u64,
    /// Grid columns (vertical lines of samples).
    pub columns: u64,
    /// Columns whose samples came from an elevation (direct extraction).
    pub elevation_columns: u64,
    /// Field evaluations at grid samples (#C).
    pub field_evaluations: u64,
    /// Elevation evaluations `h(x, y)` for samples (direct extraction): one per
    /// elevation column.
    pub height_evaluations: u64,
    /// Elevation evaluations spent on vertices (normals, refinement).
    pub vertex_height_evaluations: u64,
    /// Field evaluations spent placing vertices (refinement, mixed edges).
    pub vertex_evaluations: u64,
    /// Gradient evaluations for normals.
    pub gradient_evaluations: u64,
    /// Output vertices.
    pub vertices: u64,
    /// Output triangles.
    pub triangles: u64,
    /// Wall time of each stage, in order.
    pub stages: Vec<(&'static str, Duration)>,
}

impl MeshStats {
    /// Total wall time.
    pub fn total_time(&self) -> Duration {
        self.stages.iter().map(|s| s.1).sum()
    }

    /// `#C0 / #C`: how many times fewer samples than plain Marching Cubes.
    pub fn evaluation_ratio(&self) -> f64 {
        self.grid_points as f64 / self.field_evaluations.max(1) as f64
    }
}

impl fmt::Display for MeshStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let pct = |a: u64, b: u64| 100.0 * a as f64 / b.max(1) as f64;
        writeln!(
            f,
            "cells visited     {:>14} of {} ({:.1}%)",
            self.cells_visited,
            self.cells,
            pct(self.cells_visited, self.cells)
        )?;
        writeln!(
            f,
            "field evals #C    {:>14}   #C0 {}   #C0/#C {:.2}",
            self.field_evaluations,
            self.grid_points,
            self.evaluation_ratio()
        )?;
        if self.columns > 0 {
            writeln!(
                f,
                "elevation columns {:>14} of {}   height evals {}",
                self.elevation_columns, self.columns, self.height_evaluations
            )?;
            writeln!(
                f,
                "vertex evals      {:>14}   gradient evals {}   vertex height evals {}",
                self.vertex_evaluations, self.gradient_evaluations, self.vertex_height_evaluations
            )?;
        }
        writeln!(
            f,
            "vertices          {:>14}   triangles {}",
            self.vertices, self.triangles
        )?;
        for (name, t) in &self.stages {
            writeln!(f, "time {name:<12} {:>12.1} ms", t.as_secs_f64() * 1e3)?;
        }
        write!(
            f,
            "time total        {:>12.1} ms",
            self.total_time().as_secs_f64() * 1e3
        )
    }
}

//! Large terrains as tiles (`karstic tile`): a quadtree plan of square tiles with levels
//! of detail, each tile meshed by an independent process (a batch scheduler's array job),
//! and a 3D Tiles 1.1 tileset over the results. See `docs/tiles.md`.
//!
//! * [`plan`]: the quadtree over a region, the finest grid, each tile's grid window.
//! * [`mesh`]: one tile — its core meshed on a window of its level's grid with a halo, so
//!   that neighbours share their border vertices bit for bit; skirts between levels.
//! * [`tileset`]: the merge into `tileset.json`.
//! * [`ecef`]: the root transform from a UTM or geographic DEM frame to ECEF.

pub mod ecef;
pub mod mesh;
pub mod plan;
pub mod tileset;

pub use mesh::{Loaded, TileSummary, add_skirts, mesh_core, run_tile};
pub use plan::{Plan, Tile};
pub use tileset::{MergeReport, merge};

use anyhow::Context;

/// The environment variables that carry an array job's task index, in the order they are
/// read: Slurm job arrays, Kubernetes Indexed Jobs, AWS Batch array jobs.
pub const INDEX_VARIABLES: [&str; 3] = [
    "SLURM_ARRAY_TASK_ID",
    "JOB_COMPLETION_INDEX",
    "AWS_BATCH_JOB_ARRAY_INDEX",
];

/// The tile index to run: `explicit` when given, else the first of [`INDEX_VARIABLES`]
/// that `var` finds set. Errors when none is, or when the value is not an index.
pub fn array_index(
    explicit: Option<usize>,
    var: impl Fn(&str) -> Option<String>,
) -> anyhow::Result<usize> {
    if let Some(i) = explicit {
        return Ok(i);
    }
    for name in INDEX_VARIABLES {
        if let Some(v) = var(name) {
            return v
                .trim()
                .parse()
                .with_context(|| format!("{name}={v:?}: expected a tile index (0, 1, 2, …)"));
        }
    }
    anyhow::bail!(
        "no tile index: give --index I, or run as an array job ({} is set there)",
        INDEX_VARIABLES.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_index_comes_from_the_flag_or_the_scheduler() {
        let env = |pairs: &'static [(&'static str, &'static str)]| {
            move |k: &str| pairs.iter().find(|p| p.0 == k).map(|p| p.1.to_string())
        };
        assert_eq!(
            array_index(Some(3), env(&[("SLURM_ARRAY_TASK_ID", "7")])).unwrap(),
            3
        );
        assert_eq!(
            array_index(None, env(&[("SLURM_ARRAY_TASK_ID", "7")])).unwrap(),
            7
        );
        assert_eq!(
            array_index(None, env(&[("JOB_COMPLETION_INDEX", "2")])).unwrap(),
            2
        );
        assert_eq!(
            array_index(None, env(&[("AWS_BATCH_JOB_ARRAY_INDEX", "11\n")])).unwrap(),
            11
        );
        let e = array_index(None, env(&[("SLURM_ARRAY_TASK_ID", "x")])).unwrap_err();
        assert!(format!("{e:#}").contains("SLURM_ARRAY_TASK_ID"), "{e:#}");
        assert!(array_index(None, env(&[])).is_err());
    }
}

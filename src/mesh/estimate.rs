//! The memory of an extraction, known before its bands stage runs: the column index is
//! exact from the grid's size, the samples are estimated from the bands of a few tiles
//! spread over the grid, so a grid far over the budget is refused in milliseconds
//! instead of after minutes of work.

use super::MeshError;
use super::columns::{TileGrid, tile_bands};
use super::grid::GridSpec;
use crate::field::Field;
use crate::io::check_budget;

/// Bytes per stored sample: its value and three vertex slots.
pub(crate) const SAMPLE_BYTES: u64 = 16;

/// Bytes per grid column of bookkeeping (ids, spans, elevations).
pub(crate) const COLUMN_BYTES: u64 = 64;

/// Tiles whose bands are computed to estimate the samples of a large grid.
const PROBED_TILES: usize = 64;

/// Refuses an extraction on `grid` whose memory is known to exceed `budget` before any
/// of it is taken: the column index (exact), then with `prune` the samples estimated
/// from [`PROBED_TILES`] tiles, without it every sample (exact). Grids whose every
/// sample would fit are not probed.
pub(crate) fn check_before_bands(
    field: &dyn Field,
    grid: &GridSpec,
    layout: &TileGrid,
    prune: bool,
    elevation: bool,
    budget: u64,
) -> Result<(), MeshError> {
    let [cx, cy, cz] = grid.cells;
    let columns = layout.columns_total();
    let index = columns.saturating_mul(COLUMN_BYTES);
    check_budget(
        format!("the column index of a {cx}×{cy}×{cz}-cell grid"),
        index,
        budget,
    )?;
    let every = grid.point_count().saturating_mul(SAMPLE_BYTES);
    if index.saturating_add(every) <= budget {
        return Ok(());
    }
    if !prune {
        check_budget(
            format!("every sample of a {cx}×{cy}×{cz}-cell grid"),
            index.saturating_add(every),
            budget,
        )?;
        return Ok(());
    }
    let tiles = layout.len();
    let probed = PROBED_TILES.min(tiles);
    let mut samples = 0u64;
    let mut probed_columns = 0u64;
    for k in 0..probed {
        // Evenly spread, the last tile included.
        let t = if probed == 1 {
            0
        } else {
            k * (tiles - 1) / (probed - 1)
        };
        let bands = tile_bands(field, grid, layout, t, elevation);
        // Each run of cells needs its layers plus one samples in its own grid column;
        // the union with the neighbours' runs only adds to this.
        samples += bands
            .cells
            .1
            .iter()
            .map(|r| (r[1] - r[0]) as u64 + 1)
            .sum::<u64>();
        probed_columns += layout.columns(t).count() as u64;
    }
    let estimate = (samples as f64 * columns as f64 / probed_columns.max(1) as f64) as u64;
    check_budget(
        format!(
            "about {estimate} samples of a {cx}×{cy}×{cz}-cell grid (estimated from {probed} of its {tiles} tiles)"
        ),
        index.saturating_add(estimate.saturating_mul(SAMPLE_BYTES)),
        budget,
    )?;
    Ok(())
}

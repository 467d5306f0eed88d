//! The memory of an extraction, known before its bands stage runs: the column index is
//! exact from the grid's size, the samples are estimated from the bands of a lattice of
//! tiles spread over the grid, so a grid far over the budget is refused in milliseconds
//! instead of after minutes of work. The estimate is the median tile's sample density
//! over the whole grid: it errs low where detail is concentrated (the exact check after
//! the bands stage still refuses those), and one probe that hits a small dense feature
//! does not make the whole grid look dense.

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
    if columns > u32::MAX as u64 {
        return Err(MeshError::GridShape(format!(
            "{cx}×{cy}×{cz} cells: more than 2³² grid columns"
        )));
    }
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
    // A lattice of tiles evenly spread over both axes (a diagonal would alias with the
    // scene's features).
    let per_axis = PROBED_TILES.isqrt();
    let spread = |count: usize| {
        let p = per_axis.min(count);
        (0..p).map(move |a| (2 * a + 1) * count / (2 * p))
    };
    // Samples per column of each probed tile: each run of cells needs its layers plus
    // one samples in its own grid column (the union with the neighbours' runs only adds).
    let mut density: Vec<f64> = Vec::new();
    for tj in spread(layout.count[1]) {
        for ti in spread(layout.count[0]) {
            let t = ti + layout.count[0] * tj;
            let bands = tile_bands(field, grid, layout, t, elevation);
            let samples: u64 = bands.cells.1.iter().map(|r| (r[1] - r[0]) as u64 + 1).sum();
            density.push(samples as f64 / layout.columns(t).count() as f64);
        }
    }
    // The median tile: a small, dense feature that one probe happens to hit does not
    // make the whole grid look dense.
    density.sort_by(f64::total_cmp);
    let (probed, tiles) = (density.len(), layout.len());
    let estimate = (density[probed / 2] * columns as f64) as u64;
    check_budget(
        format!(
            "about {estimate} samples of a {cx}×{cy}×{cz}-cell grid (from the median of {probed} of its {tiles} tiles)"
        ),
        index.saturating_add(estimate.saturating_mul(SAMPLE_BYTES)),
        budget,
    )?;
    Ok(())
}

//! Heightmaps of trees: the top surface of the final 3D terrain, one elevation per
//! column, as a DEM georeferenced like the scene's terrain — what game engines and GIS
//! tools take.
//!
//! * [`HeightmapGrid`] places the samples: on the lattice of the scene's terrain
//!   heightfield (its samples, or a coarser or finer cell from the same corner), over its
//!   extent or a region, with the terrain DEM's georeference; without a terrain, over the
//!   tree's support in a local frame.
//! * [`heightmap`] finds every column's top ([`column`]) in parallel and returns a
//!   [`Dem`] for [`crate::dem::write`] (GeoTIFF, PNG16 + sidecar, ESRI ASCII). Columns
//!   with no solid are nodata.

mod column;

pub use column::{Columns, TopOptions};

use glam::Vec2;
use rayon::prelude::*;

use crate::dem::{Dem, DemError, Georef, Heightfield, HeightfieldField};
use crate::field::{Rect, Tree};

/// The most samples a heightmap may have, whatever the memory budget: past this a
/// request is a mistaken cell or region, not a terrain.
const MAX_SAMPLES: f64 = 1e12;

/// Where a heightmap's samples lie.
#[derive(Clone, Debug, PartialEq)]
pub struct HeightmapGrid {
    /// Tree-frame position of sample `(0, 0)`, the south-west one.
    pub origin: Vec2,
    /// Sample spacing `(dx, dy)`, metres.
    pub cell: [f64; 2],
    /// Samples along x (east) and y (north).
    pub size: [usize; 2],
    /// The georeference of the samples (local frame: sample `(0, 0)` at `(0, 0)`).
    pub georef: Georef,
}

impl HeightmapGrid {
    /// The grid of a scene with terrain `ground`: the ground's lattice from its
    /// south-west sample, at `cell` metres (default the ground's own cells), over
    /// `region` (tree frame; default the ground's extent), georeferenced like the
    /// ground's DEM. Without a ground, `cell` is required and the grid covers `region` or
    /// the footprint of `support` in a local frame whose coordinates are the tree's.
    pub fn new(
        ground: Option<&HeightfieldField>,
        support: Rect,
        cell: Option<f64>,
        region: Option<Rect>,
    ) -> Result<HeightmapGrid, DemError> {
        let invalid = |what: String| Err(DemError::Invalid { what });
        if let Some(c) = cell
            && !(c > 0.0 && c.is_finite())
        {
            return invalid(format!("the heightmap cell must be > 0 metres, got {c}"));
        }
        // The lattice's anchor (tree frame) and its position in the DEM's local frame.
        let (anchor, anchor_local, native, extent) = match ground {
            Some(g) => {
                let hf = g.heightfield();
                let local = hf.origin() - g.params().placement;
                let c = hf.cell();
                (
                    hf.origin(),
                    [f64::from(local.x), f64::from(local.y)],
                    Some([f64::from(c.x), f64::from(c.y)]),
                    hf.extent(),
                )
            }
            None => {
                let r = region.unwrap_or(support);
                (r.min, [0.0; 2], None, r)
            }
        };
        let step = match (cell, native) {
            (Some(c), _) => [c, c],
            (None, Some(n)) => n,
            (None, None) => {
                return invalid(
                    "the scene has no terrain heightfield: give the heightmap's cell size".into(),
                );
            }
        };
        let rect = region.unwrap_or(extent);
        if !(rect.min.x < rect.max.x && rect.min.y < rect.max.y && rect.min.is_finite()) {
            return invalid(format!("the heightmap region {rect:?} is empty"));
        }
        // Lattice indices inside the rectangle (a millionth of a cell of slack).
        let range = |lo: f32, hi: f32, a: f32, s: f64| {
            let i0 = ((f64::from(lo) - f64::from(a)) / s - 1e-6).ceil();
            let i1 = ((f64::from(hi) - f64::from(a)) / s + 1e-6).floor();
            (i0, i1)
        };
        let (i0, i1) = range(rect.min.x, rect.max.x, anchor.x, step[0]);
        let (j0, j1) = range(rect.min.y, rect.max.y, anchor.y, step[1]);
        let (nx, ny) = (i1 - i0 + 1.0, j1 - j0 + 1.0);
        let cells = format!(
            "{nx}×{ny} samples of {} × {} m over ({}, {}) .. ({}, {})",
            step[0], step[1], rect.min.x, rect.min.y, rect.max.x, rect.max.y
        );
        if !(nx >= 2.0 && ny >= 2.0) {
            return invalid(format!(
                "a heightmap needs at least 2×2 samples: {cells} (give a finer cell or a larger region)"
            ));
        }
        if nx * ny > MAX_SAMPLES {
            return invalid(format!(
                "a heightmap of {cells} is more than {MAX_SAMPLES:e} samples (give a coarser cell \
                 or a smaller region)"
            ));
        }
        let offset = [i0 * step[0], j0 * step[1]];
        let origin = anchor + Vec2::new(offset[0] as f32, offset[1] as f32);
        let local = [anchor_local[0] + offset[0], anchor_local[1] + offset[1]];
        let georef = match ground.and_then(HeightfieldField::georef) {
            Some(g) => Georef {
                origin: g.local_to_crs(local),
                ..if cell.is_some() {
                    g.with_cell_size(step[0], step[1])
                } else {
                    g.clone()
                }
            },
            None => Georef {
                origin: [f64::from(origin.x), f64::from(origin.y)],
                ..Georef::local(step[0], step[1])
            },
        };
        Ok(HeightmapGrid {
            origin,
            cell: step,
            size: [nx as usize, ny as usize],
            georef,
        })
    }

    /// Tree-frame position of sample `(i, j)`.
    pub fn at(&self, i: usize, j: usize) -> Vec2 {
        self.origin
            + Vec2::new(
                (i as f64 * self.cell[0]) as f32,
                (j as f64 * self.cell[1]) as f32,
            )
    }
}

/// The top surface of `tree` on `grid`: every column's highest crossing into the solid,
/// NaN where the column holds none. Refuses grids over `budget` bytes.
pub fn heightmap(
    tree: &Tree,
    grid: &HeightmapGrid,
    opts: &TopOptions,
    budget: u64,
) -> Result<Dem, DemError> {
    let [nx, ny] = grid.size;
    // the samples, and the copy a writer makes
    crate::io::check_budget(
        format!("the {nx}×{ny} heightmap"),
        (nx as u64).saturating_mul(ny as u64).saturating_mul(8),
        budget,
    )
    .map_err(DemError::Io)?;
    let mut z = vec![f32::NAN; nx * ny];
    z.par_chunks_mut(nx).enumerate().for_each_init(
        || Columns::new(tree, opts),
        |columns, (j, row)| {
            for (i, out) in row.iter_mut().enumerate() {
                *out = columns.top(grid.at(i, j)).unwrap_or(f32::NAN);
            }
        },
    );
    let empty = z.iter().filter(|v| v.is_nan()).count();
    let cell = Vec2::new(grid.cell[0] as f32, grid.cell[1] as f32);
    let heightfield = Heightfield::new(nx, ny, Vec2::ZERO, cell, z)?;
    let notices = if empty > 0 {
        vec![format!(
            "{empty} of {} columns hold no solid: they are nodata",
            nx * ny
        )]
    } else {
        Vec::new()
    };
    Ok(Dem {
        heightfield,
        georef: grid.georef.clone(),
        notices,
    })
}

/// `dem` without the rows and columns of its border that hold nodata, peeled from the
/// outside in (the ring where the implicit terrain ends, around a heightmap of a DEM
/// scene), its grid's origin and its georeference moved to match; `dem` itself when
/// nothing is peeled or fewer than 2×2 samples would stay.
pub fn trim_nodata_border(dem: Dem) -> Dem {
    let hf = &dem.heightfield;
    let (nx, ny) = (hf.nx(), hf.ny());
    // Nodata fraction of row j over columns i0..i1, and of column i over rows j0..j1.
    let row = |j: usize, i0: usize, i1: usize| {
        (i0..i1).filter(|&i| hf.at(i, j).is_nan()).count() as f64 / (i1 - i0) as f64
    };
    let col = |i: usize, j0: usize, j1: usize| {
        (j0..j1).filter(|&j| hf.at(i, j).is_nan()).count() as f64 / (j1 - j0) as f64
    };
    let (mut i0, mut i1, mut j0, mut j1) = (0, nx, 0, ny);
    // Peel the border line with the most nodata first, so that a ring of nodata goes as
    // whole lines and does not eat the rows it crosses.
    while i1 - i0 >= 2 && j1 - j0 >= 2 {
        let sides = [
            row(j0, i0, i1),
            row(j1 - 1, i0, i1),
            col(i0, j0, j1),
            col(i1 - 1, j0, j1),
        ];
        let (side, &most) = sides
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(&a.0)))
            .expect("four sides");
        if most == 0.0 {
            break;
        }
        match side {
            0 => j0 += 1,
            1 => j1 -= 1,
            2 => i0 += 1,
            _ => i1 -= 1,
        }
    }
    if (i0, i1, j0, j1) == (0, nx, 0, ny) || i1 - i0 < 2 || j1 - j0 < 2 {
        return dem;
    }
    let z = (j0..j1)
        .flat_map(|j| (i0..i1).map(move |i| hf.at(i, j)))
        .collect();
    let origin = hf.origin() + Vec2::new(i0 as f32, j0 as f32) * hf.cell();
    let Ok(heightfield) = Heightfield::new(i1 - i0, j1 - j0, origin, hf.cell(), z) else {
        return dem;
    };
    let g = &dem.georef;
    let georef = Georef {
        origin: [
            g.origin[0] + i0 as f64 * g.step[0],
            g.origin[1] + j0 as f64 * g.step[1],
        ],
        ..g.clone()
    };
    let mut notices = dem.notices.clone();
    notices.push(format!(
        "trimmed the nodata border: {nx}×{ny} → {}×{} samples",
        i1 - i0,
        j1 - j0
    ));
    Dem {
        heightfield,
        georef,
        notices,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trimming_peels_the_nodata_rings_and_moves_the_georeference() {
        let (nx, ny) = (9, 7);
        // Two rings of nodata on the west and south, one on the east and north.
        let z = (0..nx * ny)
            .map(|k| {
                let (i, j) = (k % nx, k / nx);
                if i < 2 || j < 2 || i == nx - 1 || j == ny - 1 {
                    f32::NAN
                } else {
                    k as f32
                }
            })
            .collect();
        let hf = Heightfield::new(nx, ny, Vec2::new(100.0, 200.0), Vec2::splat(10.0), z).unwrap();
        let dem = Dem {
            heightfield: hf,
            georef: Georef {
                origin: [5000.0, 7000.0],
                ..Georef::local(10.0, 10.0)
            },
            notices: Vec::new(),
        };
        let t = trim_nodata_border(dem.clone());
        let h = &t.heightfield;
        assert_eq!((h.nx(), h.ny()), (6, 4));
        assert_eq!(h.nodata_count(), 0);
        assert_eq!(h.origin(), Vec2::new(120.0, 220.0));
        assert_eq!(h.at(0, 0), dem.heightfield.at(2, 2));
        assert_eq!(t.georef.origin, [5020.0, 7020.0]);
        // Nothing to peel: unchanged.
        let again = trim_nodata_border(t.clone());
        assert_eq!(again.heightfield, t.heightfield);
    }
}

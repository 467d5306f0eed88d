//! The tile plan: a quadtree of square tiles over a region, one level per cell size, with
//! the halo each tile is meshed with; written as `plan.json` in the tiles folder.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail, ensure};
use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::ecef::tree_to_ecef;
use crate::dem::HeightfieldField;
use crate::field::Aabb;
use crate::io::{read_regular, write_bytes_atomic};
use crate::mesh::GridSpec;
use crate::mesh::columns::TILE;

/// The most tiles a plan holds: a 256 km square at 1 m in tiles of 256 cells, far past
/// what one array job meshes, and a plan file of tens of megabytes.
pub const MAX_TILES: u64 = 1_000_000;

/// Version of the plan file format.
pub const PLAN_VERSION: u32 = 1;

/// Name of the plan file in a tiles folder.
pub const PLAN_FILE: &str = "plan.json";

/// Cells of halo on each side of a tile: one tile of the mesher's column tiling, so a
/// tile's grid window has the same column tiling as the level's whole grid around the
/// tile's core, and every sample of the core is evaluated as in a single run.
pub const HALO: usize = TILE;

/// Largest tree file a plan hashes (tree files are text; their DEMs are read apart).
const TREE_BYTES: u64 = 256 << 20;

/// Most levels a plan may have (the coarsest cell is `2^(levels − 1)` finest cells).
pub const MAX_LEVELS: usize = 12;

/// A plan: the region, the finest grid, and the tiles of every level.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// [`PLAN_VERSION`].
    pub version: u32,
    /// The tree file (absolute path: every machine of the array reads it there).
    pub tree: PathBuf,
    /// FNV-1a 64-bit hash of the tree file's bytes when planned (hexadecimal).
    pub tree_hash: String,
    /// Minimum corner of the planned region (tree frame, metres).
    pub region_min: [f32; 3],
    /// Maximum corner of the planned region.
    pub region_max: [f32; 3],
    /// Cells per tile side, the same at every level (a multiple of [`HALO`]).
    pub tile_cells: usize,
    /// Number of levels; level 0 is the coarsest.
    pub levels: usize,
    /// Position of the finest grid's sample `(0, 0, 0)` (the region's minimum).
    pub origin: [f32; 3],
    /// The finest grid's spacing: the requested cell, shrunk to fit the region exactly.
    pub spacing: [f32; 3],
    /// The finest grid's cells per axis.
    pub cells: [usize; 3],
    /// The root transform of the tileset (tree frame to ECEF, 4 × 4 column-major), when
    /// the tree's terrain has a CRS the tiles know (see [`super::ecef`]).
    pub transform: Option<Vec<f64>>,
    /// How the tiles are placed on Earth, or why they are not.
    pub georeference: String,
    /// Every tile, coarsest level first, row-major (x fastest) within a level; the array
    /// index of a tile is its position here.
    pub tiles: Vec<Tile>,
}

/// One tile of the quadtree.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Tile {
    /// Level (0 is the coarsest).
    pub level: usize,
    /// Column of the tile in its level.
    pub x: usize,
    /// Row of the tile in its level.
    pub y: usize,
}

impl Tile {
    /// Its mesh and summary, relative to the tiles folder: `tiles/LEVEL/X_Y`.
    pub fn stem(&self) -> String {
        format!("tiles/{}/{}_{}", self.level, self.x, self.y)
    }
}

impl Plan {
    /// Plans `levels` levels of tiles of `tile_cells` cells over `region` (finest cell
    /// `cell`), for the tree file `tree` (made absolute).
    pub fn new(
        tree: &Path,
        region: &Aabb,
        cell: f32,
        tile_cells: usize,
        levels: usize,
    ) -> anyhow::Result<Plan> {
        ensure!(
            tile_cells >= HALO && tile_cells.is_multiple_of(HALO),
            "--tile {tile_cells}: expected a positive multiple of {HALO} cells \
             (tiles align with the mesher's column tiling)"
        );
        ensure!(
            (1..=MAX_LEVELS).contains(&levels),
            "--levels {levels}: expected 1 to {MAX_LEVELS}"
        );
        let grid = GridSpec::with_cell(region, cell)
            .with_context(|| format!("the region at {cell} m cells"))?;
        let bytes = read_regular(tree, TREE_BYTES)
            .with_context(|| format!("cannot read {}", tree.display()))?;
        let tree = std::path::absolute(tree)
            .with_context(|| format!("{}: no absolute path", tree.display()))?;
        let mut plan = Plan {
            version: PLAN_VERSION,
            tree,
            tree_hash: hash_hex(&bytes),
            region_min: region.min.to_array(),
            region_max: region.max.to_array(),
            tile_cells,
            levels,
            origin: grid.origin.to_array(),
            spacing: grid.spacing.to_array(),
            cells: grid.cells,
            transform: None,
            georeference: "local: the tree's frame (no terrain with a CRS)".into(),
            tiles: Vec::new(),
        };
        let count = (0..levels)
            .map(|level| {
                let [nx, ny] = plan.tile_counts(level);
                (nx as u64).saturating_mul(ny as u64)
            })
            .fold(0u64, u64::saturating_add);
        ensure!(
            count > 0,
            "the region {:?} .. {:?} holds no tile at {cell} m cells",
            region.min.to_array(),
            region.max.to_array()
        );
        ensure!(
            count <= MAX_TILES,
            "a plan of {count} tiles at {cell} m cells and {tile_cells} cells a tile: at most \
             {MAX_TILES} (give a coarser --cell or larger --tile)"
        );
        for level in 0..levels {
            let [nx, ny] = plan.tile_counts(level);
            for y in 0..ny {
                for x in 0..nx {
                    plan.tiles.push(Tile { level, x, y });
                }
            }
        }
        plan.check(Path::new(PLAN_FILE))?;
        Ok(plan)
    }

    /// Errors unless the plan's numbers are consistent (a hand-edited plan file).
    fn check(&self, path: &Path) -> anyhow::Result<()> {
        let bad = |what: String| anyhow::anyhow!("{}: {what}", path.display());
        if !(1..=MAX_LEVELS).contains(&self.levels) {
            return Err(bad(format!(
                "levels {}: expected 1 to {MAX_LEVELS}",
                self.levels
            )));
        }
        if self.tile_cells < HALO || !self.tile_cells.is_multiple_of(HALO) {
            return Err(bad(format!(
                "tile_cells {}: expected a positive multiple of {HALO}",
                self.tile_cells
            )));
        }
        GridSpec::new(
            Vec3::from(self.origin),
            Vec3::from(self.spacing) * self.scale(0) as f32,
            self.cells,
        )
        .map_err(|e| bad(format!("the grid: {e}")))?;
        if self.transform.as_ref().is_some_and(|m| m.len() != 16) {
            return Err(bad("transform: expected 16 numbers".into()));
        }
        if self.tiles.is_empty() {
            return Err(bad("tiles: the plan lists none".into()));
        }
        for (i, t) in self.tiles.iter().enumerate() {
            let ok = t.level < self.levels && {
                let [nx, ny] = self.tile_counts(t.level);
                t.x < nx && t.y < ny
            };
            if !ok {
                return Err(bad(format!("tiles[{i}]: {t:?} is outside the quadtree")));
            }
        }
        Ok(())
    }

    /// Sets the root transform to ECEF from the terrain's georeference (see
    /// [`super::ecef::tree_to_ecef`], at the region's centre); returns why there is none
    /// when the terrain has a CRS the tiles do not know.
    pub fn georeference(&mut self, ground: Option<&HeightfieldField>) -> Option<String> {
        let (g, georef) = ground.and_then(|g| Some((g, g.georef()?)))?;
        let placement = g.params().placement;
        let to_crs = |p: [f64; 2]| {
            georef.local_to_crs([p[0] - f64::from(placement.x), p[1] - f64::from(placement.y)])
        };
        let region = self.region();
        let center = region.center().as_dvec3();
        let span = f64::from(region.size().truncate().max_element());
        match tree_to_ecef(georef, to_crs, center, span) {
            Ok(m) => {
                self.transform = Some(m.to_cols_array().to_vec());
                self.georeference = format!(
                    "{}: root transform to ECEF (WGS 84) at the region's centre",
                    georef.crs.describe()
                );
                None
            }
            Err(why) => {
                self.georeference = format!("no root transform: {why}");
                Some(why)
            }
        }
    }

    /// The region planned.
    pub fn region(&self) -> Aabb {
        Aabb::new(Vec3::from(self.region_min), Vec3::from(self.region_max))
    }

    /// The finest level's grid: the region cut into cells of the requested size.
    pub fn grid(&self) -> GridSpec {
        self.level_grid(self.levels - 1)
    }

    /// Finest cells per cell of `level`: `2^(levels − 1 − level)`.
    pub fn scale(&self, level: usize) -> usize {
        1 << (self.levels - 1 - level)
    }

    /// The grid of `level`: the finest grid's origin, its spacing times
    /// [`Plan::scale`] on every axis, and enough cells to cover the finest grid.
    pub fn level_grid(&self, level: usize) -> GridSpec {
        let s = self.scale(level);
        GridSpec {
            origin: Vec3::from(self.origin),
            spacing: Vec3::from(self.spacing) * s as f32,
            cells: self.cells.map(|c| c.div_ceil(s)),
            offset: [0, 0],
        }
    }

    /// Tiles along x and y at `level`.
    pub fn tile_counts(&self, level: usize) -> [usize; 2] {
        let g = self.level_grid(level);
        [
            g.cells[0].div_ceil(self.tile_cells),
            g.cells[1].div_ceil(self.tile_cells),
        ]
    }

    /// The cells `[lo, hi)` along x and y of `tile`'s core in its level's grid.
    pub fn core(&self, tile: &Tile) -> [[usize; 2]; 2] {
        let g = self.level_grid(tile.level);
        let at = |i: usize, axis: usize| {
            let lo = i * self.tile_cells;
            [lo, (lo + self.tile_cells).min(g.cells[axis])]
        };
        [at(tile.x, 0), at(tile.y, 1)]
    }

    /// The window of the level's grid `tile` is meshed on (its core and [`HALO`] cells
    /// around, within the grid), and the core's cells in the window's indices.
    pub fn window(&self, tile: &Tile) -> anyhow::Result<(GridSpec, [[usize; 2]; 2])> {
        let g = self.level_grid(tile.level);
        let core = self.core(tile);
        let lo = core.map(|c| c[0].saturating_sub(HALO));
        let hi = [0, 1].map(|a| (core[a][1] + HALO).min(g.cells[a]));
        let window = g.window(lo, [hi[0] - lo[0], hi[1] - lo[1]])?;
        let keep = [0, 1].map(|a| [core[a][0] - lo[a], core[a][1] - lo[a]]);
        Ok((window, keep))
    }

    /// The core's footprint box of `tile` (its level's full z range).
    pub fn core_box(&self, tile: &Tile) -> Aabb {
        let g = self.level_grid(tile.level);
        let [x, y] = self.core(tile);
        Aabb::new(g.point(x[0], y[0], 0), g.point(x[1], y[1], g.cells[2]))
    }

    /// A hash of the plan (FNV-1a of its JSON): the tiles' summaries carry it, so the merge
    /// never mixes tiles of an earlier plan written to the same folder.
    pub fn id(&self) -> String {
        hash_hex(serde_json::to_string(self).unwrap_or_default().as_bytes())
    }

    /// Position of `tile` in [`Plan::tiles`].
    pub fn index_of(&self, tile: &Tile) -> Option<usize> {
        self.tiles.iter().position(|t| t == tile)
    }

    /// The children of `tile` at the next level that exist (up to four).
    pub fn children(&self, tile: &Tile) -> Vec<Tile> {
        if tile.level + 1 >= self.levels {
            return Vec::new();
        }
        let [nx, ny] = self.tile_counts(tile.level + 1);
        let mut out = Vec::new();
        for dy in 0..2 {
            for dx in 0..2 {
                let (x, y) = (2 * tile.x + dx, 2 * tile.y + dy);
                if x < nx && y < ny {
                    out.push(Tile {
                        level: tile.level + 1,
                        x,
                        y,
                    });
                }
            }
        }
        out
    }

    /// Writes `DIR/plan.json` (atomically), creating `DIR`.
    pub fn write(&self, dir: &Path) -> anyhow::Result<()> {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the tiles folder {}", dir.display()))?;
        let mut text = serde_json::to_string_pretty(self)?;
        text.push('\n');
        write_bytes_atomic(&dir.join(PLAN_FILE), text.as_bytes())?;
        Ok(())
    }

    /// Reads `DIR/plan.json`, checking its version and that its tree file is unchanged.
    pub fn read(dir: &Path) -> anyhow::Result<Plan> {
        let path = dir.join(PLAN_FILE);
        let bytes = read_regular(&path, 1 << 30)
            .with_context(|| format!("{}: run `karstic tile plan` first", path.display()))?;
        let plan: Plan = serde_json::from_slice(&bytes)
            .with_context(|| format!("{}: not a karstic tile plan", path.display()))?;
        if plan.version != PLAN_VERSION {
            bail!(
                "{}: plan version {} (this karstic reads version {PLAN_VERSION})",
                path.display(),
                plan.version
            );
        }
        plan.check(&path)?;
        let tree = read_regular(&plan.tree, TREE_BYTES).with_context(|| {
            format!(
                "{}: cannot read its tree {}",
                path.display(),
                plan.tree.display()
            )
        })?;
        if hash_hex(&tree) != plan.tree_hash {
            bail!(
                "{}: the tree {} changed since it was planned; plan again",
                path.display(),
                plan.tree.display()
            );
        }
        Ok(plan)
    }
}

/// The content hash of `bytes` ([`crate::io::content_hash`]), as 16
/// hexadecimal digits.
pub(crate) fn hash_hex(bytes: &[u8]) -> String {
    format!("{:016x}", crate::io::content_hash(&[bytes]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(levels: usize) -> Plan {
        let region = Aabb::new(Vec3::new(3.0, -2.0, 0.0), Vec3::new(203.0, 98.0, 10.0));
        Plan::new(Path::new("Cargo.toml"), &region, 1.0, 64, levels).unwrap()
    }

    #[test]
    fn levels_nest() {
        let p = plan(3);
        assert_eq!(p.cells, [200, 100, 10]);
        assert_eq!(p.tile_counts(2), [4, 2]);
        assert_eq!(p.tile_counts(1), [2, 1]);
        assert_eq!(p.tile_counts(0), [1, 1]);
        assert_eq!(p.tiles.len(), 8 + 2 + 1);
        for t in &p.tiles {
            let outer = p.core_box(t);
            for c in p.children(t) {
                let inner = p.core_box(&c);
                assert!(outer.min.cmple(inner.min).all() && inner.max.cmple(outer.max).all());
            }
        }
        // The finest tiles cover the region exactly.
        let area: f32 = p
            .tiles
            .iter()
            .filter(|t| t.level == 2)
            .map(|t| {
                let s = p.core_box(t).size();
                s.x * s.y
            })
            .sum();
        assert_eq!(area, 200.0 * 100.0);
    }

    #[test]
    fn windows_hold_a_halo() {
        let p = plan(1);
        let t = Tile {
            level: 0,
            x: 1,
            y: 0,
        };
        let (w, keep) = p.window(&t).unwrap();
        assert_eq!(w.offset, [64 - HALO, 0]);
        assert_eq!(keep, [[HALO, HALO + 64], [0, 64]]);
        assert_eq!(w.point(keep[0][0], 0, 0), p.grid().point(64, 0, 0));
        assert!(Plan::new(Path::new("Cargo.toml"), &p.region(), 1.0, 40, 1).is_err());
        assert!(Plan::new(Path::new("Cargo.toml"), &p.region(), 1.0, 64, 0).is_err());
    }
}

//! `tileset.json`: the tiles of a plan as an explicit 3D Tiles 1.1 tileset — a tile per
//! quadtree node with its GLB content, a bounding box, a geometric error halving with
//! each level, and the DEM's georeference as the root's transform to ECEF.

use std::path::Path;

use anyhow::{Context, bail};
use glam::Vec3;
use serde_json::{Value, json};

use super::mesh::TileSummary;
use super::plan::{Plan, Tile};
use crate::field::Aabb;
use crate::io::{read_regular, write_bytes_atomic};

/// Name of the tileset in a tiles folder.
pub const TILESET_FILE: &str = "tileset.json";

/// Least half-height of a bounding box, metres (a flat tile still has a volume).
const MIN_HALF_HEIGHT: f32 = 0.01;

/// What the merge wrote.
pub struct MergeReport {
    /// The tileset file.
    pub path: std::path::PathBuf,
    /// Tiles in the tileset (with content or with descendants that have some).
    pub tiles: usize,
    /// Tiles with a mesh.
    pub contents: usize,
    /// Triangles over all meshes.
    pub triangles: usize,
}

/// The geometric error of a tile of `level`: the cell size of its level (a coarser mesh is
/// off the finest by about one of its cells), and 0 at the finest level.
pub fn geometric_error(plan: &Plan, level: usize) -> f64 {
    if level + 1 == plan.levels {
        0.0
    } else {
        f64::from(plan.level_grid(level).spacing.x)
    }
}

/// Reads every tile's summary, refusing a folder where some tile has not run.
pub fn read_summaries(dir: &Path, plan: &Plan) -> anyhow::Result<Vec<TileSummary>> {
    let id = plan.id();
    let mut out = Vec::with_capacity(plan.tiles.len());
    let (mut missing, mut stale) = (Vec::new(), Vec::new());
    for (i, t) in plan.tiles.iter().enumerate() {
        let path = dir.join(t.stem()).with_extension("json");
        match read_regular(&path, 1 << 20) {
            Ok(bytes) => {
                let s: TileSummary = serde_json::from_slice(&bytes)
                    .with_context(|| format!("{}: not a tile summary", path.display()))?;
                if s.tile != *t {
                    bail!(
                        "{}: the summary of {:?}, expected {t:?}",
                        path.display(),
                        s.tile
                    );
                }
                check_tile(dir, &s, &path)?;
                if s.plan != id {
                    stale.push(i);
                }
                out.push(s);
            }
            Err(crate::io::IoError::Read { source, .. })
                if source.kind() == std::io::ErrorKind::NotFound =>
            {
                missing.push(i)
            }
            Err(e) => return Err(e).context(format!("tile {i}'s summary")),
        }
    }
    if let Some(first) = out.first()
        && let Some(other) = out.iter().find(|s| s.inputs != first.inputs)
    {
        bail!(
            "{}: tiles {} and {} were run on different versions of the tree's inputs (the tree, \
             a DEM or a curves file changed between runs): run every tile again",
            dir.display(),
            first.tile.stem(),
            other.tile.stem()
        );
    }
    for (list, what) in [
        (&missing, "have not run"),
        (&stale, "were run for another plan"),
    ] {
        if !list.is_empty() {
            bail!(
                "{}: {} of {} tiles {what} (indices {}); run `karstic tile run {} --index I` for each",
                dir.display(),
                list.len(),
                plan.tiles.len(),
                shown(list),
                dir.display()
            );
        }
    }
    Ok(out)
}

/// Errors unless the tile summarised by `s` (read from `path`) can be merged: its bounds
/// are finite numbers in order, and its mesh file is there, whole, the one its run wrote.
fn check_tile(dir: &Path, s: &TileSummary, path: &Path) -> anyhow::Result<()> {
    if s.triangles == 0 {
        return Ok(());
    }
    let (min, max) = (Vec3::from(s.min), Vec3::from(s.max));
    if !(min.is_finite() && max.is_finite() && min.cmple(max).all()) {
        bail!(
            "{}: the mesh's bounds {min} .. {max} are not a box",
            path.display()
        );
    }
    let glb = dir.join(s.tile.stem()).with_extension("glb");
    let bytes = read_regular(&glb, crate::io::DEFAULT_MEMORY_BUDGET)
        .with_context(|| format!("tile {}'s mesh", s.tile.stem()))?;
    if bytes.len() as u64 != s.mesh_bytes || super::plan::hash_hex(&bytes) != s.mesh_hash {
        bail!(
            "{}: {} bytes, not the {} its run wrote (truncated or replaced since): run tile {} again",
            glb.display(),
            bytes.len(),
            s.mesh_bytes,
            s.tile.stem()
        );
    }
    Ok(())
}

/// The first indices of `list`, with an ellipsis when there are more.
fn shown(list: &[usize]) -> String {
    let mut s: Vec<String> = list.iter().take(8).map(|i| i.to_string()).collect();
    if list.len() > s.len() {
        s.push("…".into());
    }
    s.join(", ")
}

/// Writes `DIR/tileset.json` from the plan and the tiles' summaries.
pub fn merge(dir: &Path, plan: &Plan) -> anyhow::Result<MergeReport> {
    let summaries = read_summaries(dir, plan)?;
    let mut report = MergeReport {
        path: dir
            .join(super::plan::PLAN_FILE)
            .with_file_name(TILESET_FILE),
        tiles: 0,
        contents: 0,
        triangles: 0,
    };
    let [nx, ny] = plan.tile_counts(0);
    let roots: Vec<(Value, Aabb)> = (0..ny)
        .flat_map(|y| (0..nx).map(move |x| Tile { level: 0, x, y }))
        .filter_map(|t| node(plan, &summaries, &t, &mut report))
        .collect();
    if roots.is_empty() {
        bail!(
            "{}: no tile has a mesh: the surface misses the planned region",
            dir.display()
        );
    }
    let mut root = if roots.len() == 1 {
        roots.into_iter().next().map(|r| r.0).expect("one root")
    } else {
        let b = roots.iter().fold(Aabb::EMPTY, |b, r| b.union(r.1));
        report.tiles += 1;
        json!({
            "boundingVolume": bounding_box(&b),
            "geometricError": 2.0 * geometric_error(plan, 0).max(f64::from(plan.spacing[0])),
            "refine": "REPLACE",
            "children": roots.into_iter().map(|r| r.0).collect::<Vec<_>>(),
        })
    };
    if let Some(m) = &plan.transform {
        root["transform"] = json!(m);
    }
    let root_error = root["geometricError"].as_f64().unwrap_or(0.0);
    let tileset = json!({
        "asset": {
            "version": "1.1",
            "generator": concat!("karstic ", env!("CARGO_PKG_VERSION")),
        },
        "geometricError": 2.0 * root_error.max(f64::from(plan.spacing[0])),
        "root": root,
        "extras": {
            "karstic": {
                "georeference": plan.georeference,
                "levels": plan.levels,
                "tileCells": plan.tile_cells,
            }
        },
    });
    let mut text = serde_json::to_string_pretty(&tileset)?;
    text.push('\n');
    write_bytes_atomic(&report.path, text.as_bytes())?;
    Ok(report)
}

/// The tileset node of `tile` and its bounds (its mesh's and its children's), or `None`
/// when neither it nor any descendant has a mesh.
fn node(
    plan: &Plan,
    summaries: &[TileSummary],
    tile: &Tile,
    report: &mut MergeReport,
) -> Option<(Value, Aabb)> {
    let s = &summaries[plan.index_of(tile)?];
    let children: Vec<(Value, Aabb)> = plan
        .children(tile)
        .iter()
        .filter_map(|c| node(plan, summaries, c, report))
        .collect();
    let mut b = children.iter().fold(Aabb::EMPTY, |b, c| b.union(c.1));
    if s.triangles > 0 {
        b = b.union(Aabb::new(Vec3::from(s.min), Vec3::from(s.max)));
    }
    if b.is_empty() {
        return None;
    }
    // x and y are the core's footprint, so a child's box lies in its parent's.
    let core = plan.core_box(tile);
    let b = Aabb::new(core.min.with_z(b.min.z), core.max.with_z(b.max.z));
    let mut n = json!({
        "boundingVolume": bounding_box(&b),
        "geometricError": geometric_error(plan, tile.level),
        "refine": "REPLACE",
    });
    if s.triangles > 0 {
        n["content"] = json!({ "uri": format!("{}.glb", tile.stem()) });
        report.contents += 1;
        report.triangles += s.triangles;
    }
    if !children.is_empty() {
        n["children"] = Value::Array(children.into_iter().map(|c| c.0).collect());
    }
    report.tiles += 1;
    Some((n, b))
}

/// A 3D Tiles `box` bounding volume: centre, then the three half-axes.
fn bounding_box(b: &Aabb) -> Value {
    let c = b.center();
    let h = b.size() * 0.5;
    let f = |x: f32| f64::from(x);
    json!({
        "box": [
            f(c.x), f(c.y), f(c.z),
            f(h.x), 0.0, 0.0,
            0.0, f(h.y), 0.0,
            0.0, 0.0, f(h.z.max(MIN_HALF_HEIGHT)),
        ]
    })
}

//! Meshing one tile: its level's grid window (core and halo), the core's triangles, and
//! skirts along the core's sides that hide the cracks between levels.

use std::path::Path;

use anyhow::Context;
use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::plan::{Plan, Tile};
use crate::analysis::texture_frame;
use crate::field::{Aabb, Field};
use crate::io::write_bytes_atomic;
use std::sync::Arc;

use crate::compile::Compiled;
use crate::io::files_hash;
use crate::mesh::export::{self, ExportOptions, Origin};
use crate::mesh::{Mesh, MeshOptions, polygonize};
use crate::scene::SceneFile;

/// Skirt depth in cells of the tile's level.
pub const SKIRT_CELLS: f32 = 2.0;

/// What `karstic tile run` records beside a tile's mesh (`tiles/LEVEL/X_Y.json`); the
/// merge reads these.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TileSummary {
    /// The plan the tile was run for ([`Plan::id`]).
    pub plan: String,
    /// The tile.
    pub tile: Tile,
    /// Vertices of the written mesh (skirts included).
    pub vertices: usize,
    /// Triangles of the written mesh (skirts included); 0 when the surface misses the
    /// tile, which then has no mesh file.
    pub triangles: usize,
    /// Minimum corner of the written mesh (tree frame).
    pub min: [f32; 3],
    /// Maximum corner of the written mesh.
    pub max: [f32; 3],
    /// Bytes of the written mesh file (0 without one).
    pub mesh_bytes: u64,
    /// Content hash of the written mesh file: the merge checks the file is the one this run
    /// wrote (not deleted, truncated or replaced since).
    pub mesh_hash: String,
    /// Content hash of the contents of every file the tree reads (the tree, its DEMs and
    /// curve files): tiles run on different versions of an input do not merge.
    pub inputs: String,
}

/// The surface in `tile`'s core, meshed on its level's grid window: the triangles of the
/// core's cells, with vertices at exactly the positions a single run over the level's
/// whole grid gives them (the window shares the grid's samples and column tiling, see
/// [`super::plan::HALO`]). No skirts.
pub fn mesh_core(field: &dyn Field, plan: &Plan, tile: &Tile, budget: u64) -> anyhow::Result<Mesh> {
    let (window, keep) = plan.window(tile)?;
    let opts = MeshOptions {
        budget,
        keep: Some(keep),
        ..MeshOptions::default()
    };
    let (mesh, _) = polygonize(field, &window, &opts)
        .with_context(|| format!("meshing tile {}", tile.stem()))?;
    Ok(mesh)
}

/// Adds a skirt under every boundary edge of `mesh` that lies on a side of `footprint`
/// (within a thousandth of `depth`): a quad hanging `depth` metres down from the edge,
/// wound to face out of the tile, its vertices carrying the edge's normals.
pub fn add_skirts(mesh: &mut Mesh, footprint: &Aabb, depth: f32) {
    let tol = 1e-3 * depth;
    let side = |p: Vec3| -> [bool; 4] {
        [
            (p.x - footprint.min.x).abs() <= tol,
            (p.x - footprint.max.x).abs() <= tol,
            (p.y - footprint.min.y).abs() <= tol,
            (p.y - footprint.max.y).abs() <= tol,
        ]
    };
    // Only edges along a side can hang a skirt, and an edge's reverse runs along the same
    // side, so the search keeps to them (a few thousand of a tile's millions of edges).
    let sides: Vec<[bool; 4]> = mesh.positions.iter().map(|&p| side(p.into())).collect();
    let mut edges: Vec<(u32, u32)> = mesh
        .triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .filter(|&(a, b)| {
            let (sa, sb) = (sides[a as usize], sides[b as usize]);
            (0..4).any(|k| sa[k] && sb[k])
        })
        .collect();
    edges.sort_unstable();
    // A directed edge is on the boundary when its reverse is not in the mesh.
    let boundary: Vec<(u32, u32)> = edges
        .iter()
        .copied()
        .filter(|&(a, b)| edges.binary_search(&(b, a)).is_err())
        .collect();
    let mut lowered: Vec<(u32, u32)> = Vec::new();
    let mut below = |v: u32, mesh: &mut Mesh| -> u32 {
        match lowered.binary_search_by_key(&v, |e| e.0) {
            Ok(i) => lowered[i].1,
            Err(i) => {
                let mut p = mesh.positions[v as usize];
                p[2] -= depth;
                let n = mesh.normals[v as usize];
                mesh.positions.push(p);
                mesh.normals.push(n);
                let id = mesh.positions.len() as u32 - 1;
                lowered.insert(i, (v, id));
                id
            }
        }
    };
    for (a, b) in boundary {
        let (la, lb) = (below(a, mesh), below(b, mesh));
        mesh.triangles.push([b, a, la]);
        mesh.triangles.push([b, la, lb]);
    }
}

/// A loaded tree: the scene file and what it compiled to.
pub struct Loaded {
    /// The scene file.
    pub file: SceneFile,
    /// The compiled tree and its terrain.
    pub compiled: Compiled,
}

impl Loaded {
    /// Loads `plan`'s tree and compiles what the tiles numbered `tiles` need, within
    /// `budget` bytes: only their windows are ever evaluated, so features (Feature
    /// Volumes) whose regions miss them are not built ([`SceneFile::compile_within`]);
    /// the values in the windows are those of the whole tree.
    pub fn new(plan: &Plan, budget: u64, tiles: &[usize]) -> anyhow::Result<Loaded> {
        let file = crate::scene::load(&plan.tree)?;
        let mut roi = Aabb::EMPTY;
        for &i in tiles {
            let tile = plan.tiles.get(i).with_context(|| {
                format!("tile index {i}: the plan has {} tiles", plan.tiles.len())
            })?;
            let (window, _) = plan.window(tile)?;
            // A cell of margin: vertex normals may look just past the window's samples.
            roi = roi.union(window.bounds().dilate(window.spacing.max_element()));
        }
        let compiled = file.compile_within(budget, roi)?;
        Ok(Loaded { file, compiled })
    }
}

/// Meshes tile number `index` of `plan`, writes its mesh (`DIR/tiles/LEVEL/X_Y.glb`, with
/// skirts, vertex colours from the scene's materials and UVs over the DEM frame) and its
/// summary beside it, and returns the summary.
pub fn run_tile(
    dir: &Path,
    plan: &Plan,
    loaded: &Loaded,
    index: usize,
    budget: u64,
) -> anyhow::Result<TileSummary> {
    let tile = *plan.tiles.get(index).with_context(|| {
        format!(
            "tile index {index}: the plan has {} tiles (0..={})",
            plan.tiles.len(),
            plan.tiles.len().saturating_sub(1)
        )
    })?;
    let tree = &loaded.compiled.tree;
    let mut mesh = mesh_core(tree, plan, &tile, budget)?;
    let depth = SKIRT_CELLS * plan.level_grid(tile.level).spacing.x;
    add_skirts(&mut mesh, &plan.core_box(&tile), depth);
    let stem = dir.join(tile.stem());
    let folder = stem.parent().expect("a tile stem has a folder");
    std::fs::create_dir_all(folder)
        .with_context(|| format!("cannot create {}", folder.display()))?;
    let glb = stem.with_extension("glb");
    if mesh.triangles.is_empty() {
        // A tile the surface misses has no content; drop a mesh left by an earlier run.
        match std::fs::remove_file(&glb) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(e).with_context(|| format!("cannot remove {}", glb.display()));
            }
            _ => {}
        }
    } else {
        let ground = loaded.compiled.ground.clone();
        let opts = ExportOptions {
            // The plan's region stands for the tree's support: the same scale in every
            // tile, whatever part of the tree each compiled.
            albedo: Some(Arc::new(crate::picture::materials_in(
                &loaded.file.scene,
                plan.region(),
                ground.clone(),
            ))),
            origin: Origin::Dem,
            uv_frame: Some(texture_frame(None, ground.as_deref(), &plan.region())),
        };
        export::write(&mesh, &glb, &opts)?;
    }
    let written = match mesh.triangles.is_empty() {
        true => Vec::new(),
        false => crate::io::read_regular(&glb, crate::io::DEFAULT_MEMORY_BUDGET)?,
    };
    let b = mesh.bounds();
    let (min, max) = if mesh.triangles.is_empty() {
        ([0.0; 3], [0.0; 3])
    } else {
        (b.min.to_array(), b.max.to_array())
    };
    let summary = TileSummary {
        plan: plan.id(),
        tile,
        vertices: mesh.positions.len(),
        triangles: mesh.triangles.len(),
        min,
        max,
        mesh_bytes: written.len() as u64,
        mesh_hash: super::plan::hash_hex(&written),
        inputs: format!("{:016x}", files_hash(&loaded.file.inputs())),
    };
    let mut text = serde_json::to_string_pretty(&summary)?;
    text.push('\n');
    write_bytes_atomic(&stem.with_extension("json"), text.as_bytes())?;
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn skirts_hang_under_the_sides() {
        // A 2 × 1 quad at z = 1 on the footprint [0, 2] × [0, 1], wound upward.
        let mut m = Mesh {
            positions: vec![
                [0.0, 0.0, 1.0],
                [2.0, 0.0, 1.0],
                [2.0, 1.0, 1.0],
                [0.0, 1.0, 1.0],
            ],
            normals: vec![[0.0, 0.0, 1.0]; 4],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            attributes: Vec::new(),
        };
        let fp = Aabb::new(Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0));
        add_skirts(&mut m, &fp, 0.5);
        assert_eq!(m.positions.len(), 8);
        assert_eq!(m.triangles.len(), 2 + 4 * 2);
        assert!(m.positions[4..].iter().all(|p| p[2] == 0.5));
        // Every skirt faces out of the footprint.
        let c = Vec3::new(1.0, 0.5, 0.0);
        for t in &m.triangles[2..] {
            let n = m.triangle_normal(t);
            let mid = (m.position(t[0]) + m.position(t[1]) + m.position(t[2])) / 3.0;
            assert!(n.dot((mid - c).with_z(0.0)) > 0.0, "{t:?} faces in");
            assert_eq!(n.z, 0.0);
        }
        // The mesh with its skirts is still consistently oriented.
        m.check_topology(Some((
            &Aabb::new(Vec3::new(0.0, 0.0, 0.5), Vec3::new(2.0, 1.0, 1.0)),
            1e-6,
        )))
        .unwrap();
    }
}

//! `karstic tile`: neighbouring tiles share their border vertices bit for bit, a level's
//! tiles weld into the single mesh of the region, every tile is valid glTF, the tileset is
//! 3D Tiles 1.1 with nested bounds and decreasing errors, the array index comes from the
//! scheduler's variable, and a real Slurm job array gives the single process's bytes.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use glam::{DMat4, DVec3};
use karstic::field::Aabb;
use karstic::mesh::{Mesh, MeshOptions, polygonize};
use karstic::tiles::mesh::SKIRT_CELLS;
use karstic::tiles::{Loaded, Plan, Tile, mesh_core};
use serde_json::Value;

use crate::common::{REQUIRE_SLURM, unavailable};
use crate::gltf_validator::assert_valid;

const BUDGET: u64 = 4 << 30;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The tunnel scene (a Feature Volume through the Jacksboro ridge, UTM 16N).
fn tree() -> PathBuf {
    root().join("trees/ridge_tunnel.ron")
}

/// The job region of the tunnel scene: the tunnel crosses tile borders.
fn region() -> Aabb {
    Aabb::new(
        glam::Vec3::new(3150.0, 6090.0, 780.0),
        glam::Vec3::new(4250.0, 6310.0, 1000.0),
    )
}

/// A two-level plan of 32-cell tiles over the region at 4 m, and the compiled tree.
fn planned() -> &'static (Plan, Loaded) {
    static P: OnceLock<(Plan, Loaded)> = OnceLock::new();
    P.get_or_init(|| {
        let plan = Plan::new(&tree(), &region(), 4.0, 32, 2).unwrap();
        let all: Vec<usize> = (0..plan.tiles.len()).collect();
        let loaded = Loaded::new(&plan, BUDGET, &all).unwrap();
        (plan, loaded)
    })
}

fn bits(p: [f32; 3]) -> [u32; 3] {
    p.map(f32::to_bits)
}

/// The mesh's vertices within a thousandth of a cell of the plane `axis = at`, as bits.
fn on_plane(m: &Mesh, axis: usize, at: f32, cell: f32) -> Vec<[u32; 3]> {
    let mut v: Vec<[u32; 3]> = m
        .positions
        .iter()
        .filter(|p| (p[axis] - at).abs() <= 1e-3 * cell)
        .map(|&p| bits(p))
        .collect();
    v.sort_unstable();
    v
}

/// The meshes welded on exactly equal positions.
fn weld(meshes: &[Mesh]) -> Mesh {
    let mut index: HashMap<[u32; 3], u32> = HashMap::new();
    let mut out = Mesh::default();
    for m in meshes {
        let remap: Vec<u32> = m
            .positions
            .iter()
            .zip(&m.normals)
            .map(|(&p, &n)| {
                *index.entry(bits(p)).or_insert_with(|| {
                    out.positions.push(p);
                    out.normals.push(n);
                    out.positions.len() as u32 - 1
                })
            })
            .collect();
        out.triangles
            .extend(m.triangles.iter().map(|t| t.map(|v| remap[v as usize])));
    }
    out
}

#[test]
fn neighbours_share_borders_and_a_level_welds_into_the_single_mesh() {
    let (plan, loaded) = planned();
    let tree = &loaded.compiled.tree;
    for level in 0..plan.levels {
        let grid = plan.level_grid(level);
        let cell = grid.spacing.x;
        let tiles: Vec<Tile> = plan
            .tiles
            .iter()
            .copied()
            .filter(|t| t.level == level)
            .collect();
        let meshes: HashMap<(usize, usize), Mesh> = tiles
            .iter()
            .map(|t| ((t.x, t.y), mesh_core(tree, plan, t, BUDGET).unwrap()))
            .collect();
        let mut shared = 0;
        for t in &tiles {
            let a = &meshes[&(t.x, t.y)];
            let core = plan.core(t);
            for (axis, next) in [(0, (t.x + 1, t.y)), (1, (t.x, t.y + 1))] {
                let Some(b) = meshes.get(&next) else { continue };
                let at = if axis == 0 {
                    grid.point(core[0][1], 0, 0).x
                } else {
                    grid.point(0, core[1][1], 0).y
                };
                let (va, vb) = (on_plane(a, axis, at, cell), on_plane(b, axis, at, cell));
                assert!(
                    !va.is_empty(),
                    "level {level}: tile {t:?} has no vertex on its border"
                );
                assert_eq!(
                    va, vb,
                    "level {level}: tile {t:?} and its neighbour {next:?} differ"
                );
                shared += va.len();
            }
        }
        assert!(shared > 0);

        let parts: Vec<Mesh> = tiles.iter().map(|t| meshes[&(t.x, t.y)].clone()).collect();
        let union = weld(&parts);
        let (single, _) = polygonize(tree, &grid, &MeshOptions::default()).unwrap();
        // Watertight across the tile borders: edges used once lie on the region's box only.
        let tol = 1e-3 * cell;
        let topo = union
            .check_topology(Some((&grid.bounds(), tol)))
            .unwrap_or_else(|e| panic!("level {level}: {e}"));
        let single_topo = single.check_topology(Some((&grid.bounds(), tol))).unwrap();
        assert_eq!(
            topo.boundary_edges, single_topo.boundary_edges,
            "level {level}"
        );
        let (a, b) = (union.area(), single.area());
        assert!((a - b).abs() <= 1e-3 * b, "level {level}: area {a} vs {b}");
        assert_eq!(
            union.triangles.len(),
            single.triangles.len(),
            "level {level}"
        );
        let mut vu: Vec<[u32; 3]> = union.positions.iter().map(|&p| bits(p)).collect();
        let mut vs: Vec<[u32; 3]> = single.positions.iter().map(|&p| bits(p)).collect();
        vu.sort_unstable();
        vs.sort_unstable();
        assert!(
            vu == vs,
            "level {level}: the tiles' vertices are not the single mesh's"
        );
    }
}

/// The top of the mesh's section by the plane `axis = at`, at `u` along the other
/// horizontal axis: the highest point of the mesh's edges lying in the plane over `u`.
/// A tile compiles only the features its window meets: one far from the tunnel leaves its
/// Feature Volume unbuilt (a smaller tree), and every tile's mesh, near the tunnel or
/// not, is the mesh of the whole tree bit for bit.
#[test]
fn a_tile_builds_only_the_features_its_window_meets() {
    // Wider than the tunnel's domain (x 3180–4220), so that some windows miss it.
    let wide = Aabb::new(
        glam::Vec3::new(1000.0, 5900.0, 700.0),
        glam::Vec3::new(6400.0, 6500.0, 1100.0),
    );
    let plan = Plan::new(&tree(), &wide, 16.0, 32, 1).unwrap();
    let all: Vec<usize> = (0..plan.tiles.len()).collect();
    let whole = Loaded::new(&plan, BUDGET, &all).unwrap();
    let full_nodes = whole.compiled.tree.nodes().len();
    let (mut far, mut near, mut far_meshed) = (0, 0, 0);
    for i in all {
        let alone = Loaded::new(&plan, BUDGET, &[i]).unwrap();
        let tile = &plan.tiles[i];
        let (window, _) = plan.window(tile).unwrap();
        let (lo, hi) = (window.bounds().min.x, window.bounds().max.x);
        let nodes = alone.compiled.tree.nodes().len();
        let is_far = hi < 3180.0 - 32.0 || lo > 4220.0 + 32.0;
        if hi >= 3400.0 && lo <= 4000.0 {
            near += 1;
            assert_eq!(nodes, full_nodes, "tile {i} meets the tunnel");
        } else if is_far {
            far += 1;
            assert!(
                nodes < full_nodes,
                "tile {i} built the tunnel it never sees"
            );
        }
        let a = mesh_core(&whole.compiled.tree, &plan, tile, BUDGET).unwrap();
        let b = mesh_core(&alone.compiled.tree, &plan, tile, BUDGET).unwrap();
        far_meshed += usize::from(is_far && !a.triangles.is_empty());
        assert_eq!(a.triangles, b.triangles, "tile {i}");
        let pos = |m: &Mesh| m.positions.iter().map(|&p| bits(p)).collect::<Vec<_>>();
        assert_eq!(pos(&a), pos(&b), "tile {i}");
    }
    assert!(far >= 2 && near >= 2, "{far} far and {near} near tiles");
    assert!(far_meshed > 0, "no far tile holds any surface");
}

fn top_on_plane(m: &Mesh, axis: usize, at: f32, cell: f32, u: f32) -> Option<f32> {
    let other = 1 - axis;
    let on = |p: [f32; 3]| (p[axis] - at).abs() <= 1e-3 * cell;
    let mut top: Option<f32> = None;
    for t in &m.triangles {
        for k in 0..3 {
            let (a, b) = (
                m.positions[t[k] as usize],
                m.positions[t[(k + 1) % 3] as usize],
            );
            if !(on(a) && on(b)) || a[other] == b[other] {
                continue;
            }
            let s = (u - a[other]) / (b[other] - a[other]);
            if (0.0..=1.0).contains(&s) {
                let z = a[2] + s * (b[2] - a[2]);
                top = Some(top.map_or(z, |t: f32| t.max(z)));
            }
        }
    }
    top
}

#[test]
fn skirts_are_deep_enough_to_hide_the_cracks_between_levels() {
    let (plan, loaded) = planned();
    let tree = &loaded.compiled.tree;
    let coarse_cell = plan.level_grid(0).spacing.x;
    let depth = SKIRT_CELLS * coarse_cell;
    let of = |level: usize| -> Vec<(Tile, Aabb, Mesh)> {
        plan.tiles
            .iter()
            .filter(|t| t.level == level)
            .map(|t| {
                (
                    *t,
                    plan.core_box(t),
                    mesh_core(tree, plan, t, BUDGET).unwrap(),
                )
            })
            .collect()
    };
    let (coarse, fine) = (of(0), of(1));
    let mut compared = 0;
    let mut worst = 0.0f32;
    // Where a coarse tile's side is a fine tile's side, the two sections may differ (a
    // crack a viewer would see through) by less than the coarse tile's skirt.
    for (_, cb, cm) in &coarse {
        for (_, fb, fm) in &fine {
            for axis in 0..2 {
                let other = 1 - axis;
                let lo = cb.min[other].max(fb.min[other]);
                let hi = cb.max[other].min(fb.max[other]);
                for (at_c, at_f) in [(cb.max[axis], fb.min[axis]), (cb.min[axis], fb.max[axis])] {
                    if at_c != at_f || hi <= lo {
                        continue;
                    }
                    for n in 1..64 {
                        let u = lo + (hi - lo) * n as f32 / 64.0;
                        let zc = top_on_plane(cm, axis, at_c, coarse_cell, u);
                        let zf = top_on_plane(fm, axis, at_f, coarse_cell, u);
                        if let (Some(zc), Some(zf)) = (zc, zf) {
                            worst = worst.max((zc - zf).abs());
                            compared += 1;
                        }
                    }
                }
            }
        }
    }
    assert!(compared > 100, "only {compared} points compared");
    assert!(
        worst < depth,
        "a crack of {worst} m under skirts of {depth} m"
    );
    eprintln!("largest crack between levels: {worst:.2} m ({compared} points; skirts {depth} m)");
}

fn karstic(args: &[&str], env: &[(&str, &str)]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_karstic"))
        .args(args)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("JOB_COMPLETION_INDEX")
        .env_remove("AWS_BATCH_JOB_ARRAY_INDEX")
        .envs(env.iter().copied())
        .output()
        .unwrap();
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    (out.status.success(), text)
}

/// `karstic tile plan TREE --job-region --cell CELL --tile 64 --levels 2 -o DIR`.
fn plan_job_region(tree: &Path, dir: &str, cell: &str) -> (bool, String) {
    let tree = tree.to_str().unwrap();
    let args = ["tile", "plan", tree, "--job-region", "--cell", cell];
    karstic(
        &[&args[..], &["--tile", "64", "--levels", "2", "-o", dir]].concat(),
        &[],
    )
}

/// The box's corners `(min, max)` from a 3D Tiles `box` (axis-aligned half-axes).
fn corners(b: &Value) -> (DVec3, DVec3) {
    let v: Vec<f64> = b["boundingVolume"]["box"]
        .as_array()
        .expect("a box bounding volume")
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(v.len(), 12);
    assert!(v.iter().all(|x| x.is_finite()));
    let c = DVec3::new(v[0], v[1], v[2]);
    let h = DVec3::new(v[3], v[7], v[11]);
    assert!(h.min_element() > 0.0, "{b}");
    (c - h, c + h)
}

/// Checks a tile and its descendants against 3D Tiles 1.1 and the nesting rules; returns
/// the number of tiles with content.
fn check_tile(dir: &Path, tile: &Value, parent: Option<(f64, (DVec3, DVec3))>) -> usize {
    let error = tile["geometricError"].as_f64().expect("geometricError");
    assert!(error >= 0.0);
    let bounds = corners(tile);
    if let Some((pe, (pmin, pmax))) = parent {
        assert!(
            error < pe,
            "geometricError {error} not below its parent's {pe}"
        );
        let eps = 1e-3;
        assert!(
            bounds.0.cmpge(pmin - eps).all() && bounds.1.cmple(pmax + eps).all(),
            "a child's box {bounds:?} leaves its parent's {:?}",
            (pmin, pmax)
        );
    }
    if let Some(r) = tile.get("refine") {
        assert!(matches!(r.as_str(), Some("ADD" | "REPLACE")), "{r}");
    }
    let mut contents = 0;
    if let Some(c) = tile.get("content") {
        let uri = c["uri"].as_str().expect("content.uri");
        let bytes = std::fs::read(dir.join(uri)).unwrap();
        assert_eq!(&bytes[..4], b"glTF", "{uri}");
        contents += 1;
    }
    for child in tile["children"].as_array().into_iter().flatten() {
        contents += check_tile(dir, child, Some((error, bounds)));
    }
    contents
}

#[test]
fn the_tiles_are_valid_gltf_and_the_tileset_is_3d_tiles() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("tiles");
    let d = dir.to_str().unwrap();
    let tree = tree();
    let (ok, out) = plan_job_region(&tree, d, "4");
    assert!(ok, "{out}");
    assert!(out.contains("8 tiles over 2 levels"), "{out}");
    // The merge refuses a folder whose tiles have not run, naming them.
    let (ok, out) = karstic(&["tile", "merge", d], &[]);
    assert!(!ok && out.contains("8 of 8 tiles have not run"), "{out}");
    let (ok, out) = karstic(&["tile", "run", d, "--index", "8"], &[]);
    assert!(!ok && out.contains("tile index 8"), "{out}");
    let (ok, out) = karstic(&["tile", "run", d], &[]);
    assert!(!ok && out.contains("SLURM_ARRAY_TASK_ID"), "{out}");

    let (ok, out) = karstic(&["tile", "run", d, "--all"], &[]);
    assert!(ok, "{out}");
    let (ok, out) = karstic(&["tile", "merge", d], &[]);
    assert!(ok, "{out}");

    let tileset: Value =
        serde_json::from_slice(&std::fs::read(dir.join("tileset.json")).unwrap()).unwrap();
    assert_eq!(tileset["asset"]["version"], "1.1");
    let root = &tileset["root"];
    let top = tileset["geometricError"].as_f64().unwrap();
    assert!(top >= root["geometricError"].as_f64().unwrap());
    let contents = check_tile(&dir, root, None);
    assert_eq!(contents, 8);
    for entry in walk(&dir.join("tiles")) {
        if entry.extension().is_some_and(|e| e == "glb") {
            assert_valid(&entry);
        }
    }

    // The root transform puts the region on the Earth's surface near Jacksboro, Tennessee.
    let m: Vec<f64> = root["transform"]
        .as_array()
        .expect("a root transform (the DEM is UTM 16N)")
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let m = DMat4::from_cols_slice(&m);
    let (lo, hi) = corners(root);
    let p = m.transform_point3((lo + hi) * 0.5);
    let r = p.length();
    assert!(
        (6_360_000.0..6_380_000.0).contains(&r),
        "{p}: {r} m from the centre"
    );
    let lat = (p.z / r).asin().to_degrees();
    let lon = p.y.atan2(p.x).to_degrees();
    assert!(
        (lat - 36.4).abs() < 0.5 && (lon + 84.2).abs() < 0.5,
        "{lat} {lon}"
    );

    // An array task finds its index in the scheduler's variable and, on one thread, writes
    // the bytes the all-tiles run wrote on all of them.
    let again = tmp.path().join("again");
    std::fs::create_dir_all(&again).unwrap();
    std::fs::copy(dir.join("plan.json"), again.join("plan.json")).unwrap();
    for (var, index) in [("JOB_COMPLETION_INDEX", "3"), ("SLURM_ARRAY_TASK_ID", "7")] {
        let (ok, out) = karstic(
            &["tile", "run", again.to_str().unwrap()],
            &[(var, index), ("RAYON_NUM_THREADS", "1")],
        );
        assert!(ok, "{out}");
        assert!(out.contains(&format!("tile {index} (")), "{out}");
    }
    // A new plan in the same folder does not merge the tiles of the old one.
    let (ok, out) = plan_job_region(&tree, d, "4.4");
    assert!(ok, "{out}");
    let (ok, out) = karstic(&["tile", "merge", d], &[]);
    assert!(!ok && out.contains("were run for another plan"), "{out}");
    for stem in ["tiles/1/0_0", "tiles/1/4_0"] {
        for ext in ["glb", "json"] {
            let f = format!("{stem}.{ext}");
            assert_eq!(
                std::fs::read(dir.join(&f)).unwrap(),
                std::fs::read(again.join(&f)).unwrap(),
                "{f}"
            );
        }
    }
}

/// Every file under `dir`, in a fixed order.
fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for e in entries {
        if e.is_dir() {
            out.extend(walk(&e));
        } else {
            out.push(e);
        }
    }
    out
}

#[test]
fn a_slurm_job_array_gives_the_single_process_bytes() {
    let have = |tool: &str| {
        Command::new("sh")
            .args(["-c", &format!("command -v {tool}")])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if let Some(tool) = ["slurmctld", "slurmd", "sbatch", "munged"]
        .into_iter()
        .find(|t| !have(t))
    {
        unavailable(
            REQUIRE_SLURM,
            &format!("Slurm: {tool} not found (apt-get install slurm-wlm munge)"),
        );
        return;
    }
    let uid = Command::new("id").arg("-u").output().unwrap();
    if String::from_utf8_lossy(&uid.stdout).trim() != "0" {
        unavailable(REQUIRE_SLURM, "Slurm: the one-node cluster needs root");
        return;
    }
    let out = Command::new("bash")
        .arg(root().join(".ci/slurm.sh"))
        .arg(env!("CARGO_BIN_EXE_karstic"))
        .output()
        .unwrap();
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("8 tiles as array job") && text.contains("identical to a single-process run"),
        "{text}"
    );
}

/// `tile merge` checks what it merges: a tile's mesh truncated (or deleted) since its run,
/// and tiles run on different versions of an input (the DEM changed between two tasks of
/// the array) are refused, naming the tile; run again, the tiles merge.
#[test]
fn merge_refuses_changed_meshes_and_mixed_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let asc = dir.path().join("dem.asc");
    std::fs::copy(root().join("trees/data/jacksboro_crop.asc"), &asc).unwrap();
    let tree = dir.path().join("t.ron");
    std::fs::write(
        &tree,
        "(version: 1, root: Heightfield(source: \"dem.asc\", falloff: 60))",
    )
    .unwrap();
    let tiles = dir.path().join("tiles");
    let (t, d) = (tree.to_str().unwrap(), tiles.to_str().unwrap());
    let (ok, out) = karstic(
        &["tile", "plan", t, "-o", d, "--cell", "90", "--tile", "32"],
        &[],
    );
    assert!(ok, "{out}");
    let (ok, out) = karstic(&["tile", "run", d, "--all"], &[]);
    assert!(ok, "{out}");
    let (ok, out) = karstic(&["tile", "merge", d], &[]);
    assert!(ok, "{out}");
    // A mesh cut short after its run.
    let glb = tiles.join("tiles/0/0_0.glb");
    let bytes = std::fs::read(&glb).unwrap();
    std::fs::write(&glb, &bytes[..bytes.len() / 2]).unwrap();
    let (ok, out) = karstic(&["tile", "merge", d], &[]);
    assert!(
        !ok && out.contains("0_0.glb") && out.contains("run tile"),
        "{out}"
    );
    std::fs::remove_file(&glb).unwrap();
    let (ok, out) = karstic(&["tile", "merge", d], &[]);
    assert!(!ok && out.contains("0_0.glb"), "{out}");
    // The DEM raised by 50 m before one more task ran.
    let raised: String = std::fs::read_to_string(&asc)
        .unwrap()
        .lines()
        .enumerate()
        .map(|(i, l)| match i < 6 {
            true => format!("{l}\n"),
            false => {
                let v: Vec<String> = l
                    .split_whitespace()
                    .map(|v| format!("{}", v.parse::<f64>().unwrap() + 50.0))
                    .collect();
                format!("{}\n", v.join(" "))
            }
        })
        .collect();
    std::fs::write(&asc, raised).unwrap();
    let (ok, out) = karstic(&["tile", "run", d, "--index", "0"], &[]);
    assert!(ok, "{out}");
    let (ok, out) = karstic(&["tile", "merge", d], &[]);
    assert!(!ok && out.contains("different versions"), "{out}");
    let (ok, out) = karstic(&["tile", "run", d, "--all"], &[]);
    assert!(ok, "{out}");
    let (ok, out) = karstic(&["tile", "merge", d], &[]);
    assert!(ok, "{out}");
}

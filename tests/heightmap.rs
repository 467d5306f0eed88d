//! Issue 16, export: `karstic heightmap` — the top surface of a tree per column, on the
//! lattice and with the georeference of the scene's DEM.

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::{Vec2, Vec3};
use karstic::compile::Compiled;
use karstic::dem::{self, Dem, ReadOptions};
use karstic::field::{Field, ISO, Tree};
use karstic::heightmap::{HeightmapGrid, TopOptions, heightmap};

use crate::common::{REQUIRE_GDAL, unavailable};

const BUDGET: u64 = 1 << 30;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A scene of one DEM and nothing volumetric, written into `dir`.
fn dem_scene(dir: &Path, dem: &Path) -> PathBuf {
    let path = dir.join("plain.ron");
    let text = format!(
        "(version: 1, name: \"plain\", root: Heightfield(name: \"dem\", source: {:?}, falloff: 30.0, interpolation: Bicubic))",
        dem.display()
    );
    std::fs::write(&path, text).unwrap();
    path
}

fn compile(path: &Path) -> Compiled {
    karstic::scene::load(path).unwrap().compile().unwrap()
}

/// The heightmap of `c` at `cell` (default the DEM's), traced or direct.
fn top(c: &Compiled, cell: Option<f64>, direct: bool) -> (HeightmapGrid, Dem) {
    let grid = HeightmapGrid::new(
        c.ground.as_deref(),
        c.tree.support().footprint(),
        cell,
        None,
    )
    .unwrap();
    let tolerance = 1e-3 * grid.cell[0] as f32;
    let dem = heightmap(&c.tree, &grid, &TopOptions { tolerance, direct }, BUDGET).unwrap();
    (grid, dem)
}

#[test]
fn heightmap_of_a_dem_scene_is_its_dem_within_a_hundredth_of_a_cell() {
    let dir = tempfile::tempdir().unwrap();
    let source = root().join("trees/data/jacksboro_crop.asc");
    let c = compile(&dem_scene(dir.path(), &source));
    let ground = c.ground.clone().unwrap();
    let read = dem::read(&source, &ReadOptions::default()).unwrap();
    for direct in [false, true] {
        // At the DEM's own cell the samples are the DEM's.
        let (grid, hm) = top(&c, None, direct);
        assert_eq!(grid.size, [128, 128]);
        assert_eq!(hm.georef, read.georef, "georeferenced like the DEM");
        for j in 0..128 {
            for i in 0..128 {
                let (got, want) = (hm.heightfield.at(i, j), read.heightfield.at(i, j));
                if edge_ring(&grid, i, j) {
                    // The domain's edge: the 3D terrain ends there, no column has a top.
                    assert!(
                        got.is_nan(),
                        "({i}, {j}) direct {direct}: {got} on the edge"
                    );
                    continue;
                }
                assert!(
                    (got - want).abs() <= 0.9,
                    "({i}, {j}) direct {direct}: {got} vs the DEM's {want} (cells of 90 m)"
                );
            }
        }
        // At another cell, the DEM's surface between its samples.
        let (grid, hm) = top(&c, Some(37.0), direct);
        assert_eq!(grid.size, [(127.0 * 90.0 / 37.0) as usize + 1; 2]);
        for j in 0..grid.size[1] {
            for i in 0..grid.size[0] {
                let (got, want) = (hm.heightfield.at(i, j), ground.height(grid.at(i, j)));
                if edge_ring(&grid, i, j) && got.is_nan() {
                    continue;
                }
                assert!(
                    (got - want).abs() <= 0.37,
                    "({i}, {j}) direct {direct}: {got} vs {want}"
                );
            }
        }
    }
}

/// Whether sample `(i, j)` is on the grid's outer ring, where the heightfield leaf's
/// domain ends (its field only reaches `T` inside).
fn edge_ring(grid: &HeightmapGrid, i: usize, j: usize) -> bool {
    i == 0 || j == 0 || i + 1 == grid.size[0] || j + 1 == grid.size[1]
}

/// The column tops of `c` over the rectangle `(min, max)` at a 2 m cell, located to
/// `tolerance` (direct where the tree is a heightfield).
fn tops_over(c: &Compiled, (min, max): (Vec2, Vec2), tolerance: f32) -> (HeightmapGrid, Dem) {
    let rect = karstic::field::Rect::new(min, max);
    let grid = HeightmapGrid::new(
        c.ground.as_deref(),
        c.tree.support().footprint(),
        Some(2.0),
        Some(rect),
    )
    .unwrap();
    let opts = TopOptions {
        tolerance,
        direct: true,
    };
    let hm = heightmap(&c.tree, &grid, &opts, BUDGET).unwrap();
    (grid, hm)
}

/// The highest solid sample of the column over `xy`, scanning down in steps of `dz`.
fn brute_top(t: &Tree, xy: Vec2, dz: f32) -> Option<f32> {
    let s = t.support();
    let n = ((s.max.z - s.min.z) / dz) as usize;
    (0..=n)
        .map(|k| s.max.z - k as f32 * dz)
        .find(|&z| t.value(xy.extend(z)) > ISO)
}

#[test]
fn over_the_main_jobs_arch_the_top_is_the_arch() {
    let c = compile(&root().join("trees/jacksboro_caves.ron"));
    let ground = c.ground.clone().unwrap();
    // Over the middle of the opening (the span runs from (4250, 5012) to (4300, 4992)).
    let (grid, hm) = tops_over(
        &c,
        (Vec2::new(4264.0, 4996.0), Vec2::new(4286.0, 5008.0)),
        0.01,
    );
    let mut over = 0;
    for j in 0..grid.size[1] {
        for i in 0..grid.size[0] {
            let xy = grid.at(i, j);
            let got = hm.heightfield.at(i, j);
            let want = brute_top(&c.tree, xy, 0.02).expect("solid in the column");
            assert!((got - want).abs() <= 0.05, "{xy}: top {got}, scan {want}");
            // Just above the top: empty; just below: solid.
            assert!(c.tree.value(xy.extend(got + 0.05)) < ISO);
            assert!(c.tree.value(xy.extend(got - 0.05)) > ISO);
            // The arch's lintel stands far above the ground.
            let floor = ground.height(xy);
            if got > floor + 20.0 {
                over += 1;
                // Below the arch's top there is air before the ground.
                let gap = (1..200).any(|k| {
                    let z = got - k as f32 * (got - floor) / 200.0;
                    c.tree.value(Vec3::new(xy.x, xy.y, z)) < ISO
                });
                assert!(
                    gap,
                    "{xy}: no air under the arch's top {got} (ground {floor})"
                );
            }
        }
    }
    assert!(over > 10, "only {over} columns over the arch");
}

#[test]
fn heightmaps_round_trip_through_our_readers() {
    let dir = tempfile::tempdir().unwrap();
    let source = root().join("trees/data/jacksboro_crop.asc");
    let c = compile(&dem_scene(dir.path(), &source));
    let (_, hm) = top(&c, Some(45.0), true);
    let (lo, hi) = hm.heightfield.z_range().unwrap();
    for (name, tol) in [
        ("top.tif", 0.0),
        ("top.png", (hi - lo) / 65535.0),
        ("top.asc", 1e-3),
    ] {
        let path = dir.path().join(name);
        dem::write(&hm, &path).unwrap();
        let back = dem::read(&path, &ReadOptions::default()).unwrap();
        assert_eq!(back.heightfield.nx(), hm.heightfield.nx(), "{name}");
        assert_eq!(back.heightfield.ny(), hm.heightfield.ny(), "{name}");
        assert_eq!(back.georef.crs, hm.georef.crs, "{name}");
        for k in 0..2 {
            assert!(
                (back.georef.origin[k] - hm.georef.origin[k]).abs() < 1e-6,
                "{name}"
            );
            assert!(
                (back.georef.step[k] - hm.georef.step[k]).abs() < 1e-9,
                "{name}"
            );
        }
        let worst = back
            .heightfield
            .samples()
            .iter()
            .zip(hm.heightfield.samples())
            .map(|(a, b)| {
                assert_eq!(a.is_nan(), b.is_nan(), "{name}: nodata moved");
                if a.is_nan() { 0.0 } else { (a - b).abs() }
            })
            .fold(0.0f32, f32::max);
        assert!(worst <= tol * 1.01 + 1e-4, "{name}: {worst}");
    }
}

/// `gdalinfo -json FILE` (GDAL's own reader, not ours), or `None` (with a notice, or a failure where GDAL is required)
/// when `gdalinfo` cannot run.
fn gdalinfo(file: &Path) -> Option<serde_json::Value> {
    match Command::new("gdalinfo").arg("-json").arg(file).output() {
        Ok(o) if o.status.success() => Some(serde_json::from_slice(&o.stdout).unwrap()),
        Ok(o) => panic!(
            "gdalinfo {}: {}",
            file.display(),
            String::from_utf8_lossy(&o.stderr)
        ),
        Err(e) => {
            unavailable(REQUIRE_GDAL, &format!("gdalinfo cannot run ({e})"));
            None
        }
    }
}

#[test]
fn gdal_reads_the_heightmap_with_the_dems_size_crs_and_geotransform() {
    let dir = tempfile::tempdir().unwrap();
    let source = root().join("../shared/data/dem/jacksboro_utm16n_90m.tif");
    let tree = dem_scene(dir.path(), &source);
    let out = dir.path().join("top.tif");
    let o = Command::new(env!("CARGO_BIN_EXE_karstic"))
        .args([
            "heightmap".as_ref(),
            tree.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let Some(want) = gdalinfo(&source) else {
        return;
    };
    let got = gdalinfo(&out).unwrap();
    println!("gdal: {}", got["driverLongName"]);
    assert_eq!(got["size"], want["size"]);
    assert_eq!(got["size"], serde_json::json!([344, 363]));
    let epsg = |v: &serde_json::Value| v["stac"]["proj:epsg"].as_i64();
    assert_eq!(epsg(&got), Some(32616), "{}", got["coordinateSystem"]);
    assert_eq!(epsg(&got), epsg(&want));
    let gt = |v: &serde_json::Value| -> Vec<f64> {
        v["geoTransform"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    for (a, b) in gt(&got).iter().zip(gt(&want)) {
        assert!((a - b).abs() < 1e-6, "{:?} vs {:?}", gt(&got), gt(&want));
    }
    assert_eq!(got["bands"][0]["type"], "Float32");
}

/// An arch standing on the DEM (a rotated fin less a noisy carved opening): the local
/// Lipschitz bounds over its columns are loose (hundreds), the tracer's steps millimetres,
/// and a column whose band ran out of steps took the top of a band far below (z = 180 m
/// under ground at 626 m).
#[test]
fn column_tops_over_a_carved_arch_are_the_scanned_tops() {
    let dem = root().join("trees/data/jacksboro_crop.asc");
    let text = format!(
        "(version: 1, seed: 11, root: Landform(name: \"arch\", seed: 5, cell: 5.0, \
         region: (min: (4120, 4900, 500), max: (4440, 5100, 760)), \
         base: Heightfield(name: \"dem\", source: {:?}, falloff: 30.0, interpolation: Bicubic), \
         generator: Arch(from: (4250, 5012), to: (4300, 4992), weathering: 0)))",
        dem.display()
    );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("arch.ron");
    std::fs::write(&path, text).unwrap();
    let c = compile(&path);
    let (grid, hm) = tops_over(
        &c,
        (Vec2::new(4236.0, 5000.0), Vec2::new(4264.0, 5030.0)),
        0.002,
    );
    for j in 0..grid.size[1] {
        for i in 0..grid.size[0] {
            let xy = grid.at(i, j);
            let want = brute_top(&c.tree, xy, 0.02).expect("solid in the column");
            let got = hm.heightfield.at(i, j);
            assert!((got - want).abs() <= 0.05, "{xy}: top {got}, scan {want}");
        }
    }
}

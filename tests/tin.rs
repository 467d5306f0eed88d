//! Issue 16, export: `karstic tin` — greedy-insertion TINs within a vertical error of
//! every grid point of their source, and valid triangulations of its extent.

use std::process::Command;

use glam::Vec2;
use karstic::dem::{self, Heightfield, ReadOptions};
use karstic::mesh::tin::{Tin, TinError, greedy};

use crate::common::Rng;
use crate::gltf_validator;

const BUDGET: u64 = 1 << 30;

/// A rough procedural heightfield: sines and white noise, `nx × ny` samples of 7 m.
fn procedural(nx: usize, ny: usize) -> Heightfield {
    let mut rng = Rng(16);
    let z = (0..nx * ny)
        .map(|k| {
            let (x, y) = ((k % nx) as f32, (k / nx) as f32);
            300.0
                + 80.0 * (0.07 * x).sin() * (0.05 * y).cos()
                + 30.0 * (0.31 * x + 0.17 * y).sin()
                + 4.0 * rng.f32()
        })
        .collect();
    Heightfield::new(nx, ny, Vec2::new(-120.0, 40.0), Vec2::splat(7.0), z).unwrap()
}

/// The bundled Jacksboro crop (128² samples of 90 m).
fn jacksboro() -> Heightfield {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/trees/data/jacksboro_crop.asc");
    dem::read(path.as_ref(), &ReadOptions::default())
        .unwrap()
        .heightfield
}

/// Checks, independently of the TIN's own bookkeeping, that `tin` triangulates the
/// extent of `hf` (every triangle counter-clockwise, areas summing to the extent, every
/// grid point inside some triangle) with its vertices on grid points, and returns the
/// largest vertical distance between the TIN and a grid point.
fn check(tin: &Tin, hf: &Heightfield) -> f64 {
    let (nx, ny) = (hf.nx(), hf.ny());
    let (o, c) = (hf.origin(), hf.cell());
    // Vertices back to grid indices: they must be grid points with the grid's heights.
    let grid: Vec<[i64; 2]> = tin
        .positions
        .iter()
        .map(|p| {
            let i = ((p[0] - o.x) / c.x).round();
            let j = ((p[1] - o.y) / c.y).round();
            assert!((o.x + i * c.x - p[0]).abs() < 1e-3 && (o.y + j * c.y - p[1]).abs() < 1e-3);
            let (i, j) = (i as usize, j as usize);
            assert!(i < nx && j < ny, "{p:?} outside the grid");
            assert_eq!(p[2], hf.at(i, j), "vertex ({i}, {j}) off the grid's height");
            [i as i64, j as i64]
        })
        .collect();
    let orient = |p: [i64; 2], q: [i64; 2], r: [i64; 2]| {
        (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    };
    let mut area2 = 0i64;
    let mut covered = vec![false; nx * ny];
    let mut worst = 0.0f64;
    for t in &tin.triangles {
        let [a, b, c] = t.map(|v| grid[v as usize]);
        let z = t.map(|v| f64::from(tin.positions[v as usize][2]));
        let det = orient(a, b, c);
        assert!(
            det > 0,
            "triangle {t:?} is not counter-clockwise seen from above"
        );
        area2 += det;
        for y in a[1].min(b[1]).min(c[1])..=a[1].max(b[1]).max(c[1]) {
            for x in a[0].min(b[0]).min(c[0])..=a[0].max(b[0]).max(c[0]) {
                let r = [x, y];
                let (wa, wb, wc) = (orient(b, c, r), orient(c, a, r), orient(a, b, r));
                if wa < 0 || wb < 0 || wc < 0 {
                    continue;
                }
                let k = x as usize + nx * y as usize;
                covered[k] = true;
                let p = (wa as f64 * z[0] + wb as f64 * z[1] + wc as f64 * z[2]) / det as f64;
                worst = worst.max((p - f64::from(hf.samples()[k])).abs());
            }
        }
    }
    assert_eq!(
        area2,
        2 * (nx as i64 - 1) * (ny as i64 - 1),
        "the triangles' areas do not add up to the grid's extent"
    );
    assert!(
        covered.iter().all(|&c| c),
        "some grid point is in no triangle"
    );
    worst
}

#[test]
fn tin_error_is_within_the_bound_at_every_grid_point() {
    for (name, hf) in [
        ("procedural", procedural(157, 101)),
        ("jacksboro", jacksboro()),
    ] {
        let mut last = usize::MAX;
        for e in [0.5, 2.0, 8.0, 30.0] {
            let tin = greedy(&hf, e, BUDGET).unwrap();
            let worst = check(&tin, &hf);
            assert!(
                worst <= e + 1e-9,
                "{name} E = {e}: error {worst} at a grid point"
            );
            assert!(
                (tin.max_error - worst).abs() < 1e-6,
                "{name} E = {e}: reported {} but the grid says {worst}",
                tin.max_error
            );
            // A looser bound takes fewer triangles, and the bound is used: greedy
            // insertion stops as soon as the worst point is within it.
            assert!(tin.triangles.len() < last, "{name} E = {e}");
            assert!(
                tin.triangles.len() < 2 * (hf.nx() - 1) * (hf.ny() - 1),
                "{name} E = {e}: every grid point inserted"
            );
            last = tin.triangles.len();
        }
    }
}

#[test]
fn a_zero_bound_keeps_every_grid_point_that_is_off_a_plane() {
    let hf = procedural(23, 17);
    let tin = greedy(&hf, 0.0, BUDGET).unwrap();
    assert!(check(&tin, &hf) < 1e-9);
    // A tilted plane needs its four corners only.
    let z = (0..23 * 17)
        .map(|k| (k % 23) as f32 * 0.5 + (k / 23) as f32 * 2.0)
        .collect();
    let plane = Heightfield::new(23, 17, Vec2::ZERO, Vec2::ONE, z).unwrap();
    let tin = greedy(&plane, 1e-4, BUDGET).unwrap();
    assert_eq!((tin.positions.len(), tin.triangles.len()), (4, 2));
    assert!(check(&tin, &plane) <= 1e-4);
}

#[test]
fn empty_grids_and_bad_bounds_are_errors() {
    let hf = Heightfield::new(4, 4, Vec2::ZERO, Vec2::ONE, vec![f32::NAN; 16]).unwrap();
    assert!(matches!(greedy(&hf, 1.0, BUDGET), Err(TinError::NoData)));
    let hf = procedural(5, 5);
    for e in [-1.0, f64::NAN, f64::INFINITY] {
        assert!(
            matches!(greedy(&hf, e, BUDGET), Err(TinError::Bound(_))),
            "{e}"
        );
    }
    let err = greedy(&hf, 1.0, 100).unwrap_err().to_string();
    assert!(err.contains("5×5"), "{err}");
}

#[test]
fn cli_writes_a_valid_gltf_tin_of_a_dem_and_of_a_tree() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("crop.glb");
    let run = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_karstic"))
            .args(args)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let o = out.to_str().unwrap();
    let err = run(&[
        "tin",
        "trees/data/jacksboro_crop.asc",
        "-o",
        o,
        "--max-error",
        "10",
    ]);
    assert!(err.contains("max error") && err.contains("≤ 10 m"), "{err}");
    gltf_validator::assert_valid(&out);
    let tree = dir.path().join("arch.gltf");
    let t = tree.to_str().unwrap();
    let err = run(&[
        "tin",
        "trees/arch.ron",
        "-o",
        t,
        "--max-error",
        "0.5",
        "--cell",
        "2",
        "--region",
        "-50",
        "-30",
        "50",
        "30",
    ]);
    assert!(err.contains("triangles"), "{err}");
    gltf_validator::assert_valid(&tree);
    // Heightmap flags place a tree's samples; a DEM keeps its own grid.
    let o = Command::new(env!("CARGO_BIN_EXE_karstic"))
        .args([
            "tin",
            "trees/data/jacksboro_crop.asc",
            "-o",
            o,
            "--max-error",
            "1",
        ])
        .args(["--cell", "30"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("--cell"), "{err}");
}

/// A DEM with nodata (the bundled UTM DEM's rotated edges: 6,742 void samples) is
/// triangulated over its valid area: no vertex in a void, no triangle over a void sample,
/// the bound held at every valid grid point it covers, and every valid point whose 3 × 3
/// neighbourhood is valid covered (it refused: "a TIN needs every grid point").
#[test]
fn a_dem_with_voids_is_triangulated_over_its_valid_area() {
    let d = dem::read(
        std::path::Path::new("../shared/data/dem/jacksboro_utm16n_90m.tif"),
        &ReadOptions::default(),
    )
    .unwrap();
    let hf = &d.heightfield;
    assert!(hf.nodata_count() > 1000);
    let tin = greedy(hf, 5.0, BUDGET).unwrap();
    let (lo, hi) = hf.z_range().unwrap();
    assert!(tin.positions.iter().all(|p| (lo..=hi).contains(&p[2])));
    let (nx, ny) = (hf.nx(), hf.ny());
    let (o, c) = (hf.origin(), hf.cell());
    let mut covered = vec![false; nx * ny];
    for t in &tin.triangles {
        let p = t.map(|v| tin.positions[v as usize]);
        let g = p.map(|q| Vec2::new((q[0] - o.x) / c.x, (q[1] - o.y) / c.y));
        let (i0, i1) = (
            g.iter().map(|v| v.x).fold(f32::MAX, f32::min),
            g.iter().map(|v| v.x).fold(f32::MIN, f32::max),
        );
        let (j0, j1) = (
            g.iter().map(|v| v.y).fold(f32::MAX, f32::min),
            g.iter().map(|v| v.y).fold(f32::MIN, f32::max),
        );
        let area = (g[1] - g[0]).perp_dot(g[2] - g[0]);
        for j in j0.round() as usize..=j1.round() as usize {
            for i in i0.round() as usize..=i1.round() as usize {
                let q = Vec2::new(i as f32, j as f32);
                let w = [
                    (g[2] - g[1]).perp_dot(q - g[1]) / area,
                    (g[0] - g[2]).perp_dot(q - g[2]) / area,
                    (g[1] - g[0]).perp_dot(q - g[0]) / area,
                ];
                if w.iter().any(|&w| w < -1e-4) {
                    continue;
                }
                let h = hf.at(i, j);
                assert!(!h.is_nan(), "a triangle covers the void sample ({i}, {j})");
                let z = w[0] * p[0][2] + w[1] * p[1][2] + w[2] * p[2][2];
                assert!((z - h).abs() <= 5.0 + 1e-2, "({i}, {j}): {z} against {h}");
                covered[i + nx * j] = true;
            }
        }
    }
    let inner = |i: usize, j: usize| {
        i > 0
            && j > 0
            && i + 1 < nx
            && j + 1 < ny
            && (j - 1..=j + 1).all(|b| (i - 1..=i + 1).all(|a| !hf.at(a, b).is_nan()))
    };
    let missed = (0..ny)
        .flat_map(|j| (0..nx).map(move |i| (i, j)))
        .filter(|&(i, j)| inner(i, j) && !covered[i + nx * j])
        .count();
    assert_eq!(
        missed, 0,
        "valid points inside the valid area left uncovered"
    );
}

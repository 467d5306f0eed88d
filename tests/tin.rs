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
fn voids_and_bad_bounds_are_errors() {
    let mut z = vec![1.0f32; 16];
    z[5] = f32::NAN;
    let hf = Heightfield::new(4, 4, Vec2::ZERO, Vec2::ONE, z).unwrap();
    assert!(matches!(greedy(&hf, 1.0, BUDGET), Err(TinError::NoData(1))));
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

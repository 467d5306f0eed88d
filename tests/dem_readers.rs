//! The readers on the real Jacksboro DEM in `../shared/data/dem/` (written by GDAL), and
//! round trips through our writers.

use std::path::{Path, PathBuf};

use karstic::dem::{self, Crs, Dem, Heightfield, ReadOptions};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data/dem")
        .join(name)
}

fn read(name: &str) -> Dem {
    dem::read(&data(name), &ReadOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Largest |a − b| over samples valid in both; panics when the nodata masks differ.
fn max_diff(a: &Heightfield, b: &Heightfield) -> f32 {
    assert_eq!((a.nx(), a.ny()), (b.nx(), b.ny()));
    let mut worst = 0.0f32;
    for (k, (x, y)) in a.samples().iter().zip(b.samples()).enumerate() {
        assert_eq!(x.is_nan(), y.is_nan(), "nodata differs at sample {k}");
        if !x.is_nan() {
            worst = worst.max((x - y).abs());
        }
    }
    worst
}

/// `jacksboro.json`: 403 × 344, 3″ cells, north-west corner (−84.41375, 36.7329166…), PNG
/// raw 0 ↦ 236 m, 65535 ↦ 1076 m.
const NW: [f64; 2] = [-84.41375, 36.73291666666667];
const STEP: f64 = 0.000_833_333_333_333_333_4;

#[test]
fn geographic_formats_decode_to_the_same_elevations() {
    let i16 = read("jacksboro_int16.tif");
    let f32 = read("jacksboro_float32.tif");
    let asc = read("jacksboro.asc");
    let png = read("jacksboro_u16.png");
    let h = &i16.heightfield;
    assert_eq!((h.nx(), h.ny()), (403, 344));
    assert_eq!(h.nodata_count(), 0);
    assert_eq!(h.z_range(), Some((236.0, 1076.0)));
    // the file's first row is the north: row 0, column 0 is 483 m, the next 487 m
    assert_eq!(h.at(0, 343), 483.0);
    assert_eq!(h.at(1, 343), 487.0);
    assert_eq!(max_diff(h, &f32.heightfield), 0.0);
    assert_eq!(max_diff(h, &asc.heightfield), 0.0);
    let q = (1076.0 - 236.0) / 65535.0;
    let d = max_diff(h, &png.heightfield);
    assert!(d <= 0.5 * q + 1e-4, "PNG differs by {d} m, quantum {q}");

    for (name, d) in [
        ("int16", &i16),
        ("float32", &f32),
        ("asc", &asc),
        ("png", &png),
    ] {
        let g = &d.georef;
        assert_eq!(g.crs, Crs::Geographic { epsg: Some(4326) }, "{name}");
        // the south-west sample is the centre of the south-west pixel
        let sw = [NW[0] + 0.5 * STEP, NW[1] - 343.5 * STEP];
        assert!(
            (g.origin[0] - sw[0]).abs() < 1e-9 && (g.origin[1] - sw[1]).abs() < 1e-9,
            "{name}: {:?}",
            g.origin
        );
        assert!(
            (g.step[0] - STEP).abs() < 1e-12 && (g.step[1] - STEP).abs() < 1e-12,
            "{name}"
        );
        // metres at the centre latitude (≈ 36.59°): 74.6 m × 92.5 m
        let c = d.heightfield.cell();
        assert!(
            (c.x - 74.58).abs() < 0.1 && (c.y - 92.48).abs() < 0.1,
            "{name}: {c}"
        );
        assert!(
            d.notices.iter().any(|n| n.contains("centre latitude")),
            "{name}: {:?}",
            d.notices
        );
    }
}

#[test]
fn utm_geotransform_and_nodata_match_gdal() {
    let tif = read("jacksboro_utm16n_90m.tif");
    let asc = read("jacksboro_utm16n_90m.asc");
    for (name, d) in [("tif", &tif), ("asc", &asc)] {
        let (h, g) = (&d.heightfield, &d.georef);
        assert_eq!((h.nx(), h.ny()), (344, 363), "{name}");
        assert_eq!(g.crs, Crs::Projected { epsg: Some(32616) }, "{name}");
        assert_eq!(g.step, [90.0, 90.0]);
        assert_eq!(h.cell(), glam::Vec2::splat(90.0));
        // GDAL: xllcorner 730939.219465799048, yllcorner 4036556.162225268781
        let sw = [730_939.219_465_799 + 45.0, 4_036_556.162_225_269 + 45.0];
        assert!(
            (g.origin[0] - sw[0]).abs() < 1e-6 && (g.origin[1] - sw[1]).abs() < 1e-6,
            "{name}: {:?}",
            g.origin
        );
        // and the tiepoint: top-left corner (730939.219465799, 4069226.162225269)
        let nw = g.north_west_corner(h.ny());
        assert!(
            (nw[0] - 730_939.219_465_799).abs() < 1e-6
                && (nw[1] - 4_069_226.162_225_269).abs() < 1e-6
        );
        assert_eq!(
            h.nodata_count(),
            6742,
            "{name}: the rotated edges are nodata"
        );
        let (lo, hi) = h.z_range().unwrap();
        assert!(
            (lo - 242.478_33).abs() < 0.01 && (hi - 1_072.204_3).abs() < 0.01,
            "{name}: {lo} {hi}"
        );
        assert!(d.notices.is_empty(), "{name}: {:?}", d.notices);
    }
    // the ASCII grid prints two decimals
    assert!(max_diff(&tif.heightfield, &asc.heightfield) <= 0.005 + 1e-4);
    // local ↔ UTM: the south-west sample is local (0, 0)
    let g = &tif.georef;
    let p = g.local_to_crs([900.0, 1800.0]);
    assert!(
        (p[0] - g.origin[0] - 900.0).abs() < 1e-9 && (p[1] - g.origin[1] - 1800.0).abs() < 1e-9
    );
}

#[test]
fn written_files_read_back_identically() {
    let dir = tempfile::tempdir().unwrap();
    for src in ["jacksboro_utm16n_90m.tif", "jacksboro_int16.tif"] {
        let d = read(src);
        for ext in ["tif", "asc", "png"] {
            let out = dir.path().join(format!("out.{ext}"));
            dem::write(&d, &out).unwrap();
            let back = dem::read(&out, &ReadOptions::default()).unwrap();
            let diff = max_diff(&d.heightfield, &back.heightfield);
            let (lo, hi) = d.heightfield.z_range().unwrap();
            let tol = if ext == "png" {
                0.5 * (hi - lo) / 65534.0 + 1e-4
            } else {
                0.0
            };
            assert!(diff <= tol, "{src} → {ext}: {diff} > {tol}");
            let (a, b) = (&d.georef, &back.georef);
            assert_eq!(a.crs, b.crs, "{src} → {ext}");
            for k in 0..2 {
                assert!(
                    (a.origin[k] - b.origin[k]).abs() < 1e-9 * a.origin[k].abs().max(1.0),
                    "{src} → {ext}: {a:?} vs {b:?}"
                );
                assert!(
                    (a.step[k] - b.step[k]).abs() < 1e-12 * a.step[k],
                    "{src} → {ext}"
                );
            }
            assert_eq!(
                d.heightfield.cell(),
                back.heightfield.cell(),
                "{src} → {ext}"
            );
        }
    }
}

#[test]
fn resampling_the_utm_dem_to_30m() {
    let d = read("jacksboro_utm16n_90m.tif");
    let r = d
        .resample(30.0, dem::Interpolation::Bilinear, 1 << 30)
        .unwrap();
    let h = &r.heightfield;
    assert_eq!((h.nx(), h.ny()), (1030, 1087));
    assert_eq!(r.georef.step, [30.0, 30.0]);
    assert_eq!(r.georef.origin, d.georef.origin);
    // every third sample is an original one
    for (i, j) in [(100, 100), (200, 50), (150, 300)] {
        let (a, b) = (d.heightfield.at(i, j), h.at(3 * i, 3 * j));
        assert!(a.is_nan() && b.is_nan() || (a - b).abs() < 1e-3, "{a} {b}");
    }
}

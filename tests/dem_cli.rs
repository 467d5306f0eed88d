//! `karstic dem info` and `karstic dem convert` end to end.

use std::path::Path;
use std::process::Command;

fn karstic(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_karstic"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn info_reports_size_cells_crs_range_and_nodata() {
    let (ok, out, err) = karstic(&["dem", "info", "../shared/data/dem/jacksboro_utm16n_90m.tif"]);
    assert!(ok, "{err}");
    for want in [
        "344 × 363 samples",
        "90.000 m × 90.000 m",
        "projected (EPSG:32616)",
        "242.48 .. 1072.20 m",
        "6742 samples",
    ] {
        assert!(out.contains(want), "{want:?} missing from:\n{out}");
    }
    let (ok, out, err) = karstic(&["dem", "info", "../shared/data/dem/jacksboro.asc"]);
    assert!(
        ok && out.contains("geographic (EPSG:4326)") && out.contains("74.573 m"),
        "{out}"
    );
    assert!(
        err.contains("note: geographic DEM"),
        "the degree notice goes to stderr: {err}"
    );
}

#[test]
fn convert_resamples_and_writes_readable_files() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("utm30.png");
    let png_s = png.to_str().unwrap();
    let (ok, _, err) = karstic(&[
        "dem",
        "convert",
        "../shared/data/dem/jacksboro_utm16n_90m.tif",
        "-o",
        png_s,
        "--resample",
        "30",
    ]);
    assert!(ok, "{err}");
    assert!(
        Path::new(&png.with_extension("json")).is_file(),
        "the sidecar is written"
    );
    let (ok, out, err) = karstic(&["dem", "info", png_s]);
    assert!(ok, "{err}");
    assert!(
        out.contains("1030 × 1087 samples")
            && out.contains("30.000 m × 30.000 m")
            && out.contains("EPSG:32616"),
        "{out}"
    );
}

#[test]
fn errors_name_the_file_and_exit_non_zero() {
    let (ok, _, err) = karstic(&["dem", "info", "tests/data/dem_corpus/nan.asc"]);
    assert!(!ok);
    assert!(
        err.contains("nan.asc:8:3: expected a finite number"),
        "{err}"
    );
    let (ok, _, err) = karstic(&[
        "dem",
        "info",
        "tests/data/dem_corpus/huge.tif",
        "--max-memory",
        "1M",
    ]);
    assert!(!ok && err.contains("memory budget is 1.0 MiB"), "{err}");
    let (ok, _, err) = karstic(&[
        "dem",
        "info",
        "tests/data/dem_corpus/no_sidecar.png",
        "--z-range",
        "-10",
        "300",
    ]);
    assert!(ok, "an explicit range replaces the sidecar: {err}");
}

/// `dem info` prints the origin of a tree's frame, the south-west sample's centre: half a
/// cell inside the header's outer corner (the main job's docs said the corner, 45 m and
/// 90 m off), and the heightmap export's geotransform agrees with it.
#[test]
fn dem_info_prints_the_frame_origin_the_exports_use() {
    let crop = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/data/jacksboro_crop.asc");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_karstic"))
        .args(["dem", "info"])
        .arg(&crop)
        .output()
        .unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    let line = text
        .lines()
        .find(|l| l.starts_with("origin"))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(
        line.contains("(744664.219465799, 4037591.162225269)"),
        "{line}"
    );
    let d = karstic::dem::read(&crop, &karstic::dem::ReadOptions::default()).unwrap();
    assert_eq!(
        d.georef.local_to_crs([0.0, 0.0]),
        [744664.219465799, 4037591.162225269]
    );
}

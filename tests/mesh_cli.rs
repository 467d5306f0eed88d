//! `karstic build` and `karstic sample` from the command line.

use std::path::Path;
use std::process::Command;

use glam::Vec3;
use karstic::io::write_atomic;
use karstic::mesh::npy;
use karstic::mesh::sample::{Sidecar, grid_spanning};

fn karstic(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_karstic"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Writes a 40³ grid of a ball of radius 0.8 (value 1 − |p|/0.8 + 0.5 so iso 0.5).
fn write_ball(path: &Path) {
    let spec = grid_spanning(&karstic::field::Aabb::around(Vec3::ZERO, 1.0), [40, 40, 40]).unwrap();
    let mut values = Vec::new();
    for k in 0..40 {
        for j in 0..40 {
            for i in 0..40 {
                let p = spec.origin + Vec3::new(i as f32, j as f32, k as f32) * spec.step;
                values.push(0.5 + (0.8 - p.length()));
            }
        }
    }
    let side = Sidecar::new(&spec, &values);
    write_atomic(path, |w| npy::write_f32(w, &side.shape, &values)).unwrap();
    std::fs::write(
        Sidecar::path_for(path),
        serde_json::to_string(&side).unwrap(),
    )
    .unwrap();
}

#[test]
fn builds_a_sampled_grid_with_stats() {
    let dir = tempfile::tempdir().unwrap();
    let grid = dir.path().join("ball.npy");
    write_ball(&grid);
    let out = dir.path().join("ball.glb");
    let (ok, stdout, stderr) = karstic(&[
        "build",
        grid.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--stats",
        "--tint",
    ]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("#C0") && stdout.contains("triangles"),
        "{stdout}"
    );
    assert!(stderr.contains("vertices"), "{stderr}");
    let bytes = std::fs::read(&out).unwrap();
    assert_eq!(&bytes[..4], b"glTF");
    for ext in ["obj", "ply", "gltf"] {
        let o = dir.path().join(format!("ball.{ext}"));
        let (ok, _, stderr) = karstic(&[
            "build",
            grid.to_str().unwrap(),
            "-o",
            o.to_str().unwrap(),
            "--quiet",
        ]);
        assert!(ok && stderr.is_empty(), "{stderr}");
        assert!(o.exists());
    }
    // A grid beside a sidecar of other values, same shape (a sample killed between its
    // two renames): refused, not meshed in the wrong place.
    let side = Sidecar::path_for(&grid);
    let text = std::fs::read_to_string(&side).unwrap();
    let mut other: Sidecar = serde_json::from_str(&text).unwrap();
    other.values = Some(Sidecar::hash(&[0.0; 3]));
    std::fs::write(&side, serde_json::to_string(&other).unwrap()).unwrap();
    let (ok, _, stderr) = karstic(&["build", grid.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(
        !ok && stderr.contains("written for other values"),
        "{stderr}"
    );
}

#[test]
fn refuses_what_it_cannot_do() {
    let dir = tempfile::tempdir().unwrap();
    let grid = dir.path().join("ball.npy");
    write_ball(&grid);
    let g = grid.to_str().unwrap();
    let out = dir.path().join("x.glb");
    let o = out.to_str().unwrap();
    // Over the memory budget: refused, saying how much it needs, nothing written.
    let (ok, _, err) = karstic(&["build", g, "-o", o, "--max-memory", "1000"]);
    assert!(!ok && err.contains("would need"), "{err}");
    assert!(!out.exists());
    // Unknown output format.
    let (ok, _, err) = karstic(&["build", g, "-o", "x.stl"]);
    assert!(!ok && err.contains("x.stl"), "{err}");
    // Grid flags on a grid.
    let (ok, _, err) = karstic(&["build", g, "-o", o, "--cell", "2"]);
    assert!(!ok && err.contains("--cell"), "{err}");
    // A tree that does not exist: the error names it.
    let (ok, _, err) = karstic(&["build", "no/such/tree.ron", "-o", o]);
    assert!(!ok && err.contains("no/such/tree.ron"), "{err}");
    let (ok, _, err) = karstic(&[
        "sample",
        "no/such/tree.ron",
        "--res",
        "4",
        "4",
        "4",
        "-o",
        "f.npy",
    ]);
    assert!(!ok && err.contains("no/such/tree.ron"), "{err}");
    // A grid without its sidecar.
    std::fs::remove_file(Sidecar::path_for(&grid)).unwrap();
    let (ok, _, err) = karstic(&["build", g, "-o", o]);
    assert!(!ok && err.contains("ball.json"), "{err}");
}

/// A section on a plane is one sample thick: `--res NX 1 NZ` over a box flat in y samples
/// the plane (it was refused: "each axis needs at least 2 samples").
#[test]
fn samples_a_section_on_a_plane() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.npy");
    let tree = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/arch.ron");
    let sample = |ny: &str| {
        let (t, o) = (tree.to_str().unwrap(), out.to_str().unwrap());
        let flat = ["-20", "0", "0", "20", "0", "30"];
        let mut args = vec!["sample", t, "--box"];
        args.extend(flat);
        args.extend(["--res", "41", ny, "31", "-o", o]);
        karstic(&args)
    };
    let (ok, _, err) = sample("1");
    assert!(ok, "{err}");
    let side: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("s.json")).unwrap()).unwrap();
    assert_eq!(side["shape"], serde_json::json!([31, 1, 41]));
    assert_eq!(side["spacing"][1], 0.0);
    let (ok, _, err) = sample("2");
    assert!(
        !ok && err.contains("positive size on every axis of more than one sample"),
        "{err}"
    );
}

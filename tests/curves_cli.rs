//! `karstic curves build`: outputs, statistics and error messages.

use std::path::Path;
use std::process::Command;

fn karstic() -> Command {
    Command::new(env!("CARGO_BIN_EXE_karstic"))
}

/// Runs `cmd`, asserts it succeeded (showing its stderr otherwise), returns its stdout.
fn stdout_of(cmd: &mut Command) -> String {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn builds_a_field_and_prints_stats() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/curves/cliff.ron");
    let (npy, obj) = (dir.path().join("cliff.npy"), dir.path().join("ribbons.obj"));
    let text = stdout_of(
        karstic()
            .args(["curves", "build"])
            .arg(&scene)
            .arg("-o")
            .arg(&npy)
            .arg("--ribbons")
            .arg(&obj)
            .arg("--stats"),
    );
    for row in [
        "voxelization",
        "guidance diffusion",
        "surface propagation",
        "smoothing",
        "peak grid memory",
    ] {
        assert!(text.contains(row), "missing {row} in\n{text}");
    }
    let bytes = std::fs::read(&npy).unwrap();
    assert_eq!(&bytes[..6], b"\x93NUMPY");
    let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + hlen]).unwrap();
    assert!(header.contains("'shape': (64, 64, 96)"), "{header}");
    assert_eq!((10 + hlen) % 64, 0);
    let data: &[u8] = &bytes[10 + hlen..];
    assert_eq!(data.len(), 64 * 64 * 96 * 4);
    let v: Vec<f32> = data
        .chunks(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    // Rock behind the cliff's edge, air in front of its face.
    assert!(v[30 * 64 * 96 + 50 * 96 + 48] > 0.5 && v[30 * 64 * 96 + 10 * 96 + 48] < 0.5);
    assert!(
        std::fs::read_to_string(&obj)
            .unwrap()
            .lines()
            .any(|l| l.starts_with("f "))
    );
}

#[test]
fn reports_bad_files_with_position() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.ron");
    std::fs::write(
        &bad,
        "FeatureVolume(\n  curves: Inline(),\n  domain: ((0, 0, 0), (10, 10, 10)),\n  voxel: 0,\n)",
    )
    .unwrap();
    let out = karstic()
        .args(["curves", "build"])
        .arg(&bad)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.ron:4:") && err.contains("expected a number > 0"),
        "{err}"
    );
    let out = karstic()
        .args(["curves", "build"])
        .arg(dir.path().join("missing.ron"))
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.ron"));
}

#[test]
fn meshes_tree_files_and_bare_volumes() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/curves/tunnel.ron");
    let glb = dir.path().join("tunnel.glb");
    let text = stdout_of(
        karstic()
            .args(["curves", "build"])
            .arg(&scene)
            .arg("-o")
            .arg(&glb)
            .arg("--stats"),
    );
    assert!(text.contains("surface propagation") && text.contains("cells visited"));
    let bytes = std::fs::read(&glb).unwrap();
    assert_eq!(&bytes[..4], b"glTF");
    assert!(bytes.len() > 100_000, "a real mesh, {} bytes", bytes.len());

    // A bare FeatureVolume file and a tree holding two volumes (pick one with --node).
    let bare = dir.path().join("bare.ron");
    let volume = |name: &str, x: i32| {
        format!(
            "FeatureVolume(name: \"{name}\", curves: Inline(curves: [(points: [Abs(-4, 16, 20), Abs({x}, 16, 20)], \
             constraints: [(t: 0, left: Slope(0), right: Slope(90))])]), domain: ((0, 0, 0), (31, 31, 31)), voxel: 1)"
        )
    };
    std::fs::write(&bare, volume("edge", 36)).unwrap();
    let obj = dir.path().join("bare.obj");
    stdout_of(
        karstic()
            .args(["curves", "build"])
            .arg(&bare)
            .arg("-o")
            .arg(&obj),
    );
    assert!(
        std::fs::read_to_string(&obj)
            .unwrap()
            .lines()
            .any(|l| l.starts_with("f "))
    );
    let two = dir.path().join("two.ron");
    std::fs::write(
        &two,
        format!(
            "// two volumes\n(version: 1, root: Union(children: [{}, {}]))",
            volume("a", 36),
            volume("b", 30)
        ),
    )
    .unwrap();
    let run = |extra: &[&str]| {
        karstic()
            .args(["curves", "build"])
            .arg(&two)
            .args(extra)
            .arg("-o")
            .arg(dir.path().join("two.ply"))
            .output()
            .unwrap()
    };
    let out = run(&[]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--node") && err.contains("a, b"), "{err}");
    assert!(run(&["--node", "b"]).status.success());
    let err = String::from_utf8_lossy(&run(&["--node", "c"]).stderr).to_string();
    assert!(err.contains("no FeatureVolume named \"c\""), "{err}");
    let out = karstic()
        .args(["curves", "build"])
        .arg(&scene)
        .args(["-o", "x.stl"])
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown output type"));
}

/// The pipeline's volume is kept in the disk cache (`KARSTIC_CACHE`) and read back by the
/// next run bit for bit; a damaged cache file is a miss: recomputed and rewritten.
#[test]
fn volumes_are_cached_on_disk_and_read_back_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/curves/cliff.ron");
    let build = |out: &str| {
        let npy = dir.path().join(out);
        stdout_of(
            karstic()
                .env("KARSTIC_CACHE", &cache)
                .args(["curves", "build"])
                .arg(&scene)
                .arg("-o")
                .arg(&npy),
        );
        std::fs::read(npy).unwrap()
    };
    let files = || -> Vec<std::path::PathBuf> {
        std::fs::read_dir(&cache)
            .map(|d| d.map(|e| e.unwrap().path()).collect())
            .unwrap_or_default()
    };
    let first = build("a.npy");
    let stored = files();
    assert_eq!(stored.len(), 1, "{stored:?}");
    assert!(stored[0].extension().is_some_and(|x| x == "kvol"));
    let size = std::fs::metadata(&stored[0]).unwrap().len();
    assert!(first == build("b.npy"), "the cached volume differs");
    std::fs::write(&stored[0], b"karstic-volume1\ntruncated").unwrap();
    assert!(first == build("c.npy"), "the recomputed volume differs");
    assert_eq!(files(), stored);
    // Rewritten whole (the stage times in its statistics may print a digit more or less).
    let again = std::fs::metadata(&stored[0]).unwrap().len();
    assert!(again.abs_diff(size) < 64, "{again} bytes, first {size}");
}

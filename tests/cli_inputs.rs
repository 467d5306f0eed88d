//! Bad input and limits through the command line: sizes refused before memory is taken,
//! inputs that never end or block, outputs that would destroy inputs, jobs checked at
//! load, empty trees, header lines.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Runs `karstic args` (stdin from `input`), killing it after `limit`: `(success,
/// stderr, how long it ran)`. A run that had to be killed fails the test.
fn karstic_with(args: &[&str], input: &str, limit: Duration) -> (bool, String, Duration) {
    let started = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_karstic"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.as_bytes())
        .unwrap();
    while child.try_wait().unwrap().is_none() {
        if started.elapsed() > limit {
            child.kill().unwrap();
            panic!("karstic {args:?} still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
        started.elapsed(),
    )
}

fn karstic(args: &[&str]) -> (bool, String) {
    let (ok, err, _) = karstic_with(args, "", Duration::from_secs(120));
    (ok, err)
}

fn trees() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("trees")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Runs `karstic args`, expecting it to refuse to overwrite an input and `file` to still
/// hold `original`.
fn refused_leaving(args: &[&str], file: &Path, original: &[u8]) {
    let (ok, err) = karstic(args);
    assert!(
        !ok && err.contains("refusing to overwrite"),
        "{args:?}: {err}"
    );
    assert_eq!(std::fs::read(file).unwrap(), original, "{args:?}");
}

/// A tree `dem.ron` in `dir` reading the DEM `dem.png` beside it (which holds the bytes
/// `not overwritten`, not a PNG: nothing may read or write it before the check).
fn tree_beside_its_dem(dir: &Path) -> (PathBuf, PathBuf) {
    let (tree, png) = (dir.join("dem.ron"), dir.join("dem.png"));
    std::fs::write(&png, b"not overwritten").unwrap();
    std::fs::write(
        &tree,
        "(version: 1, root: Heightfield(source: \"dem.png\", falloff: 2))",
    )
    .unwrap();
    (tree, png)
}

/// A scratch folder holding a copy of `trees/arch.ron`.
fn with_arch() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let tree = dir.path().join("arch.ron");
    std::fs::copy(trees().join("arch.ron"), &tree).unwrap();
    (dir, tree)
}

#[test]
fn huge_grids_are_refused_in_milliseconds_with_the_amount() {
    let (dir, tree) = with_arch();
    let out = dir.path().join("a.glb");
    // 10¹⁰ columns used to abort the process (the column index was allocated first);
    // 10⁴ cells per side ran for minutes at 5 GB before the samples were refused.
    for (res, want) in [("100000", "column index"), ("10000", "samples")] {
        let (ok, err, took) = karstic_with(
            &["build", s(&tree), "-o", s(&out), "--res", res],
            "",
            Duration::from_secs(60),
        );
        assert!(
            !ok && err.contains(want) && err.contains("GiB"),
            "{res}: {err}"
        );
        assert!(took < Duration::from_secs(10), "--res {res}: {took:?}");
        assert!(!out.exists());
    }
    // The Feature Curve mesher's cell: 95,000 cells a side.
    let overhang = trees().join("curves/overhang.ron");
    let (ok, err, took) = karstic_with(
        &[
            "curves",
            "build",
            s(&overhang),
            "-o",
            s(&out),
            "--cell",
            "0.001",
        ],
        "",
        Duration::from_secs(120),
    );
    assert!(!ok && err.contains("would need"), "{err}");
    assert!(took < Duration::from_secs(60), "{took:?}");
    // Budgets in any unit, the same parser for every command.
    let (ok, err) = karstic(&["build", s(&tree), "-o", s(&out), "--max-memory", "1MB"]);
    assert!(!ok && err.contains("memory budget is 976.6 KiB"), "{err}");
}

#[cfg(unix)]
#[test]
fn dem_sources_that_never_end_or_block_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.path().join("zero.asc")).unwrap();
    let made = Command::new("mkfifo")
        .arg(dir.path().join("fifo.tif"))
        .status()
        .unwrap();
    assert!(made.success());
    for (source, want) in [("zero.asc", "character device"), ("fifo.tif", "FIFO")] {
        let tree = dir.path().join(format!("{source}.ron"));
        std::fs::write(
            &tree,
            format!("(version: 1, root: Heightfield(source: \"{source}\", falloff: 2))"),
        )
        .unwrap();
        // Before: /dev/zero was read until 4 GB were taken, the FIFO blocked forever.
        let (ok, err, _) =
            karstic_with(&["tree", "validate", s(&tree)], "", Duration::from_secs(30));
        assert!(!ok && err.contains(want) && err.contains(source), "{err}");
        let dem = dir.path().join(source);
        let (ok, err, _) = karstic_with(&["dem", "info", s(&dem)], "", Duration::from_secs(30));
        assert!(!ok && err.contains(want), "{err}");
    }
}

#[test]
fn outputs_never_overwrite_inputs() {
    let (dir, tree) = with_arch();
    let original = std::fs::read(&tree).unwrap();
    let dotted = dir.path().join(".").join("arch.ron");
    let npy = dir.path().join("s.json");
    for args in [
        vec!["render", s(&tree), "-o", s(&tree)],
        vec!["render", s(&tree), "-o", s(&dotted), "--size", "8", "8"],
        vec!["render", s(&tree), "-o", "x.png", "--cost", s(&tree)],
        vec!["sample", s(&tree), "--res", "4", "4", "4", "-o", s(&tree)],
        vec!["curves", "build", s(&tree), "--ribbons", s(&tree)],
    ] {
        refused_leaving(&args, &tree, &original);
    }
    // A DEM the tree reads is one of its inputs too.
    let (dem_tree, png) = tree_beside_its_dem(dir.path());
    let (ok, err) = karstic(&["render", s(&dem_tree), "-o", s(&png)]);
    assert!(!ok && err.contains("refusing to overwrite"), "{err}");
    assert_eq!(std::fs::read(&png).unwrap(), b"not overwritten");
    // The array and its sidecar would be the same file.
    let (ok, err) = karstic(&["sample", s(&tree), "--res", "4", "4", "4", "-o", s(&npy)]);
    assert!(!ok && err.contains("are the same file"), "{err}");
    assert!(!npy.exists());
    // A DEM and its .prj are the inputs of `dem convert`.
    let asc = dir.path().join("d.asc");
    std::fs::copy(trees().join("data/jacksboro_crop.asc"), &asc).unwrap();
    std::fs::copy(
        trees().join("data/jacksboro_crop.prj"),
        asc.with_extension("prj"),
    )
    .unwrap();
    let before = std::fs::read(&asc).unwrap();
    for out in ["d.asc", "./d.asc"] {
        let out = dir.path().join(out);
        let (ok, err) = karstic(&["dem", "convert", s(&asc), "-o", s(&out)]);
        assert!(!ok && err.contains("refusing to overwrite"), "{err}");
        assert_eq!(std::fs::read(&asc).unwrap(), before);
    }
}

#[test]
fn run_checks_its_job_before_meshing() {
    let dir = tempfile::tempdir().unwrap();
    let tree = dir.path().join("t.ron");
    std::fs::write(
        &tree,
        "(version: 1, job: (cell: 0.5, camera: (eye: (0, 0, 9), target: (0, 0, 0))),\n \
         root: Primitive(shape: Sphere(center: (0, 0, 0), radius: 2), falloff: 1))",
    )
    .unwrap();
    let out = dir.path().join("out");
    let (ok, err) = karstic(&["run", s(&tree), "-o", s(&out)]);
    assert!(
        !ok && err.contains("job.camera") && err.contains("vertical"),
        "{err}"
    );
    assert!(!out.exists(), "nothing meshed or written");
    let (ok, err) = karstic(&["tree", "validate", s(&tree)]);
    assert!(!ok && err.contains("t.ron:1:"), "{err}");
    // An output "folder" that is a file is named in the error.
    let file = dir.path().join("file");
    std::fs::write(&file, "x").unwrap();
    let arch = trees().join("arch.ron");
    let (ok, err) = karstic(&["run", s(&arch), "-o", s(&file), "--no-render", "--quiet"]);
    assert!(!ok && err.contains(s(&file)), "{err}");
}

#[test]
fn empty_trees_say_what_is_empty() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("g.glb");
    // Guidance curves alone make a field that is zero everywhere.
    let guidance = trees().join("curves/guidance.ron");
    let (ok, err) = karstic(&["build", s(&guidance), "-o", s(&out)]);
    assert!(!ok && err.contains("zero everywhere"), "{err}");
    assert!(!err.contains("inf"), "{err}");
    let (ok, err) = karstic(&["render", s(&guidance), "-o", "g.png"]);
    assert!(!ok && err.contains("zero everywhere"), "{err}");
    let empty = dir.path().join("e.ron");
    std::fs::write(
        &empty,
        "(version: 1, root: Blend(name: \"all\", children: []))",
    )
    .unwrap();
    let (ok, err) = karstic(&["build", s(&empty), "-o", s(&out)]);
    assert!(
        !ok && err.contains("Blend \"all\" has no children"),
        "{err}"
    );
}

#[test]
fn eval_tells_headers_from_bad_numbers() {
    let arch = trees().join("arch.ron");
    let limit = Duration::from_secs(60);
    let (ok, err, _) = karstic_with(&["eval", s(&arch)], "\u{feff}x,y,z\n0,0,1\n", limit);
    assert!(ok, "{err}");
    let (ok, err, _) = karstic_with(&["eval", s(&arch)], "nan,0,0\n0,0,1\n", limit);
    assert!(
        !ok && err.contains("<stdin>:1: expected a finite number"),
        "{err}"
    );
}

/// `eval` reads its points as the DEM readers read their files: a regular file only
/// (`--points /dev/zero` grew to 4 GB before an abort, a FIFO blocked for ever), lines of
/// at most 4 KB (`/dev/zero` on stdin), and a bad number quoted short (a 50 MB line was
/// quoted whole).
#[test]
fn eval_reads_points_from_regular_files_in_bounded_lines() {
    let arch = trees().join("arch.ron");
    let limit = Duration::from_secs(60);
    let (ok, err, took) = karstic_with(&["eval", s(&arch), "--points", "/dev/zero"], "", limit);
    assert!(!ok && err.contains("not a regular file"), "{err}");
    assert!(took < Duration::from_secs(10), "{took:?}");
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("points.fifo");
    if Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success())
    {
        let (ok, err, _) = karstic_with(&["eval", s(&arch), "--points", s(&fifo)], "", limit);
        assert!(!ok && err.contains("not a regular file"), "{err}");
    }
    let endless = "0".repeat(20_000);
    let (ok, err, _) = karstic_with(&["eval", s(&arch)], &endless, limit);
    assert!(
        !ok && err.contains("<stdin>:1: a line longer than 4096 bytes"),
        "{err}"
    );
    let long = format!("1,2,{}\n", "9".repeat(3000) + "x");
    let (ok, err, _) = karstic_with(&["eval", s(&arch)], &format!("0,0,0\n{long}"), limit);
    assert!(!ok && err.contains("<stdin>:2") && err.len() < 300, "{err}");
}

#[test]
fn tree_set_takes_tree_file_values() {
    let (_dir, tree) = with_arch();
    let (ok, err) = karstic(&[
        "tree",
        "set",
        s(&tree),
        "left_leg.shape",
        "Sphere(center: (-25, 0, 0), radius: 3)",
    ]);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&tree).unwrap();
    assert!(text.contains("Sphere("), "{text}");
    let (ok, err) = karstic(&["tree", "set", s(&tree), "ground.falloff", "NaN"]);
    assert!(!ok && err.contains("found NaN"), "{err}");
    // A count given a fraction is told so in plain words (RON said "Expected comma").
    let noise = "(amplitude: 0.5, wavelength: 2, octaves: 3)";
    let (ok, err) = karstic(&["tree", "set", s(&tree), "ground.noise", noise]);
    assert!(ok, "{err}");
    let (ok, err) = karstic(&["tree", "set", s(&tree), "ground.noise.octaves", "9.5"]);
    assert!(
        !ok && err.contains("`octaves` takes a whole number, not 9.5"),
        "{err}"
    );
}

/// `tree set` changes only the text of the value it sets: one edit of the main job's
/// grotto rewrote the whole file in canonical layout (31 comment lines became 0, 226 diff
/// lines, defaults written out, the final newline dropped). A value the file leaves out is
/// added inside its node; a nested one (`shape.radius`) is set in place.
#[test]
fn tree_set_keeps_the_file_as_written() {
    let dir = tempfile::tempdir().unwrap();
    let tree = dir.path().join("caves.ron");
    let data = format!("\"{}/data/", trees().display());
    let original = std::fs::read_to_string(trees().join("jacksboro_caves.ron"))
        .unwrap()
        .replace("\"data/", &data);
    std::fs::write(&tree, &original).unwrap();
    let (ok, err) = karstic(&["tree", "set", s(&tree), "grotto.offset", "2.5"]);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&tree).unwrap();
    let changed: Vec<(&str, &str)> = original
        .lines()
        .zip(text.lines())
        .filter(|(a, b)| a != b)
        .collect();
    assert_eq!(original.lines().count(), text.lines().count());
    assert_eq!(
        changed,
        [("                offset: 0,", "                offset: 2.5,")]
    );
    assert!(text.ends_with('\n'));
    // The backup is the file before the edit, byte for byte; two more edits move it
    // back a generation each (the `.bak` kept one state only).
    assert_eq!(
        std::fs::read_to_string(tree.with_extension("ron.bak")).unwrap(),
        original
    );
    for offset in ["3", "4"] {
        let (ok, err) = karstic(&["tree", "set", s(&tree), "grotto.offset", offset]);
        assert!(ok, "{err}");
    }
    let bak = |k: &str| std::fs::read_to_string(tree.with_extension(format!("ron.bak{k}")));
    assert_eq!(bak(".2").unwrap(), original);
    assert!(bak(".1").unwrap().contains("offset: 2.5,"));
    assert!(bak("").unwrap().contains("offset: 3,"));

    // In the arch scene: a parameter, a nested one, and one the node leaves out; each
    // changes one line, and the comments stay.
    let (_d, arch) = with_arch();
    for (target, value, line) in [
        ("span.falloff", "6.5", "falloff: 6.5"),
        ("left_leg.shape.radius", "3", "radius: 3)"),
        (
            "left_leg.noise",
            "(amplitude: 0.5, wavelength: 2, octaves: 2)",
            "noise: (amp",
        ),
    ] {
        let before = std::fs::read_to_string(&arch).unwrap();
        let (ok, err) = karstic(&["tree", "set", s(&arch), target, value]);
        assert!(ok, "{err}");
        let after = std::fs::read_to_string(&arch).unwrap();
        let diff: Vec<&str> = before
            .lines()
            .zip(after.lines())
            .filter(|(a, b)| a != b)
            .map(|(_, b)| b)
            .collect();
        assert!(
            diff.len() == 1 && diff[0].contains(line),
            "{target}: {diff:?}"
        );
        assert_eq!(before.matches("//").count(), after.matches("//").count());
    }
}

/// `tree add` appends the node's text to its parent's list, indented as the list is, and
/// `tree rm` takes the node's lines out: the rest of the file, comments included, stays
/// byte for byte (both rewrote the whole file in canonical layout).
#[test]
fn tree_add_and_rm_keep_the_rest_of_the_file() {
    let (_d, arch) = with_arch();
    let original = std::fs::read_to_string(&arch).unwrap();
    let rock = "Primitive(name: \"rock\", shape: Sphere(center: (30, 0, 2), radius: 3), \
                falloff: 2)";
    let (ok, err) = karstic(&["tree", "add", s(&arch), "scene", rock]);
    assert!(ok, "{err}");
    let added = std::fs::read_to_string(&arch).unwrap();
    let new_lines: Vec<&str> = added.lines().filter(|l| !original.contains(*l)).collect();
    assert_eq!(new_lines.len(), 1, "{added}");
    assert!(
        new_lines[0]
            .trim_start()
            .starts_with("Primitive(name: \"rock\"")
    );
    assert_eq!(original.matches("//").count(), added.matches("//").count());
    let (ok, err) = karstic(&["tree", "rm", s(&arch), "rock"]);
    assert!(ok, "{err}");
    let removed = std::fs::read_to_string(&arch).unwrap();
    // Back to the original but for the comma the list's last element now carries.
    let strip = |t: &str| t.replace([',', ' ', '\n'], "");
    assert_eq!(strip(&removed), strip(&original), "{removed}");
    assert_eq!(original.lines().count(), removed.lines().count());
}

/// The data-loss reproducers: a special file as output, `run`, `tree expand` and
/// `edit --screenshot` writing over their inputs, a mask stem that leaves its folder,
/// a file's mode lost by `tree set`, and data files' content echoed in errors.
#[test]
fn outputs_never_replace_inputs_special_files_or_modes() {
    let (dir, tree) = with_arch();
    let original = std::fs::read(&tree).unwrap();
    // A symlink to a character device: the rename would replace the link with a file
    // (and, for root writing the device itself, the device node).
    #[cfg(unix)]
    {
        let dev = dir.path().join("dev.png");
        std::os::unix::fs::symlink("/dev/null", &dev).unwrap();
        let (ok, err) = karstic(&["render", s(&tree), "-o", s(&dev), "--size", "8", "8"]);
        assert!(!ok && err.contains("not a regular file"), "{err}");
        assert!(
            std::fs::symlink_metadata(&dev)
                .unwrap()
                .file_type()
                .is_symlink()
        );
    }
    // `run` with a tree beside its DEM: the preview would be `dem.png`.
    let (dem_tree, png) = tree_beside_its_dem(dir.path());
    let (ok, err) = karstic(&["run", s(&dem_tree), "-o", s(dir.path()), "--quiet"]);
    assert!(!ok && err.contains("refusing to overwrite"), "{err}");
    assert_eq!(std::fs::read(&png).unwrap(), b"not overwritten");
    // A tree named `.glb` run into its own folder.
    let glb_tree = dir.path().join("t.glb");
    std::fs::copy(&tree, &glb_tree).unwrap();
    let run = ["run", s(&glb_tree), "-o", s(dir.path()), "--no-render"];
    refused_leaving(&run, &glb_tree, &original);
    // `tree expand` and `edit --screenshot` over their tree.
    for args in [
        vec!["tree", "expand", s(&tree), "-o", s(&tree)],
        vec!["edit", s(&tree), "--screenshot", s(&tree)],
    ] {
        refused_leaving(&args, &tree, &original);
    }
    // A mask stem is a file name, not a path.
    let out = dir.path().join("masks");
    let (ok, err) = karstic(&["masks", s(&tree), "-o", s(&out), "--stem", "../../evil"]);
    assert!(!ok && err.contains("--stem"), "{err}");
    assert!(!dir.path().join("evil_slope.png").exists());
    // `tree set` keeps the file's mode on the file and its backup.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&tree, std::fs::Permissions::from_mode(0o600)).unwrap();
        let (ok, err) = karstic(&["tree", "set", s(&tree), "span.falloff", "6.5"]);
        assert!(ok, "{err}");
        for p in [tree.clone(), tree.with_extension("ron.bak")] {
            let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode, 0o600, "{}", p.display());
        }
        // Through a symbolic link, the tree it names is edited and the link stays one
        // (it was replaced by a regular file).
        let link = dir.path().join("link.ron");
        std::os::unix::fs::symlink(&tree, &link).unwrap();
        let (ok, err) = karstic(&["tree", "set", s(&link), "span.falloff", "7.5"]);
        assert!(ok, "{err}");
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert!(std::fs::read_to_string(&tree).unwrap().contains("7.5"));
    }
}

/// A parse error in a data file names the file and position, never its content (a
/// source symlinked to a secret must not leak its first line).
#[test]
fn data_file_errors_do_not_echo_content() {
    let dir = tempfile::tempdir().unwrap();
    let secret = "root:$6$s3cr3tHash:19000:0:99999:7:::";
    let asc = dir.path().join("d.asc");
    std::fs::write(&asc, format!("{secret}\nnobody:*:1:2\n")).unwrap();
    let png = dir.path().join("d.png");
    std::fs::copy(
        trees().join("data/jacksboro_crop.asc"),
        dir.path().join("x.asc"),
    )
    .unwrap();
    let (ok, err) = karstic(&[
        "dem",
        "convert",
        s(&dir.path().join("x.asc")),
        "-o",
        s(&png),
    ]);
    assert!(ok, "{err}");
    std::fs::write(
        png.with_extension("json"),
        format!("{{\"cell\": \"{secret}\"}}"),
    )
    .unwrap();
    for dem in [&asc, &png] {
        let (ok, err) = karstic(&["dem", "info", s(dem)]);
        assert!(!ok, "{err}");
        assert!(!err.contains("s3cr3t") && !err.contains("root:"), "{err}");
        assert!(err.contains("d."), "names the file: {err}");
    }
    // The secret as a tree, and as a tree's curves file: the parse error at its first
    // word says what the file is not, quoting nothing (RON said "found `root`").
    let tree = dir.path().join("t.ron");
    std::fs::write(&tree, format!("{secret}\n")).unwrap();
    let with_curves = dir.path().join("v.ron");
    std::fs::write(
        &with_curves,
        format!(
            "(version: 1, root: FeatureVolume(name: \"v\", curves: Path(\"{}\"), \
             domain: ((0, 0, 0), (10, 10, 10)), voxel: 1))",
            tree.display()
        ),
    )
    .unwrap();
    for t in [&tree, &with_curves] {
        let (ok, err) = karstic(&["tree", "validate", s(t)]);
        assert!(!ok, "{err}");
        assert!(!err.contains("s3cr3t") && !err.contains("root"), "{err}");
        assert!(
            err.contains("t.ron:1:1") && err.contains("not a karstic"),
            "{err}"
        );
    }
}

/// Requests past the machine are refused at once, never an abort: a tile plan of two
/// billion tiles allocated 12 GB first (SIGABRT), the editor's screenshot at the largest
/// picture side reached 24 GB (OOM-killed) where `render` refused it, and a DEM whose
/// header claims 2·10¹⁰ values aborted on the allocation once `--max-memory` was raised,
/// as did a TIFF claiming 10¹⁰, a sample and a generated grid of 30 and 150 GiB.
#[test]
fn requests_past_the_machine_are_errors_not_aborts() {
    let (dir, tree) = with_arch();
    let caves = trees().join("jacksboro_caves.ron");
    let plan = dir.path().join("tiles");
    let (ok, err, took) = karstic_with(
        &["tile", "plan", s(&caves), "--cell", "0.001", "-o", s(&plan)],
        "",
        Duration::from_secs(60),
    );
    assert!(
        !ok && err.contains("tiles") && err.contains("at most"),
        "{err}"
    );
    assert!(took < Duration::from_secs(10), "{took:?}");

    let shot = dir.path().join("e.png");
    let (ok, err, took) = karstic_with(
        &[
            "edit",
            s(&tree),
            "--screenshot",
            s(&shot),
            "--size",
            "32768",
            "32768",
        ],
        "",
        Duration::from_secs(60),
    );
    assert!(!ok && err.contains("memory budget"), "{err}");
    assert!(took < Duration::from_secs(10), "{took:?}");
    assert!(!shot.exists());

    let asc = dir.path().join("huge_claim.asc");
    std::fs::write(
        &asc,
        "ncols 200000\nnrows 100000\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n",
    )
    .unwrap();
    let (ok, err) = karstic(&["dem", "info", s(&asc), "--max-memory", "1T"]);
    let refused = err.contains("values, but the file") || err.contains("the system refused it");
    assert!(!ok && refused, "{err}");

    // A 150-byte TIFF whose header claims 5000 × 5000 float samples in one strip.
    let tif = dir.path().join("huge_claim.tif");
    let (w, h) = (5000u32, 5000u32);
    let entries: [(u16, u16, u32); 10] = [
        (256, 4, w),
        (257, 4, h),
        (258, 3, 32),
        (259, 3, 1),
        (262, 3, 1),
        (273, 4, 8),
        (277, 3, 1),
        (278, 4, h),
        (279, 4, w * h * 4 % u32::MAX),
        (339, 3, 3),
    ];
    let mut b = b"II*\0".to_vec();
    b.extend_from_slice(&24u32.to_le_bytes());
    b.extend_from_slice(&[0; 16]);
    b.extend_from_slice(&(entries.len() as u16).to_le_bytes());
    for (tag, kind, value) in entries {
        b.extend_from_slice(&tag.to_le_bytes());
        b.extend_from_slice(&kind.to_le_bytes());
        b.extend_from_slice(&1u32.to_le_bytes());
        b.extend_from_slice(&value.to_le_bytes());
    }
    b.extend_from_slice(&0u32.to_le_bytes());
    std::fs::write(&tif, b).unwrap();
    let (ok, err) = karstic(&["dem", "info", s(&tif), "--max-memory", "1T"]);
    assert!(
        !ok && err.contains("more than a file of 150 bytes"),
        "{err}"
    );

    // Grids the system cannot give, with the budget raised past it: errors, not aborts
    // (rc 134 before). Where the kernel promises any amount (overcommit 1), a refusal
    // cannot be seen before the pages are touched: the check is the default policy's.
    let overcommit = std::fs::read_to_string("/proc/sys/vm/overcommit_memory");
    if overcommit.is_ok_and(|o| o.trim() != "1") {
        let (ok, err) = karstic(&[
            "generate",
            "fbm",
            "--size",
            "1000000",
            "1000000",
            "-o",
            s(&dir.path().join("g.asc")),
            "--max-memory",
            "100T",
        ]);
        assert!(!ok && err.contains("the system refused it"), "{err}");
        let (ok, err) = karstic(&[
            "sample",
            s(&tree),
            "-o",
            s(&dir.path().join("x.npy")),
            "--res",
            "20000",
            "20000",
            "20000",
            "--max-memory",
            "100T",
        ]);
        assert!(!ok && err.contains("the system refused it"), "{err}");
    }
}

/// Counts past what a generator takes are refused with the limit, not quietly cut down
/// (`--faults 4000000000` made 100,000 faults, a 10⁶ × 10⁶ deposition 10⁸ particles).
#[test]
fn generator_counts_past_their_limits_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("g.tif");
    let grid = ["--size", "33", "33", "--cell", "10", "--relief", "100"];
    let run = |kind: &str, extra: &[&str]| {
        let mut args = vec!["generate", kind, "-o", s(&out)];
        args.extend_from_slice(&grid);
        args.extend_from_slice(extra);
        karstic(&args)
    };
    let (ok, err) = run("faults", &["--faults", "4000000000"]);
    assert!(!ok && err.contains("at most 100000"), "{err}");
    let (ok, err) = run("deposition", &["--deposition", "1000000", "1000000", "8"]);
    assert!(!ok && err.contains("100000000 particles"), "{err}");
    assert!(!out.exists());
    let (ok, err) = run("faults", &["--faults", "100000"]);
    assert!(ok, "{err}");
}

/// Messages say what is wrong: a NaN flag is named as such where it is given (it was
/// "the heightmap region … is empty"), a far-away camera is far away (it was "eye and
/// target coincide"), a heightmap past the samples allowed says so (it was "at least 2×2
/// samples is needed"), and a tile's summary that is a folder is not "not run".
#[test]
fn messages_name_the_real_problem() {
    let (dir, tree) = with_arch();
    // A box whose minimum is past its maximum is refused, not silently swapped.
    let glb = dir.path().join("b.glb");
    let flipped = ["--box", "10", "0", "0", "0", "10", "10"];
    let (ok, err) = karstic(&[&["build", s(&tree), "-o", s(&glb)][..], &flipped].concat());
    assert!(
        !ok && err.contains("--box: the minimum x 10 is past the maximum 0"),
        "{err}"
    );
    let out = dir.path().join("h.tif");
    let (ok, err) = karstic(&[
        "heightmap",
        s(&tree),
        "-o",
        s(&out),
        "--cell",
        "1",
        "--region",
        "0",
        "0",
        "NaN",
        "5",
    ]);
    assert!(
        !ok && err.contains("NaN is not a finite number") && err.contains("--region"),
        "{err}"
    );
    let (ok, err) = karstic(&["heightmap", s(&tree), "-o", s(&out), "--cell", "0.00001"]);
    assert!(!ok && err.contains("is more than 1e12 samples"), "{err}");
    let png = dir.path().join("far.png");
    let (ok, err) = karstic(&[
        "render",
        s(&tree),
        "-o",
        s(&png),
        "--size",
        "32",
        "18",
        "--camera",
        "1e30",
        "0",
        "0",
        "0",
        "0",
        "0",
    ]);
    assert!(ok && !err.contains("coincide"), "{err}");
    let tiles = dir.path().join("tiles");
    let (ok, err) = karstic(&["tile", "plan", s(&tree), "-o", s(&tiles), "--cell", "1"]);
    assert!(ok, "{err}");
    std::fs::create_dir_all(tiles.join("tiles/0/0_0.json")).unwrap();
    let (ok, err) = karstic(&["tile", "merge", s(&tiles)]);
    assert!(
        !ok && err.contains("not a regular file") && !err.contains("have not run"),
        "{err}"
    );
}

/// `--quiet` is quiet: the loader's notices (a geographic DEM's cells taken as metres) are
/// printed without it and not with it.
#[test]
fn quiet_runs_print_no_notices() {
    let dir = tempfile::tempdir().unwrap();
    let tree = dir.path().join("geo.ron");
    let dem = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/dem/jacksboro.asc");
    std::fs::write(
        &tree,
        format!(
            "(version: 1, root: Heightfield(source: {:?}, falloff: 200))",
            s(&dem)
        ),
    )
    .unwrap();
    let png = dir.path().join("g.png");
    let render = ["render", s(&tree), "-o", s(&png), "--size", "32", "18"];
    let (ok, err) = karstic(&render);
    assert!(ok && err.contains("notice: geographic DEM"), "{err}");
    let (ok, err) = karstic(&[&render[..], &["--quiet"]].concat());
    assert!(ok && err.is_empty(), "{err}");
}

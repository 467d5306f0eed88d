//! Tree files: every example loads and compiles, round trips are lossless, malformed files
//! give the right error at the right place, and the edit commands keep files valid.

use std::path::{Path, PathBuf};

use karstic::scene::{self, parse_scene};

use karstic::compile::edit;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tree_files() -> Vec<PathBuf> {
    let trees = repo().join("trees");
    let mut v: Vec<PathBuf> = [trees.clone(), trees.join("paper")]
        .iter()
        .flat_map(|dir| std::fs::read_dir(dir).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    v.sort();
    v
}

#[test]
fn every_example_loads_compiles_and_round_trips() {
    let files = tree_files();
    assert!(files.len() >= 4, "expected the example scenes in trees/");
    for f in files {
        let sf = scene::load(&f).unwrap_or_else(|e| panic!("{e}"));
        sf.compile().unwrap_or_else(|e| panic!("{e}"));
        let text = sf.scene.to_ron();
        let again = parse_scene(&text, &f)
            .unwrap_or_else(|e| panic!("re-reading {}: {e}\n{text}", f.display()));
        assert_eq!(again, sf.scene, "{} does not round trip", f.display());
        assert_eq!(
            again.to_ron(),
            text,
            "{}: writing is not stable",
            f.display()
        );
    }
}

#[test]
fn malformed_files_give_the_right_error_and_position() {
    let dir = repo().join("tests/data/bad_trees");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let path = e.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        let expect = text
            .lines()
            .next()
            .unwrap()
            .strip_prefix("// expect: ")
            .expect("first line: // expect: L:C: message");
        let (pos, message) = expect.split_once(": ").unwrap();
        let err = scene::load(&path)
            .and_then(|s| s.compile().map(|_| ()))
            .expect_err(&path.display().to_string());
        let shown = err.to_string();
        let want = format!("{}:{pos}: ", path.display());
        assert!(
            shown.starts_with(&want),
            "{}: got {shown:?}, want position {pos}",
            path.display()
        );
        assert!(
            shown.contains(message),
            "{}: got {shown:?}, want {message:?}",
            path.display()
        );
        n += 1;
    }
    assert!(n >= 10, "only {n} malformed files");
}

fn scratch(name: &str, text: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    (dir, path)
}

const SMALL: &str = r#"// two boulders
(
    version: 1,
    seed: 9,
    root: Blend(
        name: "root",
        children: [
            Primitive(name: "a", shape: Sphere(center: (0, 0, 0), radius: 2), falloff: 1.5),
            Transform(name: "moved", translate: (10, 0, 0), child: Primitive(name: "b", shape: Point(center: (0, 0, 0)), falloff: 4)),
        ],
    ),
)
"#;

#[test]
fn set_add_rm_edit_validate_and_keep_a_backup() {
    let (_d, path) = scratch("t.ron", SMALL);
    edit::set_param(&path, "a.falloff", "2.5").unwrap();
    edit::set_param(&path, "a.shape.radius", "3").unwrap();
    edit::set_param(&path, "moved.translate", "(12, 1, 0)").unwrap();
    let s = scene::load(&path).unwrap().scene;
    let text = s.to_ron();
    assert!(
        text.contains("falloff: 2.5") && text.contains("radius: 3.0"),
        "{text}"
    );
    assert!(text.contains("translate: (12.0, 1.0, 0.0)"), "{text}");
    assert_eq!(s.seed, 9, "untouched data survives");
    let bak = path.with_extension("ron.bak");
    assert!(bak.exists());

    // Invalid edits are refused and leave the file as it was.
    let before = std::fs::read_to_string(&path).unwrap();
    let e = edit::set_param(&path, "a.falloff", "-1")
        .unwrap_err()
        .to_string();
    assert!(e.contains("expected a number > 0"), "{e}");
    let e = edit::set_param(&path, "a.colour", "1")
        .unwrap_err()
        .to_string();
    assert!(e.contains("has no parameter"), "{e}");
    let e = edit::set_param(&path, "nobody.falloff", "1")
        .unwrap_err()
        .to_string();
    assert!(e.contains("no node named"), "{e}");
    assert_eq!(std::fs::read_to_string(&path).unwrap(), before);

    edit::add_node(
        &path,
        "root",
        r#"Primitive(name: "c", shape: Point(center: (0, 5, 0)), falloff: 2)"#,
    )
    .unwrap();
    let e = edit::add_node(
        &path,
        "root",
        r#"Primitive(name: "c", shape: Point(center: (0, 5, 0)), falloff: 2)"#,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("duplicate node name"), "{e}");
    edit::remove_node(&path, "a").unwrap();
    let e = edit::remove_node(&path, "b").unwrap_err().to_string();
    assert!(e.contains("only required child"), "{e}");
    let s = scene::load(&path).unwrap().scene;
    let names: Vec<&str> = s.all_nodes().into_iter().filter_map(|n| n.name()).collect();
    assert_eq!(names, ["root", "moved", "b", "c"]);
}

#[test]
fn set_takes_values_as_written_in_tree_files() {
    let (_d, path) = scratch("t.ron", SMALL);
    // An enum value in its tree-file form, and back.
    edit::set_param(&path, "a.shape", "Point(center: (1, 2, 3))").unwrap();
    let text = scene::load(&path).unwrap().scene.to_ron();
    assert!(
        text.contains("shape: Point(") && !text.contains("Sphere("),
        "{text}"
    );
    edit::set_param(&path, "a.shape", "Sphere(center: (0, 0, 0), radius: 4)").unwrap();
    edit::set_param(&path, "a.shape.radius", "5").unwrap();
    let text = scene::load(&path).unwrap().scene.to_ron();
    assert!(text.contains("radius: 5.0"), "{text}");
    // An optional parameter the node leaves out is added; its inner fields then follow.
    edit::set_param(&path, "a.noise", "(amplitude: 0.5, wavelength: 8)").unwrap();
    edit::set_param(&path, "a.noise.amplitude", "0.25").unwrap();
    let text = scene::load(&path).unwrap().scene.to_ron();
    assert!(
        text.contains("amplitude: 0.25") && text.contains("wavelength: 8.0"),
        "{text}"
    );

    let before = std::fs::read_to_string(&path).unwrap();
    let refused = |target: &str, value: &str| {
        let e = edit::set_param(&path, target, value)
            .unwrap_err()
            .to_string();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), before, "{target}");
        e
    };
    let e = refused("a.falloff", "NaN");
    assert!(e.contains("expected a finite number, found NaN"), "{e}");
    let e = refused("a.colour", "1");
    assert!(
        e.contains("has no parameter \"colour\"") && e.contains("falloff"),
        "{e}"
    );
    let e = refused("a.falloff", "1, energy: 3");
    assert!(e.contains("expected one value"), "{e}");
    // A duplicate name made by an edit is reported by name: the rewritten text is not
    // the file, a line and column in it would point nowhere useful.
    let e = refused("b.name", "\"a\"");
    let want = format!(
        "{}: after the edit: duplicate node name \"a\"",
        path.display()
    );
    assert_eq!(e, want, "no line and column");
    let e = edit::add_node(&path, "root", "Blend(name: \"empty\", children: [])")
        .unwrap_err()
        .to_string();
    assert!(e.contains("Blend \"empty\" has no children"), "{e}");
}

#[test]
fn a_byte_order_mark_is_skipped_and_positions_stay_right() {
    let (_d, path) = scratch("bom.ron", &format!("\u{feff}{SMALL}"));
    assert_eq!(scene::load(&path).unwrap().scene.seed, 9);
    let (_d, path) = scratch(
        "bad.ron",
        "\u{feff}(\n    version: 1,\n    root: Bogus(),\n)",
    );
    let e = scene::load(&path).unwrap_err().to_string();
    assert!(e.contains("bad.ron:3:11:"), "{e}");
}

#[test]
fn empty_operators_and_bad_jobs_are_refused_at_load() {
    let check = |text: &str, want: &str| {
        let (_d, path) = scratch("t.ron", text);
        let e = scene::load(&path).unwrap_err().to_string();
        assert!(e.contains(want), "{text}\n{e}");
    };
    check(
        "(version: 1, root: Blend(children: []))",
        "t.ron:1:1: an unnamed Blend has no children",
    );
    check(
        "(version: 1, root: Union(name: \"u\", children: []))",
        "t.ron:1:32: Union \"u\" has no children",
    );
    // A definition without a name cannot be used: it was accepted and ignored.
    check(
        "(version: 1,\n defs: [Primitive(shape: Point(center: (0, 0, 0)), falloff: 1)],\n \
         root: Primitive(shape: Point(center: (0, 0, 0)), falloff: 2))",
        "t.ron:2:2: defs[0] (Primitive) has no name",
    );
    let ball = "Primitive(shape: Point(center: (0, 0, 0)), falloff: 1)";
    let job = |section: &str| format!("(version: 1,\n job: (cell: 1, {section}),\n root: {ball})");
    check(
        &job("image: (0, 10)"),
        "t.ron:2:17: job.image: image size 0 × 10",
    );
    check(&job("fov: 200"), "job.fov: bad camera: field of view 200°");
    check(
        &job("camera: (eye: (0, 0, 5), target: (0, 0, 5))"),
        "job.camera: bad camera: eye and target coincide",
    );
    check(
        &job("camera: (eye: (0, 0, 50), target: (0, 0, 0))"),
        "the view direction is vertical",
    );
    check(
        &job("region: (min: (0, 0, 0), max: (10, 0, 10))"),
        "job.region: min",
    );
    check(
        &job("region: (min: (0, 0, 0), max: (1e8, 1e8, 1e8))"),
        "job.cell: bad grid",
    );
    check(
        &job("sun: (azimuth: 90, elevation: -5)"),
        "job.sun: elevation -5° is not above the horizon",
    );
    check(
        &job("sun: (azimuth: 90, elevation: 30, height: 2)"),
        "height",
    );
}

#[test]
fn validation_is_linear_in_named_nodes_and_instance_chains() {
    // 100,000 named primitives and a chain of 2,000 instances: seconds before (104 s
    // and 28 s: names and references were looked up by scanning the whole file).
    let prims: Vec<String> = (0..100_000)
        .map(|i| {
            format!(
                "Primitive(name: \"p{i}\", shape: Point(center: ({}, {}, 0)), falloff: 1)",
                i % 300,
                i / 300
            )
        })
        .collect();
    let many = format!(
        "(version: 1, root: Blend(name: \"root\", children: [{}]))",
        prims.join(",\n")
    );
    let mut defs =
        vec!["Primitive(name: \"d0\", shape: Point(center: (0, 0, 0)), falloff: 1)".to_string()];
    for i in 1..2000 {
        defs.push(format!(
            "Transform(name: \"d{i}\", translate: (0.001, 0, 0), child: Instance(of: \"d{}\"))",
            i - 1
        ));
    }
    let chain = format!(
        "(version: 1, defs: [{}], root: Instance(of: \"d1999\"))",
        defs.join(",\n")
    );
    let started = std::time::Instant::now();
    scene::parse_scene(&many, Path::new("big.ron")).unwrap();
    // The chain is checked as fast, and refused: 4,000 levels deep (each link a
    // Transform and an instance) is past what the compiler and evaluators take.
    let e = scene::parse_scene(&chain, Path::new("chain.ron")).unwrap_err();
    assert!(e.to_string().contains("nests deeper than"), "{e}");
    let took = started.elapsed();
    assert!(took.as_secs_f64() < 5.0, "validation took {took:?}");
    // A cycle at the end of a long chain is still found, and named.
    let cyclic = chain.replace("Instance(of: \"d0\")", "Instance(of: \"d1999\")");
    let cyclic = cyclic.replacen(
        "Primitive(name: \"d0\", shape: Point(center: (0, 0, 0)), falloff: 1)",
        "Transform(name: \"d0\", child: Instance(of: \"d1999\"))",
        1,
    );
    let e = scene::parse_scene(&cyclic, Path::new("c.ron"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("is inside the node it instances (a cycle)"),
        "{e}"
    );
}

#[test]
fn asset_paths_are_relative_to_the_tree_file() {
    let sf = scene::load(repo().join("trees/arch.ron")).unwrap();
    assert_eq!(
        sf.base_dir,
        Path::new(env!("CARGO_MANIFEST_DIR")).join("trees")
    );
}

/// The offsets just after each `(` of `text` that opens a struct with named fields (the
/// next token is `name:`), outside strings and comments.
fn struct_openings(text: &str) -> Vec<usize> {
    let b = text.as_bytes();
    let skip_blank = |mut i: usize| {
        loop {
            while i < b.len() && b[i].is_ascii_whitespace() {
                i += 1;
            }
            if b[i..].starts_with(b"//") {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            } else {
                return i;
            }
        }
    };
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'"' => {
                i += 1;
                while i < b.len() && b[i] != b'"' {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
            }
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'(' => {
                let j = skip_blank(i + 1);
                let k = (j..b.len())
                    .find(|&k| !(b[k].is_ascii_alphanumeric() || b[k] == b'_'))
                    .unwrap_or(b.len());
                let colon = skip_blank(k);
                if k > j
                    && b[j].is_ascii_lowercase()
                    && b.get(colon) == Some(&b':')
                    && b.get(colon + 1) != Some(&b':')
                {
                    out.push(i + 1);
                }
            }
            _ => {}
        }
        i += 1;
    }
    out
}

/// Every type of the file format refuses a field it does not know (a misspelled
/// `on_terain` must not validate "ok" while the feature it meant to set is silently
/// left at its default): an unknown field put into each struct of each scene of `trees/`
/// (the Feature Volumes' curve specs, the solver, the landforms, the geology, the job…)
/// is an error that names it.
#[test]
fn every_struct_of_every_tree_refuses_an_unknown_field() {
    let mut files = tree_files();
    let curves = repo().join("trees").join("curves");
    files.extend(
        std::fs::read_dir(&curves)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "ron")),
    );
    let mut tried = 0;
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        parse_scene(&text, f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        let openings = struct_openings(&text);
        assert!(!openings.is_empty(), "{}: no struct found", f.display());
        for at in openings {
            let bad = format!("{}zz_unknown_field: 0, {}", &text[..at], &text[at..]);
            let line = text[..at].lines().count();
            match parse_scene(&bad, f) {
                Ok(_) => panic!(
                    "{}:{line}: a struct accepted an unknown field:\n{}",
                    f.display(),
                    text.lines().nth(line - 1).unwrap_or("")
                ),
                Err(e) => assert!(
                    e.to_string().contains("zz_unknown_field"),
                    "{}:{line}: the error does not name the field: {e}",
                    f.display()
                ),
            }
            tried += 1;
        }
    }
    assert!(tried > 300, "only {tried} structs tried");
}

/// A curves file is read as the DEMs are: a device or a FIFO named as one is refused at
/// once (`/dev/zero` was read to 8 GB, a FIFO blocked forever), and so is a file past the
/// size bound.
#[test]
fn curves_files_must_be_regular_files() {
    use karstic::voxel::FeatureSet;
    use karstic::voxel::spec::load_ron;
    let e = load_ron::<FeatureSet>(Path::new("/dev/zero")).unwrap_err();
    assert!(e.to_string().contains("not a regular file"), "{e}");
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("curves.ron");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|s| s.success()) {
        let e = load_ron::<FeatureSet>(&fifo).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
    }
    // The scene names the file: validation fails with it, quickly.
    let tree = dir.path().join("t.ron");
    std::fs::write(
        &tree,
        r#"(version: 1, root: FeatureVolume(name: "v", curves: Path("/dev/zero"),
            domain: ((0, 0, 0), (10, 10, 10)), voxel: 1.0))"#,
    )
    .unwrap();
    let t = std::time::Instant::now();
    let e = scene::load(&tree).and_then(|f| f.compile().map(|_| ()));
    let e = karstic::io::chain(&e.unwrap_err());
    assert!(
        e.contains("/dev/zero") && e.contains("not a regular file"),
        "{e}"
    );
    assert!(t.elapsed().as_secs() < 5, "took {:?}", t.elapsed());
}

/// `depth` Blends, each the only child of the next, around a point.
fn nested_blends(depth: usize) -> String {
    let mut s = "Primitive(shape: Point(center: (0, 0, 0)), falloff: 1.0, energy: 1.0)".to_string();
    for _ in 0..depth {
        s = format!("Blend(children: [{s}])");
    }
    format!("(version: 1, root: {s})")
}

/// Deep trees get a clear error, never a stack overflow: a chain of 1,700 instance links
/// (each node a `Union` of an instance of the one before, the last one instanced first)
/// aborted every command; 20 nested Blends answered with the parser's API ("increase
/// `recursion_limit`"), and now parse, compile and render; past the format's nesting the
/// message says how deep a file may go.
#[test]
fn deep_trees_are_refused_clearly_not_overflowed() {
    let mut chain = String::from("(version: 1, root: Union(children: [Instance(of: \"n1699\"), ");
    chain.push_str(
        "Primitive(name: \"n0\", shape: Point(center: (0, 0, 0)), falloff: 1.0, energy: 1.0)",
    );
    for i in 1..1700 {
        chain.push_str(&format!(
            ", Union(name: \"n{i}\", children: [Instance(of: \"n{}\")])",
            i - 1
        ));
    }
    chain.push_str("]))");
    let e = parse_scene(&chain, Path::new("chain.ron"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("nests deeper than 256 levels"), "{e}");
    assert!(e.starts_with("chain.ron:1:"), "{e}");

    let twenty = parse_scene(&nested_blends(20), Path::new("t.ron")).unwrap();
    let file = scene::SceneFile {
        scene: twenty,
        path: PathBuf::from("t.ron"),
        base_dir: PathBuf::from("."),
    };
    let tree = file.compile().unwrap().tree;
    assert!(karstic::field::Field::value(&tree, glam::Vec3::ZERO) > 0.5);

    let e = parse_scene(&nested_blends(400), Path::new("deep.ron"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("nest deeper than 1024 levels"), "{e}");
    assert!(!e.contains("recursion_limit"), "{e}");
}

/// A diamond of shared instances (`Blend([Instance(next), Instance(next)])` at each of 64
/// levels) validated in no time and then never finished compiling or evaluating: an
/// instance is evaluated wherever it is used, 2⁶⁴ times here. It is refused at once, in
/// time linear in the file, with the size it would have.
#[test]
fn a_diamond_of_instances_is_refused_at_once() {
    let mut parts = vec![
        "Primitive(name: \"d64\", shape: Point(center: (0, 0, 0)), falloff: 1.0, energy: 1.0)"
            .to_string(),
    ];
    for i in (0..64).rev() {
        parts.push(format!(
            "Blend(name: \"d{i}\", children: [Instance(of: \"d{}\"), Instance(of: \"d{}\")])",
            i + 1,
            i + 1
        ));
    }
    let text = format!(
        "(version: 1, root: Union(children: [{}]))",
        parts.join(", ")
    );
    let t = std::time::Instant::now();
    let e = parse_scene(&text, Path::new("diamond.ron"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("instances expanded"), "{e}");
    assert!(t.elapsed().as_secs_f32() < 1.0, "{:?}", t.elapsed());
}

/// A feature placed wholly outside its Feature Volume's domain validated and ran, and the
/// cave was simply missing: it is now an error naming the feature and the domain, while
/// a tunnel that opens out of the domain (`trees/curves/tunnel.ron`) still builds.
#[test]
fn a_feature_wholly_outside_its_domain_is_an_error() {
    let path = repo().join("trees/curves/tunnel.ron");
    let text = std::fs::read_to_string(&path).unwrap();
    let open = scene::SceneFile {
        scene: parse_scene(&text, &path).unwrap(),
        path: path.clone(),
        base_dir: repo().join("trees/curves"),
    };
    open.compile().unwrap();
    let moved = text
        .replace("Abs(-12, 30, 30)", "Abs(-12, 300, 30)")
        .replace("Abs(40, 22, 27)", "Abs(40, 220, 27)")
        .replace("Abs(88, 42, 35)", "Abs(88, 420, 35)")
        .replace("Abs(139, 32, 30)", "Abs(139, 320, 30)");
    assert_ne!(moved, text);
    let away = scene::SceneFile {
        scene: parse_scene(&moved, &path).unwrap(),
        ..open
    };
    let e = karstic::io::chain(&away.compile().map(|_| ()).unwrap_err());
    assert!(
        e.contains("tunnel 0 \"main\"") && e.contains("wholly outside the volume's domain"),
        "{e}"
    );
}

/// The Feature Volume memo is keyed by what the volume is built from, contents included:
/// a curves file edited in place (same length, its modification time put back) gives
/// the edited volume, not the one built before (the key was the file's time and length).
#[test]
fn a_curves_file_edited_in_place_rebuilds_its_volume() {
    let dir = tempfile::tempdir().unwrap();
    let curves = dir.path().join("c.ron");
    let set = |w: u32| {
        format!(
            "(tunnels: [(name: \"main\", path: [Abs(-12, 30, 30), Abs(60, 30, 30), \
             Abs(139, 32, 30)], width: Const({w}), height: Const(10))])"
        )
    };
    std::fs::write(&curves, set(12)).unwrap();
    let tree = dir.path().join("t.ron");
    std::fs::write(
        &tree,
        "(version: 1, seed: 3, root: FeatureVolume(name: \"v\", curves: Path(\"c.ron\"), \
         domain: ((0, 0, 0), (127, 63, 63)), voxel: 1.0))",
    )
    .unwrap();
    let value = || {
        let t = scene::load(&tree).unwrap().compile().unwrap().tree;
        karstic::field::Field::value(&t, glam::Vec3::new(60.0, 36.5, 30.0))
    };
    let before = value();
    let stamp = std::fs::metadata(&curves).unwrap().modified().unwrap();
    std::fs::write(&curves, set(16)).unwrap();
    std::fs::File::options()
        .write(true)
        .open(&curves)
        .unwrap()
        .set_modified(stamp)
        .unwrap();
    let after = value();
    assert_ne!(
        before, after,
        "the memo served the volume of the file as it was"
    );
}

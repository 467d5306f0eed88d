//! Tree files: every example loads and compiles, round trips are lossless, malformed files
//! give the right error at the right place, and the edit commands keep files valid.

use std::path::{Path, PathBuf};

use karstic::scene::{self, edit, parse_scene};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tree_files() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(repo().join("trees"))
        .unwrap()
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
fn asset_paths_are_relative_to_the_tree_file() {
    let sf = scene::load(repo().join("trees/arch.ron")).unwrap();
    assert_eq!(
        sf.base_dir,
        Path::new(env!("CARGO_MANIFEST_DIR")).join("trees")
    );
}

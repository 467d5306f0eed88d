//! `karstic render` argument parsing and outputs (through `render_tree`, the part after
//! the tree file is loaded).

use crate::common;

use karstic::field::Field;

use clap::Parser;
use common::{Terrain, tapes};
use karstic::cli::render::{LoadedTree, RenderArgs, load_tree, render_tree};
use karstic::cli::{Cli, Command};

fn args(extra: &[&str]) -> RenderArgs {
    let mut argv = vec!["karstic", "render", "scene.ron", "-o", "out.png"];
    argv.extend_from_slice(extra);
    match Cli::try_parse_from(argv).unwrap().command {
        Command::Render(a) => a,
        other => panic!("parsed as {other:?}"),
    }
}

#[test]
fn flags_parse() {
    let a = args(&[
        "--size", "64", "48", "--method", "sphere", "--camera", "-10", "5", "3.5", "0", "0", "-1",
        "--fov", "30", "--gpu", "--quiet", "--cost", "c.png",
    ]);
    assert_eq!(a.size, vec![64, 48]);
    assert_eq!(a.method, karstic::render::Method::Sphere);
    assert_eq!(a.camera, Some(vec![-10.0, 5.0, 3.5, 0.0, 0.0, -1.0]));
    assert!(a.gpu && a.quiet && a.cost.is_some());
    let d = args(&[]);
    assert_eq!(d.size, vec![960, 540]);
    assert_eq!(d.method, karstic::render::Method::Segment);
    assert!(
        Cli::try_parse_from(["karstic", "render", "x.ron", "-o", "o.png", "--size", "5"]).is_err()
    );
    assert!(
        Cli::try_parse_from([
            "karstic", "render", "x.ron", "-o", "o.png", "--method", "bogus"
        ])
        .is_err()
    );
}

#[test]
fn renders_png_and_cost_image_and_checks_the_budget() {
    let dir = tempfile::tempdir().unwrap();
    let terrain = Terrain::new(100.0, 12.0, 4.0);
    let tree = LoadedTree {
        field: Box::new(terrain),
        tape: None,
    };
    let mut a = args(&["--size", "120", "80", "--quiet"]);
    a.output = dir.path().join("t.png");
    a.cost = Some(dir.path().join("cost.png"));
    render_tree(&a, &tree).unwrap();
    let img = image::open(&a.output).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (120, 80));
    let cost = image::open(a.cost.as_ref().unwrap()).unwrap().to_rgba8();
    assert_eq!(cost.dimensions(), (120, 80));
    // Sky in a top corner, terrain in the middle: the image is not uniform.
    assert_ne!(img.get_pixel(0, 0), img.get_pixel(60, 45));

    // An explicit camera looking away from the scene sees only sky.
    let mut away = a.clone();
    away.output = dir.path().join("away.png");
    away.cost = None;
    away.camera = Some(vec![0.0, 0.0, 500.0, 0.0, 1.0, 1000.0]);
    render_tree(&away, &tree).unwrap();
    let sky = image::open(&away.output).unwrap().to_rgba8();
    assert!(sky.pixels().all(|p| p[2] >= p[0]), "bluish sky everywhere");

    // Over budget: refused before rendering, nothing written.
    let mut big = a.clone();
    big.output = dir.path().join("big.png");
    big.max_memory = 1000;
    let e = render_tree(&big, &tree).unwrap_err().to_string();
    assert!(e.contains("memory budget"), "{e}");
    assert!(!big.output.exists());
    let mut bad = a.clone();
    bad.size = vec![0, 10];
    assert!(render_tree(&bad, &tree).is_err());
}

#[test]
fn gpu_flag_falls_back_or_renders() {
    let dir = tempfile::tempdir().unwrap();
    let terrain = Terrain::new(100.0, 12.0, 4.0);
    let tape = tapes::terrain(&terrain, 48);
    let tree = LoadedTree {
        field: Box::new(tape.clone()),
        tape: Some(Ok(tape)),
    };
    let mut a = args(&["--size", "48", "32", "--gpu", "--quiet"]);
    a.output = dir.path().join("g.png");
    render_tree(&a, &tree).unwrap();
    assert_eq!(
        image::open(&a.output).unwrap().to_rgba8().dimensions(),
        (48, 32)
    );
}

#[test]
fn tree_files_load_with_their_tape_or_the_reason_they_have_none() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("trees");
    // Without the GPU asked for, no tape is built.
    assert!(
        load_tree(&dir.join("blobs.ron"), false)
            .unwrap()
            .tape
            .is_none()
    );
    let blobs = load_tree(&dir.join("blobs.ron"), true).unwrap();
    let tape = blobs
        .tape
        .as_ref()
        .unwrap()
        .as_ref()
        .expect("point blobs encode");
    assert!(blobs.field.support().contains_box(&tape.support()));
    // Every scene of trees/ encodes (tests/render_trees.rs); a disc skeleton does not.
    let spire = load_tree(&dir.join("rock_spire.ron"), true).unwrap();
    assert!(matches!(spire.tape, Some(Ok(_))), "the cone spire encodes");
    let out = tempfile::tempdir().unwrap();
    let disc_file = out.path().join("disc.ron");
    std::fs::write(
        &disc_file,
        "(version: 1, root: Primitive(name: \"disc\", shape: Disc(center: (0, 0, 0), normal: (0, 0.6, 0.8), radius: 4), falloff: 2))",
    )
    .unwrap();
    let disc = load_tree(&disc_file, true).unwrap();
    let e = disc
        .tape
        .as_ref()
        .unwrap()
        .as_ref()
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("\"disc\"") && e.contains("no GPU encoding"),
        "{e}"
    );
    // --gpu without an encoding still renders, on the CPU.
    let mut a = args(&["--size", "40", "30", "--gpu", "--quiet"]);
    a.output = out.path().join("disc.png");
    render_tree(&a, &disc).unwrap();
    assert_eq!(
        image::open(&a.output).unwrap().to_rgba8().dimensions(),
        (40, 30)
    );
}

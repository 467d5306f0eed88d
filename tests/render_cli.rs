//! `karstic render` from the command line, and the library's GPU-or-CPU rendering
//! ([`Renderable::render_with_fallback`]) it stands on.

use crate::common;

use std::path::Path;
use std::process::Command;

use common::{Terrain, tapes};
use indicatif::ProgressBar;
use karstic::field::Field;
use karstic::render::{Camera, Device, Fallback, Method, RenderSettings, Renderable};

/// Runs the `karstic` binary: `(success, stderr)`.
pub(crate) fn karstic(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_karstic"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn trees() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("trees")
}

/// Renders `subject` at `w × h`, framed from its support.
fn render(subject: &Renderable, w: u32, h: u32) -> (karstic::render::Frame, Device<'_>) {
    let support = subject.field.support();
    let camera = Camera::view(None, &support, 40.0, w, h).unwrap();
    let settings = RenderSettings::for_scene(&support, &camera, Method::Segment);
    subject.render_with_fallback(&camera, &settings, &ProgressBar::hidden())
}

#[test]
fn renders_png_and_cost_image_and_checks_the_budget() {
    let dir = tempfile::tempdir().unwrap();
    let tree = trees().join("arch.ron");
    let tree = tree.to_str().unwrap();
    let out = dir.path().join("t.png");
    let cost = dir.path().join("cost.png");
    let (ok, err) = karstic(&[
        "render",
        tree,
        "-o",
        out.to_str().unwrap(),
        "--cost",
        cost.to_str().unwrap(),
        "--size",
        "120",
        "80",
        "--quiet",
    ]);
    assert!(ok, "{err}");
    let img = image::open(&out).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (120, 80));
    assert_eq!(
        image::open(&cost).unwrap().to_rgba8().dimensions(),
        (120, 80)
    );
    // Sky in a top corner, the arch's ground in the middle: the image is not uniform.
    assert_ne!(img.get_pixel(0, 0), img.get_pixel(60, 45));

    // An explicit camera looking away from the scene sees only sky.
    let away = dir.path().join("away.png");
    let (ok, err) = karstic(&[
        "render",
        tree,
        "-o",
        away.to_str().unwrap(),
        "--size",
        "40",
        "30",
        "--quiet",
        "--camera",
        "0",
        "0",
        "500",
        "0",
        "1",
        "1000",
    ]);
    assert!(ok, "{err}");
    let sky = image::open(&away).unwrap().to_rgba8();
    assert!(sky.pixels().all(|p| p[2] >= p[0]), "bluish sky everywhere");

    // Over budget (in any unit): refused before rendering, nothing written.
    let big = dir.path().join("big.png");
    for budget in ["1000", "1K", "0.001MB"] {
        let (ok, err) = karstic(&[
            "render",
            tree,
            "-o",
            big.to_str().unwrap(),
            "--size",
            "120",
            "80",
            "--max-memory",
            budget,
        ]);
        assert!(!ok && err.contains("memory budget"), "{budget}: {err}");
        assert!(!big.exists());
    }
    let (ok, err) = karstic(&[
        "render",
        tree,
        "-o",
        big.to_str().unwrap(),
        "--size",
        "0",
        "10",
    ]);
    assert!(!ok && err.contains("image size 0 × 10"), "{err}");
}

#[test]
fn the_gpu_renders_or_the_cpu_takes_over() {
    let terrain = Terrain::new(100.0, 12.0, 4.0);
    let tape = tapes::terrain(&terrain, 48);
    // The tests ask for software adapters explicitly (lavapipe on CI).
    let subject = Renderable {
        field: Box::new(tape.clone()),
        tape: Some(Ok(tape)),
        allow_software: true,
    };
    let (frame, device) = render(&subject, 48, 32);
    assert_eq!((frame.width, frame.height), (48, 32));
    assert!(frame.hits() > 0, "the terrain is in view");
    match device {
        Device::Gpu(adapter) => assert!(!adapter.is_empty()),
        Device::CpuInstead(Fallback::Failed(e)) => eprintln!("no GPU here: {e}"),
        other => panic!("a tape was given: {other:?}"),
    }
    let cpu = Renderable {
        field: Box::new(terrain),
        tape: None,
        allow_software: false,
    };
    let (frame, device) = render(&cpu, 48, 32);
    assert!(matches!(device, Device::Cpu), "{device:?}");
    assert!(frame.hits() > 0);
}

#[test]
fn tree_files_load_with_their_tape_or_the_reason_they_have_none() {
    let load = |path: &Path, gpu: bool| {
        let tree = karstic::scene::load(path).unwrap().compile().unwrap().tree;
        Renderable::from_tree(tree, gpu)
    };
    // Without the GPU asked for, no tape is built.
    assert!(load(&trees().join("blobs.ron"), false).tape.is_none());
    let blobs = load(&trees().join("blobs.ron"), true);
    let tape = blobs
        .tape
        .as_ref()
        .unwrap()
        .as_ref()
        .expect("point blobs encode");
    assert!(blobs.field.support().contains_box(&tape.support()));
    // Every scene of trees/ encodes (tests/render_trees.rs); a disc skeleton does not.
    let spire = load(&trees().join("rock_spire.ron"), true);
    assert!(matches!(spire.tape, Some(Ok(_))), "the cone spire encodes");
    let out = tempfile::tempdir().unwrap();
    let disc_file = out.path().join("disc.ron");
    std::fs::write(
        &disc_file,
        "(version: 1, root: Primitive(name: \"disc\", shape: Disc(center: (0, 0, 0), normal: (0, 0.6, 0.8), radius: 4), falloff: 2))",
    )
    .unwrap();
    let disc = load(&disc_file, true);
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
    // Without an encoding the CPU renders, saying why.
    let (frame, device) = render(&disc, 40, 30);
    assert_eq!((frame.width, frame.height), (40, 30));
    let Device::CpuInstead(Fallback::NoTape(why)) = device else {
        panic!("{device:?}")
    };
    assert!(why.to_string().contains("no GPU encoding"), "{why}");
    // And so does the command line, with the reason on stderr.
    let png = out.path().join("disc.png");
    let (ok, err) = karstic(&[
        "render",
        disc_file.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--size",
        "40",
        "30",
        "--gpu",
    ]);
    assert!(ok, "{err}");
    assert!(
        err.contains("--gpu:") && err.contains("on the CPU"),
        "{err}"
    );
    assert_eq!(image::open(&png).unwrap().to_rgba8().dimensions(), (40, 30));
}

/// `--gpu` names the adapter it rendered on; a software adapter (lavapipe here) gives way
/// to the CPU with a one-line notice unless `--software-gpu` asks for it; Mesa's
/// `XDG_RUNTIME_DIR` complaint never shows.
#[test]
fn software_adapters_give_way_to_the_cpu_quietly() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("arch.png");
    let arch = trees().join("arch.ron");
    let run = |extra: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_karstic"))
            .args([
                "render",
                arch.to_str().unwrap(),
                "-o",
                png.to_str().unwrap(),
            ])
            .args(["--size", "32", "18", "--gpu"])
            .args(extra)
            .env_remove("XDG_RUNTIME_DIR")
            .output()
            .unwrap();
        assert!(out.status.success());
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let err = run(&[]);
    assert!(!err.contains("XDG_RUNTIME_DIR"), "{err}");
    match karstic::render::gpu::GpuContext::new() {
        Ok(ctx) if ctx.software => {
            assert!(
                err.contains("software") && err.contains("on the CPU"),
                "{err}"
            );
            let err = run(&["--software-gpu"]);
            assert!(
                err.contains(&format!("on the GPU ({})", ctx.adapter)),
                "{err}"
            );
        }
        Ok(ctx) => assert!(
            err.contains(&format!("on the GPU ({})", ctx.adapter)),
            "{err}"
        ),
        Err(_) => assert!(err.contains("on the CPU instead"), "{err}"),
    }
}

/// `karstic render TREE -o PNG --size 96 54 EXTRA…`, which must succeed; its stderr.
fn render_small(tree: &Path, png: &Path, extra: &[&str]) -> String {
    let mut args = vec![
        "render",
        tree.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ];
    args.extend(["--size", "96", "54"]);
    args.extend(extra);
    let (ok, err) = karstic(&args);
    assert!(ok, "{err}");
    err
}

/// On a tree whose job has a region, `karstic render` meshes what its camera sees of the
/// region and follows the mesh (as `karstic run`'s pictures do): on the main job the
/// picture is the one `--no-guide` traces from the whole field on all but a few grazed
/// pixels, for under half the evaluations a ray; the summary line says so.
#[test]
fn render_follows_the_jobs_mesh_unless_told_not_to() {
    let dir = tempfile::tempdir().unwrap();
    let tree = trees().join("jacksboro_caves.ron");
    let render = |name: &str, extra: &[&str]| {
        let png = dir.path().join(name);
        let err = render_small(&tree, &png, extra);
        let steps: f64 = err
            .split(" steps per ray")
            .next()
            .and_then(|s| s.rsplit(' ').next())
            .and_then(|s| s.parse().ok())
            .unwrap_or_else(|| panic!("no steps in {err:?}"));
        (image::open(&png).unwrap().to_rgb8(), steps, err)
    };
    let (guided, guided_steps, said) = render("guided.png", &[]);
    let (plain, plain_steps, plain_said) = render("plain.png", &["--no-guide"]);
    assert!(said.contains("guided by the job's mesh"), "{said}");
    assert!(!plain_said.contains("guided"), "{plain_said}");
    assert!(
        guided_steps < 0.5 * plain_steps,
        "{guided_steps} steps a ray guided, {plain_steps} not"
    );
    let close = guided
        .pixels()
        .zip(plain.pixels())
        .filter(|(a, b)| (0..3).all(|c| a[c].abs_diff(b[c]) <= 6))
        .count();
    assert!(
        close * 100 >= 97 * 96 * 54,
        "{close} of {} pixels match",
        96 * 54
    );
}

/// When `--gpu` falls back to the CPU (no adapter, a software one, a tree without an
/// encoding), the CPU follows the job's mesh as plain `render` does: the fallback was
/// 13× slower than `render` without `--gpu` (49 steps a ray against 2.7).
#[test]
fn the_gpu_fallback_follows_the_jobs_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("v.png");
    let valley = trees().join("elevation_valley.ron");
    let (ok, err) = karstic(&[
        "render",
        valley.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--size",
        "80",
        "45",
        "--gpu",
    ]);
    // An elevation tree has no GPU encoding: whatever the machine, the CPU renders.
    assert!(ok && err.contains("rendered on the CPU instead"), "{err}");
    assert!(err.contains("guided by the job's mesh"), "{err}");
}

/// `--bare` leaves out the trees a job's pictures grow: on the bluff's hillside the
/// picture changes (and lightens: crowns are darker than the ground) where it draws them.
#[test]
fn render_bare_leaves_out_the_trees() {
    let dir = tempfile::tempdir().unwrap();
    let tree = trees().join("jacksboro_bluff.ron");
    let draw = |name: &str, extra: &[&str]| {
        let png = dir.path().join(name);
        render_small(&tree, &png, extra);
        image::open(&png).unwrap().to_luma8().into_raw()
    };
    let (wooded, bare) = (
        draw("w.png", &["--quiet"]),
        draw("b.png", &["--quiet", "--bare"]),
    );
    let changed = wooded
        .iter()
        .zip(&bare)
        .filter(|(a, b)| a.abs_diff(**b) > 8)
        .count();
    assert!(
        changed * 5 > wooded.len(),
        "{changed} of {} pixels",
        wooded.len()
    );
    let mean = |v: &[u8]| v.iter().map(|&x| x as f32).sum::<f32>() / v.len() as f32;
    assert!(mean(&bare) > mean(&wooded) + 5.0);
}

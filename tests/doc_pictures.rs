//! The pictures of README.md and docs/*.md are made by the tool and stay small: every
//! picture link resolves to a file in `docs/img/`, every file there is linked and made by
//! [`COMMANDS`], and each (and all together) stays within the byte budget.
//!
//! Regenerate them all with
//!
//! ```sh,no-run
//! KARSTIC_BLESS=1 cargo test --locked --test tests doc_pictures
//! ```
//!
//! or only some of them, named (`KARSTIC_BLESS=hoodoo_field.png,sea_cliffs.png`): then only
//! the commands writing their outputs run (a picture whose command reads another's output,
//! as `heightmap_top.png` reads `top.tif`, needs that picture named too),
//!
//! which runs [`COMMANDS`] with the binary under test in a sandbox (`doc_util::Sandbox`),
//! draws `karstic sample` sections rock / air and `karstic build` meshes' triangles, halves
//! renders and drawings to at most [`MAX_WIDTH`] pixels (each output pixel averages 2 × 2
//! traced ones), and writes indexed PNGs of at most 256 colours (`doc_util::write_indexed`), replacing every picture in `docs/img/`.

use std::collections::BTreeSet;
use std::path::Path;

use image::imageops::FilterType;
use karstic::scene::spec::Nary;
use karstic::scene::{HeightfieldSpec, NodeSpec, Scene};
use karstic::value::Positive;
use karstic::voxel::spec::CurveSource;

use crate::doc_util::{
    Sandbox, mesh_picture, pages, picture_links, root, section_picture, shown, write_indexed,
};

/// Where the pictures live, from the repository root.
const IMG: &str = "docs/img";

/// Largest picture, in bytes (rough terrain, detail-amplified, compresses worse than
/// smooth hills: its pictures take 60–80 KB; a close-up of weathered rock, relief and
/// streaks, up to 101 KB).
const MAX_PICTURE: u64 = 112 * 1024;

/// All pictures together, in bytes (about 50 pictures of 10–100 KB; raised from 1 MiB when
/// the geology and landform pages brought six, from 1.5 MiB when the rock was weathered,
/// from 1.75 MiB when the gallery's Fig. 4 sections, the sea cliff of joint blocks and
/// the waves on water came, and from 2 MiB when the ground got its grain, the rock its
/// flakes and the cliffs' feet their rubble: 2.13 MiB then).
const MAX_TOTAL: u64 = 2304 * 1024;

/// Widest picture, in pixels: renders are made at twice this and halved.
const MAX_WIDTH: u32 = 480;

/// Pictures kept at the size their command wrote: screenshots of the editor, whose text
/// would not survive halving.
const KEPT_AT_SIZE: &[&str] = &["editor.png"];

/// The commands that make the pictures, run in a sandbox after [`prepare`] wrote the
/// variants of the main job's tree they read. Renders are 960 × 540 (the job's preview
/// size and `render`'s default).
const COMMANDS: &str = "\
karstic run trees/jacksboro_bluff.ron -o out --quiet
karstic run trees/jacksboro_bare.ron -o bare --quiet
karstic sample trees/jacksboro_bluff.ron --box 3470 4880 790 3470.5 5070 980 --res 2 761 761 -o cave_section.npy
karstic sample trees/jacksboro_bluff.ron --box 3360 4860 868 3840 5080 868.5 --res 961 441 2 -o cave_plan.npy
karstic render trees/curves/overhang.ron -o curves_overhang.png --quiet
karstic render trees/curves/arch.ron -o curves_arch.png --quiet
karstic render trees/curves/jacksboro_arch.ron -o meld_arch_after.png --quiet
karstic render trees/arch_unaware.ron -o meld_arch_before.png --camera 4700 5330 700 4620 4950 625 --fov 50 --quiet
karstic render trees/ridge_tunnel.ron -o meld_portal.png --camera 4190 6150 878 4130 6205 858 --fov 55 --quiet
karstic render trees/rock_spire.ron -o rock_spire.png --quiet
karstic render trees/warped_rocks.ron -o warped_rocks.png --quiet
karstic render trees/arch.ron -o arch.png --quiet
karstic render trees/floating_island.ron -o floating_island.png --quiet
karstic render trees/blobs.ron -o blobs.png --cost blobs_cost.png --quiet
karstic render trees/elevation_valley.ron -o elevation_valley.png --quiet
karstic sample trees/elevation_valley.ron --box 212 1050 100 212.5 1550 520 --res 2 501 421 -o elevation_section.npy
karstic build trees/arch.ron -o arch_mesh.obj --res 40 --quiet
karstic masks trees/jacksboro_caves.ron -o masks --cell 5 --box 3300 4840 480 4860 5330 1100 --quiet
karstic render trees/jacksboro_caves.ron -o heightmap_tree.png --camera 4258 4925 662 4281 5012 642 --fov 40 --quiet
karstic heightmap trees/jacksboro_caves.ron -o top.tif --cell 2.5 --region 4100 4800 4500 5200
karstic render trees/heightmap_top.ron -o heightmap_top.png --camera 4258 4925 662 4281 5012 642 --fov 40 --quiet
karstic render trees/jacksboro_bare.ron -o detail_on.png --camera 3920 5150 790 3560 5120 880 --fov 50 --bare --quiet
karstic render trees/jacksboro_smooth.ron -o detail_off.png --camera 3920 5150 790 3560 5120 880 --fov 50 --bare --quiet
karstic render trees/jacksboro_bare.ron -o amplify_on.png --camera 4150 5000 1100 3650 5050 860 --fov 50 --size 640 360 --bare --quiet
karstic render trees/jacksboro_unamplified.ron -o amplify_off.png --camera 4150 5000 1100 3650 5050 860 --fov 50 --size 640 360 --bare --quiet
karstic render trees/eroded_range.ron -o eroded_range.png --camera 600 380 300 660 700 200 --fov 50 --quiet
karstic render trees/strata_cliff.ron -o strata_cliff.png --quiet
karstic render trees/strata_islands.ron -o strata_islands.png --quiet
karstic geology section trees/strata_cliff.ron --plane -100 0 60 0 --z -5 75 --width 960 --outline -o strata_cliff_section.png
karstic geology section trees/paper/fig4_fold.ron --plane -100 0 60 0 --z -5 75 --width 960 --outline -o fig4_fold_section.png
karstic geology section trees/paper/fig4_local.ron --plane -100 0 60 0 --z -5 75 --width 960 --outline -o fig4_local_section.png
karstic geology section trees/paper/fig4_fault.ron --plane -100 0 60 0 --z -5 75 --width 960 --outline -o fig4_fault_section.png
karstic render trees/sea_cliffs.ron -o sea_cliffs.png --quiet
karstic render trees/sea_stacks.ron -o sea_stacks.png --quiet
karstic render trees/sea_stacks.ron -o sea_stacks_foot.png --camera 190 20 6 150 80 9 --fov 55 --quiet
karstic sample trees/karst_network.ron --box 0 300 -5 396 300.5 75 --res 397 2 161 -o karst_section.npy
karstic render trees/hoodoo_field.ron -o hoodoo_field.png --size 640 360 --quiet
karstic render trees/fin_arch.ron -o fin_arch.png --size 640 360 --quiet
karstic render trees/jacksboro_canyon.ron -o jacksboro_canyon.png --quiet
karstic geology section trees/jacksboro_canyon.ron --plane 5350 6450 5950 6450 --z 280 560 --width 960 --outline -o canyon_section.png
karstic sample trees/strata_islands.ron --box 330 455 40 490 455.5 135 --res 480 2 286 -o islands_caves.npy
karstic render trees/strata_islands.ron -o islands_cave_mouth.png --camera 392 424 138 416 450 104 --fov 60 --size 640 360 --quiet
karstic edit trees/jacksboro_caves.ron --screenshot editor.png --size 900 540 --select arch --graph --cpu
";

/// What [`COMMANDS`] write that becomes a picture, and the picture's name in `docs/img/`.
/// An output ending in `*.png` takes every PNG of its folder with that prefix under its
/// own name: the main job's preview, and the views `karstic run` writes beside it.
const PICTURES: &[(&str, &str)] = &[
    ("out/jacksboro_bluff*.png", ""),
    ("editor.png", "editor.png"),
    ("bare/jacksboro_bare.png", "jacksboro_bare.png"),
    ("cave_section.npy", "cave_section.png"),
    ("cave_plan.npy", "cave_plan.png"),
    ("elevation_section.npy", "elevation_section.png"),
    ("elevation_valley.png", "elevation_valley.png"),
    ("curves_overhang.png", "curves_overhang.png"),
    ("curves_arch.png", "curves_arch.png"),
    ("meld_arch_after.png", "meld_arch_after.png"),
    ("meld_arch_before.png", "meld_arch_before.png"),
    ("meld_portal.png", "meld_portal.png"),
    ("rock_spire.png", "rock_spire.png"),
    ("warped_rocks.png", "warped_rocks.png"),
    ("arch.png", "arch.png"),
    ("floating_island.png", "floating_island.png"),
    ("blobs.png", "blobs.png"),
    ("blobs_cost.png", "blobs_cost.png"),
    ("arch_mesh.obj", "arch_mesh.png"),
    ("masks/jacksboro_caves_cave.png", "masks_cave.png"),
    ("masks/jacksboro_caves_flow.png", "masks_flow.png"),
    ("heightmap_tree.png", "heightmap_tree.png"),
    ("heightmap_top.png", "heightmap_top.png"),
    ("detail_on.png", "detail_on.png"),
    ("detail_off.png", "detail_off.png"),
    ("amplify_on.png", "amplify_on.png"),
    ("amplify_off.png", "amplify_off.png"),
    ("eroded_range.png", "eroded_range.png"),
    ("strata_cliff.png", "strata_cliff.png"),
    ("strata_islands.png", "strata_islands.png"),
    ("strata_cliff_section.png", "strata_cliff_section.png"),
    ("fig4_fold_section.png", "fig4_fold_section.png"),
    ("fig4_local_section.png", "fig4_local_section.png"),
    ("fig4_fault_section.png", "fig4_fault_section.png"),
    ("sea_cliffs.png", "sea_cliffs.png"),
    ("sea_stacks.png", "sea_stacks.png"),
    ("sea_stacks_foot.png", "sea_stacks_foot.png"),
    ("karst_section.npy", "karst_section.png"),
    ("hoodoo_field.png", "hoodoo_field.png"),
    ("fin_arch.png", "fin_arch.png"),
    ("jacksboro_canyon.png", "jacksboro_canyon.png"),
    ("canyon_section.png", "canyon_section.png"),
    ("islands_caves.npy", "islands_caves.png"),
    ("islands_cave_mouth.png", "islands_cave_mouth.png"),
];

/// Whether [`PICTURES`] makes a picture named `name`.
fn made(name: &str) -> bool {
    PICTURES
        .iter()
        .any(|&(output, file)| match output.strip_suffix("*.png") {
            Some(_) => made_by(output, name),
            None => file == name,
        })
}

/// Whether the output pattern `output` (ending in `*.png`) makes a picture named `name`.
fn made_by(output: &str, name: &str) -> bool {
    output.strip_suffix("*.png").is_some_and(|prefix| {
        let prefix = prefix.rsplit('/').next().unwrap_or(prefix);
        name.starts_with(prefix) && name.ends_with(".png")
    })
}

/// Half-length across the span of the ground curve under the arch of `arch_unaware.ron`,
/// in metres: the thesis's way to give a lone arch a ground (Becher 2016, Figure 7.6).
const UNAWARE_GROUND: f32 = 80.0;

/// Writes the variants of the main job's tree that [`COMMANDS`] render into the sandbox's
/// `trees/`: `jacksboro_bare.ron`, its terrain alone under the same `job` section (the DEM
/// before amplification, seen as the main job sees it), and `arch_unaware.ron`, the arch
/// volume of `curves/jacksboro_arch.ron` built without the terrain (`on_terrain: false`)
/// but with a ground curve under the apex, united with the terrain (not amplified: it has no job) — what a Feature
/// Volume did to a terrain before `Replace`; `jacksboro_smooth.ron`, the terrain without its
/// detail amplification; `jacksboro_unamplified.ron`, the terrain without its eroded
/// amplification; and `heightmap_top.ron`, the main job's heightmap as a scene.
fn prepare(trees: &Path) {
    let mut main = karstic::scene::load(trees.join("jacksboro_bluff.ron"))
        .expect("the main job's tree")
        .scene;
    // The DEM alone: without the rock's colours either.
    main.geology = None;
    let named = main.named();
    let terrain = main
        .terrain
        .as_deref()
        .expect("the main job names its terrain");
    let dem = named[terrain].clone();
    // The Feature Curves arch on the same DEM (its volume names no file).
    let curve_arch = karstic::scene::load(trees.join("curves/jacksboro_arch.ron"))
        .expect("the curve arch's tree")
        .scene;
    let mut arch = curve_arch.named()["arch"].clone();
    let NodeSpec::FeatureVolume(volume) = &mut arch else {
        panic!("the curve arch's `arch` is a FeatureVolume")
    };
    volume.on_terrain = false;
    let CurveSource::Inline(features) = &mut volume.curves else {
        panic!("the curve arch is written inline")
    };
    for a in &mut features.arches {
        a.ground = Some(Positive::new(UNAWARE_GROUND));
    }
    let write = |file: &str, scene: Scene| {
        let path = trees.join(file);
        std::fs::write(&path, scene.to_ron()).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    };
    // The main job's heightmap around the arch (`top.tif`, written by COMMANDS at the
    // sandbox's root) as the only node of a scene.
    let top = "(version: 1, root: Heightfield(source: \"../top.tif\", falloff: 5.0, placement: (4100, 4800)))";
    std::fs::write(trees.join("heightmap_top.ron"), top).expect("heightmap_top.ron");
    // At three quarters of the preview's size: the bare slopes' texture fills more bytes
    // than the cliff does, and the page shows both at one width.
    let mut bare_job = main.job.clone().expect("the main job has a job section");
    bare_job.image = (bare_job.image.0 * 3 / 4, bare_job.image.1 * 3 / 4);
    write(
        "jacksboro_bare.ron",
        Scene {
            name: Some("jacksboro_bare".into()),
            root: dem.clone(),
            job: Some(bare_job),
            ..main.clone()
        },
    );
    let NodeSpec::Heightfield(mut smooth) = dem.clone() else {
        panic!("the main job's terrain is a Heightfield")
    };
    assert!(
        smooth.amplify.is_some(),
        "the main job's terrain is amplified"
    );
    write(
        "jacksboro_unamplified.ron",
        Scene {
            name: Some("jacksboro_unamplified".into()),
            root: NodeSpec::Heightfield(HeightfieldSpec {
                amplify: None,
                ..smooth.clone()
            }),
            ..main.clone()
        },
    );
    assert!(smooth.detail.is_some(), "the main job's terrain has detail");
    smooth.detail = None;
    write(
        "jacksboro_smooth.ron",
        Scene {
            name: Some("jacksboro_smooth".into()),
            root: NodeSpec::Heightfield(smooth),
            ..main.clone()
        },
    );
    // Without a job, nothing gives the amplification its region: the DEM as read.
    let NodeSpec::Heightfield(plain) = dem else {
        panic!("the main job's terrain is a Heightfield")
    };
    let plain = NodeSpec::Heightfield(HeightfieldSpec {
        amplify: None,
        ..plain
    });
    write(
        "arch_unaware.ron",
        Scene {
            name: Some("arch_unaware".into()),
            job: None,
            root: NodeSpec::Union(Nary {
                name: None,
                children: vec![plain, arch],
            }),
            ..main
        },
    );
}

/// Whether `command` (a line of [`COMMANDS`]) writes `output` (of [`PICTURES`]): its `-o`
/// names the output's file or folder.
fn writes(command: &str, output: &str) -> bool {
    let target = output.split('/').next().unwrap_or(output);
    let words: Vec<&str> = command.split_whitespace().collect();
    words
        .windows(2)
        .any(|w| (w[0] == "-o" || w[0] == "--screenshot") && w[1] == target)
}

/// Makes the pictures into `docs/img/`: all of them (the folder emptied first) when `only`
/// is `None`, else those named.
fn regenerate(only: Option<&BTreeSet<String>>) {
    let wanted = |&&(output, file): &&(&str, &str)| {
        only.is_none_or(|names| {
            names.contains(file) || (file.is_empty() && names.iter().any(|n| made_by(output, n)))
        })
    };
    let pictures: Vec<&(&str, &str)> = PICTURES.iter().filter(wanted).collect();
    assert!(
        !pictures.is_empty(),
        "KARSTIC_BLESS names no picture of PICTURES"
    );
    let commands: Vec<&str> = COMMANDS
        .lines()
        .filter(|c| only.is_none() || pictures.iter().any(|(output, _)| writes(c, output)))
        .collect();
    let sandbox = Sandbox::new();
    prepare(&sandbox.repo().join("trees"));
    let ran = sandbox.run(&format!("set -e\n{}\n", commands.join("\n")));
    assert!(ran.ok, "the picture commands failed:\n{}", ran.output);
    let img = root().join(IMG);
    if img.is_dir() && only.is_none() {
        for entry in std::fs::read_dir(&img).expect("docs/img") {
            let path = entry.expect("docs/img entry").path();
            std::fs::remove_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        }
    }
    std::fs::create_dir_all(&img).expect("docs/img");
    for &&(output, file) in &pictures {
        let from = sandbox.repo().join(output);
        let outputs: Vec<(std::path::PathBuf, String)> = match output.strip_suffix("*.png") {
            Some(prefix) => {
                let (dir, stem) = prefix.rsplit_once('/').unwrap_or((".", prefix));
                let dir = sandbox.repo().join(dir);
                let mut found: Vec<_> = std::fs::read_dir(&dir)
                    .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
                    .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
                    .filter(|n| n.starts_with(stem) && n.ends_with(".png"))
                    .map(|n| (dir.join(&n), n))
                    .collect();
                found.sort();
                assert!(!found.is_empty(), "no {output} written");
                found
            }
            None => vec![(from, file.to_string())],
        };
        for (from, name) in outputs {
            let full = match from.extension().and_then(|e| e.to_str()) {
                Some("npy") => section_picture(&from),
                Some("obj") => mesh_picture(&from, 2 * MAX_WIDTH, 2 * MAX_WIDTH * 9 / 16),
                _ => image::open(&from)
                    .unwrap_or_else(|e| panic!("{}: {e}", from.display()))
                    .to_rgb8(),
            };
            let factor = if KEPT_AT_SIZE.contains(&name.as_str()) {
                1
            } else {
                full.width().div_ceil(MAX_WIDTH).max(1)
            };
            let (w, h) = (full.width() / factor, full.height() / factor);
            let picture = image::imageops::resize(&full, w, h, FilterType::Triangle);
            write_indexed(&picture, &img.join(name));
        }
    }
}

#[test]
fn doc_pictures_are_linked_made_by_the_tool_and_small() {
    if let Some(bless) = std::env::var_os("KARSTIC_BLESS") {
        let bless = bless.to_string_lossy();
        let names: BTreeSet<String> = bless
            .split(',')
            .filter(|n| n.ends_with(".png"))
            .map(str::to_string)
            .collect();
        regenerate((!names.is_empty()).then_some(&names));
    }
    let img = root().join(IMG);
    let mut problems = Vec::new();
    let mut linked = BTreeSet::new();
    for (page, text) in pages() {
        let dir = page.parent().expect("a page's folder");
        for (line, alt, target) in picture_links(&text) {
            let at = format!("{}:{line}: ![{alt}]({target})", shown(&page));
            let path = dir.join(&target);
            let file = path.canonicalize().ok();
            match file
                .as_deref()
                .and_then(|f| f.strip_prefix(img.canonicalize().ok()?).ok())
            {
                Some(name) if path.is_file() => {
                    linked.insert(name.to_string_lossy().into_owned());
                }
                _ => problems.push(format!("{at}: not a file in {IMG}/")),
            }
            if alt.trim().is_empty() {
                problems.push(format!("{at}: say what the picture shows in its alt text"));
            }
        }
    }
    let mut total = 0;
    let mut files = BTreeSet::new();
    for entry in std::fs::read_dir(&img).expect("docs/img") {
        let path = entry.expect("docs/img entry").path();
        let name = path
            .file_name()
            .expect("a name")
            .to_string_lossy()
            .into_owned();
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        total += bytes.len() as u64;
        if !bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
            problems.push(format!("{IMG}/{name}: not a PNG"));
        }
        if bytes.len() as u64 > MAX_PICTURE {
            problems.push(format!(
                "{IMG}/{name}: {} bytes > {MAX_PICTURE}",
                bytes.len()
            ));
        }
        if !made(&name) {
            problems.push(format!(
                "{IMG}/{name}: not made by the picture commands (PICTURES)"
            ));
        }
        if !linked.contains(&name) {
            problems.push(format!("{IMG}/{name}: linked from no page"));
        }
        files.insert(name);
    }
    for &(_, file) in PICTURES {
        if !file.is_empty() && !files.contains(file) {
            problems.push(format!("{IMG}/{file} is missing: regenerate the pictures"));
        }
    }
    if total > MAX_TOTAL {
        problems.push(format!("{IMG}/: {total} bytes in all > {MAX_TOTAL}"));
    }
    assert!(
        problems.is_empty(),
        "{}\n(regenerate with `KARSTIC_BLESS=1 cargo test --locked --test tests doc_pictures`)",
        problems.join("\n")
    );
    // The README shows what the tool makes.
    assert!(
        [
            "jacksboro_bluff.png",
            "jacksboro_bare.png",
            "cave_section.png"
        ]
        .iter()
        .all(|f| linked.contains(*f)),
        "{linked:?}"
    );
}

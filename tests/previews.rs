//! The pictures the main job makes: a preview that reads as terrain (no white band, not
//! one flat colour), a close-up of each feature that shows it (into the tunnel's mouth,
//! through the arch), a contact sheet; `karstic render` takes the tree's job camera.

use std::path::Path;

use karstic::field::Field;
use karstic::job::{self, JobOptions};
use karstic::render::{Camera, Materials, Method, TraceParams, cpu, views};

use crate::render_cli::karstic;

const SCENE: &str = "trees/jacksboro_caves.ron";

/// A quiet job writing to `out_dir`, with the feature views when `views`.
fn quiet_job(out_dir: &Path, views: bool) -> JobOptions {
    JobOptions {
        out_dir: out_dir.to_path_buf(),
        full: false,
        no_render: false,
        no_views: !views,
        quiet: true,
        budget: karstic::io::DEFAULT_MEMORY_BUDGET,
        origin: karstic::mesh::export::Origin::Dem,
        masks: false,
    }
}

fn rgb(path: &Path) -> image::RgbImage {
    image::open(path).unwrap().to_rgb8()
}

#[test]
fn main_preview_reads_as_terrain_and_each_feature_gets_a_view() {
    let dir = tempfile::tempdir().unwrap();
    let opts = quiet_job(dir.path(), true);
    let r = job::run(Path::new(SCENE), &opts).unwrap();
    // Named after the file.
    let preview = r.image_path.clone().unwrap();
    assert_eq!(preview.file_name().unwrap(), "jacksboro_caves.png");
    let img = rgb(&preview);
    let n = (img.width() * img.height()) as f64;
    let white = img
        .pixels()
        .filter(|p| p.0.iter().all(|&c| c > 235))
        .count() as f64;
    assert!(white <= 0.02 * n, "{:.1}% near white", 100.0 * white / n);
    let green = img
        .pixels()
        .filter(|p| p[1] as i32 > p[0] as i32 + 8 && p[1] as i32 > p[2] as i32 + 8)
        .count() as f64;
    assert!(green <= 0.6 * n, "{:.0}% green", 100.0 * green / n);
    let mut bins = std::collections::HashMap::new();
    for p in img.pixels() {
        *bins.entry(p.0.map(|c| c / 32)).or_insert(0usize) += 1;
    }
    let top = *bins.values().max().unwrap() as f64;
    assert!(top <= 0.35 * n, "one colour covers {:.0}%", 100.0 * top / n);

    // A view of each feature a camera can see, the sealed chamber excepted, and a sheet.
    let names: Vec<&str> = r.views.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["grotto", "arch", "cave", "sheet"]);
    assert!(
        r.notices.iter().any(|n| n.contains("\"chamber\"")),
        "{:?}",
        r.notices
    );
    for (_, p) in &r.views {
        assert!(rgb(p).width() > 0);
    }

    // The views' cameras, found again as the job finds them.
    let tree = &r.tree;
    let file = karstic::scene::load(Path::new(SCENE)).unwrap();
    let ground = file.compile().unwrap().ground;
    let job = file.scene.job.clone().unwrap();
    let materials = Materials::for_scene(&r.region, ground);
    let view = |name: &str| {
        let feature = tree
            .info(karstic::landform::feature_node(tree, name).unwrap())
            .support
            .intersection(r.region);
        // The job's camera for the feature when it names one, else its automatic close-up.
        let cam = match job.views.get(name) {
            Some(c) => Camera::look_at(c.eye.0, c.target.0, job.fov.0, 160, 90).unwrap(),
            None => views::feature_view(tree, &[], &feature, &materials, 40.0, (160, 90))
                .unwrap()
                .unwrap(),
        };
        let params = TraceParams::for_scene(Method::Segment, 2.0 * tree.support().radius())
            .with_pixel_angle(cam.pixel_angle());
        let depth = cpu::depth(tree, &cam, &params).0;
        (cam, depth, feature)
    };

    // Into the tunnel's mouth: the centre lies deeper than the terrain around the mouth.
    let (cam, depth, _) = view("cave");
    let (w, h) = (cam.width as i32, cam.height as i32);
    let at = |i: i32, j: i32| depth[(i + j * w) as usize];
    let median = |mut v: Vec<f32>| {
        v.sort_by(f32::total_cmp);
        v[v.len() / 2]
    };
    let centre = median(
        (-4..=4)
            .flat_map(|dj| (-4..=4).map(move |di| (w / 2 + di, h / 2 + dj)))
            .map(|(i, j)| at(i, j))
            .collect(),
    );
    let ring = median(
        (0..w)
            .flat_map(|i| [(i, h / 8), (i, h - 1 - h / 8)])
            .chain((0..h).flat_map(|j| [(w / 8, j), (w - 1 - w / 8, j)]))
            .map(|(i, j)| at(i, j))
            .filter(|t| t.is_finite())
            .collect(),
    );
    assert!(
        centre > ring + 10.0,
        "tunnel centre at {centre} m, around it {ring} m"
    );

    // Through the arch: across its opening, not along its span (end-on, a thin arch is
    // a pillar of rock): in many rows, pixels between two pixels of the arch see sky or
    // ground farther than the arch — at least a tenth as many as the arch covers.
    let (cam, depth, feature) = view("arch");
    let w = cam.width;
    let on_arch = |k: usize| {
        let t = depth[k];
        let p = cam.pixel_ray(k as u32 % w, k as u32 / w).at(t);
        t.is_finite() && feature.contains(p) && materials.feature(p) >= 1.0
    };
    let (mut arch_pixels, mut through) = (0, 0);
    for j in 0..cam.height as usize {
        let row: Vec<usize> = (0..w as usize).map(|i| i + j * w as usize).collect();
        let arch: Vec<usize> = row.iter().copied().filter(|&k| on_arch(k)).collect();
        arch_pixels += arch.len();
        let (Some(&first), Some(&last)) = (arch.first(), arch.last()) else {
            continue;
        };
        let far = arch.iter().map(|&k| depth[k]).fold(0.0f32, f32::max);
        through += (first..last)
            .filter(|&k| !on_arch(k) && depth[k] > far + 10.0)
            .count();
    }
    assert!(
        through * 10 >= arch_pixels,
        "the arch view sees {through} pixels behind the span, the arch covers {arch_pixels}"
    );
}

#[test]
fn render_takes_the_job_camera_and_frames_the_surface_without_one() {
    let dir = tempfile::tempdir().unwrap();
    let out = |name: &str| dir.path().join(name);
    let run = |args: &[&str]| {
        let (ok, err) = karstic(args);
        assert!(ok, "{err}");
    };
    let a = out("job.png");
    run(&[
        "render",
        SCENE,
        "-o",
        a.to_str().unwrap(),
        "--size",
        "96",
        "54",
        "--quiet",
    ]);
    let b = out("explicit.png");
    run(&[
        "render",
        SCENE,
        "-o",
        b.to_str().unwrap(),
        "--size",
        "96",
        "54",
        "--quiet",
        "--camera",
        "4900",
        "4380",
        "780",
        "4480",
        "4990",
        "690",
    ]);
    assert_eq!(
        rgb(&a).as_raw(),
        rgb(&b).as_raw(),
        "the job's camera is the default"
    );

    // Without a job, the surface is centred and spans two thirds of the image or more
    // (the floating island sat in the top-left third when its support box was framed).
    let tree = karstic::scene::load(Path::new("trees/floating_island.ron"))
        .unwrap()
        .compile()
        .unwrap()
        .tree;
    let cam: Camera = views::frame_surface(&tree, 40.0, 96, 54).unwrap();
    let params = TraceParams::for_scene(Method::Segment, 2.0 * tree.support().radius())
        .with_pixel_angle(cam.pixel_angle());
    let depth = cpu::depth(&tree, &cam, &params).0;
    let hit = |i: u32, j: u32| depth[(i + j * 96) as usize].is_finite();
    let cols: Vec<u32> = (0..96).filter(|&i| (0..54).any(|j| hit(i, j))).collect();
    let rows: Vec<u32> = (0..54).filter(|&j| (0..96).any(|i| hit(i, j))).collect();
    let span = |v: &[u32]| v.last().unwrap() - v.first().unwrap() + 1;
    assert!(
        span(&cols) >= 64 || span(&rows) >= 36,
        "{} × {} of 96 × 54",
        span(&cols),
        span(&rows)
    );
    let mid = |v: &[u32], n: u32| (v.first().unwrap() + v.last().unwrap()) as i32 - n as i32 + 1;
    assert!(
        mid(&cols, 96).abs() <= 10 && mid(&rows, 54).abs() <= 8,
        "centred: {} {}",
        mid(&cols, 96),
        mid(&rows, 54)
    );
}

/// One tree, one picture: `run`'s preview of `sea_cliffs` is `render`'s (the job drew no
/// sea and no geology colours when it built its settings apart).
#[test]
fn run_and_render_draw_the_same_picture() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string("trees/sea_cliffs.ron").unwrap();
    let data = std::fs::canonicalize("trees/data").unwrap();
    let small = text
        .replace("image: (960, 540)", "image: (192, 108)")
        .replace("\"data/", &format!("\"{}/", data.display()));
    assert_ne!(
        small, text,
        "the job's image size is where the test expects it"
    );
    let tree = dir.path().join("sea.ron");
    std::fs::write(&tree, small).unwrap();
    let opts = quiet_job(&dir.path().join("out"), false);
    let report = job::run(&tree, &opts).unwrap();
    let rendered = dir.path().join("render.png");
    let (ok, err) = karstic(&[
        "render",
        tree.to_str().unwrap(),
        "-o",
        rendered.to_str().unwrap(),
        "--size",
        "192",
        "108",
        "--quiet",
    ]);
    assert!(ok, "{err}");
    let (a, b) = (rgb(&report.image_path.unwrap()), rgb(&rendered));
    assert_eq!(a.dimensions(), b.dimensions());
    let diffs: Vec<u8> = a
        .as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(x, y)| x.abs_diff(*y))
        .collect();
    let mean = diffs.iter().map(|&d| d as f64).sum::<f64>() / diffs.len() as f64;
    let far = diffs.iter().filter(|&&d| d > 24).count() as f64 / diffs.len() as f64;
    eprintln!(
        "run vs render: mean {mean:.2}, {:.2}% beyond 24",
        100.0 * far
    );
    assert!(
        mean < 1.5 && far < 0.03,
        "mean {mean:.2}, {:.2}% beyond 24",
        100.0 * far
    );
}

/// A job view under a name that is no feature is a close-up of its own, written after the
/// features' (a part of a landform: an arch, a shelter).
#[test]
fn a_job_view_of_no_feature_is_written_after_the_features() {
    let dir = tempfile::tempdir().unwrap();
    let tree = dir.path().join("t.ron");
    std::fs::write(
        &tree,
        "(version: 1, job: (region: (min: (-40, -30, -6), max: (40, 30, 30)), cell: 2.0, \
         image: (64, 36), views: {\"overlook\": (eye: (0, -60, 20), target: (0, 0, 10))}), \
         root: Difference(base: Primitive(name: \"ground\", shape: Box(center: (0, 0, -4), \
         half_size: (60, 40, 4)), falloff: 3.0), carves: [Primitive(name: \"pit\", \
         shape: Sphere(center: (0, 0, 0), radius: 6), falloff: 2.0)]))",
    )
    .unwrap();
    let r = job::run(&tree, &quiet_job(&dir.path().join("out"), true)).unwrap();
    let names: Vec<&str> = r.views.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["pit", "overlook", "sheet"]);
    assert!(rgb(&r.views[1].1).width() == 32);
}

/// A scene's climate sets the cover between the rocks: `Arid` (trees/fin_arch.ron) gives
/// red sand and dark scrub where the same scene, temperate, grows green grass; the rock
/// stays the rock.
#[test]
fn an_arid_scene_lies_on_sand_and_scrub_a_temperate_one_on_grass() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/fin_arch.ron");
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(
        text.contains("climate: Arid"),
        "the fin arch stands in a desert"
    );
    let cover = |text: &str| {
        let scene = karstic::scene::parse_scene(text, &path).unwrap();
        let tree = karstic::scene::SceneFile {
            scene: scene.clone(),
            path: path.clone(),
            base_dir: path.parent().unwrap().to_path_buf(),
        }
        .compile()
        .unwrap()
        .tree;
        let m = karstic::picture::materials(&scene, &tree, None);
        // Flat ground far from the fin, at many places (patches of the second cover), on
        // the top surface (3 m under it, a point lies under a roof).
        let top = m
            .top
            .as_ref()
            .expect("the job's pictures find the top surface");
        let flat: Vec<glam::Vec3> = (0..200)
            .map(|k| {
                let xy = glam::Vec2::new(-70.0 + 0.7 * k as f32, 30.0);
                m.albedo(xy.extend(top.height(xy).unwrap()), glam::Vec3::Z)
            })
            .collect();
        (flat, m.rock)
    };
    let (arid, arid_rock) = cover(&text);
    let (temperate, rock) = cover(&text.replace("climate: Arid,", ""));
    assert_eq!(arid_rock, rock);
    let sand = arid.iter().filter(|a| a.x > 1.3 * a.y).count();
    let grass = temperate.iter().filter(|a| a.y > a.x).count();
    assert!(sand > 100, "{sand} of 200 arid samples are red sand");
    assert!(grass > 100, "{grass} of 200 temperate samples are green");
    assert!(arid.iter().all(|a| a.y <= a.x), "no green in the desert");
}

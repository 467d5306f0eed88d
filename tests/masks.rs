//! Texture masks over the main job's region: the cave mask marks the tunnel, the chamber,
//! the grotto and the arch, and nothing far from them; the slope mask is the DEM's slope
//! where the tree is the DEM; the PNGs are north-up over the frame; `karstic masks`.

use std::process::Command;

use glam::Vec2;
use karstic::analysis::masks::Layer;
use karstic::analysis::{Masks, Raster};
use karstic::field::{Aabb, Field, Rect};
use karstic::render::Materials;

const SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/trees/jacksboro_caves.ron");

/// The masks of the main job's region at 5 m pixels, and the tree's terrain.
fn main_job_masks() -> (Masks, std::sync::Arc<karstic::dem::HeightfieldField>) {
    let file = karstic::scene::load(SCENE).unwrap();
    let job = file.scene.job.clone().unwrap().region.unwrap();
    let compiled = file.compile().unwrap();
    let region = Aabb::new(job.min.0, job.max.0);
    let raster = Raster::new(region.footprint(), 5.0, karstic::io::DEFAULT_MEMORY_BUDGET).unwrap();
    let ground = compiled.ground.clone().unwrap();
    // At the region's scale, as the job makes its masks, mesh colours and pictures.
    let materials = Materials::for_scene(&region, compiled.ground);
    (Masks::compute(&compiled.tree, &materials, &raster), ground)
}

/// Far from every feature of the main job: east of the cave's domain (x ≤ 3860) and the
/// grotto, north of the arch's fin (y ≤ 5045).
const CLEAR: Rect = Rect {
    min: Vec2::new(3920.0, 5060.0),
    max: Vec2::new(4400.0, 5330.0),
};

#[test]
fn main_job_masks_mark_the_caves_and_follow_the_dem() {
    let (masks, ground) = main_job_masks();
    let cave = |x: f32, y: f32| masks.at(Layer::Cave, Vec2::new(x, y)).unwrap();
    // Columns over the tunnel inside the hill (ground, roof, floor), the chamber above its inner end, the
    // grotto under the northern slope and the arch's span over the valley.
    for (what, x, y) in [
        ("tunnel", 3560.0, 4958.0),
        ("tunnel", 3450.0, 4984.0),
        ("chamber", 3470.0, 4980.0),
        ("grotto", 3645.0, 5220.0),
        ("arch", 4275.0, 5002.0),
    ] {
        assert!(
            cave(x, y) > 0.99,
            "{what} at ({x}, {y}): cave mask {}",
            cave(x, y)
        );
    }
    // Nothing far from the features.
    let r = masks.raster;
    let mut worst_slope = 0.0f32;
    let mut checked = 0;
    for j in 0..r.ny {
        for i in 0..r.nx {
            let xy = r.center(i, j);
            if !(CLEAR.contains_rect(&Rect::new(xy, xy))) {
                continue;
            }
            let k = i + r.nx * j;
            assert_eq!(
                masks.cave[k], 0.0,
                "cave mask set far from the features at {xy}"
            );
            // There the tree is the DEM's leaf: its slope is the leaf's at its (detailed)
            // surface.
            let top = xy.extend(ground.height(xy));
            let n = -ground.value_grad(top).1.normalize();
            let dem = n.z.clamp(-1.0, 1.0).acos().to_degrees();
            let mask = masks.slope[k] * 90.0;
            worst_slope = worst_slope.max((mask - dem).abs());
            checked += 1;
        }
    }
    assert!(checked > 5000, "{checked} pixels in the clear area");
    // (the rough ground's normal turns fast: the probe's top and the leaf's root differ
    // by a hair)
    assert!(
        worst_slope < 0.5,
        "slope mask off the DEM's slope by {worst_slope}°"
    );
    // The cave mask is not everywhere: a few percent of the region.
    let set = masks.cave.iter().filter(|&&c| c > 0.5).count() as f32 / masks.cave.len() as f32;
    assert!(
        set > 0.005 && set < 0.1,
        "cave mask covers {set} of the region"
    );
    // The arch's top is feature rock; the valley's flow concentrates (a channel drains
    // far more than a median pixel).
    assert!(masks.at(Layer::Rock, Vec2::new(4275.0, 5002.0)).unwrap() > 0.99);
    let mut flow = masks.flow.clone();
    flow.sort_by(f32::total_cmp);
    let (median, max) = (flow[flow.len() / 2], flow[flow.len() - 1]);
    assert!(
        max > 0.999 && median < 0.6,
        "flow mask: median {median}, max {max}"
    );

    // The PNGs: one per layer, north row first, the cave mask 255 over the grotto.
    let dir = tempfile::tempdir().unwrap();
    let files = masks.write(dir.path(), "job").unwrap();
    assert_eq!(files.len(), Layer::ALL.len() + 1);
    let png = image::open(dir.path().join("job_cave.png"))
        .unwrap()
        .to_luma8();
    assert_eq!((png.width() as usize, png.height() as usize), (r.nx, r.ny));
    let (i, j) = r.pixel_at(Vec2::new(3645.0, 5220.0)).unwrap();
    assert_eq!(png.get_pixel(i as u32, (r.ny - 1 - j) as u32)[0], 255);
    let (i, j) = r.pixel_at(Vec2::new(4100.0, 5000.0)).unwrap();
    assert_eq!(png.get_pixel(i as u32, (r.ny - 1 - j) as u32)[0], 0);
}

#[test]
fn masks_command_writes_the_layers_and_refuses_bad_cells() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m");
    let run = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_karstic"))
            .args(["masks", "trees/arch.ron", "-o"])
            .arg(&out)
            .args(extra)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap()
    };
    let ok = run(&["--quiet", "--cell", "2"]);
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    for layer in ["slope", "rock", "cave", "flow"] {
        let png = image::open(out.join(format!("arch_{layer}.png"))).unwrap();
        assert!(png.width() >= 2 && png.height() >= 2);
    }
    let sidecar: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("arch_masks.json")).unwrap()).unwrap();
    assert_eq!(sidecar["first_row"], "north");
    let bad = run(&["--cell", "0"]);
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("cell size must be > 0"), "{err}");
}

/// The eroded amplification's traces as masks (issue 38): on the amplified main job
/// (`trees/jacksboro_bluff.ron`) the wear mask follows the channels — high where the flow
/// mask is, low on the interfluves — and talus and sediment show somewhere; on a terrain
/// without amplification (`jacksboro_caves.ron`) the three are 0.
#[test]
fn amplification_traces_are_masks() {
    let file = karstic::scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/trees/jacksboro_bluff.ron"
    ))
    .unwrap();
    let compiled = file.compile().unwrap();
    // Down the open slope east of the cliff line, inside the amplified region.
    let region = Aabb::new(
        glam::Vec3::new(3700.0, 4860.0, 700.0),
        glam::Vec3::new(3940.0, 5300.0, 1100.0),
    );
    let raster = Raster::new(region.footprint(), 2.5, karstic::io::DEFAULT_MEMORY_BUDGET).unwrap();
    let materials = Materials::for_scene(&region, compiled.ground);
    let masks = Masks::compute(&compiled.tree, &materials, &raster);
    let mean = |v: &[f32], pick: &dyn Fn(usize) -> bool| {
        let (s, n) = (0..v.len())
            .filter(|&k| pick(k))
            .fold((0.0, 0), |(s, n), k| (s + v[k], n + 1));
        s / n.max(1) as f32
    };
    let mut flow = masks.flow.clone();
    flow.sort_by(f32::total_cmp);
    let high = flow[flow.len() * 95 / 100];
    let low = flow[flow.len() / 2];
    let channels = mean(&masks.wear, &|k| masks.flow[k] >= high);
    let slopes = mean(&masks.wear, &|k| masks.flow[k] <= low);
    assert!(
        channels > 2.0 * slopes && channels > 0.2,
        "wear {channels} along the channels, {slopes} on the slopes"
    );
    assert!(masks.deposit.iter().any(|&v| v > 0.1), "no sediment");
    for l in [Layer::Talus, Layer::Deposit, Layer::Wear] {
        assert!(
            masks.layer(l).iter().all(|v| (0.0..=1.0).contains(v)),
            "{l:?}"
        );
    }
    let (plain, _) = main_job_masks();
    for l in [Layer::Talus, Layer::Deposit, Layer::Wear] {
        assert!(
            plain.layer(l).iter().all(|&v| v == 0.0),
            "{l:?} without amplification"
        );
    }
}

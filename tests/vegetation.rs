//! The pictures' trees and shrubs (`render::vegetation`) on the scenes of `trees/`: they
//! stand on the ground, on soil and grass and not on rock faces, above the water, out of
//! a view's sight line; they grow the same at any number of threads; the pictures draw
//! them and their shadows.

use std::path::Path;

use glam::Vec3;
use indicatif::ProgressBar;
use karstic::compile::Compiled;
use karstic::field::{Field, ISO};
use karstic::render::trace::{TraceParams, trace};
use karstic::render::{Camera, Method, Ray, RenderSettings, Vegetation, render};
use karstic::scene::SceneFile;

/// The tree file `trees/NAME.ron`, compiled, with its preview's camera at `w × h` and
/// the settings `karstic render` gives it.
fn job(name: &str, w: u32, h: u32) -> (SceneFile, Compiled, Camera, RenderSettings) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("trees")
        .join(format!("{name}.ron"));
    let file = karstic::scene::load(&path).unwrap();
    let compiled = file.compile().unwrap();
    let tree = &compiled.tree;
    let cam = karstic::picture::camera(&file.scene, tree, None, None, w, h).unwrap();
    let settings = karstic::picture::settings(
        &file.scene,
        tree,
        compiled.ground.clone(),
        &cam,
        Method::Segment,
    );
    (file, compiled, cam, settings)
}

/// The height of `field`'s first surface down from 3 m over `p`, if within 6 m.
fn ground_under(field: &dyn Field, p: Vec3) -> Option<f32> {
    let down = Ray {
        origin: p + Vec3::Z * 3.0,
        dir: -Vec3::Z,
    };
    let params = TraceParams::for_scene(Method::Segment, 100.0);
    let tr = trace(field, &down, (0.0, 6.0), &params);
    tr.hit().then(|| down.at(tr.t).z)
}

/// Every plant's foot lies on `field`'s surface (within `tol` metres: neither floating
/// nor buried), on ground no steeper than a rock face, with air over it.
fn stand_on_the_ground(name: &str, field: &dyn Field, v: &Vegetation, tol: f32) {
    let (mut sampled, mut sloped) = (0, 0);
    for (k, p) in v.plants().iter().enumerate().step_by(5) {
        sampled += 1;
        let z = ground_under(field, p.base);
        assert!(
            z.is_some_and(|z| (z - p.base.z).abs() < tol),
            "{name}: plant {k} at {} stands off the ground ({z:?})",
            p.base
        );
        // The surface's slope about the foot, from its heights a metre away.
        let at = |dx: f32, dy: f32| ground_under(field, p.base + Vec3::new(dx, dy, 0.0));
        if let (Some(e), Some(w), Some(n), Some(s)) =
            (at(1.0, 0.0), at(-1.0, 0.0), at(0.0, 1.0), at(0.0, -1.0))
        {
            let n = Vec3::new(w - e, s - n, 2.0).normalize();
            assert!(n.z > 0.5, "{name}: plant {k} at {} on a face ({n})", p.base);
            sloped += 1;
        }
        let crown = p.base + Vec3::Z * 0.6 * (p.top - p.base.z);
        assert!(
            field.value(crown) < ISO,
            "{name}: plant {k}'s crown is in the rock"
        );
    }
    // The slope is measured about nearly every foot, not skipped where it is hard.
    assert!(
        sloped * 10 >= sampled * 9,
        "{name}: slope of {sloped} of {sampled}"
    );
}

/// The bluff's hillside (a real DEM) is wooded: thousands of trees 2.5 to 32 m high,
/// standing on its ground, none on the cliff band's faces or inside its rock; and the
/// same plants grow on one thread and on three.
#[test]
fn woodland_stands_on_the_bluffs_ground_and_not_on_its_rock() {
    let (_, compiled, _, settings) = job("jacksboro_bluff", 320, 180);
    let v = settings.vegetation.clone().unwrap();
    assert!(v.plants().len() > 5_000, "{} plants", v.plants().len());
    stand_on_the_ground("jacksboro_bluff", &compiled.tree, &v, 0.6);
    for p in v.plants() {
        let h = p.top - p.base.z;
        assert!((2.5..32.0).contains(&h), "a tree {h} m high");
    }
    // Not on the cliff band: no foot in the rock of its features.
    let rocky = v
        .plants()
        .iter()
        .filter(|p| settings.materials.feature(p.base) > 0.5)
        .count();
    assert_eq!(rocky, 0, "{rocky} plants on the features");
    let grow = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| job("jacksboro_bluff", 320, 180).3.vegetation.unwrap())
    };
    assert!(
        grow(1).plants() == grow(3).plants(),
        "plants depend on the threads"
    );
}

/// A scene without a terrain heightfield (the fin arch on a noisy box) grows its desert
/// scrub on the field's own surface, shrubs 2 to 6 m high; the sea stacks' grow above the
/// water.
#[test]
fn scrub_grows_on_a_fields_surface_and_nothing_under_water() {
    let (_, compiled, _, settings) = job("fin_arch", 160, 90);
    let v = settings.vegetation.unwrap();
    assert!(v.plants().len() > 50, "{} shrubs", v.plants().len());
    stand_on_the_ground("fin_arch", &compiled.tree, &v, 0.6);
    assert!(v.plants().iter().all(|p| p.top - p.base.z < 6.0));
    // None on the arch's lintel or over a hollow: the rock is solid 12 m under each.
    for p in v.plants() {
        assert!(
            (1..=12).all(|d| compiled.tree.value(p.base - Vec3::Z * d as f32) >= ISO),
            "fin_arch: a shrub at {} stands over a hollow",
            p.base
        );
    }
    let (file, compiled, _, settings) = job("sea_stacks", 160, 90);
    let level = file.scene.job.unwrap().water_level.unwrap().0;
    let v = settings.vegetation.unwrap();
    assert!(!v.is_empty());
    stand_on_the_ground("sea_stacks", &compiled.tree, &v, 0.6);
    assert!(v.plants().iter().all(|p| p.base.z > level + 0.5));
}

/// The bluff's shelter close-up looks through the wood: the plants within its sight cone
/// are cleared, and only a few.
#[test]
fn no_plant_stands_in_a_views_sight_line() {
    let (file, _, _, settings) = job("jacksboro_bluff", 320, 180);
    let view = file.scene.job.as_ref().unwrap().views["shelter"];
    let cam = Camera::look_at(view.eye.0, view.target.0, 40.0, 160, 90).unwrap();
    let all = settings.vegetation.clone().unwrap();
    let cleared = karstic::picture::clear_sight(Some(&all), &cam).unwrap();
    let gone = all.plants().len() - cleared.plants().len();
    assert!((1..200).contains(&gone), "{gone} plants cleared");
    // Rays about the sight line, a sixth of the field of view across, meet none of them.
    let far = 0.85 * cam.eye.distance(cam.target);
    let sight = (cam.target - cam.eye).normalize();
    let (a, b) = sight.any_orthonormal_pair();
    let spread = (40f32.to_radians() / 12.0).tan();
    for k in 0..16 {
        let turn = k as f32 * std::f32::consts::TAU / 16.0;
        let dir = (sight + (a * turn.cos() + b * turn.sin()) * spread * (k % 2) as f32).normalize();
        let ray = Ray {
            origin: cam.eye,
            dir,
        };
        assert!(
            cleared.hit(&ray, far, 0.0).is_none(),
            "ray {k} meets a plant"
        );
    }
}

/// The preview draws the trees: with them, a fifth or more of its pixels change and the
/// hillside darkens (crowns are darker than grass, and shade the ground); the trees cast
/// shadows where the sun's rays through their crowns meet the ground.
#[test]
fn trees_show_in_the_picture_and_cast_shadows() {
    let (_, compiled, cam, settings) = job("jacksboro_bluff", 192, 108);
    let bare = RenderSettings {
        vegetation: None,
        ..settings.clone()
    };
    let a = render(&compiled.tree, &cam, &settings, &ProgressBar::hidden());
    let b = render(&compiled.tree, &cam, &bare, &ProgressBar::hidden());
    let grey = |f: &karstic::render::Frame| -> Vec<f32> {
        f.rgba
            .chunks(4)
            .map(|c| (c[0] as f32 + c[1] as f32 + c[2] as f32) / 3.0)
            .collect()
    };
    let (ga, gb) = (grey(&a), grey(&b));
    let changed = ga
        .iter()
        .zip(&gb)
        .filter(|(x, y)| (*x - *y).abs() > 8.0)
        .count();
    assert!(
        changed * 5 > ga.len(),
        "{changed} of {} pixels changed",
        ga.len()
    );
    let mean = |g: &[f32]| g.iter().sum::<f32>() / g.len() as f32;
    assert!(
        mean(&ga) < mean(&gb) - 5.0,
        "{} against {}",
        mean(&ga),
        mean(&gb)
    );
    // The ground a tree's shadow falls on: from the crown's middle away from the sun.
    let v = settings.vegetation.unwrap();
    let sun = settings.shading.sun;
    let params = TraceParams::for_scene(Method::Segment, 100.0);
    let shaded = v
        .plants()
        .iter()
        .step_by(97)
        .filter(|p| {
            let mid = p.base + Vec3::Z * 0.6 * (p.top - p.base.z);
            let away = Ray {
                origin: mid,
                dir: -sun,
            };
            let tr = trace(&compiled.tree, &away, (0.0, 200.0), &params);
            let q = away.at(tr.t) + sun * 0.1;
            tr.hit()
                && v.occludes(
                    &Ray {
                        origin: q,
                        dir: sun,
                    },
                    200.0,
                )
        })
        .count();
    let tried = v.plants().iter().step_by(97).count();
    assert!(
        shaded * 10 > tried * 7,
        "{shaded} of {tried} trees cast a shadow"
    );
}

/// Plants stand on the world's lattice, not their region's: two pictures whose regions
/// overlap (a preview and a close-up, a view and the next) grow the same plants there.
#[test]
fn overlapping_regions_grow_the_same_plants() {
    let (_, compiled, _, settings) = job("jacksboro_bluff", 64, 36);
    let everywhere = |_: glam::Vec2| true;
    let grow = |min: Vec3, max: Vec3| {
        let region = karstic::field::Aabb::new(min, max);
        Vegetation::grow(
            &compiled.tree,
            &settings.materials,
            &region,
            &everywhere,
            karstic::render::Flora::Woodland,
            0.55,
            None,
        )
    };
    let a = grow(
        Vec3::new(3400.0, 4900.0, 700.0),
        Vec3::new(3600.0, 5100.0, 1100.0),
    );
    let b = grow(
        Vec3::new(3513.7, 4961.3, 700.0),
        Vec3::new(3713.7, 5161.3, 1100.0),
    );
    let within = |p: &&karstic::render::vegetation::Plant| {
        (3513.7..3600.0).contains(&p.base.x) && (4961.3..5100.0).contains(&p.base.y)
    };
    let (sa, sb): (Vec<_>, Vec<_>) = (
        a.plants().iter().filter(within).collect(),
        b.plants().iter().filter(within).collect(),
    );
    assert!(sa.len() > 40, "{} plants in the overlap", sa.len());
    assert!(sa == sb, "{} against {} plants", sa.len(), sb.len());
}

/// Trees thin on steep ground (thin soil): on the bluff's hillside, ground of 30–37° holds
/// under three quarters of the trees a metre square that ground under 18° does (as many
/// before: blind judges saw a canyon's walls "as densely wooded as the flats").
#[test]
fn woodland_thins_on_steep_ground() {
    let (_, _, _, settings) = job("jacksboro_bluff", 320, 180);
    let v = settings.vegetation.clone().unwrap();
    let g = settings.materials.ground.clone().unwrap();
    let nz = |x: f32, y: f32| {
        let h = |dx: f32, dy: f32| g.base_height(glam::Vec2::new(x + dx, y + dy));
        Vec3::new(h(-1.0, 0.0) - h(1.0, 0.0), h(0.0, -1.0) - h(0.0, 1.0), 2.0)
            .normalize()
            .z
    };
    let class = |z: f32| match z {
        z if z > 0.95 => Some(0),
        z if (0.8..0.87).contains(&z) => Some(1),
        _ => None,
    };
    // The plants' extent, sampled every 5 m for the area of each class.
    let (lo, hi) = v.plants().iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(a, b), p| (a.min(p.base), b.max(p.base)),
    );
    let mut area = [0f32; 2];
    let mut x = lo.x;
    while x < hi.x {
        let mut y = lo.y;
        while y < hi.y {
            if let Some(c) = class(nz(x, y)) {
                area[c] += 25.0;
            }
            y += 5.0;
        }
        x += 5.0;
    }
    let mut count = [0f32; 2];
    for p in v.plants() {
        if let Some(c) = class(nz(p.base.x, p.base.y)) {
            count[c] += 1.0;
        }
    }
    let density = [count[0] / area[0], count[1] / area[1]];
    assert!(area[1] > 1e4 && count[1] > 50.0, "{area:?} {count:?}");
    assert!(
        density[1] < 0.75 * density[0],
        "steep ground holds {} trees a hectare, gentle {}",
        1e4 * density[1],
        1e4 * density[0]
    );
}

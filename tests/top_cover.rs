//! The cover of the pictures' top surface (`render::top_cover`) on the scenes of `trees/`:
//! talus lies under the bluff's cliff line, at no steeper than its angle of repose, and
//! nowhere that no rock rises over it; the canyon's floor carries a stream, in the valley's
//! bottom.

use std::path::Path;

use glam::{Vec2, Vec3};
use karstic::field::Field;
use karstic::heightmap::{Columns, TopOptions};
use karstic::render::Materials;
use karstic::render::trace::outward;

/// The tree file `trees/NAME.ron`, compiled, and its pictures' materials.
fn materials(name: &str) -> (karstic::compile::Compiled, Materials) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("trees")
        .join(format!("{name}.ron"));
    let file = karstic::scene::load(&path).unwrap();
    let compiled = file.compile().unwrap();
    let m = karstic::picture::materials(&file.scene, &compiled.tree, compiled.ground.clone());
    (compiled, m)
}

/// The top surface of `compiled`'s tree every `step` metres over `lo..hi`: `(xy, top)`
/// rows, NaN where a column holds no solid.
fn tops(compiled: &karstic::compile::Compiled, lo: Vec2, hi: Vec2, step: f32) -> Vec<Vec<f32>> {
    let opts = TopOptions {
        tolerance: 0.05,
        direct: true,
    };
    let mut columns = Columns::new(&compiled.tree, &opts);
    let (nx, ny) = (
        ((hi.x - lo.x) / step) as usize,
        ((hi.y - lo.y) / step) as usize,
    );
    (0..ny)
        .map(|j| {
            (0..nx)
                .map(|i| {
                    let xy = lo + Vec2::new(i as f32, j as f32) * step;
                    columns.top(xy).unwrap_or(f32::NAN)
                })
                .collect()
        })
        .collect()
}

/// The points of `tops` (sampled every `step` metres from `lo`) on `compiled`'s surface:
/// their sample's indices, the point and its outward normal.
fn surface(
    compiled: &karstic::compile::Compiled,
    tops: &[Vec<f32>],
    lo: Vec2,
    step: f32,
) -> Vec<(usize, usize, Vec3, Vec3)> {
    let mut out = Vec::new();
    for (j, row) in tops.iter().enumerate() {
        for (i, &z) in row.iter().enumerate() {
            if z.is_finite() {
                let p = (lo + Vec2::new(i as f32, j as f32) * step).extend(z);
                out.push((i, j, p, outward(compiled.tree.value_grad(p).1)));
            }
        }
    }
    out
}

/// The highest of `tops` within `radius` samples of `(i, j)`.
fn highest_near(tops: &[Vec<f32>], i: usize, j: usize, radius: usize) -> f32 {
    let mut h = f32::NEG_INFINITY;
    let (span, j0, i0) = (
        2 * radius + 1,
        j.saturating_sub(radius),
        i.saturating_sub(radius),
    );
    for (jj, row) in tops.iter().enumerate().skip(j0).take(span) {
        for (ii, &t) in row.iter().enumerate().skip(i0).take(span) {
            let d = ((ii as f32 - i as f32).powi(2) + (jj as f32 - j as f32).powi(2)).sqrt();
            if d <= radius as f32 && t.is_finite() {
                h = h.max(t);
            }
        }
    }
    h
}

/// Under the bluff's cliff line lies an apron of scree, on slopes no steeper than the
/// angle of repose (42° at most), each point of it within 40 m of rock standing 10 m
/// higher; where nothing within 40 m stands 1.5 m higher, there is no scree at all.
#[test]
fn talus_lies_under_the_bluffs_cliff_at_its_angle_of_repose() {
    let (compiled, m) = materials("jacksboro_bluff");
    assert!(m.top.is_some(), "the job's region has no top cover");
    let step = 5.0;
    let (lo, hi) = (Vec2::new(3310.0, 4850.0), Vec2::new(3950.0, 5320.0));
    let tops = tops(&compiled, lo, hi, step);
    let (mut talus, mut open) = (0, 0);
    for (i, j, p, n) in surface(&compiled, &tops, lo, step) {
        let scree = m.cover(p, n).scree;
        let above = highest_near(&tops, i, j, 8) - p.z;
        if scree > 0.5 {
            talus += 1;
            assert!(
                n.z >= 42f32.to_radians().cos(),
                "scree at {p} on a slope of {:.0}°",
                n.z.acos().to_degrees()
            );
            assert!(
                above > 10.0,
                "scree at {p} with only {above} m of rock above"
            );
        }
        if above < 1.5 {
            open += 1;
            assert_eq!(scree, 0.0, "scree at {p} with nothing above it");
        }
    }
    assert!(talus > 100, "{talus} samples of talus");
    assert!(open > 20, "{open} samples with nothing above");
}

/// The canyon's floor carries a stream, and the stream runs in the bottom of the valley:
/// no ground within 20 m of its water lies more than 5 m lower (the carved floor's
/// hollows, which the water spills through, are a few metres deep; a stream on a wall
/// would have tens of metres below it).
#[test]
fn the_canyons_stream_runs_along_its_floor() {
    let (compiled, m) = materials("jacksboro_canyon");
    let step = 5.0;
    // Across the gorge's middle reach, below the camera's view.
    let (lo, hi) = (Vec2::new(5300.0, 6000.0), Vec2::new(5900.0, 6900.0));
    let tops = tops(&compiled, lo, hi, step);
    let depths: Vec<Vec<f32>> = tops
        .iter()
        .map(|r| r.iter().map(|v| -v).collect())
        .collect();
    let mut water = 0;
    for (i, j, p, n) in surface(&compiled, &tops, lo, step) {
        let z = p.z;
        if m.cover(p, n).stream < 0.5 {
            continue;
        }
        water += 1;
        let lowest = -highest_near(&depths, i, j, 4);
        assert!(
            lowest > z - 5.0,
            "a stream at {p} runs {} m above the ground beside it",
            z - lowest
        );
    }
    assert!(water > 20, "{water} samples of the stream");
}

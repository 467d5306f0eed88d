//! Issue 7: the bundled default scene has an open tunnel cave, a free-standing arch and a
//! grotto, and the main job writes a valid mesh and image.

use glam::Vec3;
use karstic::field::{Field, T, Tree};

fn tree() -> Tree {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/trees/jacksboro_caves.ron");
    karstic::scene::load(path).unwrap().compile().unwrap().tree
}

fn crossings(t: &Tree, from: Vec3, to: Vec3, n: usize) -> usize {
    let mut last = t.value(from) > T;
    let mut count = 0;
    for i in 1..=n {
        let p = from.lerp(to, i as f32 / n as f32);
        let s = t.value(p) > T;
        count += usize::from(s != last);
        last = s;
    }
    count
}

#[test]
fn default_scene_has_an_open_tunnel_an_arch_and_a_grotto() {
    let t = tree();
    // A vertical line through the tunnel: ground, ceiling, floor.
    let c = crossings(
        &t,
        Vec3::new(3560.0, 4958.0, 700.0),
        Vec3::new(3560.0, 4958.0, 1100.0),
        4000,
    );
    assert!(
        c >= 3,
        "vertical line through the tunnel crosses the surface {c} times"
    );
    // Along the axis, from open air in front of the slope deep into the hill: no rock.
    for i in 0..=400 {
        let p = Vec3::new(3800.0, 4950.0, 863.0)
            .lerp(Vec3::new(3480.0, 4972.0, 867.0), i as f32 / 400.0);
        assert!(t.value(p) < T, "rock in the tunnel at {p}");
    }
    // That axis does run inside the hill: rock above it.
    assert!(t.value(Vec3::new(3480.0, 4972.0, 900.0)) > T);
    // A horizontal ray under the arch's span, between the ground and the arch.
    for i in 0..=200 {
        let p = Vec3::new(4594.0, 4950.0, 642.0)
            .lerp(Vec3::new(4690.0, 4950.0, 642.0), i as f32 / 200.0);
        assert!(t.value(p) < T, "the arch does not stand free at {p}");
    }
    let over_span = crossings(
        &t,
        Vec3::new(4630.0, 4950.0, 560.0),
        Vec3::new(4630.0, 4950.0, 720.0),
        1600,
    );
    assert!(
        over_span >= 3,
        "mid-span vertical line crosses {over_span} times (ground, arch underside, arch top)"
    );
    // The grotto cuts under the slope: air below rock at the anchor.
    let g = crossings(
        &t,
        Vec3::new(3645.0, 5220.0, 700.0),
        Vec3::new(3645.0, 5220.0, 1000.0),
        3000,
    );
    assert!(g >= 3, "the grotto makes an overhang: {g} crossings");
}

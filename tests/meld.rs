//! Issue 13: features meld with the terrain. Feature Volumes on a DEM take its surface as
//! boundary conditions and replace it inside their domain, so the terrain changes only
//! near the features; arches are rock slabs thinnest at the crown; tunnels are open from
//! portal to portal; no scene leaves debris.

use std::path::Path;

use glam::{Vec2, Vec3};
use karstic::compile::compile_scene;
use karstic::field::{Aabb, Field, Grid, ISO, Tree, eval_grid};
use karstic::mesh::{GridSpec, MeshOptions, polygonize};
use karstic::scene::{NodeSpec, SceneFile};

fn scene(name: &str) -> SceneFile {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("trees/{name}.ron"));
    karstic::scene::load(&path).unwrap()
}

fn tree(s: &SceneFile) -> Tree {
    s.compile().unwrap().tree
}

/// The scene without its features: every `Replace`, `Difference` and `Landform` is its
/// base, and n-ary nodes keep only the children holding a heightfield.
fn bare(s: &SceneFile) -> Tree {
    fn terrain(n: &NodeSpec) -> bool {
        matches!(n, NodeSpec::Heightfield(_)) || n.children().into_iter().any(terrain)
    }
    fn strip(n: &NodeSpec) -> NodeSpec {
        match n {
            NodeSpec::Replace(r) => strip(&r.base),
            NodeSpec::Difference(d) => strip(&d.base),
            NodeSpec::Landform(l) => strip(&l.base),
            NodeSpec::Union(x) | NodeSpec::Blend(x) | NodeSpec::Intersection(x) => {
                let kept: Vec<&NodeSpec> = x.children.iter().filter(|c| terrain(c)).collect();
                match kept.as_slice() {
                    [one] => strip(one),
                    _ => {
                        let mut n = n.clone();
                        if let Some(cs) = n.child_list_mut() {
                            *cs = kept.into_iter().map(strip).collect();
                        }
                        n
                    }
                }
            }
            n => {
                let mut n = n.clone();
                for c in n.children_mut() {
                    *c = strip(c);
                }
                n
            }
        }
    }
    let mut scene = s.scene.clone();
    scene.root = strip(&scene.root);
    compile_scene(&scene, &s.path, &s.base_dir).unwrap().tree
}

/// The top surface of every column of `region` (the highest crossing of `ISO`, linear
/// between samples), `cell` metres apart in plan and `dz` in height; NaN where none.
fn tops(t: &Tree, region: &Aabb, cell: f32, dz: f32) -> (Vec<Vec2>, Vec<f32>) {
    let n = |len: f32, step: f32| (len / step).round() as usize + 1;
    let size = region.size();
    let grid = Grid {
        origin: region.min,
        step: Vec3::new(cell, cell, dz),
        dims: [n(size.x, cell), n(size.y, cell), n(size.z, dz)],
    };
    let v = eval_grid(t, &grid, None);
    let [nx, ny, nz] = grid.dims;
    let mut xy = Vec::with_capacity(nx * ny);
    let mut top = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            xy.push(grid.point(i, j, 0).truncate());
            let at = |k: usize| v[i + nx * (j + ny * k)];
            let k = (1..nz).rev().find(|&k| at(k - 1) > ISO && at(k) <= ISO);
            top.push(k.map_or(f32::NAN, |k| {
                let (a, b) = (at(k - 1), at(k));
                region.min.z + (k as f32 - 1.0 + (a - ISO) / (a - b)) * dz
            }));
        }
    }
    (xy, top)
}

/// Plan distance from `p` to the polyline `line`.
fn plan_distance(p: Vec2, line: &[Vec2]) -> f32 {
    line.windows(2)
        .map(|w| {
            let (a, b) = (w[0], w[1]);
            let t = ((p - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
            p.distance(a + (b - a) * t)
        })
        .fold(f32::INFINITY, f32::min)
}

/// Compares the top surfaces of `t` and `bare` over `region`: columns farther than
/// `radius` (in plan) from `curve` differ by at most 1 m, and some column near the curve
/// changed by more than `changed` (the feature is there).
fn assert_melds(t: &Tree, bare: &Tree, region: Aabb, curve: &[Vec2], radius: f32, changed: f32) {
    let (xy, a) = tops(t, &region, 2.0, 1.0);
    let (_, b) = tops(bare, &region, 2.0, 1.0);
    let (mut far, mut worst, mut near_max) = (0, (0.0f32, Vec2::ZERO), 0.0f32);
    for ((p, a), b) in xy.iter().zip(&a).zip(&b) {
        let d = if a.is_nan() && b.is_nan() {
            0.0
        } else if a.is_nan() || b.is_nan() {
            f32::INFINITY
        } else {
            (a - b).abs()
        };
        if plan_distance(*p, curve) > radius {
            far += 1;
            if d > worst.0 {
                worst = (d, *p);
            }
        } else {
            near_max = near_max.max(d);
        }
    }
    assert!(far > 1000, "{far} far columns");
    assert!(
        worst.0 <= 1.0,
        "the terrain moved by {} m at {} ({} m from the feature)",
        worst.0,
        worst.1,
        plan_distance(worst.1, curve)
    );
    assert!(
        near_max > changed,
        "the feature changed the terrain by only {near_max} m"
    );
}

/// The plan path of the main jobs' tunnel cave (`jacksboro_caves.ron`, `jacksboro_bluff.ron`).
const TUNNEL: [Vec2; 4] = [
    Vec2::new(3800.0, 4950.0),
    Vec2::new(3660.0, 4950.0),
    Vec2::new(3520.0, 4965.0),
    Vec2::new(3390.0, 5000.0),
];

#[test]
fn default_scene_changes_the_terrain_only_near_its_features() {
    let s = scene("jacksboro_caves");
    let (t, b) = (tree(&s), bare(&s));
    // The arch: its fin from end to end (65 m each way from the middle of its span,
    // along it); 20 m is half the fin's widest block (at most 9 m), its noise and a
    // margin.
    let (middle, along) = (
        Vec2::new(4275.0, 5002.0),
        Vec2::new(50.0, -20.0).normalize(),
    );
    assert_melds(
        &t,
        &b,
        Aabb::new(
            Vec3::new(4100.0, 4860.0, 540.0),
            Vec3::new(4460.0, 5140.0, 720.0),
        ),
        &[middle - 65.0 * along, middle + 65.0 * along],
        20.0,
        15.0,
    );
    // The cave: the tunnel's path (its part in the air leaves no trace).
    assert_melds(
        &t,
        &b,
        Aabb::new(
            Vec3::new(3290.0, 4830.0, 720.0),
            Vec3::new(3910.0, 5120.0, 1040.0),
        ),
        &TUNNEL,
        30.0,
        5.0,
    );
}

/// The solid runs along `from → to` (their lengths, in order; one reaching `to` included).
fn solid_runs(t: &Tree, from: Vec3, to: Vec3, step: f32) -> Vec<f32> {
    let n = (from.distance(to) / step).ceil() as usize;
    let mut runs = Vec::new();
    let mut start = None;
    for i in 0..=n {
        let p = from.lerp(to, i as f32 / n as f32);
        match (t.value(p) > ISO, start) {
            (true, None) => start = Some(p),
            (false, Some(a)) => {
                runs.push(a.distance(p));
                start = None;
            }
            _ => {}
        }
    }
    runs.extend(start.map(|a| a.distance(to)));
    runs
}

#[test]
fn the_arch_is_a_slab_thinnest_at_the_crown_over_open_air() {
    let s = scene("curves/jacksboro_arch");
    let (t, ground) = (tree(&s), bare(&s));
    let (thickness, voxel) = (14.0, 2.0);
    // Vertical line through the crown: the ground, then the slab.
    let runs = solid_runs(
        &t,
        Vec3::new(4630.0, 4950.0, 720.0),
        Vec3::new(4630.0, 4950.0, 540.0),
        0.25,
    );
    assert_eq!(runs.len(), 2, "ground and slab under the crown: {runs:?}");
    assert!(
        (runs[0] - thickness).abs() <= voxel,
        "the crown is {} m thick",
        runs[0]
    );
    // Horizontal lines along the span through each leg, 12 m above its foot: the leg is
    // at least twice the crown's thickness there.
    for (foot, dir) in [(4470.0, 1.0), (4790.0, -1.0)] {
        let z = height(&ground, Vec2::new(foot, 4950.0)) + 12.0;
        let leg = solid_runs(
            &t,
            Vec3::new(foot - dir * 60.0, 4950.0, z),
            Vec3::new(foot + dir * 60.0, 4950.0, z),
            0.25,
        );
        let widest = leg.iter().copied().fold(0.0, f32::max);
        assert!(
            widest >= 2.0 * thickness,
            "the abutment at x = {foot} is {widest} m thick ({leg:?})"
        );
    }
    // Open air under the span, across it and along it.
    for (a, b) in [
        (
            Vec3::new(4560.0, 4950.0, 630.0),
            Vec3::new(4700.0, 4950.0, 630.0),
        ),
        (
            Vec3::new(4630.0, 4900.0, 625.0),
            Vec3::new(4630.0, 5000.0, 625.0),
        ),
    ] {
        assert!(
            solid_runs(&t, a, b, 0.5).is_empty(),
            "rock under the arch on {a} → {b}"
        );
    }
}

/// The main job's arch is a fin with an opening: under the middle of its span the ground,
/// open air, then the lintel; open air along the span under it; each abutment one rock
/// from the ground up to the lintel, beyond each foot.
#[test]
fn the_main_jobs_arch_is_a_fin_open_under_its_lintel() {
    let s = scene("jacksboro_caves");
    let (t, ground) = (tree(&s), bare(&s));
    let (middle, along) = (
        Vec2::new(4275.0, 5002.0),
        Vec2::new(50.0, -20.0).normalize(),
    );
    let floor = height(&ground, middle);
    let runs = solid_runs(&t, middle.extend(720.0), middle.extend(540.0), 0.25);
    assert_eq!(runs.len(), 2, "lintel and ground under mid-span: {runs:?}");
    assert!(
        (3.0..=15.0).contains(&runs[0]),
        "a lintel {} m thick",
        runs[0]
    );
    // The opening: 24 m high at mid-span, open from 2 m above the ground to 20 m.
    let open = solid_runs(
        &t,
        middle.extend(floor + 2.0),
        middle.extend(floor + 20.0),
        0.25,
    );
    assert!(open.is_empty(), "rock in the opening: {open:?}");
    for (foot, out) in [(-27.0f32, -1.0f32), (27.0, 1.0)] {
        // 6 m past the foot, away from the opening: rock from the ground to 15 m up.
        let xy = middle + along * (foot + 6.0 * out);
        let z0 = height(&ground, xy);
        let column = solid_runs(&t, xy.extend(z0 + 15.0), xy.extend(z0 - 3.0), 0.25);
        assert_eq!(
            column.len(),
            1,
            "the abutment at {xy} is broken: {column:?}"
        );
        assert!(column[0] >= 17.0, "the abutment at {xy}: {column:?}");
    }
}

/// The height of the first solid point below `z = 1200` at `xy`.
fn height(t: &Tree, xy: Vec2) -> f32 {
    let mut z = 1200.0;
    while t.value(xy.extend(z)) <= ISO {
        z -= 0.25;
    }
    z
}

#[test]
fn a_tunnel_through_a_ridge_is_open_from_portal_to_portal() {
    let s = scene("ridge_tunnel");
    let (t, b) = (tree(&s), bare(&s));
    // Along the bore, from the air before one portal to the air past the other: no rock.
    let (a, z) = (
        Vec3::new(3250.0, 6200.0, 860.0),
        Vec3::new(4150.0, 6201.0, 858.0),
    );
    assert!(b.value(a) < ISO && b.value(z) < ISO, "both ends in the air");
    assert!(
        solid_runs(&b, a, z, 1.0).len() == 1,
        "the bare ridge is solid between them"
    );
    let rock = solid_runs(&t, a, z, 0.5);
    assert!(rock.is_empty(), "rock in the tunnel: runs {rock:?}");
    // Under the crest the ridge stands over it: rock above and below the bore.
    let runs = solid_runs(
        &t,
        Vec3::new(3750.0, 6205.0, 980.0),
        Vec3::new(3750.0, 6205.0, 800.0),
        0.25,
    );
    assert_eq!(runs.len(), 2, "rock over and under the bore: {runs:?}");
    assert!(
        runs[0] > 60.0,
        "the ridge over the bore is {} m thick",
        runs[0]
    );
    // Its mesh at the job's cell is closed inside the region and in one piece.
    let job = s.scene.job.as_ref().expect("the scene has a job");
    let region = job.region.expect("a job region");
    let region = Aabb::new(region.min.0, region.max.0);
    let grid = GridSpec::with_cell(&region, job.cell.0).unwrap();
    let (mesh, _) = polygonize(&t, &grid, &MeshOptions::default()).unwrap();
    mesh.check_topology(Some((&grid.bounds(), 1e-3 * job.cell.0)))
        .unwrap_or_else(|e| panic!("the tunnel's mesh is not closed: {e}"));
    let pieces = mesh.component_sizes();
    assert!(
        pieces.iter().all(|&n| n >= 200),
        "pieces by faces: {pieces:?}"
    );
    // And the ridge is unchanged away from the bore.
    assert_melds(
        &t,
        &b,
        Aabb::new(
            Vec3::new(3150.0, 6090.0, 780.0),
            Vec3::new(4250.0, 6310.0, 1000.0),
        ),
        &[Vec2::new(3240.0, 6200.0), Vec2::new(4160.0, 6200.0)],
        30.0,
        5.0,
    );
}

/// On an amplified terrain (issue 38): the main job's cave volume, built on the eroded
/// amplification of its DEM (`trees/jacksboro_bluff.ron`'s `terrain_with_cave`, under the
/// same job), changes the amplified terrain only near its tunnel.
#[test]
fn a_feature_volume_melds_with_an_amplified_terrain() {
    let s = scene("jacksboro_bluff");
    let named = s.scene.named();
    let with_cave = named["terrain_with_cave"].clone();
    let NodeSpec::Replace(r) = &with_cave else {
        panic!("terrain_with_cave is a Replace")
    };
    let NodeSpec::Heightfield(dem) = &*r.base else {
        panic!("its base is the DEM")
    };
    assert!(dem.amplify.is_some(), "the main job's DEM is amplified");
    let build = |root: NodeSpec| {
        let mut scene = s.scene.clone();
        scene.root = root;
        scene.geology = None;
        compile_scene(&scene, &s.path, &s.base_dir).unwrap().tree
    };
    let (t, b) = (build(with_cave.clone()), build((*r.base).clone()));
    assert_melds(
        &t,
        &b,
        Aabb::new(
            Vec3::new(3340.0, 4880.0, 780.0),
            Vec3::new(3860.0, 5070.0, 1000.0),
        ),
        &TUNNEL,
        30.0,
        5.0,
    );
}

//! Issues 7 and 36: the bundled default scene (`trees/jacksboro_bluff.ron`, a caprock
//! cliff line on the Jacksboro DEM) has an open tunnel whose mouth opens in the cliff, a
//! natural arch through a spur of the cliff and a rock shelter under its lip, and the main
//! job writes a valid mesh and image.

use crate::gltf_validator;

use glam::{Vec2, Vec3};
use karstic::dem::HeightfieldField;
use karstic::field::{Aabb, Field, ISO, Rect, Tree};
use karstic::job::{JobOptions, JobReport};
use karstic::render::Ray;
use karstic::render::raycast::MeshRaycaster;

const SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/trees/jacksboro_bluff.ron");

/// The middle of the arch's window, in the spur that runs east from (3598, 5085).
const ARCH_MIDDLE: Vec2 = Vec2::new(3626.3, 5085.1);

/// A line across the spur through its window, 16 m above the window's floor (about
/// 850 m) and 11 m below its roof (about 877 m).
const UNDER_ARCH: (Vec3, Vec3) = (
    Vec3::new(3626.3, 5068.1, 866.1),
    Vec3::new(3626.3, 5102.1, 866.1),
);

/// A column through the rock shelter at (3565, 5225): the lip over it, the floor under it.
const SHELTER: Vec2 = Vec2::new(3556.0, 5225.0);

fn tree() -> Tree {
    karstic::scene::load(SCENE).unwrap().compile().unwrap().tree
}

fn crossings(t: &Tree, from: Vec3, to: Vec3, n: usize) -> usize {
    let mut last = t.value(from) > ISO;
    let mut count = 0;
    for i in 1..=n {
        let p = from.lerp(to, i as f32 / n as f32);
        let s = t.value(p) > ISO;
        count += usize::from(s != last);
        last = s;
    }
    count
}

#[test]
fn default_scene_has_an_open_tunnel_an_arch_and_a_shelter_in_its_cliff() {
    let t = tree();
    // The tunnel's mouth is a recess of the cliff, and the blocks over the tunnel behind
    // it stop above its roof: along the axis, from the air before the mouth deep into the
    // hill, no rock.
    for i in 0..=400 {
        let p = Vec3::new(3800.0, 4950.0, 863.0)
            .lerp(Vec3::new(3480.0, 4972.0, 867.0), i as f32 / 400.0);
        assert!(t.value(p) < ISO, "rock in the tunnel at {p}");
    }
    // It runs inside the hill: rock above its inner part, and a vertical line through it
    // crosses the ground, its ceiling and its floor.
    assert!(t.value(Vec3::new(3480.0, 4972.0, 886.0)) > ISO);
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
    // Through the spur's window: air all the way across, under a lintel of the bed's
    // top layer and over the spur's floor.
    for i in 0..=200 {
        let p = UNDER_ARCH.0.lerp(UNDER_ARCH.1, i as f32 / 200.0);
        assert!(t.value(p) < ISO, "the window is closed at {p}");
    }
    let over_span = crossings(
        &t,
        ARCH_MIDDLE.extend(820.0),
        ARCH_MIDDLE.extend(900.0),
        1600,
    );
    assert!(
        over_span >= 3,
        "mid-span vertical line crosses {over_span} times (floor, lintel's underside, its top)"
    );
    assert!(t.value(ARCH_MIDDLE.extend(880.0)) > ISO, "no lintel");
    // The shelter runs back under the cliff's lip: air under rock.
    let g = crossings(&t, SHELTER.extend(820.0), SHELTER.extend(900.0), 1600);
    assert!(g >= 3, "the shelter makes an overhang: {g} crossings");
}

/// The job's mesh: the main job without its preview (`full`: the whole DEM at the coarse
/// cell size).
fn job(dir: &std::path::Path, full: bool) -> JobReport {
    let opts = JobOptions {
        out_dir: dir.to_path_buf(),
        full,
        no_render: true,
        no_views: true,
        quiet: true,
        budget: karstic::io::DEFAULT_MEMORY_BUDGET,
        origin: karstic::mesh::export::Origin::Dem,
        masks: false,
    };
    karstic::job::run(std::path::Path::new(SCENE), &opts).unwrap()
}

/// The tree's DEM leaf.
fn dem_of(t: &Tree) -> &HeightfieldField {
    t.nodes()[t.find("dem").unwrap() as usize]
        .leaf()
        .and_then(|f| f.as_any())
        .and_then(|a| a.downcast_ref::<HeightfieldField>())
        .expect("the dem node is a heightfield")
}

/// Every crossing of the mesh along `ray` up to `t_max` (distances, ascending).
fn hits(mesh: &MeshRaycaster, ray: Ray, t_max: f32) -> Vec<f32> {
    let mut out = Vec::new();
    let mut t0 = 0.0;
    while let Some(t) = mesh.first_hit(&Ray {
        origin: ray.at(t0),
        dir: ray.dir,
    }) {
        let t = t0 + t;
        if t > t_max {
            break;
        }
        out.push(t);
        t0 = t + 1e-3;
    }
    out
}

#[test]
fn main_job_mesh_is_watertight_valid_caved_and_on_the_dem() {
    let dir = tempfile::tempdir().unwrap();
    let r = job(dir.path(), false);
    let (region, cell) = (r.region, r.cell);
    // Watertight inside the region: the only open edges lie on the box's faces.
    let topo = r
        .mesh
        .check_topology(Some((&region, 1e-3 * cell)))
        .unwrap_or_else(|e| panic!("the job's mesh is not watertight: {e}"));
    assert!(topo.faces > 100_000, "{topo:?}");
    // No debris: every piece of the mesh is a real surface (issue 13 found an 8-face
    // fragment floating near the tunnel's mouth).
    let pieces = r.mesh.component_sizes();
    assert!(
        pieces.iter().all(|&n| n >= 200),
        "pieces of the job's mesh, by faces: {pieces:?}"
    );
    gltf_validator::assert_valid(&r.mesh_path);

    let positions: Vec<Vec3> = r.mesh.positions.iter().map(|&p| p.into()).collect();
    let caster = MeshRaycaster::new(&positions, &r.mesh.triangles);
    // A vertical line through the tunnel's inner end crosses the mesh at the ground, the
    // upper chamber's roof and floor, the tunnel's ceiling and floor. (Rays here keep off
    // the grid's planes: along a grid line a ray meets vertices and edges exactly, where a
    // ray–triangle test may miss both neighbours.)
    let down = Ray {
        origin: Vec3::new(3471.1, 4981.3, region.max.z - 1.0),
        dir: Vec3::NEG_Z,
    };
    let z: Vec<f32> = hits(&caster, down, region.size().z)
        .iter()
        .map(|&t| down.at(t).z)
        .collect();
    assert!(
        z.len() >= 4,
        "the vertical line crosses the mesh at z = {z:?}"
    );
    // Along the tunnel's axis from the air in front of the mouth: no face for its length.
    let (mouth, inner) = (
        Vec3::new(3800.0, 4951.3, 863.1),
        Vec3::new(3480.0, 4972.0, 867.0),
    );
    let axis = Ray {
        origin: mouth,
        dir: (inner - mouth).normalize(),
    };
    let blocked = hits(&caster, axis, mouth.distance(inner));
    assert!(
        blocked.is_empty(),
        "the tunnel's axis meets the mesh at {blocked:?}"
    );
    // Through the arch's window: a horizontal ray across the spur meets nothing.
    let (a, b) = UNDER_ARCH;
    let under = Ray {
        origin: a,
        dir: (b - a).normalize(),
    };
    assert!(
        hits(&caster, under, a.distance(b)).is_empty(),
        "rock under the arch"
    );

    // Away from the features, the vertices lie on the DEM leaf's surface (its bicubic
    // interpolant plus its detail, as the tree defines it): within 1% of a cell where the
    // mesher places them on the elevation (where the detailed surface is a graph; none
    // in this region, all of it rough enough to fold), and within 20% of a cell (distance
    // `|f − T| / |∇f|`) where Marching Cubes interpolates the rough ground linearly: its
    // finest octave is 2 cells long, about 0.3 m high, so chords miss it by ≈ 0.4 m. A
    // mesher blind to the detail would miss it by up to its 5 m.
    let t = &r.tree;
    let dem = dem_of(t);
    let features: Vec<Aabb> = ["cliff-rocks", "cliff-hollows", "cave", "chamber"]
        .iter()
        .map(|n| t.info(t.find(n).unwrap()).support.dilate(2.0 * cell))
        .collect();
    let (mut checked, mut on) = (0, 0);
    let (mut worst, mut worst_on) = (0.0f32, 0.0f32);
    for p in &positions {
        if features.iter().any(|b| b.contains(*p)) {
            continue;
        }
        // Vertices on the region's faces close the surface there, not the DEM.
        if (0..3)
            .any(|k| (p[k] - region.min[k]).abs() < 1e-2 || (p[k] - region.max[k]).abs() < 1e-2)
        {
            continue;
        }
        let xy = Vec2::new(p.x, p.y);
        let (f, g) = dem.value_grad(*p);
        if dem.elevation(&Rect::new(xy, xy)).is_some() {
            worst_on = worst_on.max((p.z - dem.height(xy)).abs());
            on += 1;
        } else {
            worst = worst.max((f - ISO).abs() / g.length());
        }
        checked += 1;
    }
    assert!(
        checked > 50_000,
        "{checked} vertices away from the features ({on} on the elevation)"
    );
    assert!(
        worst_on <= 0.01 * cell,
        "a vertex lies {worst_on} m off the DEM's elevation (cell {cell} m)"
    );
    assert!(
        worst <= 0.2 * cell,
        "a vertex lies {worst} m off the DEM's rough surface (cell {cell} m)"
    );
}

#[test]
fn full_extent_job_meshes_the_whole_dem_watertight() {
    let dir = tempfile::tempdir().unwrap();
    let r = job(dir.path(), true);
    assert_eq!(r.cell, 15.0, "the job's full_cell");
    assert!(r.mesh_path.ends_with("jacksboro_bluff_full.glb"));
    // The region is the tree's support: the whole 128 × 128 DEM at 90 m, to within the
    // heightfield's 30 m falloff at its sides.
    let b = r.mesh.bounds();
    let side = 127.0 * 90.0;
    assert!(b.min.x <= 30.0 && b.min.y <= 30.0, "{b:?}");
    assert!(b.max.x >= side - 30.0 && b.max.y >= side - 30.0, "{b:?}");
    r.mesh
        .check_topology(Some((&r.region, 1e-3 * r.cell)))
        .unwrap_or_else(|e| panic!("the full-extent mesh is not watertight: {e}"));
    // The features are in it: along the spur that holds the arch (20 m wide, standing out
    // over the slope, its top the bed's at 884 m, worn lower toward its end) the mesh
    // stands well above the DEM's surface somewhere.
    let positions: Vec<Vec3> = r.mesh.positions.iter().map(|&p| p.into()).collect();
    let caster = MeshRaycaster::new(&positions, &r.mesh.triangles);
    let highest = (-12..=12)
        .map(|k| {
            let xy = ARCH_MIDDLE + Vec2::X * (2.0 * k as f32);
            let t = caster
                .first_hit(&Ray {
                    origin: xy.extend(1000.0),
                    dir: Vec3::NEG_Z,
                })
                .expect("the mesh covers the spur");
            1000.0 - t - dem_of(&r.tree).height(xy)
        })
        .fold(f32::NEG_INFINITY, f32::max);
    assert!(
        highest > 15.0,
        "along the spur the mesh rises at most {highest} m above the DEM"
    );
}

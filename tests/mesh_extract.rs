//! Field extraction: exact shapes within 1%, topology, pruning that changes nothing,
//! thread-count independence, direct elevation extraction.

use crate::mesh_fields;

use std::f64::consts::PI;

use glam::{Vec2, Vec3};
use karstic::field::{Aabb, ElevationSource, Field};
use karstic::mesh::{GridSpec, Mesh, MeshError, MeshOptions, MeshStats, polygonize};
use mesh_fields::*;
use proptest::prelude::*;

fn extract(f: &dyn Field, grid: &GridSpec, prune: bool, elevation: bool) -> (Mesh, MeshStats) {
    let opts = MeshOptions {
        prune,
        elevation,
        ..MeshOptions::default()
    };
    polygonize(f, grid, &opts).unwrap()
}

/// A grid of `n³` cells of size 4/n on [-2, 2]³: dyadic, so every sample position is exact.
fn dyadic(n: usize) -> GridSpec {
    GridSpec::new(Vec3::splat(-2.0), Vec3::splat(4.0 / n as f32), [n; 3]).unwrap()
}

/// Asserts two meshes are identical without printing them whole.
fn assert_same(a: &Mesh, b: &Mesh) {
    assert_eq!(a.positions.len(), b.positions.len(), "vertex counts");
    assert_eq!(a.triangles.len(), b.triangles.len(), "triangle counts");
    let first = |x: bool, what: &str| assert!(x, "first difference in {what}");
    first(a.positions == b.positions, "positions");
    first(a.normals == b.normals, "normals");
    first(a.triangles == b.triangles, "triangles");
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn sphere_area_volume_and_euler() {
    let s = unit_sphere();
    let grid = GridSpec::with_resolution(&Aabb::around(Vec3::splat(0.01), 1.4), 64).unwrap();
    for prune in [true, false] {
        let (m, stats) = extract(&s, &grid, prune, true);
        let topo = m.check_topology(None).unwrap();
        assert_eq!(topo.euler_characteristic(), 2);
        assert!(rel(m.area(), 4.0 * PI) < 0.01, "area {}", m.area());
        assert!(
            rel(m.volume(), 4.0 / 3.0 * PI) < 0.01,
            "volume {}",
            m.volume()
        );
        assert_eq!(stats.triangles as usize, m.triangles.len());
        if prune {
            assert!(stats.field_evaluations * 2 < stats.grid_points, "{stats}");
        } else {
            assert_eq!(stats.field_evaluations, stats.grid_points);
        }
    }
}

#[test]
fn torus_area_volume_and_euler() {
    let t = Torus {
        c: Vec3::new(0.03, -0.02, 0.01),
        big: 1.0,
        small: 0.4,
        falloff: 0.3,
    };
    let grid = GridSpec::with_cell(&t.support(), 0.03).unwrap();
    let (m, _) = extract(&t, &grid, true, true);
    assert_eq!(m.check_topology(None).unwrap().euler_characteristic(), 0);
    let (big, small) = (1.0f64, 0.4f64);
    assert!(
        rel(m.area(), 4.0 * PI * PI * big * small) < 0.01,
        "area {}",
        m.area()
    );
    assert!(
        rel(m.volume(), 2.0 * PI * PI * big * small * small) < 0.01,
        "volume {}",
        m.volume()
    );
}

#[test]
fn refinement_puts_vertices_on_the_surface() {
    let s = unit_sphere();
    let grid = dyadic(32);
    let opts = MeshOptions {
        refine: true,
        ..MeshOptions::default()
    };
    let (m, stats) = polygonize(&s, &grid, &opts).unwrap();
    let (plain, _) = extract(&s, &grid, true, true);
    let errors = |m: &Mesh| {
        m.positions
            .iter()
            .map(|&p| (Vec3::from(p).length() - 1.0).abs())
            .collect::<Vec<f32>>()
    };
    let mean = |e: &[f32]| e.iter().sum::<f32>() / e.len() as f32;
    let (refined, linear) = (errors(&m), errors(&plain));
    // Exact up to the clamp that keeps vertices EDGE_T_MIN of an edge away from samples.
    let bound = karstic::mesh::cell::EDGE_T_MIN * grid.spacing.x + 1e-5;
    assert!(
        refined.iter().all(|&e| e <= bound),
        "refined error above {bound}"
    );
    assert!(
        mean(&linear) > 20.0 * mean(&refined),
        "{} vs {}",
        mean(&linear),
        mean(&refined)
    );
    assert!(stats.vertex_evaluations > 0);
    assert_eq!(m.triangles, plain.triangles);
}

#[test]
fn pruning_changes_nothing_but_the_work() {
    let fields: Vec<Box<dyn Field>> = vec![
        Box::new(unit_sphere()),
        Box::new(Torus {
            c: Vec3::ZERO,
            big: 1.1,
            small: 0.35,
            falloff: 0.3,
        }),
        Box::new(Gyroid {
            freq: 5.0,
            amp: 0.4,
            clip: Aabb::around(Vec3::ZERO, 1.5),
            falloff: 0.2,
        }),
    ];
    for f in &fields {
        let grid = dyadic(64);
        let (a, sa) = extract(f.as_ref(), &grid, true, true);
        let (b, sb) = extract(f.as_ref(), &grid, false, true);
        assert!(!a.triangles.is_empty());
        assert_same(&a, &b);
        assert!(sa.field_evaluations < sb.field_evaluations);
        a.check_topology(None).unwrap();
    }
}

#[test]
fn gyroid_filling_the_grid_is_open_only_on_the_box_faces() {
    let g = Gyroid {
        freq: 6.0,
        amp: 0.5,
        clip: Aabb::around(Vec3::ZERO, 5.0),
        falloff: 0.2,
    };
    let grid = dyadic(40);
    let (m, _) = extract(&g, &grid, true, true);
    let topo = m.check_topology(Some((&grid.bounds(), 1e-5))).unwrap();
    assert!(topo.boundary_edges > 0);
}

#[test]
fn thread_count_does_not_change_the_mesh() {
    let t = caved_terrain(12);
    let grid = GridSpec::with_cell(&t.support(), 4.0).unwrap();
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| extract(&t, &grid, true, true))
    };
    let (a, sa) = run(1);
    let (b, sb) = run(2);
    assert_same(&a, &b);
    assert_eq!(sa.field_evaluations, sb.field_evaluations);
}

#[test]
fn direct_elevation_extraction_reads_heights_only() {
    let t = caved_terrain(0).ground;
    let grid = GridSpec::new(Vec3::new(0.0, 0.0, -20.0), Vec3::splat(4.0), [100, 100, 25]).unwrap();
    let (m, stats) = extract(&t, &grid, true, true);
    assert_eq!(stats.field_evaluations, 0, "{stats}");
    assert_eq!(stats.elevation_columns, stats.columns);
    assert_eq!(stats.height_evaluations, stats.columns);
    m.check_topology(Some((&grid.bounds(), 1e-3))).unwrap();
    // Every vertex lies on the bilinear interpolation of the column heights.
    let h = |i: usize, j: usize| {
        let p = grid.point(i, j, 0);
        t.h.height(Vec2::new(p.x, p.y))
    };
    for &p in &m.positions {
        let u = (p[0] - grid.origin.x) / grid.spacing.x;
        let v = (p[1] - grid.origin.y) / grid.spacing.y;
        let (i, j) = ((u.floor() as usize).min(99), (v.floor() as usize).min(99));
        let (fu, fv) = (u - i as f32, v - j as f32);
        let bil = h(i, j) * (1.0 - fu) * (1.0 - fv)
            + h(i + 1, j) * fu * (1.0 - fv)
            + h(i, j + 1) * (1.0 - fu) * fv
            + h(i + 1, j + 1) * fu * fv;
        assert!((p[2] - bil).abs() < 0.01 * grid.spacing.z, "{p:?} vs {bil}");
    }
    // The same grid through the field finds the same surface to within the cell error.
    let (f, fs) = extract(&t, &grid, true, false);
    assert_eq!(f.triangles.len(), m.triangles.len());
    assert!(fs.field_evaluations > 2 * stats.columns);
}

#[test]
fn caves_keep_the_terrain_watertight_and_save_evaluations() {
    let t = caved_terrain(12);
    let grid = GridSpec::with_cell(&t.support(), 2.0).unwrap();
    let (m, stats) = extract(&t, &grid, true, true);
    m.check_topology(Some((&grid.bounds(), 1e-3))).unwrap();
    assert!(stats.elevation_columns > 0 && stats.elevation_columns < stats.columns);
    assert!(stats.evaluation_ratio() >= 8.0, "{stats}");
    // Without direct extraction, pruning alone still matches plain MC exactly.
    let (a, _) = extract(&t, &grid, true, false);
    let (b, _) = extract(&t, &grid, false, false);
    assert_same(&a, &b);
}

#[test]
fn oversized_extractions_are_refused_before_allocating() {
    let s = unit_sphere();
    let grid = dyadic(64);
    let opts = MeshOptions {
        prune: false,
        budget: 1 << 20,
        ..MeshOptions::default()
    };
    let e = polygonize(&s, &grid, &opts).unwrap_err();
    assert!(matches!(e, MeshError::Budget(_)));
    assert!(e.to_string().contains("would need"), "{e}");
}

#[test]
fn grids_far_over_the_budget_are_refused_before_their_bands() {
    // 10¹⁰ columns: refused from the grid's size alone (the column index used to be
    // allocated first, aborting the process).
    let s = unit_sphere();
    let huge = GridSpec::new(Vec3::splat(-1.0), Vec3::splat(1e-5), [100_000, 100_000, 10]).unwrap();
    let started = std::time::Instant::now();
    let e = polygonize(&s, &huge, &MeshOptions::default()).unwrap_err();
    assert!(e.to_string().contains("column index"), "{e}");
    assert!(started.elapsed().as_secs_f64() < 1.0);

    // A terrain crossing every column: the column index fits, its samples cannot (each
    // column needs at least two). The estimate from a few tiles refuses it before the
    // bands stage; the exact count would say "N samples", without "median".
    let t = Heightfield {
        h: Hills {
            base: 0.0,
            a: 2.0,
            k: Vec2::splat(0.05),
            slope: 0.0,
        },
        falloff: 2.0,
        domain: Aabb::new(Vec3::new(-50.0, -50.0, -10.0), Vec3::new(50.0, 50.0, 10.0)),
    };
    let grid = GridSpec::with_resolution(&t.domain, 2048).unwrap();
    let columns = ((grid.cells[0] + 1) * (grid.cells[1] + 1)) as u64;
    let opts = MeshOptions {
        budget: columns * (64 + 16),
        ..MeshOptions::default()
    };
    let started = std::time::Instant::now();
    let e = polygonize(&t, &grid, &opts).unwrap_err();
    assert!(matches!(e, MeshError::Budget(_)), "{e}");
    assert!(e.to_string().contains("median"), "{e}");
    assert!(
        started.elapsed().as_secs_f64() < 2.0,
        "{:?}",
        started.elapsed()
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn random_blobs_are_manifold_and_prune_exactly(
        blobs in prop::collection::vec(((-1.2f32..1.2, -1.2f32..1.2, -1.2f32..1.2), 0.3f32..1.3, 0.6f32..1.6), 1..7)
    ) {
        let f = Blobs(blobs.into_iter().map(|((x, y, z), r, e)| (Vec3::new(x, y, z), r, e)).collect());
        let grid = dyadic(32);
        let (a, _) = extract(&f, &grid, true, true);
        let (b, _) = extract(&f, &grid, false, true);
        prop_assert!(a == b, "pruned and unpruned meshes differ");
        let topo = a.check_topology(Some((&grid.bounds(), 1e-5)));
        prop_assert!(topo.is_ok(), "{:?}", topo);
        for t in &a.triangles {
            prop_assert!(a.triangle_normal(t).length() > 0.0);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]

    /// Elevation columns meet field columns (mixed edges) without cracks, for random
    /// caves, cell sizes and boxes that cut tiles at odd places.
    #[test]
    fn caved_terrains_stay_manifold(
        caves in prop::collection::vec((20f32..380.0, 20f32..380.0, -12f32..6.0, 6f32..30.0), 0..6),
        cell in 5.0f32..13.0,
        x0 in 0f32..120.0,
    ) {
        let mut t = caved_terrain(0);
        t.caves = caves
            .into_iter()
            .map(|(x, y, dz, r)| (Vec3::new(x, y, t.ground.h.height(Vec2::new(x, y)) + dz), r))
            .collect();
        let b = Aabb::new(Vec3::new(x0, 0.0, -30.0), Vec3::new(400.0, 400.0, 70.0));
        let grid = GridSpec::with_cell(&b, cell).unwrap();
        let (m, stats) = extract(&t, &grid, true, true);
        let topo = m.check_topology(Some((&grid.bounds(), 1e-3)));
        prop_assert!(topo.is_ok(), "{:?}", topo);
        prop_assert!(stats.elevation_columns > 0);
    }
}

//! Polygonizing a DEM alone (issue 4): the Jacksboro UTM DEM resampled to 30 m cells
//! (1030 × 1087 samples), implicitized with R = 60 m, meshed over its whole support
//! (terrain, walls and floor) on a grid of 30 m cells on the DEM's samples, 30 m
//! vertically (35 sample layers: the shape of Paris et al.'s 2000² × 33 grid).
//!
//! Benches bound-pruned extraction with direct elevation extraction (the default), and
//! plain unpruned Marching Cubes on the same grid as the baseline, and prints the
//! evaluation counts of both (#C, #C0) from the same run.

use std::path::Path;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use karstic::compile::compile_scene;
use karstic::field::{Field, Tree};
use karstic::mesh::{GridSpec, MeshOptions, polygonize};
use karstic::scene::parse_scene;

/// Horizontal and vertical cell size, metres.
const CELL: f32 = 30.0;

fn tree() -> Tree {
    let text = "(version: 1, name: \"jacksboro\", root: Heightfield(name: \"dem\", \
                source: \"../shared/data/dem/jacksboro_utm16n_90m.tif\", falloff: 60.0, \
                cell_size: 30.0))";
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("dem_mesh_bench.ron");
    let scene = parse_scene(text, &path).expect("the bench tree parses");
    compile_scene(&scene, &path, root)
        .expect("the shared DEM loads")
        .tree
}

/// The support at `CELL` cells, columns on the resampled DEM's samples.
fn grid(f: &dyn Field) -> GridSpec {
    let s = f.support();
    let n = |size: f32| (size / CELL).ceil() as usize;
    let size = s.size();
    GridSpec::new(
        s.min,
        glam::Vec3::splat(CELL),
        [n(size.x), n(size.y), n(size.z)],
    )
    .unwrap()
}

fn bench(c: &mut Criterion) {
    let t = tree();
    let grid = grid(&t);
    let pruned = MeshOptions::default();
    let plain = MeshOptions {
        prune: false,
        ..MeshOptions::default()
    };
    let (_, ps) = polygonize(&t, &grid, &pruned).unwrap();
    let (_, us) = polygonize(&t, &grid, &plain).unwrap();
    println!(
        "grid {}×{}×{} cells of {CELL} m, {} threads",
        grid.cells[0],
        grid.cells[1],
        grid.cells[2],
        rayon::current_num_threads()
    );
    println!("pruned + elevation:\n{ps}");
    println!("unpruned:\n{us}");
    println!(
        "#C0 = {}, #C = {} (+ {} heights): #C0/#C = {:.1}; unpruned evaluates {} samples: {:.1}× the pruned",
        ps.grid_points,
        ps.field_evaluations,
        ps.height_evaluations,
        ps.evaluation_ratio(),
        us.field_evaluations,
        us.field_evaluations as f64 / ps.field_evaluations.max(1) as f64
    );

    let mut g = c.benchmark_group("dem_mesh");
    g.sample_size(10);
    g.bench_function("jacksboro 30 m, pruned + elevation", |b| {
        b.iter(|| polygonize(&t, &grid, &pruned).unwrap().0.triangles.len())
    });
    g.measurement_time(Duration::from_secs(10));
    g.bench_function("jacksboro 30 m, unpruned MC (baseline)", |b| {
        b.iter(|| polygonize(&t, &grid, &plain).unwrap().0.triangles.len())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

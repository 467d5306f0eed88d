//! The mesher on implicitized DEMs (issue 4, and the heightfield part of issue 3): the
//! extracted surface embeds the DEM's bilinear surface, nodata makes no surface, the mesh
//! is watertight, direct elevation extraction costs about one evaluation per column and
//! agrees with the generic path, and the floating island scene meshes without defects.

use std::path::Path;

use glam::{Vec2, Vec3};
use karstic::compile::compile_scene;
use karstic::dem::HeightfieldField;
use karstic::field::{Aabb, Field, Rect, Tree};
use karstic::mesh::{GridSpec, Mesh, MeshOptions, MeshStats, polygonize};
use karstic::scene::HeightfieldSpec;
use karstic::scene::parse_scene;

/// The bundled 128 × 128 crop (90 m cells, no nodata), relative to the crate root.
const CROP: &str = "trees/data/jacksboro_crop.asc";
/// The shared UTM DEM (344 × 363, 90 m cells, 5.4% nodata).
const UTM: &str = "../shared/data/dem/jacksboro_utm16n_90m.tif";
/// Falloff `R` of every leaf here, metres.
const R: f32 = 60.0;

fn crate_root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A compiled tree whose root is a `Heightfield` node of `source`.
fn tree(source: &str) -> Tree {
    let text = format!(
        "(version: 1, name: \"dem_mesh\", root: Heightfield(name: \"dem\", source: \"{source}\", falloff: {R:.1}))"
    );
    let path = crate_root().join("dem_mesh.ron");
    let scene = parse_scene(&text, &path).expect("the tree parses");
    compile_scene(&scene, &path, crate_root())
        .expect("the tree compiles")
        .tree
}

/// The same leaf outside a tree, for its heights and domain.
fn leaf(source: &str) -> HeightfieldField {
    HeightfieldSpec::new(source, R)
        .load(crate_root())
        .expect("the DEM loads")
}

/// A grid over the leaf's support whose columns fall on the DEM's samples every
/// `dem cell / per_cell` metres, with `dz` vertical cells: on such a grid every
/// horizontal MC edge lies inside one DEM cell along a line where the bilinear surface
/// is linear, so linear interpolation between column heights is exact.
fn aligned_grid(leaf: &HeightfieldField, per_cell: f32, dz: f32) -> GridSpec {
    let s = leaf.support();
    let dxy = leaf.heightfield().cell() / per_cell;
    let size = s.size();
    let cells = [
        (size.x / dxy.x).round() as usize,
        (size.y / dxy.y).round() as usize,
        (size.z / dz).ceil() as usize,
    ];
    GridSpec::new(s.min, dxy.extend(dz), cells).unwrap()
}

fn extract(f: &dyn Field, grid: &GridSpec, elevation: bool, refine: bool) -> (Mesh, MeshStats) {
    let opts = MeshOptions {
        elevation,
        refine,
        ..MeshOptions::default()
    };
    polygonize(f, grid, &opts).unwrap()
}

/// Whether `p` is on the terrain part of the surface, away from the falloff band of the
/// domain's edge (the leaf is its heightfield over the 1-rings of both ends of `p`'s
/// edge, two grid cells around it) and above the prism's floor.
fn on_terrain(leaf: &HeightfieldField, grid: &GridSpec, p: Vec3) -> bool {
    let xy = p.truncate();
    let d = 2.0 * grid.spacing.truncate();
    leaf.elevation(&Rect::new(xy - d, xy + d)).is_some() && p.z > leaf.prism_z().lo
}

/// Asserts every terrain vertex of `m` lies on the leaf's bilinear surface within `tol`,
/// and returns how many vertices were checked.
fn assert_on_dem(m: &Mesh, leaf: &HeightfieldField, grid: &GridSpec, tol: f32) -> usize {
    let mut checked = 0;
    let mut worst = 0f32;
    for &p in &m.positions {
        let p = Vec3::from(p);
        if !on_terrain(leaf, grid, p) {
            continue;
        }
        let h = leaf.height(p.truncate());
        let err = (p.z - h).abs();
        assert!(err <= tol, "vertex {p} is {err} m off the DEM (h = {h})");
        worst = worst.max(err);
        checked += 1;
    }
    eprintln!("{checked} terrain vertices, worst error {worst} m (tolerance {tol} m)");
    checked
}

/// Whether the DEM cell `(i, j)` has a nodata corner (no surface under bilinear
/// interpolation).
fn nodata_cell(leaf: &HeightfieldField, i: usize, j: usize) -> bool {
    let hf = leaf.heightfield();
    [(0, 0), (1, 0), (0, 1), (1, 1)]
        .iter()
        .any(|&(di, dj)| hf.at(i + di, j + dj).is_nan())
}

/// Asserts no vertex lies in a nodata cell or within `margin` of one, nor outside the
/// DEM; returns the number of vertices within `3·margin` of nodata (the walls closing
/// the holes).
fn assert_no_surface_in_nodata(m: &Mesh, leaf: &HeightfieldField, margin: f32) -> usize {
    let hf = leaf.heightfield();
    let ext = hf.extent();
    let mut near = 0;
    for &p in &m.positions {
        let xy = Vec2::new(p[0], p[1]);
        assert!(
            xy.cmpge(ext.min).all() && xy.cmple(ext.max).all(),
            "vertex {p:?} outside the DEM {ext:?}"
        );
        let cells = |r: f32| hf.cells_overlapping(&Rect::new(xy - r, xy + r)).unwrap();
        let (i0, i1, j0, j1) = cells(margin);
        for j in j0..=j1 {
            for i in i0..=i1 {
                assert!(
                    !nodata_cell(leaf, i, j),
                    "vertex {p:?} within {margin} m of the nodata cell ({i}, {j})"
                );
            }
        }
        let (i0, i1, j0, j1) = cells(3.0 * margin);
        near += (j0..=j1).any(|j| (i0..=i1).any(|i| nodata_cell(leaf, i, j))) as usize;
    }
    near
}

#[test]
fn crop_mesh_embeds_the_dem_and_is_closed() {
    let (t, l) = (tree(CROP), leaf(CROP));
    let grid = aligned_grid(&l, 3.0, 10.0);
    let (m, stats) = extract(&t, &grid, true, false);
    eprintln!("{stats}");
    // A closed surface (the terrain, the prism's walls and floor) of genus 0.
    let topo = m.check_topology(None).unwrap();
    assert_eq!(topo.euler_characteristic(), 2);
    // Terrain vertices on the bilinear surface within 1% of the cell.
    let checked = assert_on_dem(&m, &l, &grid, 0.01 * grid.spacing.min_element());
    assert!(
        checked as u64 > stats.columns * 9 / 10,
        "{checked} terrain vertices"
    );
    // The solid's volume is the DEM's above the floor, up to the walls' band.
    let ext = l.heightfield().extent();
    // The walls stand where the prism field is T: clearance (1 − 0.454) R.
    let wall = (1.0 - 0.454_202) * R;
    let inner = Rect::new(ext.min + wall, ext.max - wall);
    let (n, mut sum) = (200, 0.0f64);
    for a in 0..n {
        for b in 0..n {
            let uv = (Vec2::new(a as f32, b as f32) + 0.5) / n as f32;
            let xy = inner.min + (inner.max - inner.min) * uv;
            sum += f64::from(l.height(xy));
        }
    }
    let mean_h = sum / f64::from(n * n);
    let floor = f64::from(l.prism_z().lo - 0.454_202 * R);
    let area = f64::from((inner.max - inner.min).element_product());
    let expected = area * (mean_h - floor);
    let rel = (m.volume() - expected).abs() / expected;
    assert!(rel < 0.02, "volume {} vs {expected}", m.volume());
}

#[test]
fn crop_costs_about_one_evaluation_per_column() {
    let (t, l) = (tree(CROP), leaf(CROP));
    let grid = aligned_grid(&l, 3.0, 10.0);
    let (_, stats) = extract(&t, &grid, true, false);
    let layers = grid.cells[2] as u64;
    assert!(layers >= 100, "a fine vertical grid: {layers} layers");
    // Direct extraction answers almost every column with one height...
    assert_eq!(stats.height_evaluations, stats.elevation_columns, "{stats}");
    assert!(
        stats.elevation_columns * 100 >= stats.columns * 95,
        "{stats}"
    );
    // ...so the field is evaluated only at the walls and the floor's two layers, far
    // below one evaluation per cell.
    let per_column =
        (stats.field_evaluations + stats.height_evaluations) as f64 / stats.columns as f64;
    assert!(
        per_column < 4.0,
        "{per_column} evaluations per column\n{stats}"
    );
    assert!(stats.evaluation_ratio() > layers as f64 / 4.0, "{stats}");
    // The vertices need no root search (but on the few edges from an elevation sample
    // to a field sample, where the elevation's z-range ends).
    assert!(stats.vertex_evaluations * 100 < stats.vertices, "{stats}");
}

#[test]
fn direct_and_generic_extraction_agree() {
    let (t, l) = (tree(CROP), leaf(CROP));
    let grid = aligned_grid(&l, 3.0, 10.0);
    let (direct, ds) = extract(&t, &grid, true, false);
    let (generic, gs) = extract(&t, &grid, false, false);
    let (refined, _) = extract(&t, &grid, false, true);
    // Pseudo-values and field values have the same signs, so the two paths make the same
    // cases, the same vertices in the same order and the same triangles.
    assert_eq!(direct.triangles, generic.triangles);
    assert_eq!(direct.triangles, refined.triangles);
    assert_eq!(ds.elevation_columns, ds.height_evaluations);
    assert_eq!(gs.elevation_columns, 0);
    // Per column the generic path evaluates the terrain's band over the column's 1-ring
    // (sharpened to the column's local relief); the direct path reads one height and
    // evaluates only the floor and the walls.
    assert!(
        gs.field_evaluations > 2 * ds.field_evaluations,
        "{gs}\n{ds}"
    );
    let cell = grid.spacing.min_element();
    // On the terrain (the walls and floor are the field's on both paths, and there only
    // refinement moves vertices: it finds the walls' kinks that linear MC misses).
    let max_dist = |a: &Mesh, b: &Mesh| {
        a.positions
            .iter()
            .zip(&b.positions)
            .filter(|(p, _)| on_terrain(&l, &grid, Vec3::from(**p)))
            .map(|(p, q)| Vec3::from(*p).distance(Vec3::from(*q)))
            .fold(0f32, f32::max)
    };
    // The generic path interpolates the odd cubic σ linearly: off by a fraction of a
    // cell; refined on the true field it lands on the DEM like the direct path.
    let unrefined = max_dist(&direct, &generic);
    let refined_gap = max_dist(&direct, &refined);
    eprintln!("generic vs direct: {unrefined} m, refined: {refined_gap} m");
    assert!(unrefined < 0.05 * cell, "{unrefined} m");
    assert!(refined_gap < 0.01 * cell, "{refined_gap} m");
    assert_on_dem(&refined, &l, &grid, 0.01 * cell);
    // Normals agree too (the elevation's central differences over half a cell vs the
    // field's gradient) where both see one bilinear patch: terrain vertices at least
    // half a grid cell inside a DEM cell.
    let (o, c) = (l.heightfield().origin(), l.heightfield().cell());
    let half = 0.5 * grid.spacing.truncate() + 1e-3;
    let mut compared = 0;
    for (i, (a, b)) in direct.normals.iter().zip(&generic.normals).enumerate() {
        let p = Vec3::from(direct.positions[i]);
        let u = (p.truncate() - o) / c;
        let inside = (u - u.round()).abs() * c;
        if on_terrain(&l, &grid, p) && inside.cmpge(half).all() {
            let cos = Vec3::from(*a).dot(Vec3::from(*b));
            assert!(cos > 0.9999, "normals at {p}: {a:?} vs {b:?}");
            compared += 1;
        }
    }
    assert!(compared > 1000, "{compared} normals compared");
}

#[test]
fn unaligned_refined_grid_stays_on_the_dem() {
    // Columns off the DEM's samples: horizontal edges cross DEM cells, so only the
    // refinement along the edge puts their vertices on the bilinear surface.
    let (t, l) = (tree(CROP), leaf(CROP));
    let s = l.support();
    let b = Aabb::new(
        s.min + Vec3::new(1000.0, 1300.0, 0.0),
        Vec3::new(s.min.x + 5000.0, s.min.y + 4700.0, s.max.z),
    );
    let grid = GridSpec::with_cell(&b, 37.0).unwrap();
    let (m, stats) = extract(&t, &grid, true, true);
    m.check_topology(Some((&grid.bounds(), 1e-3))).unwrap();
    let checked = assert_on_dem(&m, &l, &grid, 0.01 * grid.spacing.min_element());
    assert!(checked as u64 > stats.columns / 2, "{checked} of {stats}");
}

#[test]
fn utm_mesh_has_no_surface_in_nodata_and_is_closed() {
    let (t, l) = (tree(UTM), leaf(UTM));
    assert!(l.heightfield().nodata_count() > 0);
    let grid = aligned_grid(&l, 1.0, 10.0);
    let (m, stats) = extract(&t, &grid, true, false);
    eprintln!("{stats}");
    m.check_topology(None).unwrap();
    let checked = assert_on_dem(&m, &l, &grid, 0.01 * grid.spacing.min_element());
    assert!(
        checked as u64 > stats.columns * 3 / 4,
        "{checked} terrain vertices"
    );
    // No surface in or near nodata, but walls close the holes around it.
    let near = assert_no_surface_in_nodata(&m, &l, 0.25 * R);
    assert!(near > 100, "{near} vertices along the nodata edge");
    assert_eq!(stats.height_evaluations, stats.elevation_columns);
    assert!(
        stats.elevation_columns * 100 >= stats.columns * 80,
        "{stats}"
    );
}

#[test]
fn utm_sub_box_is_open_only_on_its_faces() {
    let (t, l) = (tree(UTM), leaf(UTM));
    let s = l.support();
    // A box across the DEM's western edge and its nodata wedge, cut through the terrain,
    // with columns on the DEM's samples every 30 m.
    let b = Aabb::new(
        Vec3::new(s.min.x - 180.0, s.min.y + 1980.0, 400.0),
        Vec3::new(s.min.x + 9000.0, s.min.y + 12000.0, s.max.z),
    );
    let grid = GridSpec::with_cell(&b, 30.0).unwrap();
    let (m, _) = extract(&t, &grid, true, false);
    let topo = m.check_topology(Some((&grid.bounds(), 1e-2))).unwrap();
    assert!(topo.boundary_edges > 0);
    assert_no_surface_in_nodata(&m, &l, 0.25 * R);
    assert_on_dem(&m, &l, &grid, 0.01 * grid.spacing.min_element());
}

#[test]
fn floating_island_is_watertight() {
    // `karstic build trees/floating_island.ron --cell 30`: the intersection of the ridge
    // and the inverted keel floats inside the support, so its mesh is closed.
    let file = karstic::scene::load(crate_root().join("trees/floating_island.ron")).unwrap();
    let t = file.compile().unwrap().tree;
    let grid = GridSpec::with_cell(&t.support(), 30.0).unwrap();
    let (m, stats) = extract(&t, &grid, true, false);
    eprintln!("{stats}");
    let topo = m.check_topology(None).unwrap();
    assert!(topo.faces > 100_000, "{topo:?}");
    assert!(m.volume() > 0.0, "outward orientation");
    let inner = m.bounds();
    let g = grid.bounds();
    assert!(
        inner.min.z > g.min.z && inner.max.z < g.max.z,
        "the island floats"
    );
    // Pruning (bricks, z-bands of an intersection) drops no piece of it.
    let (unpruned, us) = polygonize(
        &t,
        &grid,
        &MeshOptions {
            prune: false,
            ..MeshOptions::default()
        },
    )
    .unwrap();
    // The same triangles; vertex positions agree up to float rounding (pruned spans
    // start their blocks at other layers).
    assert_eq!(m.triangles, unpruned.triangles);
    let gap = m
        .positions
        .iter()
        .zip(&unpruned.positions)
        .map(|(a, b)| Vec3::from(*a).distance(Vec3::from(*b)))
        .fold(0f32, f32::max);
    assert!(gap < 1e-3 * grid.spacing.min_element(), "{gap} m");
    assert!(
        us.field_evaluations > 8 * stats.field_evaluations,
        "{stats}\n{us}"
    );
}

/// `f` without its per-column shortcuts ([`Field::eval_column`], [`Field::z_bands_clip`]),
/// also on its pruned fields: the mesher then searches z-bands once per brick run and
/// evaluates its samples point by point and block by block, as it does for fields that
/// share nothing along vertical lines.
struct PointsAndBlocks<'a>(Box<dyn Field + 'a>);

impl Field for PointsAndBlocks<'_> {
    fn value(&self, p: Vec3) -> f32 {
        self.0.value(p)
    }
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        self.0.value_grad(p)
    }
    fn support(&self) -> Aabb {
        self.0.support()
    }
    fn interval(&self, b: &Aabb) -> karstic::field::Interval {
        self.0.interval(b)
    }
    fn lipschitz(&self) -> f32 {
        self.0.lipschitz()
    }
    fn lipschitz_box(&self, b: &Aabb) -> f32 {
        self.0.lipschitz_box(b)
    }
    fn z_bands(&self, fp: &Rect, z: karstic::field::Interval, out: &mut karstic::field::ZBands) {
        self.0.z_bands(fp, z, out)
    }
    fn prune(&self, region: &Aabb) -> Option<Box<dyn Field + '_>> {
        let pruned = self.0.prune(region)?;
        Some(Box::new(PointsAndBlocks(pruned)))
    }
    fn eval_block(&self, origin: Vec3, step: Vec3, dims: [usize; 3], out: &mut [f32]) {
        self.0.eval_block(origin, step, dims, out)
    }
    fn elevation(&self, fp: &Rect) -> Option<karstic::field::Elevation<'_>> {
        self.0.elevation(fp)
    }
}

/// The crop with the scale benchmark's detail amplification (5 m of 3D fBm at 40 m, 4
/// octaves) and falloff, as a tree.
fn detailed_tree() -> Tree {
    let text = format!(
        "(version: 1, name: \"detail\", seed: 11, root: Heightfield(name: \"dem\", source: \"{CROP}\", \
         falloff: 30.0, interpolation: Bicubic, \
         detail: (noise: (amplitude: 5.0, wavelength: 40.0, octaves: 4), steep: 0.6)))"
    );
    let path = crate_root().join("detail.ron");
    let scene = parse_scene(&text, &path).expect("the tree parses");
    compile_scene(&scene, &path, crate_root())
        .expect("the tree compiles")
        .tree
}

/// The mesher's column evaluation (one elevation lookup per grid column) and its one
/// z-band search per column give the cells, samples and mesh of the point-and-block
/// evaluation with a search per brick run, bit for bit, on a detailed DEM at 1 m, its
/// floor included; and a tree's column values are its point values, 0 outside its
/// support.
#[test]
fn column_evaluation_gives_the_block_mesh() {
    let tree = detailed_tree();
    let s = Field::support(&tree);
    // 1 m cells on whole metres: both evaluations see the same sample heights exactly.
    let origin = Vec3::new(5200.0, 5600.0, s.min.z.floor());
    let cells = [72, 64, (s.max.z - origin.z).ceil() as usize];
    let grid = GridSpec::new(origin, Vec3::ONE, cells).unwrap();
    let (lined, stats) = extract(&tree, &grid, true, false);
    let (blocks, by_runs) = extract(
        &PointsAndBlocks(Box::new(detailed_tree())),
        &grid,
        true,
        false,
    );
    // one z-band search per column (clipped to its runs) keeps the same cells
    assert_eq!(stats.cells_visited, by_runs.cells_visited);
    assert_eq!(stats.field_evaluations, by_runs.field_evaluations);
    assert!(lined.triangles.len() > 10_000, "{}", lined.triangles.len());
    assert!(
        stats.field_evaluations > 20_000,
        "{}",
        stats.field_evaluations
    );
    assert_eq!(lined.positions, blocks.positions);
    assert_eq!(lined.normals, blocks.normals);
    assert_eq!(lined.triangles, blocks.triangles);
    let xy = Vec2::new(5230.5, 5611.25);
    let zs: Vec<f32> = (0..200).map(|k| s.min.z - 50.0 + 9.7 * k as f32).collect();
    let mut out = vec![f32::NAN; zs.len()];
    assert!(tree.eval_column(xy, &zs, &mut out));
    for (&z, &v) in zs.iter().zip(&out) {
        assert_eq!(
            v.to_bits(),
            tree.value(xy.extend(z)).to_bits(),
            "at z = {z}"
        );
    }
    assert!(out[0] == 0.0 && out[199] == 0.0 && out.iter().any(|&v| v > 0.5));
}

//! Amplify a DEM from code: read it, turn it into an implicit terrain, add a cave and an
//! arch, mesh the region around them and write a glTF binary.
//!
//! ```sh
//! cargo run --release --example amplify_dem -- [OUT_DIR] [DEM] [CELL]
//! ```
//!
//! Defaults: the system's temporary folder, `trees/data/jacksboro_crop.asc` (128 × 128
//! samples of 90 m) and 4 m cells. Any DEM karstic reads will do (GeoTIFF, PNG with a
//! sidecar, ESRI ASCII, SRTM `.hgt`): the features are placed around the DEM's centre
//! and follow its ground.

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{Context, bail};
use glam::{Vec2, Vec3};
use karstic::dem::{self, HeightfieldField, ImplicitParams, Interpolation, ReadOptions};
use karstic::field::skeleton::{Capsule, Chain, Segment, catmull_rom};
use karstic::field::{Fbm, Field, Noise, Primitive, Skeleton, TreeBuilder};
use karstic::mesh::export::{self, ExportOptions};
use karstic::mesh::{GridSpec, MeshOptions, polygonize};
use karstic::render::Materials;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let out_dir = args.next().map_or_else(
        || std::env::temp_dir().join("karstic-examples"),
        PathBuf::from,
    );
    let dem_path = PathBuf::from(
        args.next()
            .unwrap_or_else(|| "trees/data/jacksboro_crop.asc".into()),
    );
    let cell: f32 = match args.next() {
        Some(s) => s
            .parse()
            .with_context(|| format!("CELL: expected metres, found {s:?}"))?,
        None => 4.0,
    };

    // The DEM as an implicit terrain (Paris et al. 2019 §5.1): solid below the ground,
    // `σ(h − z)` with a 30 m transition, bicubic between the samples.
    let dem = dem::read(&dem_path, &ReadOptions::default())?;
    let params = ImplicitParams {
        interpolation: Interpolation::Bicubic,
        ..ImplicitParams::with_falloff(30.0)
    };
    let terrain = HeightfieldField::new(&dem.heightfield, &params)?;
    let extent = dem.heightfield.extent();
    let centre = 0.5 * (extent.min + extent.max);
    let ground = |offset: Vec2| -> anyhow::Result<Vec3> {
        let xy = centre + offset;
        let z = terrain.height(xy);
        if !z.is_finite() {
            bail!(
                "{}: no ground at {xy} (nodata or off the grid)",
                dem_path.display()
            );
        }
        Ok(xy.extend(z))
    };

    // A cave: a capsule from just above the ground down into the rock, its radius of
    // influence perturbed by fBm so its walls look rocky (Paris et al. 2019 §5.2). It is
    // carved out of the terrain below.
    let mouth = ground(Vec2::ZERO)? + Vec3::new(0.0, 0.0, 8.0);
    let end = ground(Vec2::new(70.0, 30.0))? - Vec3::new(0.0, 0.0, 40.0);
    let cave = Primitive::new(
        Skeleton::Capsule(Capsule::new(Segment::new(mouth, end), 6.0)),
        6.0,
        1.0,
        Some(Noise {
            fbm: Fbm::with(7, 8.0, 4),
            amplitude: 3.0,
        }),
    )?;

    // An arch: a smooth curve skeleton from foot to foot, its crown 35 m above the
    // highest ground along the span; the feet sink 4 m into the ground and blend with it.
    let (a, b) = (
        ground(Vec2::new(-60.0, -120.0))?,
        ground(Vec2::new(60.0, -120.0))?,
    );
    let mut top = a.z.max(b.z);
    for k in 1..16 {
        top = top.max(ground(Vec2::new(-60.0 + 7.5 * k as f32, -120.0))?.z);
    }
    let crown = top + 35.0;
    let lift = |p: Vec3, z: f32| Vec3::new(p.x, p.y, z);
    let span = [
        a - Vec3::Z * 4.0,
        lift(a.lerp(b, 0.1), crown - 15.0),
        lift(a.lerp(b, 0.35), crown),
        lift(a.lerp(b, 0.65), crown),
        lift(a.lerp(b, 0.9), crown - 15.0),
        b - Vec3::Z * 4.0,
    ];
    let arch = Primitive::new(
        Skeleton::Curve(Chain::new(catmull_rom(&span))),
        16.0,
        1.0,
        Some(Noise {
            fbm: Fbm::with(11, 12.0, 3),
            amplitude: 3.0,
        }),
    )?;

    // The region to mesh: both features with room around them, tall enough for the
    // ground under its whole footprint (sampled on a lattice) so the mesh is cut only
    // by its sides.
    let mut region = cave.support().union(arch.support()).dilate(30.0);
    let (lo, hi) = (region.min, region.max);
    for i in 0..=8 {
        for j in 0..=8 {
            let t = Vec2::new(i as f32, j as f32) / 8.0;
            let xy = lo.truncate() + t * (hi - lo).truncate();
            if let Ok(p) = ground(xy - centre) {
                region = region
                    .include(p - Vec3::Z * 20.0)
                    .include(p + Vec3::Z * 20.0);
            }
        }
    }

    // The tree: (terrain + arch) with the cave carved out. Blend sums the fields, so the
    // arch's feet merge smoothly into the slopes.
    let mut tree = TreeBuilder::new();
    let terrain = Arc::new(terrain);
    let ground = terrain.clone();
    let terrain = tree.leaf(terrain, Some("dem".into()));
    let arch = tree.primitive(arch, Some("arch".into()));
    let cave = tree.primitive(cave, Some("cave".into()));
    let rock = tree.blend(vec![terrain, arch], Some("rock".into()));
    let root = tree.difference(rock, vec![cave], Some("amplified".into()));
    let tree = tree.build(root);

    // Bound-pruned Marching Cubes over the region, then a Y-up glTF binary with vertex
    // colours from the material model.
    let grid = GridSpec::with_cell(&region, cell)?;
    let (mesh, stats) = polygonize(&tree, &grid, &MeshOptions::default())?;
    std::fs::create_dir_all(&out_dir).with_context(|| format!("creating {}", out_dir.display()))?;
    let path = out_dir.join("amplified.glb");
    // The preview's materials: rock on steep faces and on the features (away from the
    // DEM's surface), soil and grass on gentler slopes.
    let opts = ExportOptions {
        albedo: Some(std::sync::Arc::new(Materials::for_scene(
            &tree.support(),
            Some(ground),
        ))),
        ..ExportOptions::default()
    };
    export::write(&mesh, &path, &opts)?;
    println!(
        "{}: {} × {} × {} cells of {cell} m, {} triangles, {} field evaluations → {}",
        dem_path.display(),
        grid.cells[0],
        grid.cells[1],
        grid.cells[2],
        mesh.triangles.len(),
        stats.field_evaluations,
        path.display()
    );
    Ok(())
}

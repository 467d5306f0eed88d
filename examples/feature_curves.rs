//! Feature Curves from code (Becher 2016): an overhanging cliff drawn as two curves with
//! Constraint Points, run through the sparse voxel pipeline into an S field, meshed and
//! written as a glTF binary.
//!
//! ```sh
//! cargo run --release --example feature_curves -- [OUT_DIR] [VOXEL]
//! ```
//!
//! Defaults: the system's temporary folder and 1.5 m voxels (the domain is 96 × 64 × 64
//! m; 1 m voxels take a few times longer).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use karstic::mesh::MeshOptions;
use karstic::mesh::export::{self, ExportOptions};
use karstic::render::Materials;
use karstic::value::{Finite, NonNegative, Unit};
use karstic::voxel::spec::{
    Bitangent, ConstraintSpec, CurveSource, CurveSpec, FeatureSet, FeatureVolumeSpec, Point,
    parse_ron,
};

/// A control vertex at absolute coordinates (metres).
fn abs(x: f32, y: f32, z: f32) -> Point {
    Point::Abs(Finite::new(x), Finite::new(y), Finite::new(z))
}

/// A Constraint Point at `t` along the curve: the surface leaves the curve at `left`
/// degrees below the horizontal on its left and `right` on its right (90: straight down;
/// beyond 90 it tilts back under the curve: an overhang).
fn slopes(t: f32, left: f32, right: f32) -> ConstraintSpec {
    ConstraintSpec {
        t: Unit::new(t),
        left: Bitangent::Slope(Finite::new(left)),
        right: Bitangent::Slope(Finite::new(right)),
        amplitude: NonNegative::new(0.0),
        roughness: NonNegative::new(0.0),
    }
}

/// A seed curve: the surface passes through it.
fn curve(name: &str, points: Vec<Point>, constraints: Vec<ConstraintSpec>) -> CurveSpec {
    CurveSpec {
        name: Some(name.into()),
        points,
        constraints,
        seed: true,
        ribbon: None,
    }
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let out_dir = args.next().map_or_else(
        || std::env::temp_dir().join("karstic-examples"),
        PathBuf::from,
    );
    let voxel: f32 = match args.next() {
        Some(s) => s
            .parse()
            .with_context(|| format!("VOXEL: expected metres, found {s:?}"))?,
        None => 1.5,
    };

    // The cliff's edge: a plateau on its left (slope 0), a face on its right that leans
    // out over its foot, more at the far end. A second curve in front makes the ground
    // the face comes down to.
    let features = FeatureSet {
        curves: vec![
            curve(
                "edge",
                vec![
                    abs(-4.0, 30.0, 46.0),
                    abs(48.0, 36.0, 46.0),
                    abs(100.0, 28.0, 46.0),
                ],
                vec![slopes(0.0, 0.0, 100.0), slopes(1.0, 0.0, 125.0)],
            ),
            curve(
                "ground",
                vec![abs(-4.0, 12.0, 12.0), abs(100.0, 12.0, 12.0)],
                vec![slopes(0.0, 0.0, 0.0)],
            ),
        ],
        ..FeatureSet::default()
    };

    // The volume: its domain box and voxel size as a tree file writes them; every other
    // setting (solid side, transition, solver, noise) keeps its default.
    let settings = format!(
        "FeatureVolume(curves: Inline(), domain: ((0, 0, 0), (96, 64, 64)), voxel: {voxel})"
    );
    let mut volume: FeatureVolumeSpec = parse_ron(&settings, Path::new("feature_curves.rs"))?;
    volume.curves = CurveSource::Inline(features);

    // The voxel pipeline (coarse to fine on sparse bricks) gives the S-field leaf: a field
    // like any other, which could blend into a DEM or carve it. Here it is meshed alone.
    let start = Instant::now();
    let field = volume.build(Path::new("."), 7)?;
    let built = start.elapsed();
    let (mesh, _) = field.extract(None, &MeshOptions::default())?;
    std::fs::create_dir_all(&out_dir).with_context(|| format!("creating {}", out_dir.display()))?;
    let path = out_dir.join("overhang.glb");
    let opts = ExportOptions {
        albedo: Some(std::sync::Arc::new(Materials::for_scene(
            &mesh.bounds(),
            None,
        ))),
        ..ExportOptions::default()
    };
    export::write(&mesh, &path, &opts)?;
    println!(
        "{} levels, {:.1} MiB of bricks, built in {:.2} s; {} triangles → {}",
        field.stats().levels.len(),
        field.memory_bytes() as f64 / (1 << 20) as f64,
        built.as_secs_f64(),
        mesh.triangles.len(),
        path.display()
    );
    Ok(())
}

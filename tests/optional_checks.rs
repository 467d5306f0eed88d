//! The tools of the optional checks, named in the log: `.ci/run` runs this module first
//! with `--nocapture`, so its output says which GPU adapter the GPU comparisons use, which
//! Khronos glTF validator and which trimesh the export tests use, and which GDAL the
//! heightmap export tests read their files back with. Where a `KARSTIC_REQUIRE_*`
//! variable is set (tests/common/optional.rs) a missing tool fails here first.

use crate::common::{REQUIRE_GDAL, gpu, trimesh_version, unavailable};
use crate::gltf_validator::{khronos_validate, version};

use glam::Vec3;
use karstic::mesh::Mesh;
use karstic::mesh::export::{self, ExportOptions};

#[test]
fn gdalinfo_runs() {
    match std::process::Command::new("gdalinfo")
        .arg("--version")
        .output()
    {
        Ok(o) if o.status.success() => {
            println!(
                "optional checks: {}",
                String::from_utf8_lossy(&o.stdout).trim()
            );
        }
        other => unavailable(REQUIRE_GDAL, &format!("gdalinfo cannot run ({other:?})")),
    }
}

#[test]
fn gpu_adapter_opens() {
    if let Some(ctx) = gpu() {
        println!("optional checks: GPU adapter {}", ctx.adapter);
    }
}

#[test]
fn trimesh_imports() {
    if let Some(v) = trimesh_version() {
        println!("optional checks: trimesh {v}");
    }
}

/// The validator really checks the data: a written `.gltf` passes, and the same file with
/// its position bounds made wrong fails with the accessor error.
#[test]
fn khronos_validator_catches_wrong_bounds() {
    let Some(v) = version() else { return };
    println!("optional checks: Khronos glTF validator {v}");
    let p = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let mesh = Mesh {
        positions: p.to_vec(),
        normals: p
            .iter()
            .map(|&q| (Vec3::from(q) - 0.25).normalize().to_array())
            .collect(),
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        attributes: vec![],
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tetra.gltf");
    export::write(&mesh, &path, &ExportOptions::default()).unwrap();
    let (ok, report) = khronos_validate(&path).unwrap();
    assert!(ok, "{report}");

    let mut json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    let at = json["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    json["accessors"][at]["max"] = serde_json::json!([2.0, 2.0, 2.0]);
    std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
    let (ok, report) = khronos_validate(&path).unwrap();
    assert!(!ok && report.contains("ACCESSOR_MAX_MISMATCH"), "{report}");
}

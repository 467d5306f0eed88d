//! Exporters: glTF accepted by the Khronos validator, Y-up conversion, OBJ/PLY layouts,
//! identical bytes whatever the thread count.

use crate::gltf_validator;
use crate::mesh_fields;

use glam::Vec3;
use gltf_validator::assert_valid;
use karstic::field::{Aabb, Field};
use karstic::mesh::export::{self, ExportOptions};
use karstic::mesh::{Attribute, GridSpec, Mesh, MeshOptions, polygonize};
use mesh_fields::*;

fn terrain_mesh() -> Mesh {
    let t = caved_terrain(6);
    let grid = GridSpec::with_cell(&t.support(), 8.0).unwrap();
    let (mut m, _) = polygonize(&t, &grid, &MeshOptions::default()).unwrap();
    let amplitude = m.positions.iter().map(|p| p[2] * 0.01).collect();
    m.attributes.push(Attribute {
        name: "AMPLITUDE".into(),
        values: amplitude,
    });
    m
}

fn sphere_mesh() -> Mesh {
    let grid = GridSpec::with_resolution(&Aabb::around(Vec3::ZERO, 1.3), 24).unwrap();
    polygonize(&unit_sphere(), &grid, &MeshOptions::default())
        .unwrap()
        .0
}

fn glb_json(bytes: &[u8]) -> gltf_json::Root {
    assert_eq!(&bytes[..4], b"glTF");
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    assert_eq!(&bytes[16..20], b"JSON");
    gltf_json::Root::from_slice(&bytes[20..20 + len]).unwrap()
}

#[test]
fn gltf_files_pass_the_khronos_validator() {
    let dir = tempfile::tempdir().unwrap();
    let opts = ExportOptions { color: true };
    for (name, mesh) in [("terrain", terrain_mesh()), ("sphere", sphere_mesh())] {
        for ext in ["glb", "gltf"] {
            let path = dir.path().join(format!("{name} mesh.{ext}"));
            export::write(&mesh, &path, &opts).unwrap();
            assert_valid(&path);
        }
    }
    // An empty mesh is still a valid (empty) asset.
    let path = dir.path().join("empty.glb");
    export::write(&Mesh::default(), &path, &opts).unwrap();
    assert_valid(&path);
}

#[test]
fn glb_is_y_up_with_bounds_and_custom_attributes() {
    let mesh = terrain_mesh();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.glb");
    export::write(&mesh, &path, &ExportOptions { color: true }).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(bytes.len() % 4, 0);
    assert_eq!(
        u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize,
        bytes.len()
    );
    let root = glb_json(&bytes);
    let prim = &root.meshes[0].primitives[0];
    let mut names: Vec<String> = prim
        .attributes
        .keys()
        .map(|k| k.as_ref().unwrap().to_string())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["COLOR_0", "NORMAL", "POSITION", "_AMPLITUDE"]
            .map(String::from)
            .to_vec()
    );
    let position = gltf_json::validation::Checked::Valid(gltf_json::mesh::Semantic::Positions);
    let pos = &root.accessors[prim.attributes[&position].value()];
    let (min, max) = (pos.min.as_ref().unwrap(), pos.max.as_ref().unwrap());
    let b = mesh.bounds();
    // glTF y is karstic z; glTF z is −y.
    assert_eq!(max[1].as_f64().unwrap() as f32, b.max.z);
    assert_eq!(min[2].as_f64().unwrap() as f32, -b.max.y);
    let idx = &root.accessors[prim.indices.unwrap().value()];
    assert_eq!(idx.count.0 as usize, mesh.triangles.len() * 3);
}

#[test]
fn glb_bytes_do_not_depend_on_threads() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mesh = pool.install(terrain_mesh);
        let path = dir.path().join(format!("t{threads}.glb"));
        export::write(&mesh, &path, &ExportOptions { color: true }).unwrap();
        std::fs::read(path).unwrap()
    };
    assert_eq!(bytes(1), bytes(2));
}

#[test]
fn obj_and_ply_layouts() {
    let mesh = sphere_mesh();
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("s.obj");
    export::write(&mesh, &obj, &ExportOptions::default()).unwrap();
    let text = std::fs::read_to_string(&obj).unwrap();
    let count = |p: &str| text.lines().filter(|l| l.starts_with(p)).count();
    assert_eq!(count("v "), mesh.positions.len());
    assert_eq!(count("vn "), mesh.normals.len());
    assert_eq!(count("f "), mesh.triangles.len());
    let first_v: Vec<f32> = text.lines().find(|l| l.starts_with("v ")).unwrap()[2..]
        .split(' ')
        .map(|s| s.parse().unwrap())
        .collect();
    let p = mesh.positions[0];
    assert_eq!(first_v, vec![p[0], p[2], -p[1]]);

    let ply = dir.path().join("s.ply");
    export::write(&mesh, &ply, &ExportOptions { color: true }).unwrap();
    let bytes = std::fs::read(&ply).unwrap();
    let end = b"end_header\n";
    let at = bytes.windows(end.len()).position(|w| w == end).unwrap() + end.len();
    let header = String::from_utf8_lossy(&bytes[..at]);
    assert!(header.contains(&format!("element vertex {}", mesh.positions.len())));
    assert!(header.contains("property uchar red"));
    assert_eq!(
        bytes.len() - at,
        mesh.positions.len() * (24 + 3) + mesh.triangles.len() * 13
    );
    let x = f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
    assert_eq!(x, mesh.positions[0][0]);

    assert!(export::write(&mesh, &dir.path().join("s.stl"), &ExportOptions::default()).is_err());
    assert!(
        export::write(
            &mesh,
            &dir.path().join("missing/s.glb"),
            &ExportOptions::default()
        )
        .is_err()
    );
    assert!(!dir.path().join("missing").exists());
}

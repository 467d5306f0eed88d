//! Exporters: glTF with materials, UVs and recentring accepted by the Khronos validator
//! and imported by trimesh, Y-up conversion, OBJ (+ .mtl) and PLY layouts, identical
//! bytes whatever the thread count.

use crate::common::trimesh_import;
use crate::gltf_validator;
use crate::mesh_fields;

use glam::Vec3;
use gltf_validator::assert_valid;
use karstic::field::{Aabb, Field};
use karstic::mesh::export::{self, ExportOptions, Origin, planar_uv, to_y_up};
use karstic::mesh::{Attribute, GridSpec, Mesh, MeshOptions, polygonize};
use karstic::render::Materials;
use mesh_fields::*;

/// Where the test terrain is moved to: kilometres from the origin, like a DEM's region.
const FAR: Vec3 = Vec3::new(4500.0, 4900.0, 600.0);

fn terrain_mesh() -> Mesh {
    let t = caved_terrain(6);
    let grid = GridSpec::with_cell(&t.support(), 8.0).unwrap();
    let (mut m, _) = polygonize(&t, &grid, &MeshOptions::default()).unwrap();
    for p in &mut m.positions {
        *p = (Vec3::from(*p) + FAR).to_array();
    }
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

/// The BIN chunk of a `.glb`.
fn glb_bin(bytes: &[u8]) -> &[u8] {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let at = 20 + len;
    let bin_len = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    assert_eq!(&bytes[at + 4..at + 8], b"BIN\0");
    &bytes[at + 8..at + 8 + bin_len]
}

/// The float vectors of the primitive's attribute `semantic` (tightly packed views).
fn attribute<const N: usize>(
    root: &gltf_json::Root,
    bin: &[u8],
    semantic: gltf_json::mesh::Semantic,
) -> Vec<[f32; N]> {
    let prim = &root.meshes[0].primitives[0];
    let acc =
        &root.accessors[prim.attributes[&gltf_json::validation::Checked::Valid(semantic)].value()];
    let view = &root.buffer_views[acc.buffer_view.unwrap().value()];
    let at = view.byte_offset.unwrap().0 as usize;
    let floats: &[f32] = bytemuck::cast_slice(&bin[at..at + view.byte_length.0 as usize]);
    assert_eq!(floats.len(), acc.count.0 as usize * N);
    floats
        .chunks_exact(N)
        .map(|c| c.try_into().unwrap())
        .collect()
}

/// The options of the engine exports: the preview's materials, UVs over a frame a little
/// larger than the mesh (like a DEM around a region), and `origin`.
fn engine_options(mesh: &Mesh, origin: Origin) -> ExportOptions {
    ExportOptions {
        albedo: Some(std::sync::Arc::new(Materials::for_scene(
            &mesh.bounds(),
            None,
        ))),
        origin,
        uv_frame: Some(mesh.bounds().footprint().dilate(25.0)),
    }
}

#[test]
fn gltf_files_pass_the_khronos_validator() {
    let dir = tempfile::tempdir().unwrap();
    for (name, mesh) in [("terrain", terrain_mesh()), ("sphere", sphere_mesh())] {
        for (origin_name, origin) in Origin::ALL {
            for ext in ["glb", "gltf"] {
                let path = dir.path().join(format!("{name} mesh {origin_name}.{ext}"));
                export::write(&mesh, &path, &engine_options(&mesh, origin)).unwrap();
                assert_valid(&path);
            }
        }
        // Plain geometry (no colours, the mesh's own UV frame) too.
        let path = dir.path().join(format!("{name} plain.glb"));
        export::write(&mesh, &path, &ExportOptions::default()).unwrap();
        assert_valid(&path);
    }
    let opts = engine_options(&terrain_mesh(), Origin::Center);
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
    export::write(&mesh, &path, &engine_options(&mesh, Origin::Dem)).unwrap();
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
        ["COLOR_0", "NORMAL", "POSITION", "TEXCOORD_0", "_AMPLITUDE"]
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
        export::write(&mesh, &path, &engine_options(&mesh, Origin::Center)).unwrap();
        std::fs::read(path).unwrap()
    };
    assert_eq!(bytes(1), bytes(2));
}

#[test]
fn glb_material_colours_and_uvs_are_the_previews() {
    let mesh = terrain_mesh();
    let opts = engine_options(&mesh, Origin::Dem);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.glb");
    export::write(&mesh, &path, &opts).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let root = glb_json(&bytes);
    let bin = glb_bin(&bytes);
    // One PBR metallic-roughness material: dielectric, rough, white base colour (times
    // COLOR_0).
    assert_eq!(root.materials.len(), 1);
    assert_eq!(root.meshes[0].primitives[0].material.unwrap().value(), 0);
    let pbr = &root.materials[0].pbr_metallic_roughness;
    assert_eq!(pbr.metallic_factor.0, 0.0);
    assert!(pbr.roughness_factor.0 >= 0.8, "{}", pbr.roughness_factor.0);
    assert_eq!(pbr.base_color_factor.0, [1.0; 4]);
    // COLOR_0 is the material model's albedo, the colour the preview shades.
    use gltf_json::mesh::Semantic;
    let materials = opts.albedo.as_deref().unwrap();
    let colors: Vec<[f32; 3]> = attribute(&root, bin, Semantic::Colors(0));
    for (i, c) in colors.iter().enumerate() {
        let want = materials.albedo(mesh.positions[i].into(), mesh.normals[i].into());
        assert_eq!(*c, want.to_array(), "vertex {i}");
    }
    // The materials are really applied: rock on the caves' walls, green on the flats.
    let greenest = colors.iter().map(|c| c[1] - c[0]).fold(f32::MIN, f32::max);
    assert!(greenest > 0.03, "no grass: {greenest}");
    // UVs: planar over the frame, u east, v south, in [0, 1].
    let frame = opts.uv_frame.unwrap();
    let uvs: Vec<[f32; 2]> = attribute(&root, bin, Semantic::TexCoords(0));
    for (i, uv) in uvs.iter().enumerate() {
        let p = mesh.positions[i];
        let u = (p[0] - frame.min.x) / (frame.max.x - frame.min.x);
        let v = (frame.max.y - p[1]) / (frame.max.y - frame.min.y);
        assert!(
            (uv[0] - u).abs() < 1e-5 && (uv[1] - v).abs() < 1e-5,
            "{uv:?}"
        );
        assert!(uv.iter().all(|x| (0.0..=1.0).contains(x)), "{uv:?}");
    }
    assert_eq!(planar_uv(&frame, frame.min), [0.0, 1.0]);
}

#[test]
fn recentred_positions_plus_the_node_translation_are_the_originals() {
    let mesh = terrain_mesh();
    let b = mesh.bounds();
    let dir = tempfile::tempdir().unwrap();
    for (origin, pivot) in [
        (Origin::Center, b.center()),
        (Origin::Min, b.min),
        (Origin::Dem, Vec3::ZERO),
    ] {
        let path = dir.path().join(format!("{}.glb", origin.name()));
        export::write(&mesh, &path, &engine_options(&mesh, origin)).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let root = glb_json(&bytes);
        let node = &root.nodes[0];
        let t = Vec3::from(node.translation.unwrap_or([0.0; 3]));
        assert_eq!(t, Vec3::from(to_y_up(pivot.to_array())), "{origin:?}");
        let positions: Vec<[f32; 3]> =
            attribute(&root, glb_bin(&bytes), gltf_json::mesh::Semantic::Positions);
        let mut written = Aabb::EMPTY;
        for (i, q) in positions.iter().enumerate() {
            let back = Vec3::from(*q) + t;
            let want = Vec3::from(to_y_up(mesh.positions[i]));
            assert!(
                back.distance(want) < 1e-3,
                "{origin:?} vertex {i}: {back} ≠ {want}"
            );
            written = written.include(Vec3::from(*q));
        }
        // The pivot is where --origin says: the box's centre, its minimum corner (Y-up:
        // least x and y, greatest z = −y), or the tree's own origin.
        let (lo, hi) = (written.min, written.max);
        let pivot_seen = match origin {
            Origin::Center => written.center(),
            Origin::Min => Vec3::new(lo.x, lo.y, hi.z),
            Origin::Dem => written.center() - Vec3::from(to_y_up(b.center().to_array())),
        };
        assert!(pivot_seen.length() < 1e-2, "{origin:?}: {pivot_seen}");
        // The offset is in the extras too, in karstic's frame.
        let extras: serde_json::Value =
            serde_json::from_str(node.extras.as_ref().unwrap().get()).unwrap();
        assert_eq!(extras["karstic"]["origin"], origin.name());
        let offset: Vec<f32> =
            serde_json::from_value(extras["karstic"]["offset_z_up"].clone()).unwrap();
        assert_eq!(offset, pivot.to_array().to_vec());
    }
}

#[test]
fn trimesh_imports_materials_uvs_and_the_recentred_placement() {
    let mesh = terrain_mesh();
    let dir = tempfile::tempdir().unwrap();
    let b = mesh.bounds();
    for ext in ["glb", "gltf", "obj"] {
        let path = dir.path().join(format!("t.{ext}"));
        export::write(&mesh, &path, &engine_options(&mesh, Origin::Center)).unwrap();
        let Some(report) = trimesh_import(&path) else {
            return;
        };
        let g = &report["geometries"][0];
        assert_eq!(
            report["geometries"].as_array().unwrap().len(),
            1,
            "{report}"
        );
        assert_eq!(g["kind"], "texture", "{ext}: {report}");
        let material = g["material"].as_str().unwrap_or_default();
        assert!(material.ends_with("Material"), "{ext}: {report}");
        assert_eq!(g["faces"], mesh.triangles.len(), "{ext}: {report}");
        assert_eq!(g["uvs"], g["vertices"], "{ext}: {report}");
        assert!(g["uvs"].as_u64().unwrap() > 0, "{ext}: {report}");
        if ext != "obj" {
            // The node's translation puts the recentred mesh back where the tree has it.
            let bounds: [[f32; 3]; 2] = serde_json::from_value(report["bounds"].clone()).unwrap();
            let lo =
                Vec3::from(to_y_up(b.min.to_array())).min(Vec3::from(to_y_up(b.max.to_array())));
            let hi =
                Vec3::from(to_y_up(b.min.to_array())).max(Vec3::from(to_y_up(b.max.to_array())));
            assert!(Vec3::from(bounds[0]).distance(lo) < 1e-2, "{report}");
            assert!(Vec3::from(bounds[1]).distance(hi) < 1e-2, "{report}");
        }
    }
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
    assert_eq!(count("vt "), mesh.positions.len());
    assert_eq!(count("vn "), mesh.normals.len());
    assert_eq!(count("f "), mesh.triangles.len());
    assert!(text.contains("mtllib s.mtl\n") && text.contains("usemtl terrain\n"));
    // The material library is written beside it, and listed among the written files.
    let mtl = std::fs::read_to_string(dir.path().join("s.mtl")).unwrap();
    assert!(
        mtl.contains("newmtl terrain\n") && mtl.contains("\nKd "),
        "{mtl}"
    );
    assert_eq!(
        export::written_files(&obj).unwrap(),
        vec![obj.clone(), dir.path().join("s.mtl")]
    );
    let f = text.lines().find(|l| l.starts_with("f ")).unwrap();
    let [a, b, c] = mesh.triangles[0].map(|v| v + 1);
    assert_eq!(f, format!("f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}"));
    let first_v: Vec<f32> = text.lines().find(|l| l.starts_with("v ")).unwrap()[2..]
        .split(' ')
        .map(|s| s.parse().unwrap())
        .collect();
    let p = mesh.positions[0];
    assert_eq!(first_v, vec![p[0], p[2], -p[1]]);

    let ply = dir.path().join("s.ply");
    export::write(&mesh, &ply, &engine_options(&mesh, Origin::Dem)).unwrap();
    let bytes = std::fs::read(&ply).unwrap();
    let end = b"end_header\n";
    let at = bytes.windows(end.len()).position(|w| w == end).unwrap() + end.len();
    let header = String::from_utf8_lossy(&bytes[..at]);
    assert!(header.contains(&format!("element vertex {}", mesh.positions.len())));
    assert!(header.contains("property uchar red"));
    assert_eq!(
        bytes.len() - at,
        mesh.positions.len() * (24 + 3 + 8) + mesh.triangles.len() * 13
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

/// OBJ vertex colours are written as importers read them, sRGB-encoded, the same bytes'
/// worth as PLY's (linear values made the OBJ terrain about 3× too dark in Blender beside
/// the same glTF or PLY).
#[test]
fn obj_vertex_colours_are_srgb_like_ply() {
    let mesh = terrain_mesh();
    let dir = tempfile::tempdir().unwrap();
    let opts = ExportOptions {
        albedo: Some(std::sync::Arc::new(Materials::for_scene(
            &mesh.bounds(),
            None,
        ))),
        ..ExportOptions::default()
    };
    let obj = dir.path().join("t.obj");
    export::write(&mesh, &obj, &opts).unwrap();
    let text = std::fs::read_to_string(&obj).unwrap();
    let albedo = opts.albedo.as_deref().unwrap();
    let mut checked = 0;
    for (i, line) in text.lines().filter(|l| l.starts_with("v ")).enumerate() {
        let v: Vec<f32> = line[2..].split(' ').map(|x| x.parse().unwrap()).collect();
        let linear = albedo.albedo(mesh.positions[i].into(), mesh.normals[i].into());
        for k in 0..3 {
            let want = linear[k].clamp(0.0, 1.0).powf(1.0 / 2.2);
            assert!(
                (v[3 + k] - want).abs() < 1e-5,
                "vertex {i}: {} against {want}",
                v[3 + k]
            );
        }
        checked += 1;
    }
    assert_eq!(checked, mesh.positions.len());
}

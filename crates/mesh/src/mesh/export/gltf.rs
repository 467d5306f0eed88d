//! glTF 2.0 export, binary (`.glb`) or JSON with a side `.bin`, built with `gltf-json`.
//!
//! glTF is Y-up: a karstic point `(x, y, z)` (Z up) is written as `(x, z, −y)`, a proper
//! rotation, so winding and normals keep their meaning. Indices are `u32`; POSITION
//! carries min/max; NORMAL is unit length; COLOR_0 (optional) is linear RGB; TEXCOORD_0
//! is planar over [`ExportOptions::uv_frame`]; each [`Attribute`](crate::mesh::Attribute)
//! becomes a float SCALAR attribute `_NAME`.
//!
//! The primitive has one PBR metallic-roughness material, `terrain`: dielectric
//! (metallic 0), rough (0.9), its base colour white when COLOR_0 carries the albedo
//! (glTF multiplies the two) and mid grey otherwise. The node's translation is the
//! [`Origin`](super::Origin) offset (Y-up), so the mesh sits where the tree put it; its
//! `extras` repeat it in karstic's Z-up frame with the UV rectangle.

use std::collections::BTreeMap;
use std::io::{self, Write};
use std::path::Path;

use gltf_json as json;
use json::validation::Checked::Valid;
use json::validation::USize64;

use super::{ExportError, ExportOptions, Prepared, to_y_up};
use crate::io::write_atomic;
use crate::mesh::Mesh;

const GLB_MAGIC: u32 = 0x4654_6c67;
const CHUNK_JSON: u32 = 0x4e4f_534a;
const CHUNK_BIN: u32 = 0x004e_4942;

/// The glTF document and its binary buffer.
struct Document {
    root: json::Root,
    bin: Vec<u8>,
}

/// Appends `data` as a buffer view (4-byte aligned) and an accessor over it.
#[allow(clippy::too_many_arguments)]
fn push_accessor(
    root: &mut json::Root,
    bin: &mut Vec<u8>,
    data: &[u8],
    count: usize,
    component: json::accessor::ComponentType,
    type_: json::accessor::Type,
    target: json::buffer::Target,
    min_max: Option<(json::Value, json::Value)>,
) -> json::Index<json::Accessor> {
    debug_assert_eq!(bin.len() % 4, 0);
    let view = root.push(json::buffer::View {
        buffer: json::Index::new(0),
        byte_length: USize64::from(data.len()),
        byte_offset: Some(USize64::from(bin.len())),
        byte_stride: None,
        name: None,
        target: Some(Valid(target)),
        extensions: None,
        extras: Default::default(),
    });
    bin.extend_from_slice(data);
    bin.resize(bin.len().next_multiple_of(4), 0);
    let (min, max) = min_max.unzip();
    root.push(json::Accessor {
        buffer_view: Some(view),
        byte_offset: Some(USize64(0)),
        count: USize64::from(count),
        component_type: Valid(json::accessor::GenericComponentType(component)),
        extensions: None,
        extras: Default::default(),
        type_: Valid(type_),
        min,
        max,
        name: None,
        normalized: false,
        sparse: None,
    })
}

fn document(mesh: &Mesh, opts: &ExportOptions, uri: Option<String>) -> Document {
    use json::accessor::{ComponentType, Type};
    use json::buffer::Target;
    let mut root = json::Root {
        asset: json::Asset {
            generator: Some(format!("karstic {}", env!("CARGO_PKG_VERSION"))),
            ..Default::default()
        },
        ..Default::default()
    };
    let mut bin = Vec::new();
    let n = mesh.positions.len();
    let mut scene_nodes = Vec::new();
    if !mesh.triangles.is_empty() {
        let prepared = Prepared::new(mesh, opts);
        let positions: Vec<[f32; 3]> = prepared.positions.iter().map(|&p| to_y_up(p)).collect();
        let normals: Vec<[f32; 3]> = mesh.normals.iter().map(|&p| to_y_up(p)).collect();
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for p in &positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let mut attributes = BTreeMap::new();
        let pos = push_accessor(
            &mut root,
            &mut bin,
            bytemuck::cast_slice(&positions),
            n,
            ComponentType::F32,
            Type::Vec3,
            Target::ArrayBuffer,
            Some((
                json::Value::from(lo.to_vec()),
                json::Value::from(hi.to_vec()),
            )),
        );
        attributes.insert(Valid(json::mesh::Semantic::Positions), pos);
        let nrm = push_accessor(
            &mut root,
            &mut bin,
            bytemuck::cast_slice(&normals),
            n,
            ComponentType::F32,
            Type::Vec3,
            Target::ArrayBuffer,
            None,
        );
        attributes.insert(Valid(json::mesh::Semantic::Normals), nrm);
        let uv = push_accessor(
            &mut root,
            &mut bin,
            bytemuck::cast_slice(&prepared.uvs),
            n,
            ComponentType::F32,
            Type::Vec2,
            Target::ArrayBuffer,
            None,
        );
        attributes.insert(Valid(json::mesh::Semantic::TexCoords(0)), uv);
        if let Some(colors) = &prepared.colors {
            let col = push_accessor(
                &mut root,
                &mut bin,
                bytemuck::cast_slice(colors),
                n,
                ComponentType::F32,
                Type::Vec3,
                Target::ArrayBuffer,
                None,
            );
            attributes.insert(Valid(json::mesh::Semantic::Colors(0)), col);
        }
        for a in &mesh.attributes {
            let acc = push_accessor(
                &mut root,
                &mut bin,
                bytemuck::cast_slice(&a.values),
                n,
                ComponentType::F32,
                Type::Scalar,
                Target::ArrayBuffer,
                None,
            );
            attributes.insert(Valid(json::mesh::Semantic::Extras(a.name.clone())), acc);
        }
        let indices = push_accessor(
            &mut root,
            &mut bin,
            bytemuck::cast_slice(&mesh.triangles),
            mesh.triangles.len() * 3,
            ComponentType::U32,
            Type::Scalar,
            Target::ElementArrayBuffer,
            None,
        );
        let material = root.push(material(prepared.colors.is_some()));
        let m = root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: Some("terrain".into()),
            primitives: vec![json::mesh::Primitive {
                attributes,
                extensions: None,
                extras: Default::default(),
                indices: Some(indices),
                material: Some(material),
                mode: Valid(json::mesh::Mode::Triangles),
                targets: None,
            }],
            weights: None,
        });
        let offset = prepared.offset.to_array();
        scene_nodes.push(root.push(json::Node {
            mesh: Some(m),
            name: Some("terrain".into()),
            translation: (offset != [0.0; 3]).then(|| to_y_up(offset)),
            extras: node_extras(opts, &prepared),
            ..Default::default()
        }));
        root.push(json::Buffer {
            byte_length: USize64::from(bin.len()),
            name: None,
            uri,
            extensions: None,
            extras: Default::default(),
        });
    }
    if !scene_nodes.is_empty() {
        let scene = root.push(json::Scene {
            extensions: None,
            extras: Default::default(),
            name: None,
            nodes: scene_nodes,
        });
        root.scene = Some(scene);
    }
    Document { root, bin }
}

/// The terrain's PBR material: dielectric and rough; white base colour when COLOR_0
/// holds the albedo (glTF multiplies them), mid grey otherwise.
fn material(vertex_colors: bool) -> json::Material {
    let base = if vertex_colors { 1.0 } else { 0.5 };
    json::Material {
        name: Some("terrain".into()),
        pbr_metallic_roughness: json::material::PbrMetallicRoughness {
            base_color_factor: json::material::PbrBaseColorFactor([base, base, base, 1.0]),
            metallic_factor: json::material::StrengthFactor(0.0),
            roughness_factor: json::material::StrengthFactor(ROUGHNESS),
            ..Default::default()
        },
        ..Default::default()
    }
}

/// Roughness of the terrain material: bare rock and soil are nearly diffuse.
pub const ROUGHNESS: f32 = 0.9;

/// The node's `extras`: the origin, its offset in karstic's frame (Z up, metres; add it
/// to the positions to get the tree's coordinates) and the UV rectangle.
fn node_extras(opts: &ExportOptions, p: &Prepared) -> json::extras::Extras {
    let f = &p.uv_frame;
    let extras = serde_json::json!({
        "karstic": {
            "origin": opts.origin.name(),
            "offset_z_up": p.offset.to_array(),
            "uv_frame": [f.min.x, f.min.y, f.max.x, f.max.y],
        }
    });
    serde_json::value::to_raw_value(&extras).ok()
}

fn json_error(e: json::Error) -> io::Error {
    io::Error::other(e)
}

/// Writes a binary glTF (`.glb`): header, JSON chunk, BIN chunk.
pub fn write_glb(mesh: &Mesh, path: &Path, opts: &ExportOptions) -> Result<(), ExportError> {
    let doc = document(mesh, opts, None);
    write_atomic(path, |w| write_glb_to(&doc, w))?;
    Ok(())
}

fn write_glb_to(doc: &Document, w: &mut dyn Write) -> io::Result<()> {
    let mut text = doc.root.to_vec().map_err(json_error)?;
    text.resize(text.len().next_multiple_of(4), b' ');
    let has_bin = !doc.bin.is_empty();
    let total = 12 + 8 + text.len() + if has_bin { 8 + doc.bin.len() } else { 0 };
    let total = u32::try_from(total)
        .map_err(|_| io::Error::other("a .glb holds at most 4 GiB; write .gltf instead"))?;
    w.write_all(&GLB_MAGIC.to_le_bytes())?;
    w.write_all(&2u32.to_le_bytes())?;
    w.write_all(&total.to_le_bytes())?;
    w.write_all(&(text.len() as u32).to_le_bytes())?;
    w.write_all(&CHUNK_JSON.to_le_bytes())?;
    w.write_all(&text)?;
    if has_bin {
        w.write_all(&(doc.bin.len() as u32).to_le_bytes())?;
        w.write_all(&CHUNK_BIN.to_le_bytes())?;
        w.write_all(&doc.bin)?;
    }
    Ok(())
}

/// Writes a JSON glTF (`.gltf`) and its buffer beside it (same stem, `.bin`).
pub fn write_gltf(mesh: &Mesh, path: &Path, opts: &ExportOptions) -> Result<(), ExportError> {
    let bin_path = bin_path(path);
    let bin_name = bin_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| ExportError::Path(path.display().to_string()))?;
    let doc = document(mesh, opts, Some(percent_encode(&bin_name)));
    if !doc.bin.is_empty() {
        write_atomic(&bin_path, |w| w.write_all(&doc.bin))?;
    }
    write_atomic(path, |w| doc.root.to_writer_pretty(w).map_err(json_error))?;
    Ok(())
}

/// The buffer file of the JSON glTF `path`: the same name with the extension `.bin`.
pub(crate) fn bin_path(path: &Path) -> std::path::PathBuf {
    path.with_extension("bin")
}

/// Escapes what a URI reference may not hold raw (glTF URIs are RFC 3986).
fn percent_encode(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    for b in name.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uri_escapes_spaces() {
        assert_eq!(percent_encode("my terrain.bin"), "my%20terrain.bin");
    }
}

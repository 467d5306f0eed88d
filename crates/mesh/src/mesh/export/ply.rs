//! Stanford PLY export, binary little-endian, in karstic's Z-up frame: positions
//! (relative to the [`Origin`](super::Origin) offset, named in a header comment),
//! normals, optional `red green blue` bytes (the materials' albedo in sRGB), texture
//! coordinates `s t` (OBJ's convention, `t` up), custom attributes as lower-case float
//! properties, and triangles as `uchar`-counted `uint` lists.

use std::path::Path;

use super::{ExportError, ExportOptions, Prepared};
use crate::io::write_atomic;
use crate::mesh::Mesh;

/// Writes `mesh` as a binary PLY file.
pub fn write_ply(mesh: &Mesh, path: &Path, opts: &ExportOptions) -> Result<(), ExportError> {
    let p = Prepared::new(mesh, opts);
    write_atomic(path, |w| {
        writeln!(w, "ply\nformat binary_little_endian 1.0")?;
        writeln!(
            w,
            "comment karstic {} (Z up, metres)",
            env!("CARGO_PKG_VERSION")
        )?;
        let [x, y, z] = p.offset.to_array();
        writeln!(
            w,
            "comment origin {}: add ({x} {y} {z}) to the positions for the tree's frame",
            opts.origin.name()
        )?;
        writeln!(w, "element vertex {}", mesh.positions.len())?;
        for p in ["x", "y", "z", "nx", "ny", "nz"] {
            writeln!(w, "property float {p}")?;
        }
        if p.colors.is_some() {
            writeln!(
                w,
                "property uchar red\nproperty uchar green\nproperty uchar blue"
            )?;
        }
        writeln!(w, "property float s\nproperty float t")?;
        for a in &mesh.attributes {
            writeln!(w, "property float {}", a.name.to_ascii_lowercase())?;
        }
        writeln!(w, "element face {}", mesh.triangles.len())?;
        writeln!(w, "property list uchar uint vertex_indices\nend_header")?;
        let mut rec = Vec::with_capacity(64);
        for i in 0..mesh.positions.len() {
            rec.clear();
            for v in p.positions[i].iter().chain(&mesh.normals[i]) {
                rec.extend_from_slice(&v.to_le_bytes());
            }
            if let Some(c) = &p.colors {
                // Linear colour to 8-bit sRGB.
                rec.extend(c[i].map(|x| (super::display_encoded(x) * 255.0).round() as u8));
            }
            let [s, t] = p.uvs[i];
            for v in [s, 1.0 - t] {
                rec.extend_from_slice(&v.to_le_bytes());
            }
            for a in &mesh.attributes {
                rec.extend_from_slice(&a.values[i].to_le_bytes());
            }
            w.write_all(&rec)?;
        }
        for t in &mesh.triangles {
            rec.clear();
            rec.push(3);
            for v in t {
                rec.extend_from_slice(&v.to_le_bytes());
            }
            w.write_all(&rec)?;
        }
        Ok(())
    })?;
    Ok(())
}

//! Wavefront OBJ export (text, Y-up like glTF) with its material library: `v` (with
//! `r g b` vertex colours when asked for, the extension Blender, MeshLab and trimesh
//! read, as sRGB: written display-encoded like PLY's), `vt` (planar UVs, OBJ's `v` up), `vn`, and `f v/vt/vn` lines using the material
//! `terrain` of the `.mtl` beside it.

use std::path::{Path, PathBuf};

use super::{ExportError, ExportOptions, Prepared, gltf::ROUGHNESS, to_y_up};
use crate::io::write_atomic;
use crate::mesh::Mesh;

/// The material library of the OBJ `path`: the same name with the extension `.mtl`.
pub(crate) fn mtl_path(path: &Path) -> PathBuf {
    path.with_extension("mtl")
}

/// Writes `mesh` as an OBJ file with one object `terrain`, and its `.mtl`.
pub fn write_obj(mesh: &Mesh, path: &Path, opts: &ExportOptions) -> Result<(), ExportError> {
    let mtl = mtl_path(path);
    let mtl_name = mtl
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| ExportError::Path(path.display().to_string()))?;
    let p = Prepared::new(mesh, opts);
    let [r, g, b] = p.mean_color();
    write_atomic(&mtl, |w| {
        writeln!(w, "# karstic {}", env!("CARGO_PKG_VERSION"))?;
        writeln!(w, "newmtl terrain")?;
        // The mean albedo, for viewers that ignore vertex colours; dielectric and rough.
        writeln!(w, "Ka 0 0 0\nKd {r} {g} {b}\nKs 0 0 0\nNs 10\nillum 1")?;
        writeln!(w, "Pr {ROUGHNESS}\nPm 0")?;
        Ok(())
    })?;
    write_atomic(path, |w| {
        writeln!(w, "# karstic {} (Y up, metres)", env!("CARGO_PKG_VERSION"))?;
        let [x, y, z] = p.offset.to_array();
        writeln!(
            w,
            "# origin {}: add ({x} {y} {z}) (Z up) to the positions for the tree's frame",
            opts.origin.name()
        )?;
        writeln!(w, "mtllib {mtl_name}")?;
        writeln!(w, "o terrain")?;
        for (i, &q) in p.positions.iter().enumerate() {
            let [x, y, z] = to_y_up(q);
            match &p.colors {
                Some(c) => {
                    let [r, g, b] = c[i].map(super::display_encoded);
                    writeln!(w, "v {x} {y} {z} {r} {g} {b}")?;
                }
                None => writeln!(w, "v {x} {y} {z}")?,
            }
        }
        for &[u, v] in &p.uvs {
            writeln!(w, "vt {u} {}", 1.0 - v)?;
        }
        for &n in &mesh.normals {
            let [x, y, z] = to_y_up(n);
            writeln!(w, "vn {x} {y} {z}")?;
        }
        writeln!(w, "usemtl terrain")?;
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|v| v + 1);
            writeln!(w, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}")?;
        }
        Ok(())
    })?;
    Ok(())
}

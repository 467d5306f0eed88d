//! Wavefront OBJ export (text, Y-up like glTF): `v`, `vn`, and `f v//vn` lines.

use std::path::Path;

use super::{ExportError, to_y_up};
use crate::io::write_atomic;
use crate::mesh::Mesh;

/// Writes `mesh` as an OBJ file with one object `terrain`.
pub fn write_obj(mesh: &Mesh, path: &Path) -> Result<(), ExportError> {
    write_atomic(path, |w| {
        writeln!(w, "# karstic {} (Y up, metres)", env!("CARGO_PKG_VERSION"))?;
        writeln!(w, "o terrain")?;
        for &p in &mesh.positions {
            let [x, y, z] = to_y_up(p);
            writeln!(w, "v {x} {y} {z}")?;
        }
        for &n in &mesh.normals {
            let [x, y, z] = to_y_up(n);
            writeln!(w, "vn {x} {y} {z}")?;
        }
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|v| v + 1);
            writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
        }
        Ok(())
    })?;
    Ok(())
}

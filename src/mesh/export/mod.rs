//! Mesh exporters: glTF 2.0 (`.glb`, `.gltf` + `.bin`), Wavefront OBJ and binary PLY,
//! all written atomically. glTF and OBJ are converted to Y-up (`(x, y, z)` → `(x, z, −y)`);
//! PLY keeps karstic's Z-up frame.

pub mod gltf;
pub mod obj;
pub mod ply;

use std::path::{Path, PathBuf};

use glam::Vec3;

use super::Mesh;
use crate::io::IoError;

/// Errors while exporting.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// Writing failed; the destination was left as it was.
    #[error(transparent)]
    Io(#[from] IoError),
    /// The output path has an extension we do not write.
    #[error("{0}: unknown mesh format (expected .glb, .gltf, .obj or .ply)")]
    Format(String),
    /// The output path has no file name.
    #[error("{0}: not a file path")]
    Path(String),
}

/// The file formats we write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Binary glTF 2.0.
    Glb,
    /// JSON glTF 2.0 with a side `.bin`.
    Gltf,
    /// Wavefront OBJ (text).
    Obj,
    /// Stanford PLY, binary little-endian.
    Ply,
}

impl Format {
    /// The format named by a path's extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Format, ExportError> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("glb") => Ok(Format::Glb),
            Some("gltf") => Ok(Format::Gltf),
            Some("obj") => Ok(Format::Obj),
            Some("ply") => Ok(Format::Ply),
            _ => Err(ExportError::Format(path.display().to_string())),
        }
    }
}

/// What to write besides positions, normals and triangles.
#[derive(Clone, Copy, Debug, Default)]
pub struct ExportOptions {
    /// Per-vertex colours tinted by slope and altitude (glTF COLOR_0, PLY red/green/blue).
    pub color: bool,
}

/// Writes `mesh` to `path` in the format its extension names.
pub fn write(mesh: &Mesh, path: &Path, opts: &ExportOptions) -> Result<(), ExportError> {
    match Format::from_path(path)? {
        Format::Glb => gltf::write_glb(mesh, path, opts),
        Format::Gltf => gltf::write_gltf(mesh, path, opts),
        Format::Obj => obj::write_obj(mesh, path),
        Format::Ply => ply::write_ply(mesh, path, opts),
    }
}

/// Every file [`write`] writes for `path`: the file itself and, for `.gltf`, its `.bin`.
pub fn written_files(path: &Path) -> Result<Vec<PathBuf>, ExportError> {
    let mut files = vec![path.to_path_buf()];
    if Format::from_path(path)? == Format::Gltf {
        files.push(gltf::bin_path(path));
    }
    Ok(files)
}

/// karstic's Z-up `(x, y, z)` as Y-up `(x, z, −y)`.
#[inline]
pub fn to_y_up(p: [f32; 3]) -> [f32; 3] {
    [p[0], p[2], -p[1]]
}

/// Linear-RGB vertex colours: grass low, bare earth higher, snow on top, rock on steep
/// slopes and overhangs (from the normal's tilt).
pub fn vertex_colors(mesh: &Mesh) -> Vec<[f32; 3]> {
    let b = mesh.bounds();
    let (z0, dz) = (b.min.z, (b.max.z - b.min.z).max(f32::MIN_POSITIVE));
    let grass = Vec3::new(0.13, 0.25, 0.07);
    let earth = Vec3::new(0.30, 0.24, 0.16);
    let snow = Vec3::new(0.85, 0.86, 0.90);
    let rock = Vec3::new(0.26, 0.25, 0.24);
    let smooth = |a: f32, b: f32, x: f32| {
        let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    };
    mesh.positions
        .iter()
        .zip(&mesh.normals)
        .map(|(p, n)| {
            let h = (p[2] - z0) / dz;
            let ground = grass
                .lerp(earth, smooth(0.3, 0.7, h))
                .lerp(snow, smooth(0.8, 0.95, h));
            let steep = 1.0 - n[2].clamp(0.0, 1.0);
            ground.lerp(rock, smooth(0.25, 0.55, steep)).into()
        })
        .collect()
}

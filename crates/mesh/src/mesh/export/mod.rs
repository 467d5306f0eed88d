//! Mesh exporters: glTF 2.0 (`.glb`, `.gltf` + `.bin`), Wavefront OBJ and binary PLY,
//! all written atomically. glTF and OBJ are converted to Y-up (`(x, y, z)` → `(x, z, −y)`);
//! PLY keeps karstic's Z-up frame.

pub mod gltf;
pub mod obj;
pub mod ply;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::Mesh;
use crate::field::{Aabb, Rect};
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

/// Where the written positions' origin lies (`--origin`). Positions are written relative
/// to [`Origin::offset`]; glTF keeps the offset as the node's translation (and in the
/// node's `extras`), OBJ and PLY in a header comment, so tiles written with different
/// origins still line up once the offset is added back.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Origin {
    /// The tree's frame as it is: the DEM's local frame (its south-west sample at
    /// `(0, 0)`), so the pivot can lie kilometres from the geometry.
    #[default]
    Dem,
    /// The centre of the mesh's bounding box.
    Center,
    /// The minimum corner of the mesh's bounding box.
    Min,
}

impl Origin {
    /// Every origin with its name, as `--origin` spells it.
    pub const ALL: [(&'static str, Origin); 3] = [
        ("dem", Origin::Dem),
        ("center", Origin::Center),
        ("min", Origin::Min),
    ];

    /// The name `--origin` gives this origin.
    pub fn name(self) -> &'static str {
        Origin::ALL
            .iter()
            .find(|(_, o)| *o == self)
            .map_or("dem", |(n, _)| n)
    }

    /// The point (karstic frame, Z up) subtracted from the positions of a mesh with
    /// bounds `b` (zero for an empty mesh).
    pub fn offset(self, b: &Aabb) -> Vec3 {
        match self {
            _ if b.is_empty() => Vec3::ZERO,
            Origin::Dem => Vec3::ZERO,
            Origin::Center => b.center(),
            Origin::Min => b.min,
        }
    }
}

impl std::str::FromStr for Origin {
    type Err = String;

    fn from_str(s: &str) -> Result<Origin, String> {
        Origin::ALL
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(s))
            .map(|&(_, o)| o)
            .ok_or_else(|| format!("unknown origin {s:?} (expected center, min or dem)"))
    }
}

/// What colours a surface for the exporters: its linear-RGB albedo at a point with its
/// outward unit normal. The pictures' materials answer it, so a coloured mesh shows the
/// colours of the preview.
pub trait Albedo: Send + Sync + std::fmt::Debug {
    /// The albedo at `p` with outward unit normal `n`.
    fn albedo(&self, p: Vec3, n: Vec3) -> Vec3;
}

/// What to write besides positions, normals and triangles.
#[derive(Clone, Debug, Default)]
pub struct ExportOptions {
    /// What colours the vertices (glTF COLOR_0, OBJ and PLY vertex colours), the same
    /// albedo as the preview's; `None`: no colours.
    pub albedo: Option<Arc<dyn Albedo>>,
    /// Where the written positions' origin lies.
    pub origin: Origin,
    /// The rectangle (tree frame, metres) the texture coordinates span: `u` west → east,
    /// `v` north → south (glTF's image convention: the masks' first row is the north);
    /// `None`: the mesh's own footprint.
    pub uv_frame: Option<Rect>,
}

/// A mesh as the exporters write it: positions moved to the origin, Z up, with the
/// per-vertex data the options ask for.
pub(crate) struct Prepared {
    /// Positions relative to `offset` (Z up).
    pub positions: Vec<[f32; 3]>,
    /// Linear-RGB colours, when asked for.
    pub colors: Option<Vec<[f32; 3]>>,
    /// Texture coordinates, glTF convention (`v` down).
    pub uvs: Vec<[f32; 2]>,
    /// The offset subtracted from the positions (karstic frame).
    pub offset: Vec3,
    /// The UV rectangle.
    pub uv_frame: Rect,
}

impl Prepared {
    /// Prepares `mesh` for writing with `opts`.
    pub(crate) fn new(mesh: &Mesh, opts: &ExportOptions) -> Prepared {
        let bounds = mesh.bounds();
        let offset = opts.origin.offset(&bounds);
        let uv_frame = opts.uv_frame.unwrap_or_else(|| bounds.footprint());
        Prepared {
            positions: mesh
                .positions
                .iter()
                .map(|&p| (Vec3::from(p) - offset).to_array())
                .collect(),
            colors: opts.albedo.as_deref().map(|m| vertex_colors(mesh, m)),
            uvs: mesh
                .positions
                .iter()
                .map(|p| planar_uv(&uv_frame, Vec2::new(p[0], p[1])))
                .collect(),
            offset,
            uv_frame,
        }
    }

    /// The mean vertex colour (mid grey without colours): the flat colour of the OBJ's
    /// material for viewers that ignore vertex colours.
    pub(crate) fn mean_color(&self) -> [f32; 3] {
        match &self.colors {
            Some(c) if !c.is_empty() => {
                let sum = c.iter().fold(Vec3::ZERO, |s, &c| s + Vec3::from(c));
                (sum / c.len() as f32).to_array()
            }
            _ => [0.5; 3],
        }
    }
}

/// Texture coordinates of the point `xy` over `frame`: `u` grows east, `v` grows south,
/// `(0, 0)` at the north-west corner (glTF's convention, where an image's first row is
/// `v = 0`). A degenerate frame maps to 0 along that axis.
pub fn planar_uv(frame: &Rect, xy: Vec2) -> [f32; 2] {
    let size = frame.max - frame.min;
    let ratio = |d: f32, s: f32| if s > 0.0 { d / s } else { 0.0 };
    [
        ratio(xy.x - frame.min.x, size.x),
        ratio(frame.max.y - xy.y, size.y),
    ]
}

/// Writes `mesh` to `path` in the format its extension names.
pub fn write(mesh: &Mesh, path: &Path, opts: &ExportOptions) -> Result<(), ExportError> {
    match Format::from_path(path)? {
        Format::Glb => gltf::write_glb(mesh, path, opts),
        Format::Gltf => gltf::write_gltf(mesh, path, opts),
        Format::Obj => obj::write_obj(mesh, path, opts),
        Format::Ply => ply::write_ply(mesh, path, opts),
    }
}

/// Every file [`write`] writes for `path`: the file itself and, for `.gltf`, its `.bin`,
/// for `.obj`, its `.mtl`.
pub fn written_files(path: &Path) -> Result<Vec<PathBuf>, ExportError> {
    let mut files = vec![path.to_path_buf()];
    match Format::from_path(path)? {
        Format::Gltf => files.push(gltf::bin_path(path)),
        Format::Obj => files.push(obj::mtl_path(path)),
        Format::Glb | Format::Ply => {}
    }
    Ok(files)
}

/// A linear colour channel in `[0, 1]` encoded for display (gamma 2.2, sRGB's
/// approximation): how OBJ and PLY vertex colours are written, since Blender, MeshLab and
/// trimesh read them as sRGB (glTF's COLOR_0 stays linear, as its specification says).
pub(crate) fn display_encoded(c: f32) -> f32 {
    c.clamp(0.0, 1.0).powf(1.0 / 2.2)
}

/// karstic's Z-up `(x, y, z)` as Y-up `(x, z, −y)`.
#[inline]
pub fn to_y_up(p: [f32; 3]) -> [f32; 3] {
    [p[0], p[2], -p[1]]
}

/// Linear-RGB vertex colours: the albedo `materials` gives each vertex, the colour the
/// preview shades the same surface with.
pub fn vertex_colors(mesh: &Mesh, materials: &dyn Albedo) -> Vec<[f32; 3]> {
    mesh.positions
        .iter()
        .zip(&mesh.normals)
        .map(|(&p, &n)| materials.albedo(p.into(), n.into()).to_array())
        .collect()
}

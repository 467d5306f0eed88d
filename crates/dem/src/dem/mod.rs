//! Digital elevation models: readers, writers, the [`Heightfield`] grid and its implicit leaf.
//!
//! * Readers: GeoTIFF ([`geotiff`]), 8/16-bit PNG heightmaps with a JSON sidecar ([`png16`]),
//!   ESRI ASCII grids ([`asc`]) and SRTM `.hgt` tiles ([`hgt`]). [`read`] picks one from the
//!   file extension.
//! * Writers: float32 GeoTIFF ([`geotiff_write`]), 16-bit PNG + sidecar ([`png16`]) and ESRI
//!   ASCII ([`asc`]). [`write`] picks one from the extension.
//! * [`Heightfield`] ([`grid`]): f32 elevations in a **local metric frame** whose origin is
//!   the south-west sample (sample `(0, 0)` sits at local `(0, 0)`), x east, y north. The
//!   georeference (CRS coordinates of that sample, in f64) lives beside it in [`Georef`], so
//!   UTM eastings never pass through f32.
//! * [`MinMaxPyramid`] ([`pyramid`]): conservative min/max over any footprint in O(1).
//! * [`Detail`] ([`detail`]): detail amplification of the elevation (Frasson et al. §5).
//! * [`Inset`] ([`inset`]): finer changes to a DEM over a rectangle, and their traces.
//! * [`HeightfieldField`] ([`implicit`]): the implicit terrain primitive of
//!   Paris et al. 2019 §5.1 (its node in tree files is `scene::HeightfieldSpec`).
//!
//! Library code never prints: notices (such as "cell size converted from degrees") are
//! returned in [`Dem::notices`] for the caller to show.

pub mod asc;
pub mod detail;
mod domain;
mod error;
mod georef;
pub mod geotiff;
pub mod geotiff_write;
pub mod grid;
pub mod hgt;
pub mod implicit;
pub mod inset;
pub mod interp;
pub mod png16;
pub mod prism;
pub mod pyramid;

use std::path::Path;

pub use detail::{Detail, DetailParams};
pub use domain::edt;
pub use error::DemError;
pub use georef::{Crs, Georef, RasterType};
pub use grid::{Heightfield, Interpolation};
pub use implicit::{HeightfieldField, ImplicitParams};
pub use inset::{Inset, Trace};
pub use png16::ZMapping;
pub use pyramid::MinMaxPyramid;

use crate::io::DEFAULT_MEMORY_BUDGET;

/// A DEM as read from a file: the grid in its local frame, its georeference and any notices
/// the reader wants the user to see.
#[derive(Clone, Debug)]
pub struct Dem {
    /// Elevations (metres, NaN = nodata) in the local frame.
    pub heightfield: Heightfield,
    /// Where the local frame sits on Earth.
    pub georef: Georef,
    /// Things the user should know (unit conversions, assumptions). Never errors.
    pub notices: Vec<String>,
}

impl Dem {
    /// A DEM read from `path`: `nx × ny` samples `z` (south row first, west first) on the
    /// georeference's cells, in the local frame with its south-west sample at the origin.
    /// A grid the samples do not fill is [`DemError::Malformed`], naming the file.
    pub fn new(
        path: &std::path::Path,
        nx: usize,
        ny: usize,
        z: Vec<f32>,
        georef: Georef,
        notices: Vec<String>,
    ) -> Result<Dem, DemError> {
        let [dx, dy] = georef.cell_size_m();
        let cell = glam::Vec2::new(dx as f32, dy as f32);
        let heightfield = Heightfield::new(nx, ny, glam::Vec2::ZERO, cell, z).map_err(|e| {
            DemError::Malformed {
                path: path.to_path_buf(),
                what: e.to_string(),
            }
        })?;
        Ok(Dem {
            heightfield,
            georef,
            notices,
        })
    }
}

/// Options shared by every reader.
#[derive(Clone, Debug)]
pub struct ReadOptions {
    /// Refuse grids that would take more bytes than this.
    pub memory_budget: u64,
    /// PNG only: the elevations of raw 0 and of the largest raw value, overriding any
    /// sidecar mapping.
    pub z_range: Option<[f64; 2]>,
    /// PNG only: an explicit sidecar file.
    pub sidecar: Option<std::path::PathBuf>,
    /// Cell size in metres for files that carry no georeference (plain PNG/TIFF).
    pub cell_size: Option<f64>,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            memory_budget: DEFAULT_MEMORY_BUDGET,
            z_range: None,
            sidecar: None,
            cell_size: None,
        }
    }
}

/// The file formats known to [`read`] and [`write`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// `.tif`, `.tiff`.
    GeoTiff,
    /// `.png` (+ `.json` sidecar).
    Png,
    /// `.asc` ESRI ASCII grid.
    Asc,
    /// `.hgt` SRTM tile (read only).
    Hgt,
}

impl Format {
    /// The format named by `path`'s extension.
    pub fn from_path(path: &Path) -> Result<Format, DemError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .unwrap_or_default();
        match ext.as_str() {
            "tif" | "tiff" | "gtiff" => Ok(Format::GeoTiff),
            "png" => Ok(Format::Png),
            "asc" => Ok(Format::Asc),
            "hgt" => Ok(Format::Hgt),
            _ => Err(DemError::UnknownFormat {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// Reads a DEM, choosing the reader from the file extension.
pub fn read(path: &Path, opts: &ReadOptions) -> Result<Dem, DemError> {
    match Format::from_path(path)? {
        Format::GeoTiff => geotiff::read(path, opts),
        Format::Png => png16::read(path, opts),
        Format::Asc => asc::read(path, opts),
        Format::Hgt => hgt::read(path, opts),
    }
}

/// The files [`read`] reads for `path`: the DEM and, when present, its PNG sidecar or
/// `.prj`.
pub fn files_read(path: &Path, opts: &ReadOptions) -> Vec<std::path::PathBuf> {
    let mut files = vec![path.to_path_buf()];
    match Format::from_path(path) {
        Ok(Format::Png) => files.extend(opts.sidecar.clone().or_else(|| png16::find_sidecar(path))),
        Ok(Format::Asc) => files.push(path.with_extension("prj")),
        _ => {}
    }
    files
}

/// The files [`write`] may write for `path`: the DEM and its PNG sidecar or `.prj`.
pub fn files_written(path: &Path) -> Result<Vec<std::path::PathBuf>, DemError> {
    let mut files = vec![path.to_path_buf()];
    match Format::from_path(path)? {
        Format::Png => files.push(path.with_extension("json")),
        Format::Asc => files.push(path.with_extension("prj")),
        Format::GeoTiff | Format::Hgt => {}
    }
    Ok(files)
}

/// Writes a DEM atomically, choosing the writer from the file extension.
pub fn write(dem: &Dem, path: &Path) -> Result<(), DemError> {
    match Format::from_path(path)? {
        Format::GeoTiff => geotiff_write::write(dem, path),
        Format::Png => png16::write(dem, path),
        Format::Asc => asc::write(dem, path),
        Format::Hgt => Err(DemError::Unsupported {
            path: path.to_path_buf(),
            what: "writing SRTM .hgt tiles (write .tif, .png or .asc)".into(),
        }),
    }
}

impl Dem {
    /// A copy resampled to cells of `cell` metres (both axes) over the same extent, with the
    /// georeference updated to match.
    pub fn resample(&self, cell: f64, interp: Interpolation, budget: u64) -> Result<Dem, DemError> {
        let heightfield = self
            .heightfield
            .resample(cell as f32, cell as f32, interp, budget)?;
        let georef = self.georef.with_cell_size(cell, cell);
        let mut notices = self.notices.clone();
        notices.push(format!(
            "resampled from {}×{} to {}×{} cells of {cell} m ({interp:?})",
            self.heightfield.nx(),
            self.heightfield.ny(),
            heightfield.nx(),
            heightfield.ny()
        ));
        Ok(Dem {
            heightfield,
            georef,
            notices,
        })
    }
}

/// Rejects grids that cannot hold a bilinear cell or would exceed `budget` bytes of f32
/// samples, before anything is allocated.
pub(crate) fn check_grid_size(
    path: &Path,
    nx: u64,
    ny: u64,
    bytes_per_sample: u64,
    budget: u64,
) -> Result<(), DemError> {
    if nx < 2 || ny < 2 {
        return Err(DemError::Malformed {
            path: path.to_path_buf(),
            what: format!("a grid of at least 2×2 samples, found {nx}×{ny}"),
        });
    }
    // the decoded samples plus the f32 grid and its pyramid (about 1/3 more)
    let need = nx
        .saturating_mul(ny)
        .saturating_mul(bytes_per_sample.saturating_add(4 + 8));
    crate::io::check_budget(
        format!("the {nx}×{ny} grid of {}", path.display()),
        need,
        budget,
    )
    .map_err(DemError::Io)
}

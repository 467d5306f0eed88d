//! GeoTIFF reader (through the `tiff` crate).
//!
//! Handles single-band rasters of 8/16/32/64-bit signed or unsigned integers and 16/32/64-bit
//! floats; None, LZW, Deflate and PackBits compression; horizontal and floating-point
//! predictors; strips and tiles. Georeferencing comes from ModelPixelScale (33550) +
//! ModelTiepoint (33922) or ModelTransformation (34264); the CRS kind and units from the
//! GeoKeyDirectory (34735); nodata from GDAL_NODATA (42113). NaN samples in float rasters
//! are nodata too (GDAL's convention).

use std::io::Cursor;
use std::path::Path;

use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::Tag;

use super::georef::{Crs, Georef, RasterType};
use super::{Dem, DemError, ReadOptions, check_grid_size};

/// GeoKey ids used here (GeoTIFF 1.0 §6).
pub(crate) mod key {
    /// GTModelTypeGeoKey: 1 projected, 2 geographic, 3 geocentric.
    pub const MODEL_TYPE: u16 = 1024;
    /// GTRasterTypeGeoKey: 1 PixelIsArea, 2 PixelIsPoint.
    pub const RASTER_TYPE: u16 = 1025;
    /// GeographicTypeGeoKey (EPSG code).
    pub const GEOGRAPHIC_TYPE: u16 = 2048;
    /// GeogAngularUnitsGeoKey.
    pub const ANGULAR_UNITS: u16 = 2054;
    /// ProjectedCSTypeGeoKey (EPSG code).
    pub const PROJECTED_TYPE: u16 = 3072;
    /// ProjLinearUnitsGeoKey.
    pub const LINEAR_UNITS: u16 = 3076;
}

/// The largest plausible |elevation| in any unit; beyond it the file lies (or hides an
/// undeclared nodata value).
pub(crate) const MAX_ABS_ELEVATION: f64 = 1e7;

/// Reads a GeoTIFF DEM. The size its header declares is checked against the budget
/// before the file is read.
pub fn read(path: &Path, opts: &ReadOptions) -> Result<Dem, DemError> {
    let (file, _) = crate::io::open_regular(path, opts.memory_budget)?;
    let (w, h) = Decoder::new(std::io::BufReader::new(file))
        .and_then(|mut d| d.dimensions())
        .map_err(|source| DemError::Tiff {
            path: path.to_path_buf(),
            source,
        })?;
    check_grid_size(path, w.into(), h.into(), 1, opts.memory_budget)?;
    let bytes = read_file(path, opts.memory_budget)?;
    read_bytes(path, &bytes, opts)
}

/// Reads a whole regular file, refusing anything else (a FIFO, a link to `/dev/zero`)
/// and a file larger than `budget`, before reading it.
pub(crate) fn read_file(path: &Path, budget: u64) -> Result<Vec<u8>, DemError> {
    Ok(crate::io::read_regular(path, budget)?)
}

/// Reads a text file beside a DEM (a PNG sidecar, a `.prj`) as [`read_file`] does,
/// without a UTF-8 byte-order mark.
pub(crate) fn read_text(path: &Path, budget: u64) -> Result<String, DemError> {
    let text = String::from_utf8(read_file(path, budget)?).map_err(|_| DemError::Malformed {
        path: path.to_path_buf(),
        what: "UTF-8 text".into(),
    })?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

/// The most bytes of samples one byte of a compressed TIFF can stand for (LZW's longest
/// code, 4096 bytes, in 12 bits; Deflate's 1032; PackBits' 64).
const MAX_PACKING: u64 = 4096;

/// Reads a GeoTIFF DEM held in memory; `path` names it in errors.
pub fn read_bytes(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<Dem, DemError> {
    let tiff_err = |source| DemError::Tiff {
        path: path.to_path_buf(),
        source,
    };
    let malformed = |what: String| DemError::Malformed {
        path: path.to_path_buf(),
        what,
    };
    let mut limits = Limits::default();
    limits.decoding_buffer_size = usize::try_from(opts.memory_budget).unwrap_or(usize::MAX);
    let mut dec = Decoder::new(Cursor::new(bytes))
        .map_err(tiff_err)?
        .with_limits(limits);

    let (w, h) = dec.dimensions().map_err(tiff_err)?;
    let bits = match dec.colortype().map_err(tiff_err)? {
        tiff::ColorType::Gray(b) => b,
        other => {
            return Err(DemError::Unsupported {
                path: path.to_path_buf(),
                what: format!("a single-band greyscale raster is expected, found {other:?}"),
            });
        }
    };
    let compression = dec
        .find_tag_unsigned::<u16>(Tag::Compression)
        .map_err(tiff_err)?
        .unwrap_or(1);
    if !matches!(compression, 1 | 5 | 8 | 32773 | 32946) {
        return Err(DemError::Unsupported {
            path: path.to_path_buf(),
            what: format!(
                "compression method {compression} (expected None, LZW, Deflate or PackBits)"
            ),
        });
    }
    let per_sample = (u64::from(bits) / 8).max(1);
    // A header that claims more samples than its file can hold: LZW, the densest of the
    // methods read, packs at most about 4096 bytes into one.
    let ratio = if compression == 1 { 1 } else { MAX_PACKING };
    let claimed = u64::from(w) * u64::from(h) * per_sample;
    if claimed > (bytes.len() as u64).saturating_mul(ratio) {
        return Err(malformed(format!(
            "the header claims {w}×{h} samples ({claimed} bytes), more than a file of {} \
             bytes can hold",
            bytes.len()
        )));
    }
    check_grid_size(path, w.into(), h.into(), per_sample, opts.memory_budget)?;

    let f64_tag = |dec: &mut Decoder<Cursor<&[u8]>>, tag| -> Result<Option<Vec<f64>>, DemError> {
        dec.find_tag(tag)
            .map_err(tiff_err)?
            .map(|v| v.into_f64_vec().map_err(tiff_err))
            .transpose()
    };
    let scale = f64_tag(&mut dec, Tag::ModelPixelScaleTag)?;
    let tie = f64_tag(&mut dec, Tag::ModelTiepointTag)?;
    let matrix = f64_tag(&mut dec, Tag::ModelTransformationTag)?;
    let keys = match dec.find_tag(Tag::GeoKeyDirectoryTag).map_err(tiff_err)? {
        Some(v) => Some(GeoKeys::parse(&v.into_u16_vec().map_err(tiff_err)?).map_err(malformed)?),
        None => None,
    };
    let nodata = match dec.find_tag(Tag::GdalNodata).map_err(tiff_err)? {
        Some(v) => {
            let s = v.into_string().map_err(tiff_err)?;
            Some(
                parse_nodata(&s)
                    .ok_or_else(|| malformed(format!("a number in GDAL_NODATA, found {s:?}")))?,
            )
        }
        None => None,
    };

    let mut notices = Vec::new();
    let transform = match (&matrix, &scale, &tie) {
        (Some(m), _, _) => Some(Transform::from_matrix(m).map_err(|e| match e {
            TransformError::Malformed(w) => malformed(w),
            TransformError::Rotated(w) => DemError::Unsupported {
                path: path.to_path_buf(),
                what: w,
            },
        })?),
        (None, Some(s), Some(t)) => Some(Transform::from_scale_tiepoint(s, t).map_err(malformed)?),
        (None, Some(_), None) | (None, None, Some(_)) => {
            return Err(malformed(
                "both ModelPixelScale and ModelTiepoint (only one of them is present)".into(),
            ));
        }
        (None, None, None) => None,
    };

    let raster_type = match keys.as_ref().and_then(|k| k.get(key::RASTER_TYPE)) {
        Some(2) => RasterType::PixelIsPoint,
        _ => RasterType::PixelIsArea,
    };
    let (nx, ny) = (w as usize, h as usize);
    let georef = match transform {
        None => {
            let c = opts.cell_size.unwrap_or(1.0);
            notices.push(format!(
                "{}: no georeference; cells taken as {c} m (set the cell size to change it)",
                path.display()
            ));
            Georef::local(c, c)
        }
        Some(t) => {
            let (origin, step) = t.south_west_sample(nx, ny, raster_type);
            let model = keys.as_ref().and_then(|k| k.get(key::MODEL_TYPE));
            match model {
                Some(2) => {
                    if let Some(u) = keys.as_ref().and_then(|k| k.get(key::ANGULAR_UNITS))
                        && u != 9102
                    {
                        return Err(DemError::Unsupported {
                            path: path.to_path_buf(),
                            what: format!(
                                "angular unit code {u} (only degrees, 9102, are handled)"
                            ),
                        });
                    }
                    let centre_lat = origin[1] + 0.5 * (ny as f64 - 1.0) * step[1];
                    let far_lat = origin[1] + (ny as f64 - 1.0) * step[1];
                    if !(origin[1].abs() <= 90.0
                        && far_lat.abs() <= 90.0
                        && origin[0].abs() <= 540.0)
                    {
                        return Err(malformed(format!(
                            "geographic coordinates within ±90° latitude, found {:.6}..{:.6}",
                            origin[1], far_lat
                        )));
                    }
                    let epsg = keys
                        .as_ref()
                        .and_then(|k| k.get(key::GEOGRAPHIC_TYPE))
                        .map(u32::from);
                    let g = Georef::geographic(
                        epsg.filter(|&e| e != 32767),
                        origin,
                        step,
                        centre_lat,
                        raster_type,
                    );
                    notices.extend(g.degrees_notice(ny));
                    g
                }
                Some(1) => {
                    let unit = match keys.as_ref().and_then(|k| k.get(key::LINEAR_UNITS)) {
                        None | Some(9001) => 1.0,
                        Some(9002) => 0.3048,
                        Some(9003) => 1200.0 / 3937.0,
                        Some(u) => {
                            return Err(DemError::Unsupported {
                                path: path.to_path_buf(),
                                what: format!(
                                    "linear unit code {u} (metres 9001, feet 9002/9003 are handled)"
                                ),
                            });
                        }
                    };
                    if unit != 1.0 {
                        notices.push(format!(
                            "{}: projected coordinates in feet converted to metres",
                            path.display()
                        ));
                    }
                    let epsg = keys
                        .as_ref()
                        .and_then(|k| k.get(key::PROJECTED_TYPE))
                        .map(u32::from);
                    Georef {
                        crs: Crs::Projected {
                            epsg: epsg.filter(|&e| e != 32767),
                        },
                        origin,
                        step,
                        unit_m: [unit, unit],
                        raster_type,
                    }
                }
                Some(m @ (0 | 3..)) => {
                    return Err(DemError::Unsupported {
                        path: path.to_path_buf(),
                        what: format!("model type {m} (expected 1 projected or 2 geographic)"),
                    });
                }
                None => {
                    notices.push(format!(
                        "{}: no GeoKeys: coordinates taken as metres in a local frame",
                        path.display()
                    ));
                    Georef {
                        crs: Crs::Local,
                        origin,
                        step,
                        unit_m: [1.0, 1.0],
                        raster_type,
                    }
                }
            }
        }
    };
    let (flip_x, flip_y) = transform.map_or((false, true), |t| (t.flip_x(), t.flip_y()));

    let mut data = DecodingResult::U8(Vec::new());
    dec.read_image_to_buffer(&mut data).map_err(tiff_err)?;
    let samples = to_f32(path, data, nx, ny, nodata)?;
    let z = reorder(&samples, nx, ny, flip_x, flip_y);
    Dem::new(path, nx, ny, z, georef, notices)
}

/// Reorders file samples (row 0 first) into the grid's south-first, west-first order:
/// `flip_y` for the usual north-up file, `flip_x` for a file whose columns run west-ward.
pub(crate) fn reorder(
    samples: &[f32],
    nx: usize,
    ny: usize,
    flip_x: bool,
    flip_y: bool,
) -> Vec<f32> {
    let mut z = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        let r = if flip_y { ny - 1 - j } else { j };
        let row = &samples[r * nx..(r + 1) * nx];
        if flip_x {
            z.extend(row.iter().rev());
        } else {
            z.extend_from_slice(row);
        }
    }
    z
}

/// The affine map from pixel (column, row) corners to CRS coordinates: `X = x0 + c·sx`,
/// `Y = y0 + r·sy` (no rotation).
#[derive(Clone, Copy, Debug)]
struct Transform {
    x0: f64,
    y0: f64,
    sx: f64,
    sy: f64,
}

enum TransformError {
    Malformed(String),
    Rotated(String),
}

impl Transform {
    fn from_scale_tiepoint(s: &[f64], t: &[f64]) -> Result<Transform, String> {
        if s.len() < 2 || t.len() < 6 {
            return Err(format!(
                "ModelPixelScale with 3 values and ModelTiepoint with 6, found {} and {}",
                s.len(),
                t.len()
            ));
        }
        let (sx, sy) = (s[0], s[1]);
        Transform {
            x0: t[3] - t[0] * sx,
            y0: t[4] + t[1] * sy,
            sx,
            sy: -sy,
        }
        .checked()
    }

    fn from_matrix(m: &[f64]) -> Result<Transform, TransformError> {
        if m.len() < 16 {
            return Err(TransformError::Malformed(format!(
                "16 values in ModelTransformation, found {}",
                m.len()
            )));
        }
        if m[1] != 0.0 || m[4] != 0.0 {
            return Err(TransformError::Rotated(format!(
                "rotated or sheared rasters (ModelTransformation terms {} and {}); warp it north-up first",
                m[1], m[4]
            )));
        }
        Transform {
            x0: m[3],
            y0: m[7],
            sx: m[0],
            sy: m[5],
        }
        .checked()
        .map_err(TransformError::Malformed)
    }

    fn checked(self) -> Result<Transform, String> {
        let ok = |v: f64| v.is_finite() && v != 0.0;
        if ok(self.sx) && ok(self.sy) && self.x0.is_finite() && self.y0.is_finite() {
            Ok(self)
        } else {
            Err(format!(
                "a finite, non-zero pixel scale and a finite tiepoint, found scale ({}, {}) at ({}, {})",
                self.sx, -self.sy, self.x0, self.y0
            ))
        }
    }

    fn flip_x(&self) -> bool {
        self.sx < 0.0
    }

    fn flip_y(&self) -> bool {
        self.sy < 0.0
    }

    /// CRS position of the south-west sample and the (positive) steps.
    fn south_west_sample(&self, nx: usize, ny: usize, rt: RasterType) -> ([f64; 2], [f64; 2]) {
        let half = match rt {
            RasterType::PixelIsArea => 0.5,
            RasterType::PixelIsPoint => 0.0,
        };
        let col = if self.flip_x() { nx as f64 - 1.0 } else { 0.0 };
        let row = if self.flip_y() { ny as f64 - 1.0 } else { 0.0 };
        (
            [
                self.x0 + (col + half) * self.sx,
                self.y0 + (row + half) * self.sy,
            ],
            [self.sx.abs(), self.sy.abs()],
        )
    }
}

/// The GeoKeyDirectory's short-valued keys.
#[derive(Debug, Default)]
pub(crate) struct GeoKeys {
    keys: Vec<(u16, u16)>,
}

impl GeoKeys {
    /// Parses the directory `[version, revision, minor, count, (id, location, count, value)*]`.
    pub(crate) fn parse(d: &[u16]) -> Result<GeoKeys, String> {
        if d.len() < 4 {
            return Err(format!(
                "a GeoKeyDirectory of at least 4 shorts, found {}",
                d.len()
            ));
        }
        let n = d[3] as usize;
        if d.len() < 4 + 4 * n {
            return Err(format!(
                "{} GeoKey entries ({} shorts) in the GeoKeyDirectory, found {} shorts",
                n,
                4 + 4 * n,
                d.len()
            ));
        }
        let keys = d[4..4 + 4 * n]
            .chunks_exact(4)
            .filter(|e| e[1] == 0)
            .map(|e| (e[0], e[3]))
            .collect();
        Ok(GeoKeys { keys })
    }

    pub(crate) fn get(&self, id: u16) -> Option<u16> {
        self.keys.iter().find(|k| k.0 == id).map(|k| k.1)
    }
}

/// Parses a GDAL_NODATA string (`"-32768"`, `"nan"`, with optional NUL/whitespace).
pub(crate) fn parse_nodata(s: &str) -> Option<f64> {
    let t = s.trim_matches(|c: char| c == '\0' || c.is_whitespace());
    if t.eq_ignore_ascii_case("nan") {
        return Some(f64::NAN);
    }
    t.parse::<f64>().ok().filter(|v| !v.is_infinite())
}

/// Converts decoded samples to f32 with nodata as NaN, checking count and values.
fn to_f32(
    path: &Path,
    data: DecodingResult,
    nx: usize,
    ny: usize,
    nodata: Option<f64>,
) -> Result<Vec<f32>, DemError> {
    let n = nx * ny;
    fn conv<T: Copy>(v: &[T], n: usize, f: impl Fn(T) -> f64) -> Vec<f64> {
        v.iter().take(n).map(|&x| f(x)).collect()
    }
    let vals: Vec<f64> = match &data {
        DecodingResult::U8(v) => conv(v, n, f64::from),
        DecodingResult::U16(v) => conv(v, n, f64::from),
        DecodingResult::U32(v) => conv(v, n, f64::from),
        DecodingResult::U64(v) => conv(v, n, |x| x as f64),
        DecodingResult::I8(v) => conv(v, n, f64::from),
        DecodingResult::I16(v) => conv(v, n, f64::from),
        DecodingResult::I32(v) => conv(v, n, f64::from),
        DecodingResult::I64(v) => conv(v, n, |x| x as f64),
        DecodingResult::F16(v) => conv(v, n, |x| f64::from(x.to_f32())),
        DecodingResult::F32(v) => conv(v, n, f64::from),
        DecodingResult::F64(v) => conv(v, n, |x| x),
    };
    drop(data);
    if vals.len() != n {
        return Err(DemError::Malformed {
            path: path.to_path_buf(),
            what: format!("{n} samples, decoded {}", vals.len()),
        });
    }
    finish_samples(path, &vals, nx, nodata)
}

/// Maps nodata to NaN and rejects infinite or absurd elevations and all-nodata grids.
/// `nx` is the row length, used to name the offending row and column.
pub(crate) fn finish_samples(
    path: &Path,
    vals: &[f64],
    nx: usize,
    nodata: Option<f64>,
) -> Result<Vec<f32>, DemError> {
    let is_nodata = |v: f64| {
        v.is_nan() || nodata.is_some_and(|nd| v == nd || (nd as f32 as f64 == v && nd.is_finite()))
    };
    let mut out = Vec::with_capacity(vals.len());
    let mut valid = 0usize;
    for (k, &v) in vals.iter().enumerate() {
        if is_nodata(v) {
            out.push(f32::NAN);
            continue;
        }
        if v.is_infinite() || v.abs() > MAX_ABS_ELEVATION {
            return Err(DemError::BadData {
                path: path.to_path_buf(),
                what: format!(
                    "elevation {v} at row {}, column {} is not plausible (|z| ≤ {MAX_ABS_ELEVATION:e}); is a nodata value undeclared?",
                    k / nx.max(1),
                    k % nx.max(1)
                ),
            });
        }
        valid += 1;
        out.push(v as f32);
    }
    if valid == 0 {
        return Err(DemError::BadData {
            path: path.to_path_buf(),
            what: format!(
                "contains no valid elevation (all {} samples are nodata)",
                vals.len()
            ),
        });
    }
    Ok(out)
}

//! Greyscale PNG heightmaps (8 or 16 bit) with a JSON sidecar.
//!
//! A PNG holds raw integers; the sidecar says which elevations two raw values stand for
//! (`"png_u16_maps": {"0": 236.0, "65535": 1076.0}`, the mapping is linear), and optionally
//! the georeference (`crs`, `cell_size_deg` | `cell_size`, `north_west_corner`), the
//! expected `rows`/`cols` and a raw `nodata_raw` value. The sidecar of `X.png` is found as
//! an explicit path, `X.json`, `X.png.json`, or `P.json` where `X` is `P_something`
//! (`jacksboro_u16.png` → `jacksboro.json`). See `docs/dem.md` for the full format.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use image::{ExtendedColorType, ImageDecoder, ImageEncoder, ImageFormat, ImageReader};
use serde_json::{Value, json};

use super::georef::{Crs, Georef, RasterType};
use super::geotiff::{finish_samples, read_file, read_text, reorder};
use super::{Dem, DemError, ReadOptions, check_grid_size};

/// How raw PNG values map to elevations: `raw[0] ↦ z[0]`, `raw[1] ↦ z[1]`, linear between.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZMapping {
    /// Two distinct raw values.
    pub raw: [f64; 2],
    /// Their elevations in metres.
    pub z: [f64; 2],
    /// A raw value meaning "no data", if any.
    pub nodata: Option<u32>,
}

impl ZMapping {
    /// Raw 0 ↦ `lo`, the largest raw value of `bits`-bit samples ↦ `hi`.
    pub fn range(lo: f64, hi: f64, bits: u32) -> ZMapping {
        ZMapping {
            raw: [0.0, ((1u64 << bits) - 1) as f64],
            z: [lo, hi],
            nodata: None,
        }
    }

    fn apply(&self, raw: f64) -> f64 {
        self.z[0] + (raw - self.raw[0]) * (self.z[1] - self.z[0]) / (self.raw[1] - self.raw[0])
    }

    fn check(&self) -> Result<(), String> {
        let ok =
            self.raw.iter().chain(&self.z).all(|v| v.is_finite()) && self.raw[0] != self.raw[1];
        if ok {
            Ok(())
        } else {
            Err(format!(
                "two distinct raw values mapped to finite elevations, found {:?} ↦ {:?}",
                self.raw, self.z
            ))
        }
    }
}

/// Reads a PNG heightmap; the mapping comes from `opts.z_mapping` or the sidecar. The
/// size its header declares is checked against the budget before the file is read.
pub fn read(path: &Path, opts: &ReadOptions) -> Result<Dem, DemError> {
    // The size the header declares, against the budget, before the file is read.
    let (file, _) = crate::io::open_regular(path, opts.memory_budget)?;
    let (w, h) = ImageReader::with_format(std::io::BufReader::new(file), ImageFormat::Png)
        .into_dimensions()
        .map_err(|source| DemError::Png {
            path: path.to_path_buf(),
            source,
        })?;
    check_grid_size(path, w.into(), h.into(), 1, opts.memory_budget)?;
    let bytes = read_file(path, opts.memory_budget)?;
    let sidecar = match &opts.sidecar {
        Some(p) => Some(p.clone()),
        None => find_sidecar(path),
    };
    let side = match &sidecar {
        Some(p) => {
            let text = read_text(p, opts.memory_budget)?;
            Some((p.clone(), text))
        }
        None => None,
    };
    read_bytes(
        path,
        &bytes,
        side.as_ref().map(|(p, t)| (p.as_path(), t.as_str())),
        opts,
    )
}

/// The sidecar of `png` by the naming rules above, if one exists.
pub fn find_sidecar(png: &Path) -> Option<PathBuf> {
    let stem = png.file_stem()?.to_str()?;
    let dir = png.parent().unwrap_or(Path::new(""));
    let mut candidates = vec![
        png.with_extension("json"),
        dir.join(format!("{stem}.png.json")),
    ];
    let mut prefix = stem;
    while let Some(at) = prefix.rfind('_') {
        prefix = &prefix[..at];
        candidates.push(dir.join(format!("{prefix}.json")));
    }
    candidates.into_iter().find(|c| c.is_file())
}

/// Reads a PNG heightmap held in memory; `sidecar` is `(its path, its text)`.
pub fn read_bytes(
    path: &Path,
    bytes: &[u8],
    sidecar: Option<(&Path, &str)>,
    opts: &ReadOptions,
) -> Result<Dem, DemError> {
    let png_err = |source| DemError::Png {
        path: path.to_path_buf(),
        source,
    };
    let mut reader = ImageReader::with_format(Cursor::new(bytes), ImageFormat::Png);
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(opts.memory_budget);
    reader.limits(limits);
    let dec = reader.into_decoder().map_err(png_err)?;
    let (w, h) = dec.dimensions();
    let bits = match dec.color_type() {
        image::ColorType::L8 => 8,
        image::ColorType::L16 => 16,
        other => {
            return Err(DemError::Unsupported {
                path: path.to_path_buf(),
                what: format!("a greyscale 8- or 16-bit PNG is expected, found {other:?}"),
            });
        }
    };
    check_grid_size(path, w.into(), h.into(), 8, opts.memory_budget)?;
    let (nx, ny) = (w as usize, h as usize);

    let side = match sidecar {
        Some((p, text)) => {
            Some(
                Sidecar::parse(text, bits).map_err(|what| DemError::Malformed {
                    path: p.to_path_buf(),
                    what,
                })?,
            )
        }
        None => None,
    };
    if let Some(s) = &side
        && let Some((rows, cols)) = s.dims
        && (rows, cols) != (ny, nx)
    {
        return Err(DemError::Malformed {
            path: path.to_path_buf(),
            what: format!("{rows} rows × {cols} columns as its sidecar says, found {ny} × {nx}"),
        });
    }
    let explicit = opts.z_range.map(|[lo, hi]| ZMapping::range(lo, hi, bits));
    let mapping = explicit.or(side.as_ref().and_then(|s| s.mapping)).ok_or_else(|| DemError::Malformed {
        path: path.to_path_buf(),
        what: format!(
            "an elevation mapping: a JSON sidecar ({}) with \"png_u{bits}_maps\", or an explicit range (--z-range LO HI)",
            path.with_extension("json").display()
        ),
    })?;
    mapping.check().map_err(|what| DemError::Malformed {
        path: sidecar.map_or(path, |s| s.0).to_path_buf(),
        what,
    })?;

    let mut buf = crate::io::try_filled(dec.total_bytes() as usize, 0u8, "the PNG's pixels")?;
    dec.read_image(&mut buf).map_err(png_err)?;
    let vals: Vec<f64> = if bits == 8 {
        buf.iter().map(|&b| f64::from(b)).collect()
    } else {
        buf.chunks_exact(2)
            .map(|b| f64::from(u16::from_ne_bytes([b[0], b[1]])))
            .collect()
    };
    drop(buf);
    let nodata = mapping.nodata.map(f64::from);
    let vals: Vec<f64> = vals
        .into_iter()
        .map(|r| {
            if Some(r) == nodata {
                f64::NAN
            } else {
                mapping.apply(r)
            }
        })
        .collect();
    let samples = finish_samples(path, &vals, nx, None)?;
    let z = reorder(&samples, nx, ny, false, true);

    let mut notices = Vec::new();
    let georef = match side.as_ref().and_then(|s| s.georef(nx, ny)) {
        Some(g) => {
            notices.extend(g.degrees_notice(ny));
            g
        }
        None => {
            let c = opts.cell_size.unwrap_or(1.0);
            notices.push(format!(
                "{}: no georeference in a sidecar; cells taken as {c} m",
                path.display()
            ));
            Georef::local(c, c)
        }
    };
    Dem::new(path, nx, ny, z, georef, notices)
}

/// What a sidecar says.
struct Sidecar {
    mapping: Option<ZMapping>,
    dims: Option<(usize, usize)>,
    crs: Crs,
    step: Option<[f64; 2]>,
    unit_m: f64,
    nw_corner: Option<[f64; 2]>,
    raster_type: RasterType,
}

/// What kind of JSON value `v` is, for messages that must not echo a file's content.
fn json_kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number out of range",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

impl Sidecar {
    fn parse(text: &str, bits: u32) -> Result<Sidecar, String> {
        let v: Value = serde_json::from_str(text).map_err(|e| format!("JSON ({e})"))?;
        let num = |k: &str| -> Result<Option<f64>, String> {
            match v.get(k) {
                None | Some(Value::Null) => Ok(None),
                Some(x) => x
                    .as_f64()
                    .filter(|x| x.is_finite())
                    .map(Some)
                    .ok_or_else(|| format!("a number for \"{k}\", found {}", json_kind(x))),
            }
        };
        let pair = |k: &str| -> Result<Option<[f64; 2]>, String> {
            match v.get(k) {
                None | Some(Value::Null) => Ok(None),
                Some(Value::Array(a)) if a.len() == 2 => {
                    let f = |x: &Value| x.as_f64().filter(|x| x.is_finite());
                    match (f(&a[0]), f(&a[1])) {
                        (Some(x), Some(y)) => Ok(Some([x, y])),
                        _ => Err(format!("two finite numbers in \"{k}\"")),
                    }
                }
                Some(x) => x
                    .as_f64()
                    .filter(|x| x.is_finite())
                    .map(|x| Some([x, x]))
                    .ok_or_else(|| {
                        format!("a number or [x, y] for \"{k}\", found {}", json_kind(x))
                    }),
            }
        };
        let maps_key = format!("png_u{bits}_maps");
        let mapping = match v.get(&maps_key).or_else(|| v.get("z_maps")) {
            None => None,
            Some(Value::Object(m)) if m.len() == 2 => {
                let mut it = m.iter().map(|(k, z)| {
                    let raw = k.trim().parse::<f64>().ok();
                    (raw, z.as_f64())
                });
                let (a, b) = (it.next().unwrap_or_default(), it.next().unwrap_or_default());
                match (a, b) {
                    ((Some(r0), Some(z0)), (Some(r1), Some(z1))) => Some(ZMapping {
                        raw: [r0, r1],
                        z: [z0, z1],
                        nodata: None,
                    }),
                    _ => {
                        return Err(format!(
                            "\"{maps_key}\" as {{\"raw\": elevation, \"raw\": elevation}}"
                        ));
                    }
                }
            }
            Some(_) => return Err(format!("\"{maps_key}\" with exactly two raw values")),
        };
        let nodata = match num("nodata_raw")? {
            Some(n) if n >= 0.0 && n.fract() == 0.0 && n < (1u64 << bits) as f64 => Some(n as u32),
            Some(n) => {
                return Err(format!(
                    "\"nodata_raw\" as a whole {bits}-bit value, found {n}"
                ));
            }
            None => None,
        };
        let mapping = mapping.map(|m| ZMapping { nodata, ..m });
        let dims = match (num("rows")?, num("cols")?) {
            (Some(r), Some(c)) => Some((r as usize, c as usize)),
            _ => None,
        };
        let epsg = v
            .get("crs")
            .and_then(|c| c.as_str())
            .and_then(|c| c.strip_prefix("EPSG:"))
            .and_then(|c| c.parse::<u32>().ok());
        let deg = pair("cell_size_deg")?;
        let kind = v.get("crs_kind").and_then(|k| k.as_str());
        let crs = match (kind, epsg, deg) {
            (Some("geographic"), ..) | (None, _, Some(_)) => Crs::Geographic { epsg },
            (None, Some(e), None) if (4000..5000).contains(&e) => Crs::Geographic { epsg },
            (Some("projected"), ..) | (None, Some(_), None) => Crs::Projected { epsg },
            _ => Crs::Local,
        };
        Ok(Sidecar {
            mapping,
            dims,
            crs,
            step: deg.or(pair("cell_size")?),
            unit_m: num("unit_m")?.filter(|u| *u > 0.0).unwrap_or(1.0),
            nw_corner: pair("north_west_corner")?,
            raster_type: match v.get("raster_type").and_then(|r| r.as_str()) {
                Some("point") => RasterType::PixelIsPoint,
                _ => RasterType::PixelIsArea,
            },
        })
    }

    fn georef(&self, _nx: usize, ny: usize) -> Option<Georef> {
        let step = self.step.filter(|s| s[0] > 0.0 && s[1] > 0.0)?;
        let nw = self.nw_corner.unwrap_or([0.0, (ny as f64) * step[1]]);
        let origin = [nw[0] + 0.5 * step[0], nw[1] - (ny as f64 - 0.5) * step[1]];
        Some(match self.crs {
            Crs::Geographic { epsg } => {
                let lat = origin[1] + 0.5 * (ny as f64 - 1.0) * step[1];
                Georef::geographic(epsg, origin, step, lat, self.raster_type)
            }
            ref crs => Georef {
                crs: crs.clone(),
                origin,
                step,
                unit_m: [self.unit_m; 2],
                raster_type: self.raster_type,
            },
        })
    }
}

/// Writes `dem` as a 16-bit PNG plus its `.json` sidecar, atomically. With voids, raw 0 is
/// nodata and raw 1..=65535 spans the elevation range; otherwise 0..=65535 does.
pub fn write(dem: &Dem, path: &Path) -> Result<(), DemError> {
    let hf = &dem.heightfield;
    let g = &dem.georef;
    let (nx, ny) = (hf.nx(), hf.ny());
    let (lo, hi) = hf.z_range().ok_or_else(|| DemError::BadData {
        path: path.to_path_buf(),
        what: "no valid elevation to write".into(),
    })?;
    let (lo, hi) = (
        f64::from(lo),
        if hi > lo {
            f64::from(hi)
        } else {
            f64::from(lo) + 1.0
        },
    );
    let voids = hf.nodata_count() > 0;
    let r0 = if voids { 1.0 } else { 0.0 };
    let mut raw = Vec::with_capacity(nx * ny * 2);
    for j in (0..ny).rev() {
        for &v in &hf.samples()[j * nx..(j + 1) * nx] {
            let q = if v.is_nan() {
                0u16
            } else {
                (r0 + (f64::from(v) - lo) / (hi - lo) * (65535.0 - r0))
                    .round()
                    .clamp(r0, 65535.0) as u16
            };
            raw.extend(q.to_ne_bytes());
        }
    }
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(&raw, nx as u32, ny as u32, ExtendedColorType::L16)
        .map_err(|source| DemError::Png {
            path: path.to_path_buf(),
            source,
        })?;
    let mut maps = serde_json::Map::new();
    maps.insert(format!("{r0}"), json!(lo));
    maps.insert("65535".into(), json!(hi));
    let (kind, step_key) = match g.crs {
        Crs::Geographic { .. } => ("geographic", "cell_size_deg"),
        Crs::Projected { .. } => ("projected", "cell_size"),
        Crs::Local => ("local", "cell_size"),
    };
    let mut side = json!({
        "source": "karstic dem convert",
        "rows": ny,
        "cols": nx,
        "png_u16_maps": maps,
        "units": "meters",
        "crs": g.crs.epsg().map_or("local".to_string(), |e| format!("EPSG:{e}")),
        "crs_kind": kind,
        step_key: [g.step[0], g.step[1]],
        "unit_m": g.unit_m[0],
        "north_west_corner": g.north_west_corner(ny),
        "raster_type": match g.raster_type { RasterType::PixelIsArea => "area", RasterType::PixelIsPoint => "point" },
    });
    if voids {
        side["nodata_raw"] = json!(0);
    }
    let text = serde_json::to_string_pretty(&side).expect("a JSON value always serializes");
    crate::io::write_bytes_atomic(path, &png)?;
    let side_path = path.with_extension("json");
    Ok(crate::io::write_bytes_atomic(&side_path, text.as_bytes())?)
}

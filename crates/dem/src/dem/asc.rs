//! ESRI ASCII grids (`.asc`): header (`ncols`, `nrows`, `xllcorner`|`xllcenter`,
//! `yllcorner`|`yllcenter`, `cellsize` or GDAL's `dx`/`dy`, optional `NODATA_value`) then
//! rows of numbers from the north. The CRS comes from a `.prj` beside the file (WKT 1, as
//! written by ESRI and GDAL); without one the coordinates are taken as local metres.

use std::fmt::Write as _;
use std::path::Path;

use super::georef::{Crs, Georef, RasterType};
use super::geotiff::{finish_samples, read_file, read_text, reorder};
use super::{Dem, DemError, ReadOptions, check_grid_size};

/// Reads an ESRI ASCII grid, and its `.prj` when there is one.
pub fn read(path: &Path, opts: &ReadOptions) -> Result<Dem, DemError> {
    let bytes = read_file(path, opts.memory_budget)?;
    let prj_path = path.with_extension("prj");
    let prj = match std::fs::symlink_metadata(&prj_path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
        _ => Some(read_text(&prj_path, opts.memory_budget)?),
    };
    read_bytes(path, &bytes, prj.as_deref(), opts)
}

/// Header of an ASCII grid.
struct Header {
    ncols: usize,
    nrows: usize,
    x: f64,
    y: f64,
    centre: bool,
    dx: f64,
    dy: f64,
    nodata: Option<f64>,
}

/// The keywords of an ESRI ASCII grid's header (any case).
const HEADER_KEYS: [&str; 10] = [
    "ncols",
    "nrows",
    "xllcorner",
    "xllcenter",
    "yllcorner",
    "yllcenter",
    "cellsize",
    "dx",
    "dy",
    "nodata_value",
];

/// Reads an ASCII grid held in memory (`prj`: the text of its `.prj`, if any).
pub fn read_bytes(
    path: &Path,
    bytes: &[u8],
    prj: Option<&str>,
    opts: &ReadOptions,
) -> Result<Dem, DemError> {
    let text = std::str::from_utf8(bytes).map_err(|e| DemError::Malformed {
        path: path.to_path_buf(),
        what: format!(
            "ASCII text, found a non-UTF-8 byte at offset {}",
            e.valid_up_to()
        ),
    })?;
    // A byte-order mark some editors write before the header.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let syntax = |line: usize, column: usize, what: String| DemError::Syntax {
        path: path.to_path_buf(),
        line,
        column,
        what,
    };
    let col_of = |line: &str, tok: &str| tok.as_ptr() as usize - line.as_ptr() as usize + 1;

    let mut lines = text.lines().enumerate().peekable();
    let mut fields: Vec<(&str, f64, usize)> = Vec::new();
    while let Some(&(ln, line)) = lines.peek() {
        let mut toks = line.split_ascii_whitespace();
        let Some(k) = toks.next() else {
            lines.next();
            continue;
        };
        if !k.starts_with(|c: char| c.is_ascii_alphabetic()) || k.eq_ignore_ascii_case("nan") {
            break;
        }
        // The file may not be a grid at all (a path to a private file): its words are
        // named only when they are the header's own keywords, never echoed.
        let k = HEADER_KEYS
            .iter()
            .find(|h| h.eq_ignore_ascii_case(k))
            .ok_or_else(|| {
                syntax(
                    ln + 1,
                    1,
                    format!("a header keyword ({})", HEADER_KEYS.join(", ")),
                )
            })?;
        let v = toks
            .next()
            .ok_or_else(|| syntax(ln + 1, line.len() + 1, format!("a value after `{k}`")))?;
        let num = v
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| syntax(ln + 1, col_of(line, v), format!("a number for `{k}`")))?;
        fields.push((k, num, ln + 1));
        lines.next();
    }
    let get = |names: &[&str]| {
        fields
            .iter()
            .find(|f| names.contains(&f.0))
            .map(|f| (f.1, f.2, f.0))
    };
    let need = |names: &[&str]| {
        get(names).ok_or_else(|| DemError::Malformed {
            path: path.to_path_buf(),
            what: format!("a `{}` line in the header", names.join("` or `")),
        })
    };
    let count = |names: &[&str]| -> Result<usize, DemError> {
        let (v, line, _) = need(names)?;
        if v < 1.0 || v.fract() != 0.0 || v > u32::MAX as f64 {
            return Err(syntax(
                line,
                1,
                format!("a positive whole `{}`, found {v}", names[0]),
            ));
        }
        Ok(v as usize)
    };
    let (x, _, xk) = need(&["xllcorner", "xllcenter"])?;
    let (y, _, _) = need(&["yllcorner", "yllcenter"])?;
    let (dx, dy) = match (get(&["cellsize"]), get(&["dx"]), get(&["dy"])) {
        (Some(c), _, _) => (c.0, c.0),
        (None, Some(a), Some(b)) => (a.0, b.0),
        _ => {
            return Err(DemError::Malformed {
                path: path.to_path_buf(),
                what: "a `cellsize` (or `dx` and `dy`) line in the header".into(),
            });
        }
    };
    if !(dx > 0.0 && dy > 0.0) {
        return Err(DemError::Malformed {
            path: path.to_path_buf(),
            what: format!("a cell size > 0, found {dx} × {dy}"),
        });
    }
    let h = Header {
        ncols: count(&["ncols"])?,
        nrows: count(&["nrows"])?,
        x,
        y,
        centre: xk == "xllcenter",
        dx,
        dy,
        nodata: get(&["nodata_value"]).map(|f| f.0),
    };
    check_grid_size(path, h.ncols as u64, h.nrows as u64, 8, opts.memory_budget)?;

    let n = h.ncols * h.nrows;
    // Each value takes a digit and a separator: a header claiming more than the file can
    // hold lies (or the file is cut short), and is refused before anything is allocated.
    if n > text.len() / 2 + 1 {
        return Err(DemError::Malformed {
            path: path.to_path_buf(),
            what: format!(
                "{}×{} = {n} values, but the file's {} bytes hold at most {}",
                h.ncols,
                h.nrows,
                text.len(),
                text.len() / 2 + 1
            ),
        });
    }
    let mut vals = crate::io::try_with_capacity(n, "the grid's values")?;
    for (ln, line) in lines {
        for tok in line.split_ascii_whitespace() {
            if vals.len() == n {
                return Err(syntax(
                    ln + 1,
                    col_of(line, tok),
                    format!("{}×{} = {n} values, found more", h.ncols, h.nrows),
                ));
            }
            let v = tok
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    syntax(
                        ln + 1,
                        col_of(line, tok),
                        "a finite number (voids use NODATA_value)".to_string(),
                    )
                })?;
            vals.push(v);
        }
    }
    if vals.len() < n {
        return Err(DemError::Malformed {
            path: path.to_path_buf(),
            what: format!(
                "{}×{} = {n} values, found {} (truncated?)",
                h.ncols,
                h.nrows,
                vals.len()
            ),
        });
    }
    let samples = finish_samples(path, &vals, h.ncols, h.nodata)?;
    drop(vals);
    let z = reorder(&samples, h.ncols, h.nrows, false, true);

    let half = if h.centre { 0.0 } else { 0.5 };
    let origin = [h.x + half * h.dx, h.y + half * h.dy];
    let mut notices = Vec::new();
    let (crs, unit) = match prj {
        Some(wkt) => parse_prj(wkt).map_err(|what| DemError::Malformed {
            path: path.with_extension("prj"),
            what,
        })?,
        None => {
            notices.push(format!(
                "{}: no .prj beside it; coordinates taken as metres in a local frame",
                path.display()
            ));
            (Crs::Local, 1.0)
        }
    };
    let georef = match crs {
        Crs::Geographic { epsg } => {
            let lat = origin[1] + 0.5 * (h.nrows as f64 - 1.0) * h.dy;
            let g = Georef::geographic(epsg, origin, [h.dx, h.dy], lat, RasterType::PixelIsArea);
            notices.extend(g.degrees_notice(h.nrows));
            g
        }
        crs => Georef {
            crs,
            origin,
            step: [h.dx, h.dy],
            unit_m: [unit, unit],
            raster_type: RasterType::PixelIsArea,
        },
    };
    Dem::new(path, h.ncols, h.nrows, z, georef, notices)
}

/// The CRS kind and the metres per linear unit of a WKT 1 `.prj`.
pub(crate) fn parse_prj(wkt: &str) -> Result<(Crs, f64), String> {
    let t = wkt.trim_start_matches('\u{feff}').trim();
    let authority = t.rfind("AUTHORITY[\"EPSG\",").and_then(|at| {
        let rest = &t[at + 17..];
        let digits: String = rest
            .trim_start_matches('"')
            .chars()
            .take_while(|c| c.is_ascii_digit())
            .collect();
        digits.parse::<u32>().ok()
    });
    if t.starts_with("GEOGCS[") {
        let wgs84 = t.contains("WGS_1984") || t.contains("WGS 84") || t.contains("WGS84");
        Ok((
            Crs::Geographic {
                epsg: authority.or(wgs84.then_some(4326)),
            },
            1.0,
        ))
    } else if t.starts_with("PROJCS[") {
        // the linear unit is the last UNIT[...] of a PROJCS
        let unit = t
            .rfind("UNIT[")
            .and_then(|at| t[at..].split(',').nth(1))
            .and_then(|v| {
                v.trim_end_matches([']', ' ', '\n', '\r'])
                    .trim()
                    .parse::<f64>()
                    .ok()
            })
            .filter(|u| u.is_finite() && *u > 0.0)
            .ok_or_else(|| "a PROJCS with a linear UNIT[\"name\", metres]".to_string())?;
        let epsg = authority.or_else(|| utm_epsg(t));
        Ok((Crs::Projected { epsg }, unit))
    } else {
        Err(format!(
            "WKT starting with GEOGCS[ or PROJCS[, found {:?}",
            t.chars().take(20).collect::<String>()
        ))
    }
}

/// EPSG code of a WGS 84 UTM zone named like `WGS_1984_UTM_Zone_16N`.
fn utm_epsg(wkt: &str) -> Option<u32> {
    let at = wkt.find("UTM_Zone_").or_else(|| wkt.find("UTM zone "))?;
    if !(wkt.contains("WGS_1984") || wkt.contains("WGS 84")) {
        return None;
    }
    let rest = &wkt[at + 9..];
    let zone: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
    let zone: u32 = zone.parse().ok().filter(|z| (1..=60).contains(z))?;
    match rest[zone.to_string().len()..].chars().next()? {
        'N' => Some(32600 + zone),
        'S' => Some(32700 + zone),
        _ => None,
    }
}

/// The `.prj` text for the CRSs we can name: WGS 84 geographic and WGS 84 UTM zones.
pub(crate) fn prj_for(crs: &Crs) -> Option<String> {
    const GEOG: &str = "GEOGCS[\"GCS_WGS_1984\",DATUM[\"D_WGS_1984\",SPHEROID[\"WGS_1984\",6378137.0,298.257223563]],PRIMEM[\"Greenwich\",0.0],UNIT[\"Degree\",0.0174532925199433]]";
    match crs {
        Crs::Geographic { epsg: Some(4326) } => Some(GEOG.into()),
        Crs::Projected {
            epsg: Some(e @ (32601..=32660 | 32701..=32760)),
        } => {
            let (zone, north) = if *e < 32700 {
                (e - 32600, true)
            } else {
                (e - 32700, false)
            };
            Some(format!(
                "PROJCS[\"WGS_1984_UTM_Zone_{zone}{}\",{GEOG},PROJECTION[\"Transverse_Mercator\"],PARAMETER[\"False_Easting\",500000.0],PARAMETER[\"False_Northing\",{}],PARAMETER[\"Central_Meridian\",{}],PARAMETER[\"Scale_Factor\",0.9996],PARAMETER[\"Latitude_Of_Origin\",0.0],UNIT[\"Meter\",1.0]]",
                if north { 'N' } else { 'S' },
                if north { "0.0" } else { "10000000.0" },
                zone as f64 * 6.0 - 183.0
            ))
        }
        _ => None,
    }
}

/// Writes `dem` as an ESRI ASCII grid (and a `.prj` when its CRS can be named), atomically.
pub fn write(dem: &Dem, path: &Path) -> Result<(), DemError> {
    let hf = &dem.heightfield;
    let g = &dem.georef;
    let (nx, ny) = (hf.nx(), hf.ny());
    let nodata = [-9999.0f32, -32768.0, -99999.0]
        .into_iter()
        .find(|v| !hf.samples().contains(v))
        .unwrap_or(f32::MIN);
    let mut s = String::with_capacity(nx * ny * 8 + 200);
    let corner = [g.origin[0] - 0.5 * g.step[0], g.origin[1] - 0.5 * g.step[1]];
    let _ = writeln!(s, "ncols        {nx}\nnrows        {ny}");
    let _ = writeln!(s, "xllcorner    {}\nyllcorner    {}", corner[0], corner[1]);
    if (g.step[0] - g.step[1]).abs() <= 1e-12 * g.step[0].abs() {
        let _ = writeln!(s, "cellsize     {}", g.step[0]);
    } else {
        let _ = writeln!(s, "dx           {}\ndy           {}", g.step[0], g.step[1]);
    }
    let _ = writeln!(s, "NODATA_value {nodata}");
    for j in (0..ny).rev() {
        for (i, v) in hf.samples()[j * nx..(j + 1) * nx].iter().enumerate() {
            let v = if v.is_nan() { nodata } else { *v };
            let _ = write!(s, "{}{v}", if i == 0 { "" } else { " " });
        }
        s.push('\n');
    }
    crate::io::write_bytes_atomic(path, s.as_bytes())?;
    if let Some(prj) = prj_for(&g.crs) {
        crate::io::write_bytes_atomic(&path.with_extension("prj"), prj.as_bytes())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prj_parsing_names_the_crs() {
        let (c, u) = parse_prj(&prj_for(&Crs::Projected { epsg: Some(32616) }).unwrap()).unwrap();
        assert_eq!((c, u), (Crs::Projected { epsg: Some(32616) }, 1.0));
        let (c, _) = parse_prj(&prj_for(&Crs::Geographic { epsg: Some(4326) }).unwrap()).unwrap();
        assert_eq!(c, Crs::Geographic { epsg: Some(4326) });
        assert_eq!(utm_epsg("PROJCS[\"WGS 84 / UTM zone 33S\""), Some(32733));
        let ft = "PROJCS[\"x\",GEOGCS[\"y\",UNIT[\"Degree\",0.017]],UNIT[\"Foot_US\",0.3048006096012192]]";
        assert!((parse_prj(ft).unwrap().1 - 0.3048006096).abs() < 1e-9);
        assert!(parse_prj("LOCAL_CS[\"x\"]").is_err());
    }

    #[test]
    fn a_byte_order_mark_before_the_header_is_skipped() {
        let grid = "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\n1 2\n3 4\n";
        let path = Path::new("bom.asc");
        let opts = ReadOptions::default();
        let plain = read_bytes(path, grid.as_bytes(), None, &opts).unwrap();
        let bom = read_bytes(path, format!("\u{feff}{grid}").as_bytes(), None, &opts).unwrap();
        assert_eq!(plain.heightfield.samples(), bom.heightfield.samples());
    }
}

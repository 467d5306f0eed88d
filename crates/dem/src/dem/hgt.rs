//! SRTM `.hgt` tiles: 1201² (3″) or 3601² (1″) big-endian i16 samples from the north-west
//! corner, void = −32768, point samples on whole-degree tile edges. The tile's south-west
//! corner comes from the file name (`N36W084.hgt` → 36° N, 84° W).

use std::path::Path;

use super::georef::{Georef, RasterType};
use super::geotiff::{finish_samples, read_file, reorder};
use super::{Dem, DemError, ReadOptions};

/// The void value of SRTM tiles.
const VOID: i16 = -32768;

/// Reads an SRTM `.hgt` tile.
pub fn read(path: &Path, opts: &ReadOptions) -> Result<Dem, DemError> {
    let bytes = read_file(path, opts.memory_budget)?;
    read_bytes(path, &bytes, opts)
}

/// Reads a tile held in memory; its origin comes from `path`'s file name.
pub fn read_bytes(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<Dem, DemError> {
    let (lat, lon) = tile_origin(path)?;
    let n = match bytes.len() {
        l if l == 1201 * 1201 * 2 => 1201,
        l if l == 3601 * 3601 * 2 => 3601,
        l => {
            return Err(DemError::Malformed {
                path: path.to_path_buf(),
                what: format!(
                    "{} bytes (1201² or 3601² big-endian 16-bit samples), found {l}",
                    1201 * 1201 * 2
                ),
            });
        }
    };
    super::check_grid_size(path, n as u64, n as u64, 8, opts.memory_budget)?;
    let vals: Vec<f64> = bytes
        .chunks_exact(2)
        .map(|b| f64::from(i16::from_be_bytes([b[0], b[1]])))
        .collect();
    let samples = finish_samples(path, &vals, n, Some(f64::from(VOID)))?;
    let z = reorder(&samples, n, n, false, true);
    let step = 1.0 / (n - 1) as f64;
    let georef = Georef::geographic(
        Some(4326),
        [lon, lat],
        [step, step],
        lat + 0.5,
        RasterType::PixelIsPoint,
    );
    let notices = georef.degrees_notice(n).into_iter().collect();
    Dem::new(path, n, n, z, georef, notices)
}

/// `(latitude, longitude)` of a tile's south-west corner from its name, e.g. `S12E130.hgt`.
pub fn tile_origin(path: &Path) -> Result<(f64, f64), DemError> {
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("");
    let parse = || -> Option<(f64, f64)> {
        let s = stem.get(..7)?.to_ascii_uppercase();
        let b = s.as_bytes();
        let lat: f64 = s.get(1..3)?.parse().ok()?;
        let lon: f64 = s.get(4..7)?.parse().ok()?;
        let lat = match b[0] {
            b'N' => lat,
            b'S' => -lat,
            _ => return None,
        };
        let lon = match b[3] {
            b'E' => lon,
            b'W' => -lon,
            _ => return None,
        };
        ((-90.0..90.0).contains(&lat) && (-180.0..180.0).contains(&lon)).then_some((lat, lon))
    };
    parse().ok_or_else(|| DemError::Malformed {
        path: path.to_path_buf(),
        what: format!("a tile name like N36W084.hgt giving its south-west corner, found {stem:?}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_a_synthetic_tile() {
        let n = 1201;
        let mut bytes = Vec::with_capacity(n * n * 2);
        for r in 0..n {
            for c in 0..n {
                let v: i16 = if (r, c) == (5, 7) {
                    VOID
                } else {
                    (r as i16) * 2 - c as i16 / 3
                };
                bytes.extend(v.to_be_bytes());
            }
        }
        let dem = read_bytes(
            Path::new("dir/s12E130.hgt"),
            &bytes,
            &ReadOptions::default(),
        )
        .unwrap();
        let hf = &dem.heightfield;
        assert_eq!(dem.georef.origin, [130.0, -12.0]);
        // file row r is grid row n-1-r
        assert_eq!(hf.at(0, n - 1), 0.0);
        assert_eq!(hf.at(10, n - 1 - 100), 200.0 - 3.0);
        assert!(hf.at(7, n - 1 - 5).is_nan());
        assert!((hf.cell().y - 92.1).abs() < 0.5, "{}", hf.cell());
        let e = read_bytes(Path::new("tile.hgt"), &bytes, &ReadOptions::default()).unwrap_err();
        assert!(e.to_string().contains("tile name like N36W084.hgt"), "{e}");
        let e = read_bytes(
            Path::new("N36W084.hgt"),
            &bytes[..1000],
            &ReadOptions::default(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("found 1000"), "{e}");
    }
}

//! Where a DEM's local frame sits on Earth, kept in f64.
//!
//! The [`Heightfield`](super::Heightfield) works in a local metric frame whose origin is the
//! south-west sample. [`Georef`] maps that frame to the file's coordinate reference system
//! and back. For geographic CRSs (degrees) the map is the equirectangular approximation at
//! the DEM's centre latitude on the WGS 84 ellipsoid, good to well under 0.1% across a
//! 1° tile.

/// The kind of coordinate reference system a DEM was georeferenced in.
#[derive(Clone, Debug, PartialEq)]
pub enum Crs {
    /// Projected, in metres (after unit conversion): UTM and friends.
    Projected {
        /// EPSG code when the file gives one (e.g. 32616 for UTM 16N).
        epsg: Option<u32>,
    },
    /// Longitude/latitude in degrees.
    Geographic {
        /// EPSG code when the file gives one (e.g. 4326 for WGS 84).
        epsg: Option<u32>,
    },
    /// No georeference: coordinates are metres in an arbitrary frame.
    Local,
}

impl Crs {
    /// `"projected (EPSG:32616)"`, `"geographic (EPSG:4326)"`, `"local"`.
    pub fn describe(&self) -> String {
        let code = |e: &Option<u32>| e.map(|c| format!(" (EPSG:{c})")).unwrap_or_default();
        match self {
            Crs::Projected { epsg } => format!("projected{}", code(epsg)),
            Crs::Geographic { epsg } => format!("geographic{}", code(epsg)),
            Crs::Local => "local (no georeference)".into(),
        }
    }

    /// The EPSG code, if known.
    pub fn epsg(&self) -> Option<u32> {
        match self {
            Crs::Projected { epsg } | Crs::Geographic { epsg } => *epsg,
            Crs::Local => None,
        }
    }
}

/// Whether the file anchored its georeference on pixel corners or centres (GeoTIFF
/// `GTRasterTypeGeoKey`). Samples are always taken at pixel centres here; this only records
/// the convention for writing the file back.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RasterType {
    /// A sample stands for the square around it (GDAL's default).
    #[default]
    PixelIsArea,
    /// A sample is a point measurement (SRTM).
    PixelIsPoint,
}

/// The georeference of a DEM: CRS coordinates of the local origin and the sample spacing.
#[derive(Clone, Debug, PartialEq)]
pub struct Georef {
    /// The coordinate system.
    pub crs: Crs,
    /// CRS coordinates (easting/longitude, northing/latitude) of sample `(0, 0)`, the
    /// south-west sample, which is local `(0, 0)`.
    pub origin: [f64; 2],
    /// CRS units between neighbouring samples along x (east) and y (north); positive.
    pub step: [f64; 2],
    /// Metres per CRS unit along x and y (1 for metric projections).
    pub unit_m: [f64; 2],
    /// The pixel anchoring the file used.
    pub raster_type: RasterType,
}

impl Georef {
    /// A local frame with `cell`-metre samples and no georeference.
    pub fn local(dx: f64, dy: f64) -> Georef {
        Georef {
            crs: Crs::Local,
            origin: [0.0, 0.0],
            step: [dx, dy],
            unit_m: [1.0, 1.0],
            raster_type: RasterType::PixelIsArea,
        }
    }

    /// Cell size in metres `(dx, dy)`.
    pub fn cell_size_m(&self) -> [f64; 2] {
        [self.step[0] * self.unit_m[0], self.step[1] * self.unit_m[1]]
    }

    /// CRS coordinates of a local point (metres from the south-west sample).
    pub fn local_to_crs(&self, local: [f64; 2]) -> [f64; 2] {
        [
            self.origin[0] + local[0] / self.unit_m[0],
            self.origin[1] + local[1] / self.unit_m[1],
        ]
    }

    /// Local coordinates (metres from the south-west sample) of a CRS point.
    pub fn crs_to_local(&self, crs: [f64; 2]) -> [f64; 2] {
        [
            (crs[0] - self.origin[0]) * self.unit_m[0],
            (crs[1] - self.origin[1]) * self.unit_m[1],
        ]
    }

    /// The same frame with a new sample spacing in metres (after resampling).
    pub fn with_cell_size(&self, dx: f64, dy: f64) -> Georef {
        Georef {
            step: [dx / self.unit_m[0], dy / self.unit_m[1]],
            ..self.clone()
        }
    }

    /// CRS coordinates of the outer north-west corner of the north-west pixel of a grid with
    /// `ny` rows (what GeoTIFF tiepoints and GDAL geotransforms store).
    pub fn north_west_corner(&self, ny: usize) -> [f64; 2] {
        [
            self.origin[0] - 0.5 * self.step[0],
            self.origin[1] + (ny as f64 - 0.5) * self.step[1],
        ]
    }

    /// Builds a geographic georeference, converting degrees to metres at `centre_lat`.
    pub fn geographic(
        epsg: Option<u32>,
        origin: [f64; 2],
        step: [f64; 2],
        centre_lat: f64,
        raster_type: RasterType,
    ) -> Georef {
        Georef {
            crs: Crs::Geographic { epsg },
            origin,
            step,
            unit_m: metres_per_degree(centre_lat),
            raster_type,
        }
    }

    /// A notice describing the degree → metre conversion of a geographic DEM, or `None`.
    pub fn degrees_notice(&self, ny: usize) -> Option<String> {
        match self.crs {
            Crs::Geographic { .. } => {
                let lat = self.origin[1] + 0.5 * (ny as f64 - 1.0) * self.step[1];
                let [dx, dy] = self.cell_size_m();
                Some(format!(
                    "geographic DEM: cells of {:.3e}° × {:.3e}° taken as {dx:.2} m × {dy:.2} m at the centre latitude {lat:.4}° (equirectangular, WGS 84)",
                    self.step[0], self.step[1]
                ))
            }
            _ => None,
        }
    }
}

/// Metres per degree of longitude and latitude at latitude `lat` (degrees) on WGS 84.
pub fn metres_per_degree(lat: f64) -> [f64; 2] {
    let p = lat.to_radians();
    let lon = 111_412.84 * p.cos() - 93.5 * (3.0 * p).cos() + 0.118 * (5.0 * p).cos();
    let lat_m =
        111_132.92 - 559.82 * (2.0 * p).cos() + 1.175 * (4.0 * p).cos() - 0.0023 * (6.0 * p).cos();
    [lon, lat_m]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metres_per_degree_matches_known_values() {
        // equator: 111.32 km / 110.57 km; 60°: 55.80 km / 111.41 km
        let [x, y] = metres_per_degree(0.0);
        assert!(
            (x - 111_319.5).abs() < 5.0 && (y - 110_574.3).abs() < 5.0,
            "{x} {y}"
        );
        let [x, y] = metres_per_degree(60.0);
        assert!(
            (x - 55_800.0).abs() < 20.0 && (y - 111_412.0).abs() < 20.0,
            "{x} {y}"
        );
    }

    #[test]
    fn local_crs_round_trip() {
        let g = Georef::geographic(
            Some(4326),
            [-84.4, 36.4],
            [1.0 / 1200.0; 2],
            36.5,
            RasterType::PixelIsArea,
        );
        let p = g.local_to_crs([1234.5, -77.25]);
        let q = g.crs_to_local(p);
        assert!((q[0] - 1234.5).abs() < 1e-6 && (q[1] + 77.25).abs() < 1e-6);
        assert!(g.degrees_notice(10).unwrap().contains("centre latitude"));
    }
}

//! Earth-centred, Earth-fixed (ECEF) coordinates of a DEM's frame: the inverse
//! transverse Mercator of the UTM zones and the WGS 84 geodetic-to-ECEF map, so a 3D
//! Tiles tileset can carry a root transform.
//!
//! The inverse projection is the standard series of Snyder 1987 (eqs. 8-18 to 8-25:
//! the footpoint latitude through the rectifying latitude μ), accurate to well under a
//! millimetre within a UTM zone. Heights are taken as ellipsoidal heights: a DEM's orthometric heights differ by
//! the geoid undulation (tens of metres), which a viewer's globe absorbs as an offset.

use glam::{DMat4, DVec3, DVec4};

use crate::dem::{Crs, Georef};

/// WGS 84 semi-major axis, metres.
const A: f64 = 6_378_137.0;
/// WGS 84 flattening.
const F: f64 = 1.0 / 298.257_223_563;
/// UTM scale factor on the central meridian.
const K0: f64 = 0.9996;
/// UTM false easting, metres.
const FALSE_EASTING: f64 = 500_000.0;
/// UTM false northing of the southern zones, metres.
const FALSE_NORTHING_SOUTH: f64 = 10_000_000.0;

/// First eccentricity squared.
fn e2() -> f64 {
    F * (2.0 - F)
}

/// A UTM zone on WGS 84.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UtmZone {
    /// Zone number, 1 to 60.
    pub zone: u32,
    /// Northern hemisphere (EPSG 326xx) or southern (327xx).
    pub north: bool,
}

impl UtmZone {
    /// The zone of an EPSG code: 32601–32660 (north) or 32701–32760 (south).
    pub fn from_epsg(epsg: u32) -> Option<UtmZone> {
        match epsg {
            32601..=32660 => Some(UtmZone {
                zone: epsg - 32600,
                north: true,
            }),
            32701..=32760 => Some(UtmZone {
                zone: epsg - 32700,
                north: false,
            }),
            _ => None,
        }
    }

    /// Longitude of the central meridian, radians.
    fn lon0(&self) -> f64 {
        (-183.0 + 6.0 * f64::from(self.zone)).to_radians()
    }

    fn false_northing(&self) -> f64 {
        if self.north {
            0.0
        } else {
            FALSE_NORTHING_SOUTH
        }
    }

    /// Geodetic latitude and longitude (radians) of easting and northing (metres).
    pub fn inverse(&self, easting: f64, northing: f64) -> (f64, f64) {
        let e2 = e2();
        let ep2 = e2 / (1.0 - e2);
        let m = (northing - self.false_northing()) / K0;
        let mu = m / (A * (1.0 - e2 / 4.0 - 3.0 * e2 * e2 / 64.0 - 5.0 * e2.powi(3) / 256.0));
        let s = (1.0 - e2).sqrt();
        let e1 = (1.0 - s) / (1.0 + s);
        let phi1 = mu
            + (3.0 * e1 / 2.0 - 27.0 * e1.powi(3) / 32.0) * (2.0 * mu).sin()
            + (21.0 * e1 * e1 / 16.0 - 55.0 * e1.powi(4) / 32.0) * (4.0 * mu).sin()
            + (151.0 * e1.powi(3) / 96.0) * (6.0 * mu).sin()
            + (1097.0 * e1.powi(4) / 512.0) * (8.0 * mu).sin();
        let (sin1, cos1) = phi1.sin_cos();
        let tan1 = phi1.tan();
        let c1 = ep2 * cos1 * cos1;
        let t1 = tan1 * tan1;
        let w = 1.0 - e2 * sin1 * sin1;
        let n1 = A / w.sqrt();
        let r1 = A * (1.0 - e2) / w.powf(1.5);
        let d = (easting - FALSE_EASTING) / (n1 * K0);
        let lat = phi1
            - (n1 * tan1 / r1)
                * (d * d / 2.0
                    - (5.0 + 3.0 * t1 + 10.0 * c1 - 4.0 * c1 * c1 - 9.0 * ep2) * d.powi(4) / 24.0
                    + (61.0 + 90.0 * t1 + 298.0 * c1 + 45.0 * t1 * t1
                        - 252.0 * ep2
                        - 3.0 * c1 * c1)
                        * d.powi(6)
                        / 720.0);
        let lon = self.lon0()
            + (d - (1.0 + 2.0 * t1 + c1) * d.powi(3) / 6.0
                + (5.0 - 2.0 * c1 + 28.0 * t1 - 3.0 * c1 * c1 + 8.0 * ep2 + 24.0 * t1 * t1)
                    * d.powi(5)
                    / 120.0)
                / cos1;
        (lat, lon)
    }

    /// Easting and northing (metres) of a geodetic latitude and longitude (radians): the
    /// forward series (Snyder 1987, eqs. 8-9 to 8-13), the check of [`UtmZone::inverse`].
    pub fn forward(&self, lat: f64, lon: f64) -> (f64, f64) {
        let e2 = e2();
        let ep2 = e2 / (1.0 - e2);
        let (sin, cos) = lat.sin_cos();
        let n = A / (1.0 - e2 * sin * sin).sqrt();
        let t = lat.tan().powi(2);
        let c = ep2 * cos * cos;
        let a = (lon - self.lon0()) * cos;
        let m = A
            * ((1.0 - e2 / 4.0 - 3.0 * e2 * e2 / 64.0 - 5.0 * e2.powi(3) / 256.0) * lat
                - (3.0 * e2 / 8.0 + 3.0 * e2 * e2 / 32.0 + 45.0 * e2.powi(3) / 1024.0)
                    * (2.0 * lat).sin()
                + (15.0 * e2 * e2 / 256.0 + 45.0 * e2.powi(3) / 1024.0) * (4.0 * lat).sin()
                - (35.0 * e2.powi(3) / 3072.0) * (6.0 * lat).sin());
        let x = FALSE_EASTING
            + K0 * n
                * (a + (1.0 - t + c) * a.powi(3) / 6.0
                    + (5.0 - 18.0 * t + t * t + 72.0 * c - 58.0 * ep2) * a.powi(5) / 120.0);
        let y = self.false_northing()
            + K0 * (m + n
                * lat.tan()
                * (a * a / 2.0
                    + (5.0 - t + 9.0 * c + 4.0 * c * c) * a.powi(4) / 24.0
                    + (61.0 - 58.0 * t + t * t + 600.0 * c - 330.0 * ep2) * a.powi(6) / 720.0));
        (x, y)
    }
}

/// ECEF position (metres) of a geodetic latitude, longitude (radians) and ellipsoidal
/// height (metres) on WGS 84.
pub fn geodetic_to_ecef(lat: f64, lon: f64, h: f64) -> DVec3 {
    let e2 = e2();
    let (sin, cos) = lat.sin_cos();
    let n = A / (1.0 - e2 * sin * sin).sqrt();
    DVec3::new(
        (n + h) * cos * lon.cos(),
        (n + h) * cos * lon.sin(),
        (n * (1.0 - e2) + h) * sin,
    )
}

/// How a CRS's coordinates become latitude and longitude.
enum Geodetic {
    Utm(UtmZone),
    Degrees,
}

impl Geodetic {
    fn of(crs: &Crs) -> Result<Geodetic, String> {
        match crs {
            Crs::Projected { epsg: Some(e) } => {
                UtmZone::from_epsg(*e).map(Geodetic::Utm).ok_or_else(|| {
                    format!("EPSG:{e} is not a WGS 84 UTM zone (EPSG 32601–32660, 32701–32760)")
                })
            }
            Crs::Geographic { epsg: Some(4326) } => Ok(Geodetic::Degrees),
            other => Err(format!(
                "{} is neither a WGS 84 UTM zone nor WGS 84 geographic (EPSG:4326)",
                other.describe()
            )),
        }
    }

    /// Latitude and longitude (radians) of CRS coordinates.
    fn lat_lon(&self, crs: [f64; 2]) -> (f64, f64) {
        match self {
            Geodetic::Utm(z) => z.inverse(crs[0], crs[1]),
            Geodetic::Degrees => (crs[1].to_radians(), crs[0].to_radians()),
        }
    }
}

/// The affine map from the tree frame (metres, Z up) to ECEF that is exact at `center` and
/// first-order around it: its columns are the derivatives of the tree-to-ECEF map along x,
/// y (central differences over `span` metres) and the ellipsoid's normal, so the grid
/// convergence and the projection's scale at the centre are kept. `to_crs` maps tree
/// x, y to CRS coordinates. Errors, saying why, for a CRS other than a WGS 84 UTM zone
/// or WGS 84 geographic.
pub fn tree_to_ecef(
    georef: &Georef,
    to_crs: impl Fn([f64; 2]) -> [f64; 2],
    center: DVec3,
    span: f64,
) -> Result<DMat4, String> {
    let g = Geodetic::of(&georef.crs)?;
    let ecef = |x: f64, y: f64, z: f64| {
        let (lat, lon) = g.lat_lon(to_crs([x, y]));
        geodetic_to_ecef(lat, lon, z)
    };
    let (lat, lon) = g.lat_lon(to_crs([center.x, center.y]));
    let origin = geodetic_to_ecef(lat, lon, center.z);
    let h = 0.5 * span.max(1.0);
    let dx = (ecef(center.x + h, center.y, center.z) - ecef(center.x - h, center.y, center.z))
        / (2.0 * h);
    let dy = (ecef(center.x, center.y + h, center.z) - ecef(center.x, center.y - h, center.z))
        / (2.0 * h);
    let up = DVec3::new(lat.cos() * lon.cos(), lat.cos() * lon.sin(), lat.sin());
    let linear = DMat4::from_cols(dx.extend(0.0), dy.extend(0.0), up.extend(0.0), DVec4::W);
    let translation = origin - linear.transform_vector3(center);
    Ok(DMat4::from_cols(
        dx.extend(0.0),
        dy.extend(0.0),
        up.extend(0.0),
        translation.extend(1.0),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utm_round_trips() {
        let z = UtmZone::from_epsg(32616).unwrap();
        assert_eq!(
            z,
            UtmZone {
                zone: 16,
                north: true
            }
        );
        // The central meridian on the equator is (500 000, 0).
        let (lat, lon) = z.inverse(500_000.0, 0.0);
        assert!(lat.abs() < 1e-12 && (lon.to_degrees() + 87.0).abs() < 1e-12);
        for (e, n) in [
            (744_574.0, 4_037_546.0),
            (300_000.0, 6_500_000.0),
            (650_000.0, 100.0),
        ] {
            let (lat, lon) = z.inverse(e, n);
            let (e2, n2) = z.forward(lat, lon);
            assert!(
                (e2 - e).abs() < 1e-3 && (n2 - n).abs() < 1e-3,
                "{e} {n}: {e2} {n2}"
            );
        }
        // The Jacksboro DEM's origin lies near Jacksboro, Tennessee (36.3° N, 84.2° W).
        let (lat, lon) = z.inverse(744_574.0, 4_037_546.0);
        assert!(
            (lat.to_degrees() - 36.45).abs() < 0.2,
            "{}",
            lat.to_degrees()
        );
        assert!(
            (lon.to_degrees() + 84.25).abs() < 0.2,
            "{}",
            lon.to_degrees()
        );
        let s = UtmZone::from_epsg(32733).unwrap();
        let (lat, _) = s.inverse(500_000.0, 10_000_000.0 - 1000.0);
        assert!(lat < 0.0);
        assert_eq!(UtmZone::from_epsg(32661), None);
    }

    #[test]
    fn ecef_of_known_points() {
        let p = geodetic_to_ecef(0.0, 0.0, 0.0);
        assert!((p - DVec3::new(A, 0.0, 0.0)).length() < 1e-6);
        let b = A * (1.0 - F);
        let p = geodetic_to_ecef(std::f64::consts::FRAC_PI_2, 0.0, 10.0);
        assert!((p - DVec3::new(0.0, 0.0, b + 10.0)).length() < 1e-6);
    }

    #[test]
    fn the_affine_map_is_close_to_the_projection() {
        let georef = Georef {
            crs: Crs::Projected { epsg: Some(32616) },
            ..Georef::local(90.0, 90.0)
        };
        let origin = [744_574.0, 4_037_546.0];
        let to_crs = |p: [f64; 2]| [origin[0] + p[0], origin[1] + p[1]];
        let c = DVec3::new(5000.0, 5000.0, 600.0);
        let m = tree_to_ecef(&georef, to_crs, c, 10_000.0).unwrap();
        let z = UtmZone::from_epsg(32616).unwrap();
        for p in [
            c,
            DVec3::new(0.0, 0.0, 300.0),
            DVec3::new(10_000.0, 8000.0, 1000.0),
        ] {
            let (lat, lon) = z.inverse(origin[0] + p.x, origin[1] + p.y);
            let exact = geodetic_to_ecef(lat, lon, p.z);
            let err = (m.transform_point3(p) - exact).length();
            // Earth's curvature over 7 km: a few metres of drop, first order misses it.
            assert!(err < 8.0, "{p}: {err} m");
        }
        assert!(
            (m.transform_point3(c) - {
                let (lat, lon) = z.inverse(origin[0] + c.x, origin[1] + c.y);
                geodetic_to_ecef(lat, lon, c.z)
            })
            .length()
                < 1e-6
        );
        let local = Georef::local(1.0, 1.0);
        assert!(tree_to_ecef(&local, to_crs, c, 1.0).is_err());
        let unknown = Georef {
            crs: Crs::Projected { epsg: Some(2154) },
            ..Georef::local(1.0, 1.0)
        };
        let why = tree_to_ecef(&unknown, to_crs, c, 1.0).unwrap_err();
        assert!(why.contains("EPSG:2154"), "{why}");
    }

    #[test]
    fn geographic_frames_map_through_degrees() {
        // A 1° tile at 36° N, 84° W, 3″ samples.
        let g = Georef::geographic(
            Some(4326),
            [-84.0, 36.0],
            [1.0 / 1200.0; 2],
            36.5,
            crate::dem::RasterType::PixelIsPoint,
        );
        let c = DVec3::new(40_000.0, 50_000.0, 500.0);
        let m = tree_to_ecef(&g, |p| g.local_to_crs(p), c, 80_000.0).unwrap();
        let [lon, lat] = g.local_to_crs([c.x, c.y]);
        let exact = geodetic_to_ecef(lat.to_radians(), lon.to_radians(), c.z);
        assert!((m.transform_point3(c) - exact).length() < 1e-6);
        // Its x column points east, its z column up, both unit length within the
        // equirectangular scale.
        let east = m.x_axis.truncate();
        assert!((east.length() - 1.0).abs() < 1e-3, "{east}");
        let up = m.z_axis.truncate();
        assert!((up.dot(exact.normalize()) - 1.0).abs() < 1e-4);
    }
}

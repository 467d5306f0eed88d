//! Float32 GeoTIFF writer: Deflate-compressed strips, ModelPixelScale + ModelTiepoint,
//! GeoKeys (model type, raster type, EPSG code, units) and GDAL_NODATA, laid out the way
//! GDAL writes them so `gdalinfo` reads the georeference back.

use std::io::Cursor;
use std::path::Path;

use tiff::encoder::{Compression, DeflateLevel, TiffEncoder, colortype::Gray32Float};
use tiff::tags::Tag;

use super::georef::{Crs, RasterType};
use super::geotiff::key;
use super::{Dem, DemError};

/// The nodata value written when the grid has voids and does not use it as an elevation.
const NODATA: f32 = -32768.0;

/// Writes `dem` as a float32 GeoTIFF at `path`, atomically.
pub fn write(dem: &Dem, path: &Path) -> Result<(), DemError> {
    let bytes = encode(dem).map_err(|source| DemError::Tiff {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(crate::io::write_bytes_atomic(path, &bytes)?)
}

/// The GeoTIFF file of `dem`, in memory.
pub fn encode(dem: &Dem) -> Result<Vec<u8>, tiff::TiffError> {
    let hf = &dem.heightfield;
    let g = &dem.georef;
    let (nx, ny) = (hf.nx(), hf.ny());
    let nodata = if hf.samples().contains(&NODATA) {
        f32::NAN
    } else {
        NODATA
    };
    let mut data = Vec::with_capacity(nx * ny);
    for r in 0..ny {
        let j = ny - 1 - r;
        data.extend(
            hf.samples()[j * nx..(j + 1) * nx]
                .iter()
                .map(|&v| if v.is_nan() { nodata } else { v }),
        );
    }

    let tie = match g.raster_type {
        RasterType::PixelIsArea => g.north_west_corner(ny),
        RasterType::PixelIsPoint => [g.origin[0], g.origin[1] + (ny as f64 - 1.0) * g.step[1]],
    };
    let mut keys: Vec<[u16; 4]> = Vec::new();
    let raster = match g.raster_type {
        RasterType::PixelIsArea => 1,
        RasterType::PixelIsPoint => 2,
    };
    let code = |e: Option<u32>| e.and_then(|c| u16::try_from(c).ok()).unwrap_or(32767);
    match &g.crs {
        Crs::Projected { epsg } => {
            keys.push([key::MODEL_TYPE, 0, 1, 1]);
            keys.push([key::RASTER_TYPE, 0, 1, raster]);
            keys.push([key::PROJECTED_TYPE, 0, 1, code(*epsg)]);
            let unit = if (g.unit_m[0] - 0.3048).abs() < 1e-9 {
                9002
            } else if (g.unit_m[0] - 1200.0 / 3937.0).abs() < 1e-9 {
                9003
            } else {
                9001
            };
            keys.push([key::LINEAR_UNITS, 0, 1, unit]);
        }
        Crs::Geographic { epsg } => {
            keys.push([key::MODEL_TYPE, 0, 1, 2]);
            keys.push([key::RASTER_TYPE, 0, 1, raster]);
            keys.push([key::GEOGRAPHIC_TYPE, 0, 1, code(*epsg)]);
            keys.push([key::ANGULAR_UNITS, 0, 1, 9102]);
        }
        Crs::Local => keys.push([key::RASTER_TYPE, 0, 1, raster]),
    }
    let mut dir = vec![1u16, 1, 0, keys.len() as u16];
    dir.extend(keys.iter().flatten());

    let mut buf = Cursor::new(Vec::new());
    {
        let mut enc = TiffEncoder::new(&mut buf)?
            .with_compression(Compression::Deflate(DeflateLevel::Balanced));
        let mut image = enc.new_image::<Gray32Float>(nx as u32, ny as u32)?;
        image.rows_per_strip(16.min(ny as u32))?;
        let e = image.encoder();
        e.write_tag(Tag::ModelPixelScaleTag, &[g.step[0], g.step[1], 0.0][..])?;
        e.write_tag(
            Tag::ModelTiepointTag,
            &[0.0, 0.0, 0.0, tie[0], tie[1], 0.0][..],
        )?;
        e.write_tag(Tag::GeoKeyDirectoryTag, &dir[..])?;
        let nd = if nodata.is_nan() {
            "nan".to_string()
        } else {
            format!("{nodata}")
        };
        e.write_tag(Tag::GdalNodata, nd.as_str())?;
        image.write_data(&data)?;
    }
    Ok(buf.into_inner())
}

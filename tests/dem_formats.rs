//! Every GeoTIFF encoding the reader claims: sample types i8..i32, u8..u16, f16/f32/f64;
//! None, LZW, Deflate, PackBits; horizontal and floating-point predictors; strips and
//! tiles; scale + tiepoint, ModelTransformation, PixelIsPoint and south-up files.
//! Fixtures from `tests/data/dem_formats/make_formats.py` (tifffile).

use std::path::Path;

use karstic::dem::{self, Crs, ReadOptions};

#[test]
fn every_encoding_decodes_to_the_same_grid() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dem_formats");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "tif") {
            continue;
        }
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let d = dem::read(&path, &ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        let h = &d.heightfield;
        assert_eq!((h.nx(), h.ny()), (37, 29), "{name}");
        let frac = if name.contains("_f") { 0.25 } else { 0.0 };
        let shift = if name.contains("_i8") { -100.0 } else { 0.0 };
        for j in 0..29 {
            for i in 0..37 {
                let row = 28 - j; // the file's row 0 is the north
                let want = 100.0 + 3.0 * row as f32 - 2.0 * i as f32 + frac + shift;
                assert_eq!(h.at(i, j), want, "{name} at ({i}, {j})");
            }
        }
        let g = &d.georef;
        assert_eq!(g.crs, Crs::Projected { epsg: Some(32616) }, "{name}");
        assert_eq!(
            g.origin,
            [500_005.0, 3_999_715.0],
            "{name}: south-west sample centre"
        );
        assert_eq!(g.step, [10.0, 10.0], "{name}");
        seen += 1;
    }
    assert_eq!(seen, 11);
}

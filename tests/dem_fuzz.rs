//! Byte-mutation fuzzing of the DEM readers: whatever the bytes, a reader returns a grid or
//! an error, never panics. Seeds are small valid files in every format and encoding; the
//! mutations are byte overwrites, truncations and insertions. Inputs that once crashed a
//! reader live on in `tests/data/dem_corpus/` (see `dem_corpus.rs`).

use std::io::Cursor;
use std::path::Path;
use std::sync::OnceLock;

use glam::Vec2;
use karstic::dem::{self, Dem, Georef, Heightfield, ReadOptions, asc, geotiff, hgt, png16};
use proptest::prelude::*;
use tiff::encoder::{Compression, DeflateLevel, Predictor, TiffEncoder, colortype};
use tiff::tags::Tag;

fn small_dem() -> Dem {
    let (nx, ny) = (9, 7);
    let z = (0..nx * ny)
        .map(|k| {
            if k == 20 {
                f32::NAN
            } else {
                100.0 + (k as f32 * 0.37).sin() * 30.0
            }
        })
        .collect();
    Dem {
        heightfield: Heightfield::new(nx, ny, Vec2::ZERO, Vec2::splat(30.0), z).unwrap(),
        georef: Georef {
            crs: dem::Crs::Projected { epsg: Some(32616) },
            ..Georef::local(30.0, 30.0)
        },
        notices: vec![],
    }
}

/// A GeoTIFF with the given sample type, compression and predictor, written by the `tiff`
/// crate (other writers than ours).
fn tiff_with<C: colortype::ColorType>(
    data: &[C::Inner],
    comp: Compression,
    pred: Predictor,
) -> Vec<u8>
where
    [C::Inner]: tiff::encoder::TiffValue,
{
    let mut buf = Cursor::new(Vec::new());
    {
        let mut enc = TiffEncoder::new(&mut buf)
            .unwrap()
            .with_compression(comp)
            .with_predictor(pred);
        let mut img = enc.new_image::<C>(8, 6).unwrap();
        img.rows_per_strip(2).unwrap();
        let e = img.encoder();
        e.write_tag(Tag::ModelPixelScaleTag, &[0.001f64, 0.001, 0.0][..])
            .unwrap();
        e.write_tag(
            Tag::ModelTiepointTag,
            &[0.0f64, 0.0, 0.0, 10.0, 45.0, 0.0][..],
        )
        .unwrap();
        e.write_tag(
            Tag::GeoKeyDirectoryTag,
            &[1u16, 1, 0, 2, 1024, 0, 1, 2, 2048, 0, 1, 4326][..],
        )
        .unwrap();
        e.write_tag(Tag::GdalNodata, "7").unwrap();
        img.write_data(data).unwrap();
    }
    buf.into_inner()
}

fn tiff_seeds() -> Vec<Vec<u8>> {
    let i16s: Vec<i16> = (0..48).map(|k| k * 13 - 200).collect();
    let u8s: Vec<u8> = (0..48).map(|k| (k * 5) as u8).collect();
    let f64s: Vec<f64> = (0..48).map(|k| k as f64 * 1.5).collect();
    let u32s: Vec<u32> = (0..48).map(|k| k * 1000).collect();
    vec![
        geotiff_write_bytes(&small_dem()),
        tiff_with::<colortype::GrayI16>(&i16s, Compression::Lzw, Predictor::Horizontal),
        tiff_with::<colortype::Gray8>(&u8s, Compression::Packbits, Predictor::None),
        tiff_with::<colortype::Gray64Float>(&f64s, Compression::Uncompressed, Predictor::None),
        tiff_with::<colortype::Gray32>(
            &u32s,
            Compression::Deflate(DeflateLevel::Fast),
            Predictor::Horizontal,
        ),
    ]
}

fn geotiff_write_bytes(d: &Dem) -> Vec<u8> {
    dem::geotiff_write::encode(d).unwrap()
}

fn png_seed() -> (Vec<u8>, String) {
    static SEED: OnceLock<(Vec<u8>, String)> = OnceLock::new();
    SEED.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.png");
        dem::write(&small_dem(), &p).unwrap();
        (
            std::fs::read(&p).unwrap(),
            std::fs::read_to_string(p.with_extension("json")).unwrap(),
        )
    })
    .clone()
}

/// Every seed: the TIFFs, the PNG and the ASCII grid.
fn all_seeds() -> &'static [Vec<u8>] {
    static SEEDS: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let mut seeds = tiff_seeds();
        seeds.push(png_seed().0);
        seeds.push(asc_seed());
        seeds
    })
}

fn asc_seed() -> Vec<u8> {
    b"ncols 4\nnrows 3\nxllcorner 100\nyllcorner 200\ncellsize 5\nNODATA_value -9999\n1 2 3 4\n5 -9999 7 8\n9 10 11 12\n".to_vec()
}

/// Cases per proptest: 400, or `DEM_FUZZ_CASES` for a long session.
fn fuzz_cases() -> u32 {
    std::env::var("DEM_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(400)
}

const PNG_SIDE: &str = "s.json";

/// Every reader on `bytes`; must not panic.
fn read_all(bytes: &[u8], side: &str) -> usize {
    let opts = ReadOptions {
        memory_budget: 64 << 20,
        ..ReadOptions::default()
    };
    let mut ok = 0;
    ok += geotiff::read_bytes(Path::new("f.tif"), bytes, &opts).is_ok() as usize;
    ok += asc::read_bytes(Path::new("f.asc"), bytes, None, &opts).is_ok() as usize;
    let prj = std::str::from_utf8(bytes).ok();
    ok += asc::read_bytes(Path::new("f.asc"), &asc_seed(), prj, &opts).is_ok() as usize;
    ok += png16::read_bytes(
        Path::new("f.png"),
        bytes,
        Some((Path::new(PNG_SIDE), side)),
        &opts,
    )
    .is_ok() as usize;
    ok += hgt::read_bytes(Path::new("N10E010.hgt"), bytes, &opts).is_ok() as usize;
    ok
}

fn mutate(
    seed: &[u8],
    edits: &[(usize, u8)],
    cut: Option<usize>,
    insert: Option<(usize, Vec<u8>)>,
) -> Vec<u8> {
    let mut b = seed.to_vec();
    for &(at, v) in edits {
        let n = b.len();
        if n > 0 {
            b[at % n] = v;
        }
    }
    if let Some((at, bytes)) = insert {
        let at = at % (b.len() + 1);
        b.splice(at..at, bytes);
    }
    if let Some(c) = cut {
        b.truncate(c % (b.len() + 1));
    }
    b
}

#[test]
fn seeds_are_valid() {
    for (k, s) in tiff_seeds().iter().enumerate() {
        let d = geotiff::read_bytes(Path::new("seed.tif"), s, &ReadOptions::default())
            .unwrap_or_else(|e| panic!("seed {k}: {e}"));
        assert!(d.heightfield.nodata_count() <= 1, "seed {k}");
    }
    let (png, side) = png_seed();
    png16::read_bytes(
        Path::new("s.png"),
        &png,
        Some((Path::new(PNG_SIDE), &side)),
        &ReadOptions::default(),
    )
    .unwrap();
    asc::read_bytes(
        Path::new("s.asc"),
        &asc_seed(),
        None,
        &ReadOptions::default(),
    )
    .unwrap();
}

/// Deterministic sweep: every header byte of every seed set to 0x00, 0xFF and +1.
#[test]
fn header_byte_sweep_never_panics() {
    let side = png_seed().1;
    for s in all_seeds() {
        for at in 0..s.len().min(400) {
            for v in [0x00, 0xFF, s[at].wrapping_add(1)] {
                read_all(&mutate(s, &[(at, v)], None, None), &side);
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(fuzz_cases()))]

    #[test]
    fn mutated_files_never_panic(
        which in 0usize..7,
        edits in proptest::collection::vec((any::<usize>(), any::<u8>()), 0..8),
        cut in proptest::option::of(any::<usize>()),
        insert in proptest::option::of((any::<usize>(), proptest::collection::vec(any::<u8>(), 1..16))),
        side_cut in any::<usize>(),
    ) {
        let side = png_seed().1;
        let seeds = all_seeds();
        let s = &seeds[which % seeds.len()];
        let bytes = mutate(s, &edits, cut, insert);
        let side = &side[..side.len() - side_cut % 3];
        read_all(&bytes, side);
    }

    #[test]
    fn mutated_sidecars_and_headers_never_panic(
        text in "[ -~\n]{0,200}",
    ) {
        let (png, _) = png_seed();
        let opts = ReadOptions::default();
        let _ = png16::read_bytes(Path::new("f.png"), &png, Some((Path::new(PNG_SIDE), &text)), &opts);
        let _ = asc::read_bytes(Path::new("f.asc"), text.as_bytes(), None, &opts);
    }
}

//! A section of a tree's field as a picture: a `karstic sample` grid two samples thick
//! along one axis, drawn rock / air (`f > T` / `f ≤ T`), the vertical axis up (z if the
//! section is vertical, y, north, if it is horizontal).

use std::path::Path;

use image::{Rgb, RgbImage};

/// Rock in a section.
const ROCK: Rgb<u8> = Rgb([122, 102, 86]);
/// Air in a section.
const AIR: Rgb<u8> = Rgb([206, 221, 236]);

/// The section through the first layer of the thin axis of the `.npy` grid at `path`.
pub fn section_picture(path: &Path) -> RgbImage {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let (shape, values) = read_npy(&bytes);
    let thin = shape
        .iter()
        .position(|&n| n == 2)
        .unwrap_or_else(|| panic!("{}: no axis two samples thick: {shape:?}", path.display()));
    let strides = [shape[1] * shape[2], shape[2], 1];
    let kept: Vec<usize> = (0..3).filter(|&a| a != thin).collect();
    let (rows, cols) = (kept[0], kept[1]);
    let (h, w) = (shape[rows], shape[cols]);
    let size = |n: usize| u32::try_from(n).expect("a section fits an image");
    RgbImage::from_fn(size(w), size(h), |x, y| {
        let row = h - 1 - y as usize;
        let f = values[row * strides[rows] + x as usize * strides[cols]];
        if f > 0.5 { ROCK } else { AIR }
    })
}

/// The shape and float32 values of a little-endian, C-order `.npy` file.
fn read_npy(bytes: &[u8]) -> ([usize; 3], Vec<f32>) {
    assert!(bytes.starts_with(b"\x93NUMPY"), "not a .npy file");
    let (header_len, start) = match bytes[6] {
        1 => (usize::from(u16::from_le_bytes([bytes[8], bytes[9]])), 10),
        _ => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
    };
    let header = std::str::from_utf8(&bytes[start..start + header_len]).expect("header text");
    assert!(header.contains("'<f4'") && header.contains("'fortran_order': False"));
    let dims = header
        .split("'shape': (")
        .nth(1)
        .and_then(|s| s.split(')').next())
        .expect("shape");
    let dims: Vec<usize> = dims
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| s.trim().parse().expect("a dimension"))
        .collect();
    let shape: [usize; 3] = dims.try_into().expect("a 3D grid");
    let values = bytes[start + header_len..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect::<Vec<_>>();
    assert_eq!(values.len(), shape.iter().product::<usize>(), "grid size");
    (shape, values)
}

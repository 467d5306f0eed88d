//! PNG pictures written atomically: the one encoder of every picture the project writes.

use std::path::Path;

use image::ImageEncoder;
use image::codecs::png::PngEncoder;

use super::{IoError, write_bytes_atomic};

/// Writes RGBA8 pixels (row-major from the top-left) as a PNG, atomically.
pub fn write_rgba_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<(), IoError> {
    let mut bytes = Vec::new();
    PngEncoder::new(&mut bytes)
        .write_image(rgba, width, height, image::ExtendedColorType::Rgba8)
        .map_err(|source| IoError::Encode {
            path: path.to_path_buf(),
            source,
        })?;
    write_bytes_atomic(path, &bytes)
}

//! A rendered frame (colour, depth, steps per pixel) and its PNG outputs.

use std::path::Path;

use super::RenderError;
use crate::io::{check_budget, write_rgba_png};

/// Bytes per pixel of a [`Frame`] (RGBA8, f32 depth, u32 steps) plus the PNG buffer.
pub const BYTES_PER_PIXEL: u64 = 4 + 4 + 4 + 4;

/// What one render produced, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Colour, 4 bytes (sRGB RGBA) per pixel.
    pub rgba: Vec<u8>,
    /// Distance along the primary ray to the surface, `∞` where the ray missed.
    pub depth: Vec<f32>,
    /// Field evaluations spent on the primary ray.
    pub steps: Vec<u32>,
}

impl Frame {
    /// Refuses a `width × height` frame that would exceed `budget` bytes.
    pub fn check_budget(width: u32, height: u32, budget: u64) -> Result<(), RenderError> {
        let need = width as u64 * height as u64 * BYTES_PER_PIXEL;
        check_budget(format!("a {width} × {height} image"), need, budget)?;
        Ok(())
    }

    /// A frame from its parts (lengths must match `width × height`).
    pub fn new(width: u32, height: u32, rgba: Vec<u8>, depth: Vec<f32>, steps: Vec<u32>) -> Self {
        let n = width as usize * height as usize;
        assert!(rgba.len() == 4 * n && depth.len() == n && steps.len() == n);
        Frame {
            width,
            height,
            rgba,
            depth,
            steps,
        }
    }

    /// Number of pixels whose ray hit the surface.
    pub fn hits(&self) -> usize {
        self.depth.iter().filter(|d| d.is_finite()).count()
    }

    /// Mean steps per ray over all pixels.
    pub fn mean_steps(&self) -> f64 {
        self.steps.iter().map(|&s| s as f64).sum::<f64>() / self.steps.len().max(1) as f64
    }

    /// Writes the colour image as a PNG, atomically.
    pub fn write_png(&self, path: &Path) -> Result<(), RenderError> {
        Ok(write_rgba_png(path, self.width, self.height, &self.rgba)?)
    }

    /// The cost image: steps per pixel on a black–blue–red–yellow–white ramp scaled to
    /// the frame's maximum, RGBA8.
    pub fn cost_rgba(&self) -> Vec<u8> {
        let max = self.steps.iter().copied().max().unwrap_or(0).max(1) as f32;
        self.steps
            .iter()
            .flat_map(|&s| heat(s as f32 / max))
            .collect()
    }

    /// Writes the cost image (see [`Frame::cost_rgba`]) as a PNG, atomically.
    pub fn write_cost_png(&self, path: &Path) -> Result<(), RenderError> {
        Ok(write_rgba_png(
            path,
            self.width,
            self.height,
            &self.cost_rgba(),
        )?)
    }
}

/// Black → blue → red → yellow → white for `x ∈ [0, 1]`.
fn heat(x: f32) -> [u8; 4] {
    const STOPS: [[f32; 3]; 5] = [
        [0.0, 0.0, 0.0],
        [0.1, 0.1, 0.8],
        [0.85, 0.1, 0.1],
        [1.0, 0.85, 0.0],
        [1.0, 1.0, 1.0],
    ];
    let x = x.clamp(0.0, 1.0) * 4.0;
    let i = (x as usize).min(3);
    let f = x - i as f32;
    let c = |k: usize| ((STOPS[i][k] * (1.0 - f) + STOPS[i + 1][k] * f) * 255.0 + 0.5) as u8;
    [c(0), c(1), c(2), 255]
}

/// Width of a thumbnail on a contact sheet, pixels.
pub const SHEET_THUMB: u32 = 480;
/// Thumbnails per row of a contact sheet.
pub const SHEET_COLUMNS: usize = 3;
/// Gap between thumbnails, pixels.
const SHEET_GAP: u32 = 4;

/// Writes `frames` as one contact sheet: thumbnails [`SHEET_THUMB`] pixels wide (each
/// keeping its aspect) in rows of [`SHEET_COLUMNS`], in order, on a dark background.
pub fn write_contact_sheet(path: &Path, frames: &[&Frame]) -> Result<(), RenderError> {
    let thumbs: Vec<image::RgbaImage> = frames
        .iter()
        .filter_map(|f| image::RgbaImage::from_raw(f.width, f.height, f.rgba.clone()))
        .map(|img| {
            let h = (SHEET_THUMB as u64 * img.height() as u64 / img.width().max(1) as u64).max(1);
            image::imageops::resize(&img, SHEET_THUMB, h as u32, image::imageops::Triangle)
        })
        .collect();
    let rows: Vec<&[image::RgbaImage]> = thumbs.chunks(SHEET_COLUMNS).collect();
    let row_h: Vec<u32> = rows
        .iter()
        .map(|r| r.iter().map(|t| t.height()).max().unwrap_or(0))
        .collect();
    let cols = thumbs.len().clamp(1, SHEET_COLUMNS) as u32;
    let w = cols * SHEET_THUMB + (cols + 1) * SHEET_GAP;
    let h = row_h.iter().sum::<u32>() + (rows.len() as u32 + 1) * SHEET_GAP;
    let mut sheet = image::RgbaImage::from_pixel(w, h.max(1), image::Rgba([24, 24, 28, 255]));
    let mut y = SHEET_GAP;
    for (row, rh) in rows.iter().zip(&row_h) {
        for (c, t) in row.iter().enumerate() {
            let x = SHEET_GAP + c as u32 * (SHEET_THUMB + SHEET_GAP);
            image::imageops::overlay(&mut sheet, t, x as i64, y as i64);
        }
        y += rh + SHEET_GAP;
    }
    Ok(write_rgba_png(
        path,
        sheet.width(),
        sheet.height(),
        sheet.as_raw(),
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trips_and_budget_refuses_huge_frames() {
        let dir = tempfile::tempdir().unwrap();
        let f = Frame::new(
            3,
            2,
            (0..24).map(|i| i as u8 * 10).collect(),
            vec![1.0, f32::INFINITY, 2.0, 3.0, f32::INFINITY, 4.0],
            vec![1, 2, 3, 4, 5, 6],
        );
        assert_eq!(f.hits(), 4);
        let p = dir.path().join("a.png");
        f.write_png(&p).unwrap();
        let back = image::open(&p).unwrap().to_rgba8();
        assert_eq!(back.dimensions(), (3, 2));
        assert_eq!(back.as_raw(), &f.rgba);
        let cost = f.cost_rgba();
        assert_eq!(&cost[20..24], &[255, 255, 255, 255], "max steps is white");
        assert!(Frame::check_budget(40_000, 40_000, 1 << 30).is_err());
        assert!(Frame::check_budget(500, 500, 1 << 30).is_ok());
    }

    #[test]
    fn contact_sheets_tile_their_frames_in_order() {
        let dir = tempfile::tempdir().unwrap();
        let solid = |v: u8, w: u32, h: u32| {
            let n = (w * h) as usize;
            Frame::new(w, h, [v, v, v, 255].repeat(n), vec![0.0; n], vec![0; n])
        };
        let (a, b, c, d) = (
            solid(200, 960, 540),
            solid(100, 480, 270),
            solid(50, 480, 270),
            solid(250, 960, 540),
        );
        let p = dir.path().join("sheet.png");
        write_contact_sheet(&p, &[&a, &b, &c, &d]).unwrap();
        let s = image::open(&p).unwrap().to_rgba8();
        assert_eq!(s.width(), 3 * SHEET_THUMB + 4 * SHEET_GAP);
        assert_eq!(s.height(), 2 * 270 + 3 * SHEET_GAP);
        let at = |col: u32, row: u32| {
            s.get_pixel(
                SHEET_GAP + col * (SHEET_THUMB + SHEET_GAP) + 10,
                SHEET_GAP + row * (270 + SHEET_GAP) + 10,
            )[0]
        };
        assert_eq!(
            [at(0, 0), at(1, 0), at(2, 0), at(0, 1)],
            [200, 100, 50, 250]
        );
    }
}

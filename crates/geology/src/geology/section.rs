//! Vertical cuts through a geology (`karstic geology section`), drawn as in
//! Paris et al. 2019 Fig. 4: pale where the rock resists, dark where it is soft, with the
//! terrain's outline and its air when a field is given.

use std::path::Path;

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use thiserror::Error;

use super::Geology;
use crate::field::{Field, ISO};
use crate::io::check_budget;

/// Colour of the softest rock (`ρ = 0`), sRGB.
pub const SOFT: [u8; 3] = [72, 46, 32];
/// Colour of the hardest rock (`ρ = 1`), sRGB.
pub const HARD: [u8; 3] = [238, 228, 204];
/// Colour of the air above (outside) the terrain, sRGB.
pub const AIR: [u8; 3] = [178, 204, 228];
/// Colour of the terrain's outline, sRGB.
pub const OUTLINE: [u8; 3] = [200, 30, 30];

/// Bytes per pixel while drawing (RGBA plus the inside/outside flags and the PNG buffer).
const BYTES_PER_PIXEL: u64 = 4 + 1 + 4;

/// Why a section cannot be drawn or written.
#[derive(Debug, Error)]
pub enum SectionError {
    /// The two ends of the cut are the same point.
    #[error("the section's two ends are the same point {0}: give two distinct points")]
    Degenerate(Vec2),
    /// The altitude range is empty or not finite.
    #[error("the section's altitude range {0} .. {1} is empty: give zmin < zmax")]
    Altitudes(f32, f32),
    /// The image size is zero.
    #[error("the section image must be at least 1 × 1 pixels, found {0} × {1}")]
    Size(u32, u32),
    /// Over the memory budget.
    #[error(transparent)]
    Budget(#[from] crate::io::IoError),
    /// The PNG could not be written.
    #[error("cannot write {path}: {message}")]
    Write {
        /// The output.
        path: std::path::PathBuf,
        /// Why.
        message: String,
    },
}

/// A vertical cut: the segment `from → to` of the map, between altitudes `z.0` and `z.1`,
/// drawn on `width × height` pixels (the first row the highest).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Section {
    from: Vec2,
    to: Vec2,
    z: (f32, f32),
    width: u32,
    height: u32,
}

impl Section {
    /// A cut from `from` to `to` between `z.0 < z.1`, on `width × height` pixels, within
    /// `budget` bytes.
    pub fn new(
        from: Vec2,
        to: Vec2,
        z: (f32, f32),
        (width, height): (u32, u32),
        budget: u64,
    ) -> Result<Self, SectionError> {
        if !(from.distance(to) > 0.0) || !from.is_finite() || !to.is_finite() {
            return Err(SectionError::Degenerate(from));
        }
        if !(z.0 < z.1) || !z.0.is_finite() || !z.1.is_finite() {
            return Err(SectionError::Altitudes(z.0, z.1));
        }
        if width == 0 || height == 0 {
            return Err(SectionError::Size(width, height));
        }
        let need = width as u64 * height as u64 * BYTES_PER_PIXEL;
        check_budget(format!("a {width} × {height} section"), need, budget)?;
        Ok(Section {
            from,
            to,
            z,
            width,
            height,
        })
    }

    /// Width and height in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The point at the centre of pixel `(i, j)` (column, row from the top).
    pub fn point(&self, i: u32, j: u32) -> Vec3 {
        let u = (i as f32 + 0.5) / self.width as f32;
        let v = (j as f32 + 0.5) / self.height as f32;
        self.from
            .lerp(self.to, u)
            .extend(self.z.1 + (self.z.0 - self.z.1) * v)
    }

    /// The colour of resistance `rho`: [`SOFT`] to [`HARD`].
    pub fn rock_colour(rho: f32) -> [u8; 3] {
        let t = rho.clamp(0.0, 1.0);
        std::array::from_fn(|k| {
            (SOFT[k] as f32 + (HARD[k] as f32 - SOFT[k] as f32) * t).round() as u8
        })
    }

    /// The cut as RGBA8, row-major from the top-left pixel: the rock's resistance; with
    /// `terrain`, its air ([`AIR`], where `f ≤ T`) and its outline ([`OUTLINE`], pixels
    /// whose right or lower neighbour lies on the other side of the surface).
    pub fn draw(&self, geology: &Geology, terrain: Option<&dyn Field>) -> Vec<u8> {
        let (w, h) = (self.width as usize, self.height as usize);
        let solid: Vec<bool> = match terrain {
            Some(f) => (0..w * h)
                .into_par_iter()
                .map(|k| f.value(self.point((k % w) as u32, (k / w) as u32)) > ISO)
                .collect(),
            None => vec![true; w * h],
        };
        let mut rgba = vec![0u8; 4 * w * h];
        rgba.par_chunks_mut(4 * w).enumerate().for_each(|(j, row)| {
            for (i, px) in row.chunks_mut(4).enumerate() {
                let k = i + w * j;
                let edge = (i + 1 < w && solid[k + 1] != solid[k])
                    || (j + 1 < h && solid[k + w] != solid[k]);
                let c = if terrain.is_some() && edge {
                    OUTLINE
                } else if solid[k] {
                    Section::rock_colour(geology.value(self.point(i as u32, j as u32)))
                } else {
                    AIR
                };
                px.copy_from_slice(&[c[0], c[1], c[2], 255]);
            }
        });
        rgba
    }

    /// Draws the cut (see [`Section::draw`]) and writes it as a PNG, atomically.
    pub fn write_png(
        &self,
        path: &Path,
        geology: &Geology,
        terrain: Option<&dyn Field>,
    ) -> Result<(), SectionError> {
        let rgba = self.draw(geology, terrain);
        crate::io::write_rgba_png(path, self.width, self.height, &rgba).map_err(|e| {
            SectionError::Write {
                path: path.to_path_buf(),
                message: e.to_string(),
            }
        })
    }
}

//! Texture masks over the DEM frame — slope, rock, cave/overhang and flow accumulation —
//! as 8-bit grey PNGs: the splat maps that landscape tools feed to game engines. Their
//! rectangle is the one the exported meshes' UVs span ([`super::texture_frame`]), their
//! first row the northern one (glTF's `v = 0`).
//!
//! * **slope**: the angle of the top surface's normal from vertical, 0 (flat) to 255
//!   (vertical or overhanging), linear in degrees.
//! * **rock**: the material model's bare-rock cover ([`Materials::cover`]) at the top
//!   surface, the rock the preview and the vertex colours show.
//! * **cave**: 255 where the vertical line meets solid over empty space (a cave's roof,
//!   an arch, an overhang: [`Column::solid_runs`] ≥ 2); elsewhere how far the top surface
//!   departs from the terrain heightfield, on the materials' feature scale (a portal cut
//!   into a slope).
//! * **flow**: drainage area of the terrain heightfield (of the top surface without one)
//!   after depression filling ([`super::flow`]), `ln(A / a) / ln(A_max / a)` for a pixel
//!   of area `a`, so channels show at every scale.
//! * **talus**, **deposit**, **wear**: the traces of the terrain's eroded amplification
//!   ([`crate::erosion::amplify`]), 0 without one: the thickness of talus and of
//!   sediment on the ground (255 = [`LOOSE_FULL`] metres or more) and how deep running
//!   water cut below the DEM (255 = [`WEAR_FULL`] metres or more).

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use image::ImageEncoder;
use image::codecs::png::PngEncoder;
use rayon::prelude::*;

use super::column::{Column, ColumnProbe};
use super::flow::{drainage_area, fill_depressions};
use crate::dem::{Heightfield, Trace};
use crate::field::{Field, Rect, Tree};
use crate::io::{IoError, check_budget, write_atomic, write_bytes_atomic};
use crate::render::Materials;
use crate::render::material::smoothstep;

/// Errors while computing or writing masks.
#[derive(Debug, thiserror::Error)]
pub enum MaskError {
    /// The raster is empty, too large, or its cell size is not positive.
    #[error("texture masks: {0}")]
    Size(String),
    /// Over the memory budget, or writing failed.
    #[error(transparent)]
    Io(#[from] IoError),
    /// PNG encoding failed.
    #[error("cannot encode {path}")]
    Encode {
        /// The PNG.
        path: PathBuf,
        /// Why.
        #[source]
        source: image::ImageError,
    },
}

/// Thickness of talus or sediment that a mask shows as 255, metres.
pub const LOOSE_FULL: f32 = 2.0;

/// Depth of cutting below the DEM that the wear mask shows as 255, metres.
pub const WEAR_FULL: f32 = 4.0;

/// Pixels per side at most.
pub const MAX_SIDE: usize = 32_768;

/// Bytes of working memory per pixel (the seven masks, the column, the flow grids).
const BYTES_PER_PIXEL: u64 = 60;

/// The pixels of the masks: `nx × ny` cells over `frame`, pixel `(i, j)` (`j = 0` the
/// southern row) centred at `frame.min + (i + ½, j + ½)·pixel`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Raster {
    /// The rectangle the masks cover (tree frame, metres).
    pub frame: Rect,
    /// Pixels along x.
    pub nx: usize,
    /// Pixels along y.
    pub ny: usize,
}

impl Raster {
    /// Pixels of about `cell` metres over `frame` (at least 2 × 2), within `budget`
    /// bytes of working memory.
    pub fn new(frame: Rect, cell: f32, budget: u64) -> Result<Raster, MaskError> {
        if !(cell.is_finite() && cell > 0.0) {
            return Err(MaskError::Size(format!(
                "the cell size must be > 0, got {cell}"
            )));
        }
        let size = frame.max - frame.min;
        if !(size.x > 0.0 && size.y > 0.0 && size.is_finite()) {
            return Err(MaskError::Size(format!(
                "the frame {:?}..{:?} is empty",
                frame.min, frame.max
            )));
        }
        let side = |s: f32| (f64::from(s) / f64::from(cell)).round().max(2.0);
        let (sx, sy) = (side(size.x), side(size.y));
        if sx > MAX_SIDE as f64 || sy > MAX_SIDE as f64 {
            return Err(MaskError::Size(format!(
                "{sx} × {sy} pixels at {cell} m: at most {MAX_SIDE} per side"
            )));
        }
        let (nx, ny) = (sx as usize, sy as usize);
        check_budget(
            format!("texture masks of {nx} × {ny} pixels"),
            nx as u64 * ny as u64 * BYTES_PER_PIXEL,
            budget,
        )?;
        Ok(Raster { frame, nx, ny })
    }

    /// The size of a pixel (metres).
    pub fn pixel(&self) -> Vec2 {
        (self.frame.max - self.frame.min) / Vec2::new(self.nx as f32, self.ny as f32)
    }

    /// The centre of pixel `(i, j)`.
    pub fn center(&self, i: usize, j: usize) -> Vec2 {
        self.frame.min + (Vec2::new(i as f32, j as f32) + 0.5) * self.pixel()
    }

    /// The pixel holding `xy`, `None` outside the frame.
    pub fn pixel_at(&self, xy: Vec2) -> Option<(usize, usize)> {
        let f = (xy - self.frame.min) / self.pixel();
        let (i, j) = (f.x.floor(), f.y.floor());
        (i >= 0.0 && j >= 0.0 && (i as usize) < self.nx && (j as usize) < self.ny)
            .then_some((i as usize, j as usize))
    }
}

/// The mask layers, in the order [`Masks::layers`] lists them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layer {
    /// Slope of the top surface.
    Slope,
    /// Bare rock.
    Rock,
    /// Caves and overhangs.
    Cave,
    /// Flow accumulation.
    Flow,
    /// Talus of the eroded amplification.
    Talus,
    /// Sediment of the eroded amplification.
    Deposit,
    /// Cutting by running water in the eroded amplification.
    Wear,
}

impl Layer {
    /// Every layer.
    pub const ALL: [Layer; 7] = [
        Layer::Slope,
        Layer::Rock,
        Layer::Cave,
        Layer::Flow,
        Layer::Talus,
        Layer::Deposit,
        Layer::Wear,
    ];

    /// The layer's name, the suffix of its file.
    pub fn name(self) -> &'static str {
        match self {
            Layer::Slope => "slope",
            Layer::Rock => "rock",
            Layer::Cave => "cave",
            Layer::Flow => "flow",
            Layer::Talus => "talus",
            Layer::Deposit => "deposit",
            Layer::Wear => "wear",
        }
    }
}

/// The masks over a raster, each value in `[0, 1]`, row-major from the south
/// (`v[i + nx·j]`).
#[derive(Clone, Debug)]
pub struct Masks {
    /// Their pixels.
    pub raster: Raster,
    /// Slope from vertical over 90°.
    pub slope: Vec<f32>,
    /// Bare-rock cover.
    pub rock: Vec<f32>,
    /// Caves and overhangs.
    pub cave: Vec<f32>,
    /// Log-scaled drainage area.
    pub flow: Vec<f32>,
    /// Talus thickness over [`LOOSE_FULL`].
    pub talus: Vec<f32>,
    /// Sediment thickness over [`LOOSE_FULL`].
    pub deposit: Vec<f32>,
    /// Depth cut below the DEM over [`WEAR_FULL`].
    pub wear: Vec<f32>,
}

/// What one pixel's column holds.
#[derive(Clone, Copy)]
struct Pixel {
    top: f32,
    slope: f32,
    rock: f32,
    cave: f32,
}

impl Masks {
    /// The masks of `tree` over `raster`, with `materials` (and its terrain) for the rock
    /// cover, the feature scale and the flow. Rows run in parallel; the result does not
    /// depend on the thread count.
    pub fn compute(tree: &Tree, materials: &Materials, raster: &Raster) -> Masks {
        let px = raster.pixel();
        // Steps along the columns: a pixel, and fine enough for the tree's height (voids
        // thinner than that may be missed, as they would be between the pixels).
        let min_step = px.min_element().min(tree.support().size().z / 512.0);
        let pixels: Vec<Pixel> = (0..raster.ny)
            .into_par_iter()
            .flat_map_iter(|j| {
                let mut probe = ColumnProbe::new(tree, min_step);
                (0..raster.nx)
                    .map(|i| pixel(tree, materials, &mut probe, raster.center(i, j)))
                    .collect::<Vec<_>>()
            })
            .collect();
        let flow = flow_mask(materials, raster, &pixels);
        let inset = materials.ground.as_ref().and_then(|g| g.inset());
        let trace = |t: Trace, full: f32| -> Vec<f32> {
            (0..raster.nx * raster.ny)
                .map(|k| {
                    let xy = raster.center(k % raster.nx, k / raster.nx);
                    inset.map_or(0.0, |i| (i.trace_at(t, xy) / full).clamp(0.0, 1.0))
                })
                .collect()
        };
        Masks {
            raster: *raster,
            slope: pixels.iter().map(|p| p.slope).collect(),
            rock: pixels.iter().map(|p| p.rock).collect(),
            cave: pixels.iter().map(|p| p.cave).collect(),
            flow,
            talus: trace(Trace::Talus, LOOSE_FULL),
            deposit: trace(Trace::Deposit, LOOSE_FULL),
            wear: trace(Trace::Incision, WEAR_FULL),
        }
    }

    /// The values of `layer`.
    pub fn layer(&self, layer: Layer) -> &[f32] {
        match layer {
            Layer::Slope => &self.slope,
            Layer::Rock => &self.rock,
            Layer::Cave => &self.cave,
            Layer::Flow => &self.flow,
            Layer::Talus => &self.talus,
            Layer::Deposit => &self.deposit,
            Layer::Wear => &self.wear,
        }
    }

    /// The value of `layer` at the pixel holding `xy` (`None` outside the frame).
    pub fn at(&self, layer: Layer, xy: Vec2) -> Option<f32> {
        let (i, j) = self.raster.pixel_at(xy)?;
        Some(self.layer(layer)[i + self.raster.nx * j])
    }

    /// The files [`Masks::write`] writes into `dir` for `stem`: a PNG per layer
    /// (`STEM_slope.png`, …) and the sidecar `STEM_masks.json`.
    pub fn files(dir: &Path, stem: &str) -> Vec<PathBuf> {
        Layer::ALL
            .iter()
            .map(|l| dir.join(format!("{stem}_{}.png", l.name())))
            .chain([dir.join(format!("{stem}_masks.json"))])
            .collect()
    }

    /// Writes each layer as an 8-bit grey PNG (first row north), and a JSON sidecar with
    /// the frame and the encodings, atomically; returns the files, as [`Masks::files`].
    pub fn write(&self, dir: &Path, stem: &str) -> Result<Vec<PathBuf>, MaskError> {
        let files = Masks::files(dir, stem);
        let (nx, ny) = (self.raster.nx, self.raster.ny);
        for (layer, path) in Layer::ALL.iter().zip(&files) {
            let v = self.layer(*layer);
            let grey: Vec<u8> = (0..ny)
                .rev()
                .flat_map(|j| &v[nx * j..nx * (j + 1)])
                .map(|&x| (x.clamp(0.0, 1.0) * 255.0).round() as u8)
                .collect();
            let mut bytes = Vec::new();
            PngEncoder::new(&mut bytes)
                .write_image(&grey, nx as u32, ny as u32, image::ExtendedColorType::L8)
                .map_err(|source| MaskError::Encode {
                    path: path.clone(),
                    source,
                })?;
            write_bytes_atomic(path, &bytes)?;
        }
        let f = &self.raster.frame;
        let sidecar = serde_json::json!({
            "frame": [f.min.x, f.min.y, f.max.x, f.max.y],
            "pixels": [nx, ny],
            "first_row": "north",
            "slope": "angle from vertical, 0 = flat, 255 = 90 degrees or overhanging",
            "rock": "bare-rock cover of the material model, 0..255",
            "cave": "255 = solid over empty space (cave, arch, overhang); below: the top surface's departure from the terrain",
            "flow": "ln(drainage area / pixel area) / ln(max / pixel area), 0..255",
            "talus": format!("talus thickness of the eroded amplification, 255 = {LOOSE_FULL} m or more"),
            "deposit": format!("sediment thickness of the eroded amplification, 255 = {LOOSE_FULL} m or more"),
            "wear": format!("depth cut below the DEM by the eroded amplification, 255 = {WEAR_FULL} m or more"),
        });
        let json = files.last().expect("the sidecar");
        write_atomic(json, |w| {
            serde_json::to_writer_pretty(&mut *w, &sidecar).map_err(std::io::Error::other)?;
            writeln!(w)
        })?;
        Ok(files)
    }
}

/// The column at `xy` and the masks it gives.
fn pixel(tree: &Tree, materials: &Materials, probe: &mut ColumnProbe, xy: Vec2) -> Pixel {
    let Column { top, solid_runs } = probe.probe(xy);
    let Some(top) = top else {
        return Pixel {
            top: f32::NAN,
            slope: 0.0,
            rock: 0.0,
            cave: 0.0,
        };
    };
    let p = Vec3::new(xy.x, xy.y, top);
    let g = tree.value_grad(p).1;
    // Solid where f > T: the outward normal is −∇f.
    let n = (-g).try_normalize().unwrap_or(Vec3::Z);
    let slope = n.z.clamp(-1.0, 1.0).acos() / std::f32::consts::FRAC_PI_2;
    let (d0, d1) = materials.feature_depth;
    let cave = if solid_runs >= 2 {
        1.0
    } else {
        smoothstep(d0, d1, materials.off_ground(p).abs())
    };
    Pixel {
        top,
        slope: slope.min(1.0),
        rock: materials.cover(p, n).rock,
        cave,
    }
}

/// The flow mask: drainage over the terrain sampled at the pixel centres (the top
/// surface without a terrain).
fn flow_mask(materials: &Materials, raster: &Raster, pixels: &[Pixel]) -> Vec<f32> {
    let z: Vec<f32> = match &materials.ground {
        Some(g) => (0..raster.nx * raster.ny)
            .map(|k| g.height(raster.center(k % raster.nx, k / raster.nx)))
            .collect(),
        None => pixels.iter().map(|p| p.top).collect(),
    };
    let px = raster.pixel();
    let Ok(hf) = Heightfield::new(raster.nx, raster.ny, raster.center(0, 0), px, z) else {
        return vec![0.0; pixels.len()];
    };
    let area = drainage_area(&fill_depressions(&hf));
    let a = px.x * px.y;
    let max = area.iter().copied().fold(0.0f32, f32::max);
    if max <= a {
        return vec![0.0; area.len()];
    }
    let scale = 1.0 / (max / a).ln();
    area.iter()
        .map(|&x| {
            if x > 0.0 {
                ((x / a).ln() * scale).max(0.0)
            } else {
                0.0
            }
        })
        .collect()
}

//! The CPU renderer: square tiles traced in parallel with rayon.
//!
//! Every pixel depends only on its own ray, so the output is identical whatever the
//! number of threads.

use indicatif::ProgressBar;
use rayon::prelude::*;

use super::camera::{Camera, Ray};
use super::image::Frame;
use super::shade::{Shading, to_srgb8};
use super::trace::{Method, Trace, TraceParams, normal, occluded, trace};
use crate::field::{Aabb, Field};

/// Side of the square tiles handed to rayon, pixels.
pub const TILE: u32 = 16;

/// How to trace and shade.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// Primary-ray tracing parameters (shadow rays use the same ones).
    pub trace: TraceParams,
    /// Lighting and materials.
    pub shading: Shading,
}

impl RenderSettings {
    /// Defaults for rendering `support` through `camera` with `method`.
    pub fn for_scene(support: &Aabb, camera: &Camera, method: Method) -> Self {
        RenderSettings {
            trace: TraceParams::for_scene(method, 2.0 * support.radius())
                .with_pixel_angle(camera.pixel_angle()),
            shading: Shading::for_scene(support),
        }
    }
}

/// What one pixel produced.
#[derive(Clone, Copy)]
struct Pixel {
    rgba: [u8; 4],
    trace: Trace,
}

/// Renders `field` through `camera`; `progress` advances by one per tile.
pub fn render(
    field: &dyn Field,
    camera: &Camera,
    settings: &RenderSettings,
    progress: &ProgressBar,
) -> Frame {
    let (w, h) = (camera.width, camera.height);
    let (tx, ty) = (w.div_ceil(TILE), h.div_ceil(TILE));
    let support = field.support();
    let tiles: Vec<Vec<Pixel>> = (0..tx * ty)
        .into_par_iter()
        .map(|k| {
            let (x0, y0) = ((k % tx) * TILE, (k / tx) * TILE);
            let mut out = Vec::with_capacity((TILE * TILE) as usize);
            for j in y0..(y0 + TILE).min(h) {
                for i in x0..(x0 + TILE).min(w) {
                    out.push(pixel(field, &support, camera.pixel_ray(i, j), settings));
                }
            }
            progress.inc(1);
            out
        })
        .collect();
    let n = w as usize * h as usize;
    let (mut rgba, mut depth, mut steps) = (vec![0u8; 4 * n], vec![0f32; n], vec![0u32; n]);
    for (k, tile) in tiles.iter().enumerate() {
        let k = k as u32;
        let (x0, y0) = ((k % tx) * TILE, (k / tx) * TILE);
        let tw = (x0 + TILE).min(w) - x0;
        for (q, px) in tile.iter().enumerate() {
            let (i, j) = (x0 + q as u32 % tw, y0 + q as u32 / tw);
            let at = (i + j * w) as usize;
            rgba[4 * at..4 * at + 4].copy_from_slice(&px.rgba);
            depth[at] = px.trace.t;
            steps[at] = px.trace.steps;
        }
    }
    progress.finish_and_clear();
    Frame::new(w, h, rgba, depth, steps)
}

/// Traces and shades one primary ray.
fn pixel(field: &dyn Field, support: &Aabb, ray: Ray, s: &RenderSettings) -> Pixel {
    let sh = &s.shading;
    let Some(span) = ray.clip(support) else {
        return Pixel {
            rgba: to_srgb8(sh.sky(ray.dir)),
            trace: Trace {
                t: f32::INFINITY,
                steps: 0,
            },
        };
    };
    let tr = trace(field, &ray, span, &s.trace);
    if !tr.hit() {
        return Pixel {
            rgba: to_srgb8(sh.sky(ray.dir)),
            trace: tr,
        };
    }
    let p = ray.at(tr.t);
    let n = normal(field, p);
    let lit = if sh.shadows && n.dot(sh.sun) > 0.0 {
        let tol = s.trace.epsilon + s.trace.cone * tr.t;
        let shadow = Ray {
            origin: p + n * (2.0 * tol),
            dir: sh.sun,
        };
        match shadow.clip(support) {
            Some(span) if occluded(field, &shadow, span, &s.trace) => 0.0,
            _ => 1.0,
        }
    } else {
        1.0
    };
    Pixel {
        rgba: to_srgb8(sh.surface(p, n, tr.t, lit)),
        trace: tr,
    }
}

/// The depth image of `field` alone (no shading): ray parameters of the hits, `∞` for
/// misses, with the steps spent. Used to compare tracers and ground truths.
pub fn depth(field: &dyn Field, camera: &Camera, params: &TraceParams) -> (Vec<f32>, Vec<u32>) {
    let support = field.support();
    let w = camera.width;
    (0..w * camera.height)
        .into_par_iter()
        .map(|k| {
            let ray = camera.pixel_ray(k % w, k / w);
            match ray.clip(&support) {
                Some(span) => {
                    let tr = trace(field, &ray, span, params);
                    (tr.t, tr.steps)
                }
                None => (f32::INFINITY, 0),
            }
        })
        .unzip()
}

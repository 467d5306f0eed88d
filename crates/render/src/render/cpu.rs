//! The CPU renderer: square tiles traced in parallel with rayon.
//!
//! Every pixel depends only on its own ray, so the output is identical whatever the
//! number of threads.

use indicatif::ProgressBar;
use rayon::prelude::*;

use super::camera::{Camera, Ray};
use super::guide::Guide;
use super::image::Frame;
use super::material::Materials;
use super::shade::{
    AO_SAMPLES, CAVE_DIRS, CAVE_STEPS, Shading, ambient_occlusion, ao_cap, cave_closed, cave_sky,
    from_srgb8, to_srgb8,
};
use super::trace::{Method, Trace, TraceParams, Tracer, outward};
use super::vegetation::{PlantHit, Vegetation};
use glam::Vec3;

use std::sync::Arc;

use crate::field::{Aabb, Field, ISO, Tree};

/// Side of the square tiles handed to rayon, pixels.
pub const TILE: u32 = 16;

/// How to trace and shade.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    /// Primary-ray tracing parameters (shadow rays use the same ones).
    pub trace: TraceParams,
    /// Lighting and atmosphere.
    pub shading: Shading,
    /// Surface materials.
    pub materials: Materials,
    /// Meshed regions, finest first, whose meshes guide the march inside them
    /// ([`Guide`]): set when the picture is of regions already meshed.
    pub guides: Vec<Arc<Guide>>,
    /// Whether [`render`] supersamples the pixels at edges ([`antialias`]): silhouettes,
    /// shadow edges and material boundaries. Off by default; the pictures' setup turns
    /// it on (the GPU path does not supersample; the editor supersamples its refined
    /// image last).
    pub antialias: bool,
    /// Trees and shrubs drawn beside the field ([`Vegetation`]); `None`: bare ground.
    pub vegetation: Option<Arc<Vegetation>>,
}

impl RenderSettings {
    /// Defaults for rendering `support` through `camera` with `method`, without a terrain
    /// (materials by slope alone).
    pub fn for_scene(support: &Aabb, camera: &Camera, method: Method) -> Self {
        RenderSettings {
            trace: TraceParams::for_scene(method, 2.0 * support.radius())
                .with_pixel_angle(camera.pixel_angle()),
            shading: Shading::for_scene(support),
            materials: Materials::for_scene(support, None),
            guides: Vec::new(),
            antialias: false,
            vegetation: None,
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
///
/// Each tile traces its primary rays through `field` pruned to the box of their
/// segments ([`Field::prune`]: children that cannot matter there are dropped, so every
/// evaluation is cheaper), and its shadow rays through `field` pruned to theirs. Pruning
/// is exact, so the image is the one the whole tree gives.
pub fn render(
    field: &dyn Field,
    camera: &Camera,
    settings: &RenderSettings,
    progress: &ProgressBar,
) -> Frame {
    let n = camera.width as usize * camera.height as usize;
    let mut frame = Frame::new(
        camera.width,
        camera.height,
        vec![0u8; 4 * n],
        vec![0f32; n],
        vec![0u32; n],
    );
    let bands = Bands {
        rows: camera.height.div_ceil(TILE),
        first: None,
        progress,
        stop: &|| false,
    };
    render_bands(field, camera, settings, &mut frame, &bands, &mut |_, _| {});
    if settings.antialias {
        antialias(field, camera, settings, &mut frame);
    }
    progress.finish_and_clear();
    frame
}

/// A pixel is an edge when a channel differs from a 4-neighbour's by more than this
/// (8-bit sRGB levels), or one of them hits the surface and the other does not.
pub const EDGE_CONTRAST: u8 = 64;

/// Sub-pixel samples an edge pixel takes, on a rotated grid, as offsets from its corner.
pub const SUBPIXELS: [(f32, f32); 4] = [
    (0.375, 0.125),
    (0.875, 0.375),
    (0.625, 0.875),
    (0.125, 0.625),
];

/// Adaptive supersampling: every edge pixel of `frame` ([`EDGE_CONTRAST`]) is traced
/// again at the [`SUBPIXELS`], each with its own point of the sun's disk, and takes the
/// mean of those and its first sample, in linear light. A pixel's depth and steps stay its
/// centre's. Silhouettes, shadow edges and material boundaries lose their stair steps and
/// penumbrae their dither, at the cost of about five samples on the edge pixels alone.
/// The edge pixels are traced tile by tile, in parallel; the result does not depend on
/// the number of threads.
pub fn antialias(field: &dyn Field, camera: &Camera, settings: &RenderSettings, frame: &mut Frame) {
    let (w, h) = (camera.width, camera.height);
    let support = field.support();
    let at = |i: u32, j: u32| (i + j * w) as usize;
    let edge = |i: u32, j: u32| {
        let k = at(i, j);
        let near = [(1i32, 0i32), (-1, 0), (0, 1), (0, -1)];
        near.iter().any(|&(di, dj)| {
            let (a, b) = (i as i32 + di, j as i32 + dj);
            if a < 0 || b < 0 || a >= w as i32 || b >= h as i32 {
                return false;
            }
            let m = at(a as u32, b as u32);
            frame.depth[k].is_finite() != frame.depth[m].is_finite()
                || (0..3)
                    .any(|c| frame.rgba[4 * k + c].abs_diff(frame.rgba[4 * m + c]) > EDGE_CONTRAST)
        })
    };
    let (tx, ty) = (w.div_ceil(TILE), h.div_ceil(TILE));
    let tiles: Vec<Vec<u32>> = (0..tx * ty)
        .map(|t| {
            let (x0, y0) = ((t % tx) * TILE, (t / tx) * TILE);
            (y0..(y0 + TILE).min(h))
                .flat_map(|j| (x0..(x0 + TILE).min(w)).map(move |i| (i, j)))
                .filter(|&(i, j)| edge(i, j))
                .map(|(i, j)| at(i, j) as u32)
                .collect()
        })
        .collect();
    let refined: Vec<Vec<(u32, [u8; 4])>> = tiles
        .par_iter()
        .map(|pixels| {
            if pixels.is_empty() {
                return Vec::new();
            }
            let rays: Vec<PixelRay> = pixels
                .iter()
                .flat_map(|&k| {
                    let (i, j) = (k % w, k / w);
                    SUBPIXELS.iter().enumerate().map(move |(q, &(dx, dy))| {
                        let ray = camera.ray(i as f32 + dx, j as f32 + dy);
                        // Its own point of the sun's disk: another pixel's of a grid
                        // twice as fine.
                        let sun = (2 * i + q as u32 % 2 + 2 * w, 2 * j + q as u32 / 2 + 2 * h);
                        (ray, ray.clip(&support), sun)
                    })
                })
                .collect();
            let samples = tile(field, &support, &rays, settings);
            pixels
                .iter()
                .zip(samples.chunks(SUBPIXELS.len()))
                .map(|(&k, sub)| {
                    let first = &frame.rgba[4 * k as usize..4 * k as usize + 4];
                    let mut sum = [0f32; 3];
                    for rgba in sub.iter().map(|p| &p.rgba[..]).chain([first]) {
                        for c in 0..3 {
                            sum[c] += from_srgb8(rgba[c]);
                        }
                    }
                    let n = (sub.len() + 1) as f32;
                    let mean = Vec3::from_array(sum) / n;
                    (k, to_srgb8(mean))
                })
                .collect()
        })
        .collect();
    for (k, rgba) in refined.into_iter().flatten() {
        let k = k as usize;
        frame.rgba[4 * k..4 * k + 3].copy_from_slice(&rgba[..3]);
    }
}

/// How [`render_bands`] goes through the image: bands of `rows` rows of tiles, top to
/// bottom (those that meet `first` before the others); `progress` advances by one per
/// tile; `stop` is asked before each tile (true: the rest of the image is not wanted).
pub struct Bands<'a> {
    /// Rows of tiles per band (at least 1).
    pub rows: u32,
    /// Image rows (pixels) to trace first: where an edit changed the picture, in the
    /// editor. `None`: from the top.
    pub first: Option<std::ops::Range<u32>>,
    /// Advanced by one per tile.
    pub progress: &'a ProgressBar,
    /// True when the image is no longer wanted.
    pub stop: &'a (dyn Fn() -> bool + Sync),
}

/// Renders `field` through `camera` into `frame` (of the camera's size) band by band, as
/// [`render`] does, calling `band_done(frame, rows)` after each band with the image rows
/// it filled (the rows not yet traced keep what `frame` held, e.g. an enlarged coarse
/// image). Returns false when `bands.stop` ended it early.
pub fn render_bands(
    field: &dyn Field,
    camera: &Camera,
    settings: &RenderSettings,
    frame: &mut Frame,
    bands: &Bands<'_>,
    band_done: &mut dyn FnMut(&Frame, std::ops::Range<u32>),
) -> bool {
    let (w, h) = (camera.width, camera.height);
    debug_assert_eq!((frame.width, frame.height), (w, h));
    let (tx, ty) = (w.div_ceil(TILE), h.div_ceil(TILE));
    let support = field.support();
    let per_band = bands.rows.max(1);
    // The image rows of the band of tile rows from `band`.
    let pixels = |band: u32| band * TILE..((band + per_band).min(ty) * TILE).min(h);
    let mut order: Vec<u32> = (0..ty).step_by(per_band as usize).collect();
    if let Some(first) = &bands.first {
        // Stable: the bands that meet `first` from the top, then the others.
        order.sort_by_key(|&band| {
            let r = pixels(band);
            !(r.start < first.end && first.start < r.end)
        });
    }
    for band in order {
        let rows = band..(band + per_band).min(ty);
        let tiles: Vec<Option<Vec<Pixel>>> = (rows.start * tx..rows.end * tx)
            .into_par_iter()
            .map(|k| {
                if (bands.stop)() {
                    return None;
                }
                let (x0, y0) = ((k % tx) * TILE, (k / tx) * TILE);
                let rays: Vec<PixelRay> = (y0..(y0 + TILE).min(h))
                    .flat_map(|j| (x0..(x0 + TILE).min(w)).map(move |i| (i, j)))
                    .map(|(i, j)| {
                        let ray = camera.pixel_ray(i, j);
                        (ray, ray.clip(&support), (i, j))
                    })
                    .collect();
                let out = tile(field, &support, &rays, settings);
                bands.progress.inc(1);
                Some(out)
            })
            .collect();
        for (k, tile) in (rows.start * tx..).zip(&tiles) {
            let Some(tile) = tile else { return false };
            let (x0, y0) = ((k % tx) * TILE, (k / tx) * TILE);
            let tw = (x0 + TILE).min(w) - x0;
            for (q, px) in tile.iter().enumerate() {
                let (i, j) = (x0 + q as u32 % tw, y0 + q as u32 / tw);
                let at = (i + j * w) as usize;
                frame.rgba[4 * at..4 * at + 4].copy_from_slice(&px.rgba);
                frame.depth[at] = px.trace.t;
                frame.steps[at] = px.trace.steps;
            }
        }
        band_done(frame, pixels(band));
    }
    true
}

/// The box of the segments `ray(t0)..ray(t1)` (each segment is the hull of its ends),
/// padded by a hair for rounding; `None` when there are none.
fn segments_box<'a>(segments: impl Iterator<Item = (&'a Ray, (f32, f32))>) -> Option<Aabb> {
    let b = segments.fold(Aabb::EMPTY, |b, (r, (t0, t1))| {
        b.union(Aabb::from_points([r.at(t0), r.at(t1)]))
    });
    (!b.is_empty()).then(|| b.dilate(1e-4 * b.radius() + 1e-6))
}

/// Trees with at most this many nodes are pruned per tile. Pruning copies the kept nodes
/// (and rebuilds blend BVHs), which pays for itself on small trees of costly leaves (a
/// DEM with a few carves: 3× cheaper evaluations) but not on large blends, whose BVH
/// already visits only the children near a point (1,000 blobs: 35% slower).
pub const PRUNE_MAX_NODES: usize = 64;

/// `field` restricted to `region`, when `field` is a small [`Tree`] (see
/// [`PRUNE_MAX_NODES`]); `None` to use `field` itself.
fn pruned<'f>(field: &'f dyn Field, region: Option<Aabb>) -> Option<Box<dyn Field + 'f>> {
    let small = field
        .as_any()
        .and_then(|a| a.downcast_ref::<Tree>())
        .is_some_and(|t| t.nodes().len() <= PRUNE_MAX_NODES);
    if !small {
        return None;
    }
    region.and_then(|r| field.prune(&r))
}

/// A ray and the span of it to trace.
type Segment = (Ray, (f32, f32));

/// What a primary ray met: its trace (the plant's distance when it met one), the outward
/// normal, the sky's share, its shadow ray, and the plant it met first if any.
type Hit = (Trace, Vec3, f32, Option<Segment>, Option<PlantHit>);

/// A primary ray, its span in the support, and its pixel.
type PixelRay = (Ray, Option<(f32, f32)>, (u32, u32));

/// Traces and shades the rays of one tile (row-major).
fn tile(field: &dyn Field, support: &Aabb, rays: &[PixelRay], s: &RenderSettings) -> Vec<Pixel> {
    let sh = &s.shading;
    let miss = Trace {
        t: f32::INFINITY,
        steps: 0,
    };
    // Occlusion samples reach `ao_radius` off the hits: the primary field must hold there.
    // (The cave-scale samples, on the few features' pixels, ask the whole field.)
    let primary = pruned(
        field,
        segments_box(rays.iter().filter_map(|(r, sp, _)| sp.map(|sp| (r, sp))))
            .map(|b| b.dilate(2.0 * sh.ao_radius)),
    );
    let f = primary.as_deref().unwrap_or(field);
    let start = beam_start(f, rays, &s.trace);
    let mut tracer = Tracer::new(f).with_guides(&s.guides);
    // Primary hits with their normals, sky occlusion and shadow rays; a plant in front of
    // the field's surface stands for it.
    let plants = s.vegetation.as_deref().filter(|v| !v.is_empty());
    let hits: Vec<Hit> = rays
        .iter()
        .map(|&(ref ray, span, (i, j))| {
            let Some(span) = span else {
                return (miss, Vec3::ZERO, 1.0, None, None);
            };
            let plant = plants.and_then(|v| v.hit(ray, span.1, s.trace.cone));
            let end = plant.map_or(span.1, |h| h.t);
            let mut tr = match start <= end {
                true => tracer.trace(ray, (span.0.max(start), end), &s.trace),
                false => miss,
            };
            let plant = plant.filter(|_| !tr.hit());
            let (p, n, ao) = match plant {
                Some(h) => {
                    tr.t = h.t;
                    (ray.at(h.t), h.n, h.ao)
                }
                None if tr.hit() => {
                    let p = ray.at(tr.t);
                    let g = tracer.gradient(ray, tr.t);
                    let n = outward(g);
                    let under = plants.map_or(1.0, |v| v.canopy(p));
                    let ao = occlusion(f, p, n, g.length(), sh)
                        * cave_light(field, p, n, s.materials.feature(p), sh)
                        * under;
                    (p, n, ao)
                }
                None => return (tr, Vec3::ZERO, 1.0, None, None),
            };
            let shadow = (sh.shadows && n.dot(sh.sun) > 0.0)
                .then(|| {
                    let tol = s.trace.epsilon + s.trace.cone * tr.t;
                    let shadow = Ray {
                        origin: p + n * (2.0 * tol),
                        dir: sh.sun_towards(i, j),
                    };
                    shadow.clip(support).map(|span| (shadow, span))
                })
                .flatten();
            (tr, n, ao, shadow, plant)
        })
        .collect();
    let shadow_field = pruned(
        field,
        segments_box(
            hits.iter()
                .filter_map(|(_, _, _, sr, _)| sr.as_ref().map(|(r, sp)| (r, *sp))),
        ),
    );
    let fs = shadow_field.as_deref().unwrap_or(field);
    let mut shadows = Tracer::new(fs).with_guides(&s.guides);
    rays.iter()
        .zip(hits)
        .map(|((ray, _, _), (tr, n, ao, shadow, plant))| {
            if !tr.hit() {
                let c = sh.seen(ray.origin, ray.dir, tr.t, Vec3::ZERO);
                return Pixel {
                    rgba: to_srgb8(sh.display(c)),
                    trace: tr,
                };
            }
            let lit = match shadow {
                Some((r, span))
                    if plants.is_some_and(|v| v.occludes(&r, span.1))
                        || shadows.occluded(&r, span, &shadow_params(&s.trace, tr.t)) =>
                {
                    0.0
                }
                _ => 1.0,
            };
            let p = ray.at(tr.t);
            let surface = match plant {
                Some(h) => h.albedo * sh.light(n, lit, ao),
                None => {
                    let look = s.materials.seen(p, n, s.trace.cone * tr.t);
                    let bed = sh.wetted(p, look.albedo) * sh.light(look.normal, lit, ao);
                    if look.stream > 0.0 {
                        bed.lerp(sh.stream(p, ray.dir, tr.t, bed), look.stream)
                    } else {
                        bed
                    }
                }
            };
            let c = sh.seen(ray.origin, ray.dir, tr.t, surface);
            Pixel {
                rgba: to_srgb8(sh.display(c)),
                trace: tr,
            }
        })
        .collect()
}

/// Candidate slabs of the beam pre-march stop shrinking below this fraction of the
/// slab box's width: thinner slabs of a wide beam gain nothing.
const BEAM_MIN_SLAB: f32 = 0.25;

/// The beam pre-march of a tile (Génevaux et al. 2015 §7.2's segment march, taken by the
/// tile's rays together): the parameter `t` before which every ray of `rays` is in the
/// air, proven by interval bounds of `field` over the box of the rays' segments
/// `[t, t + δ]` (each clamped to its ray's span); each ray may start there. Safe slabs
/// are crossed and the next candidate doubles, unsafe ones are retried four times
/// thinner until they are thinner than a quarter of their width. One interval query a
/// slab stands in for a value and a bound a ray. Returns `−∞` when the rays do not share
/// their origin (they are then traced from their spans' starts). Starting later moves
/// where a ray's steps fall, so a sliver of solid thinner along the ray than the march's
/// tolerance `ε + cone·t` (a grazed edge) may be stepped over where a march from the span's
/// start landed in it, or the reverse: the tolerance's contract, not a missed bound.
fn beam_start(field: &dyn Field, rays: &[PixelRay], params: &TraceParams) -> f32 {
    let spans: Vec<(&Ray, (f32, f32))> = rays
        .iter()
        .filter_map(|(r, sp, _)| sp.map(|sp| (r, sp)))
        .collect();
    let Some(&(first, _)) = spans.first() else {
        return f32::NEG_INFINITY;
    };
    if spans.len() < 2 || spans.iter().any(|(r, _)| r.origin != first.origin) {
        return f32::NEG_INFINITY;
    }
    let (mut t, end) = spans
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), (_, sp)| {
            (a.min(sp.0), b.max(sp.1))
        });
    let mut delta = (end - t) / 16.0;
    while t < end && params.max_steps > 0 {
        let next = (t + delta).min(end);
        let Some(b) = segments_box(
            spans
                .iter()
                .map(|&(r, sp)| (r, (t.max(sp.0), next.min(sp.1))))
                .filter(|(_, sp)| sp.0 <= sp.1),
        ) else {
            (t, delta) = (next, delta * 2.0);
            continue;
        };
        if field.interval(&b).hi < ISO {
            (t, delta) = (next, delta * 2.0);
            continue;
        }
        let width = (b.max - b.min).min_element();
        let floor = (BEAM_MIN_SLAB * width).max(params.epsilon + params.cone * t);
        if delta * 0.25 < floor {
            break;
        }
        delta *= 0.25;
    }
    t
}

/// The tracing parameters of a shadow ray from a hit at distance `t_hit`: its tolerance
/// starts at the pixel's footprint there, not at `ε` — finer shadow detail than the pixel
/// cannot show, and grazing shadow rays no longer crawl along the slope they leave. It
/// grows along the ray by the pixel's cone only: a thin sheet hides the sun's disk
/// whatever its thickness, so a tolerance grown by the penumbra would step through thin
/// roofs and arches (tried: 0.7 of the cave view's time, but a 1 m roof 30 m up lost its
/// shadow).
fn shadow_params(primary: &TraceParams, t_hit: f32) -> TraceParams {
    TraceParams {
        epsilon: primary.epsilon + primary.cone * t_hit,
        ..*primary
    }
}

/// The share of the sky seen from the surface point `p` with outward normal `n` and
/// gradient norm `slope` ([`super::shade`]): at each sample `q = p + δ n`, the drop
/// `T − f(q)` over the drop `slope·δ` open ground gives (1 there, less where a wall or a
/// roof keeps the field high). The expected drop is capped at the drop to the lowest
/// value sampled so far ([`ao_cap`]): a field that levels off in the air is open there,
/// one that rises again toward a wall is not.
fn occlusion(field: &dyn Field, p: Vec3, n: Vec3, slope: f32, sh: &Shading) -> f32 {
    if sh.ao_radius <= 0.0 || !(slope > 0.0) {
        return 1.0;
    }
    let mut lowest = 2.0 * ISO;
    ambient_occlusion((0..AO_SAMPLES).map(|k| {
        let d = sh.ao_step(k);
        let f = field.value(p + n * d);
        lowest = lowest.min(f);
        (ISO - f) / (slope * d).min(ao_cap(lowest))
    }))
}

/// The share of the sky light left at cave scale ([`super::shade`]) at the surface point
/// `p` with outward normal `n`, as much as `p` belongs to a feature (`feature`,
/// [`Materials::feature`]: the DEM's ground asks nothing): the bent normal's samples
/// first, the other directions only when it is not open.
fn cave_light(field: &dyn Field, p: Vec3, n: Vec3, feature: f32, sh: &Shading) -> f32 {
    if sh.cave_reach <= 0.0 || feature <= 0.0 {
        return 1.0;
    }
    let open = |dir: u32| {
        1.0 - (0..CAVE_STEPS)
            .map(|j| cave_closed(field.value(p + sh.cave_offset(n, dir * CAVE_STEPS + j))))
            .fold(0.0, f32::max)
    };
    let first = open(0);
    if first >= 1.0 {
        return 1.0;
    }
    let all = (first + (1..CAVE_DIRS).map(open).sum::<f32>()) / CAVE_DIRS as f32;
    1.0 + (cave_sky(first, all) - 1.0) * feature
}

/// The depth image of `field` alone (no shading): ray parameters of the hits, `∞` for
/// misses, with the steps spent. Used to compare tracers and ground truths.
pub fn depth(field: &dyn Field, camera: &Camera, params: &TraceParams) -> (Vec<f32>, Vec<u32>) {
    depth_guided(field, &[], camera, params)
}

/// [`depth`], following the meshes of `guides` inside their grids ([`Guide`]).
pub fn depth_guided(
    field: &dyn Field,
    guides: &[Arc<Guide>],
    camera: &Camera,
    params: &TraceParams,
) -> (Vec<f32>, Vec<u32>) {
    let support = field.support();
    let w = camera.width;
    (0..w * camera.height)
        .into_par_iter()
        .map_init(
            || Tracer::new(field).with_guides(guides),
            |tracer, k| {
                let ray = camera.pixel_ray(k % w, k / w);
                match ray.clip(&support) {
                    Some(span) => {
                        let tr = tracer.trace(&ray, span, params);
                        (tr.t, tr.steps)
                    }
                    None => (f32::INFINITY, 0),
                }
            },
        )
        .unzip()
}

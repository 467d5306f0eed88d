//! Framing: the box where a field's surface lies, and a close-up camera for each feature.
//!
//! * [`surface_box`]: the support box of a tree is the union of its primitives' compact
//!   supports, often far larger than the surface (an island's falloff reaches well beyond
//!   its rock). Interval bounds over an octree of the support keep only the cells where
//!   the surface can be, and their union frames the image.
//! * [`feature_view`]: a camera outside the terrain looking at a feature — into a
//!   tunnel's mouth, under an arch, at an overhang. Candidate eyes circle the feature's
//!   box; each renders a small depth image, scored by the feature's surface it sees
//!   (surface points in the box, away from the ground: [`Materials::feature`]; without a
//!   terrain, any surface in the box) and, worth more, by the pixels that see *under* the
//!   feature (through the arch, into the mouth). The camera then aims at the centre of
//!   what the best eye saw and moves in until that fills the frame.

use std::sync::Arc;

use glam::Vec3;

use super::RenderError;
use super::camera::Camera;
use super::cpu;
use super::guide::Guide;
use super::material::Materials;
use super::trace::{Method, TraceParams};
use crate::field::{Aabb, Field, ISO};

/// Octree levels [`surface_box`] descends (cells of 1/64 of the support per side).
pub const SURFACE_LEVELS: u32 = 6;

/// The box of the cells of an octree over `field`'s support (to [`SURFACE_LEVELS`]) whose
/// value intervals contain the iso-value and whose corners' values cross it: the surface,
/// sampled at 1/64 of the support. Falls back to the support when no cell does (a field
/// without a surface, or one thinner than the cells).
pub fn surface_box(field: &dyn Field) -> Aabb {
    fn rec(field: &dyn Field, b: Aabb, level: u32, out: &mut Aabb) {
        let iv = field.interval(&b);
        if !(iv.lo <= ISO && ISO <= iv.hi) {
            return;
        }
        if level == 0 {
            // Bounds are loose: keep the cell when its corners' values cross the surface.
            let v = b.corners().map(|c| field.value(c));
            let (lo, hi) = v
                .iter()
                .fold((f32::MAX, f32::MIN), |(l, h), &x| (l.min(x), h.max(x)));
            if lo <= ISO && ISO <= hi {
                *out = out.union(b);
            }
            return;
        }
        let c = b.center();
        for k in 0..8 {
            let pick = |bit: u32, lo: f32, mid: f32, hi: f32| {
                if k & bit == 0 { (lo, mid) } else { (mid, hi) }
            };
            let (x0, x1) = pick(1, b.min.x, c.x, b.max.x);
            let (y0, y1) = pick(2, b.min.y, c.y, b.max.y);
            let (z0, z1) = pick(4, b.min.z, c.z, b.max.z);
            let child = Aabb::new(Vec3::new(x0, y0, z0), Vec3::new(x1, y1, z1));
            // Skip children wholly inside what is already kept.
            if !(out.contains(child.min) && out.contains(child.max)) {
                rec(field, child, level - 1, out);
            }
        }
    }
    let support = field.support();
    if support.is_empty() || !(support.min.is_finite() && support.max.is_finite()) {
        return support;
    }
    let mut out = Aabb::EMPTY;
    rec(field, support, SURFACE_LEVELS, &mut out);
    if out.is_empty() { support } else { out }
}

/// The default view of `field`: a three-quarter view from the south-east that the
/// visible surface fills. [`Camera::frame`] of [`surface_box`] renders a small depth probe;
/// the camera then turns to the centre of what the probe hit, on the image, and moves
/// along its view until that fills 90% of the frame (framing the box alone left an
/// island's hidden underside and its falloff's margin empty in the image).
pub fn frame_surface(
    field: &dyn Field,
    fov_y: f32,
    width: u32,
    height: u32,
) -> Result<Camera, RenderError> {
    let first = Camera::frame(&surface_box(field), fov_y, width, height)?;
    let probe = Camera::look_at(
        first.eye,
        first.eye + first.basis().2,
        fov_y,
        PROBE_WIDTH,
        (PROBE_WIDTH * height / width).max(8),
    )?;
    let seen = hit_points(field, &probe);
    if seen.len() < MIN_FEATURE_PIXELS {
        return Ok(first);
    }
    let (eye, target) = fit(&probe, &seen, &seen, 0.0, 0.9);
    Camera::look_at(eye, target, fov_y, width, height)
}

/// Where to look from and at so that `points`, seen by `probe`, fill `fill` of its frame:
/// the view turns to the centre of their extent on the image (between the `q` and
/// `1 − q` quantiles on each axis, so a few stray points do not widen it) and moves along
/// itself, from the mean depth of `at` (where it should look: the points themselves, or
/// the mouth of what they line), until that extent fills the frame. Returns
/// `(eye, target)`; `points` and `at` are not empty.
fn fit(probe: &Camera, points: &[Vec3], at: &[Vec3], q: f32, fill: f32) -> (Vec3, Vec3) {
    let (right, up, forward, tan_v) = probe.basis();
    let tan_h = tan_v * probe.width as f32 / probe.height as f32;
    let (mut us, mut vs) = (Vec::new(), Vec::new());
    for p in points {
        let d = *p - probe.eye;
        let z = d.dot(forward);
        us.push(d.dot(right) / z);
        vs.push(d.dot(up) / z);
    }
    let depth = at
        .iter()
        .map(|p| (*p - probe.eye).dot(forward))
        .sum::<f32>()
        / at.len() as f32;
    let range = |v: &mut Vec<f32>| {
        v.sort_by(f32::total_cmp);
        let at = |x: f32| v[((v.len() - 1) as f32 * x).round() as usize];
        (at(q), at(1.0 - q))
    };
    let ((u0, u1), (v0, v1)) = (range(&mut us), range(&mut vs));
    let target = probe.eye + (forward + right * 0.5 * (u0 + u1) + up * 0.5 * (v0 + v1)) * depth;
    let need = ((u1 - u0) / (2.0 * tan_h)).max((v1 - v0) / (2.0 * tan_v)) / fill;
    let back = (probe.eye - target).normalize();
    (target + back * (depth * need.max(1e-3)), target)
}

/// Side of the square-ish probe images (pixels across) candidate views render.
const PROBE_WIDTH: u32 = 96;
/// Azimuths of the candidate eyes around a feature.
const AZIMUTHS: u32 = 8;
/// Elevations (degrees) of the candidate eyes above the feature's centre.
const ELEVATIONS: [f32; 2] = [6.0, 24.0];
/// Fewest feature pixels of a probe for a view to count.
const MIN_FEATURE_PIXELS: usize = 3;
/// What a pixel that sees *under* the feature (through an arch, into a tunnel's mouth,
/// beneath an overhang) is worth against one that sees its surface.
const UNDER_WEIGHT: usize = 4;
/// Share of a feature view's frame what its eye saw of the feature fills: the rest shows
/// the terrain it sits in.
const FRAME_FILL: f32 = 0.7;
/// Share of the seen points left out on each side of each image axis when framing them.
const FRAME_QUANTILE: f32 = 0.02;

/// A close-up of a feature whose surface lies in `feature` (a box), or `None` when no
/// candidate eye outside the terrain sees it (a chamber sealed in the rock).
///
/// Candidates are scored by what shows a feature *as 3D*: pixels that see under it
/// ([`Probe::under`]) count [`UNDER_WEIGHT`] times a pixel of its surface. Without that, a
/// thin arch seen end-on (a pillar of rock) out-scored the same arch seen across its
/// opening. A carve open to the sky (the main job's grotto) has few such pixels from any
/// eye and is still framed by its surface.
pub fn feature_view(
    field: &dyn Field,
    guides: &[Arc<Guide>],
    feature: &Aabb,
    materials: &Materials,
    fov_y: f32,
    (width, height): (u32, u32),
) -> Result<Option<Camera>, RenderError> {
    if feature.is_empty() || !(feature.min.is_finite() && feature.max.is_finite()) {
        return Ok(None);
    }
    let centre = feature.center();
    let reach = feature.radius().max(1.0);
    let probe_h = (PROBE_WIDTH * height / width).max(8);
    let mut best: Option<(usize, Camera, Probe)> = None;
    for e in ELEVATIONS {
        for a in 0..AZIMUTHS {
            let az = std::f32::consts::TAU * a as f32 / AZIMUTHS as f32;
            let (se, ce) = e.to_radians().sin_cos();
            let dir = Vec3::new(ce * az.cos(), ce * az.sin(), se);
            let eye = centre + dir * reach;
            if field.value(eye) >= ISO {
                continue;
            }
            let cam = Camera::look_at(eye, centre, fov_y, PROBE_WIDTH, probe_h)?;
            let seen = Probe::of(field, guides, &cam, feature, materials);
            let score = seen.surface.len() + UNDER_WEIGHT * seen.under.len();
            if seen.surface.len() + seen.under.len() >= MIN_FEATURE_PIXELS
                && best.as_ref().is_none_or(|b| score > b.0)
            {
                best = Some((score, cam, seen));
            }
        }
    }
    let Some((_, probe, seen)) = best else {
        return Ok(None);
    };
    // Aim at what the best eye saw, and come as close as frames it with its
    // surroundings; the distance is taken from where its rays pass under the feature
    // (a tunnel's mouth, not its far end), when they do.
    let points: Vec<Vec3> = seen.surface.iter().chain(&seen.under).copied().collect();
    let at = if seen.under.is_empty() {
        &seen.surface
    } else {
        &seen.under
    };
    let (eye, target) = fit(&probe, &points, at, FRAME_QUANTILE, FRAME_FILL);
    let eye = if field.value(eye) < ISO {
        eye
    } else {
        probe.eye
    };
    Camera::look_at(eye, target, fov_y, width, height).map(Some)
}

/// The depth image of `camera`'s rays (`∞` where a ray hits nothing), marched along
/// `guides` inside their grids.
fn depth_image(field: &dyn Field, guides: &[Arc<Guide>], camera: &Camera) -> Vec<f32> {
    let support = field.support();
    let params = TraceParams::for_scene(Method::Segment, 2.0 * support.radius())
        .with_pixel_angle(camera.pixel_angle());
    cpu::depth_guided(field, guides, camera, &params).0
}

/// The hit points of `camera`'s rays.
fn hit_points(field: &dyn Field, camera: &Camera) -> Vec<Vec3> {
    depth_image(field, &[], camera)
        .iter()
        .enumerate()
        .filter(|(_, t)| t.is_finite())
        .map(|(k, &t)| {
            let k = k as u32;
            camera.pixel_ray(k % camera.width, k / camera.width).at(t)
        })
        .collect()
}

/// What a probe image sees of a feature.
struct Probe {
    /// Hit points on the feature's surface (in its box, away from the ground).
    surface: Vec<Vec3>,
    /// For each pixel that sees *under* the feature, the point where its ray passes under:
    /// the nearest pixel above it in the image that is nearer by a margin lies in the
    /// feature's box and *above* the ray there (mostly in z, not beside it), so the ray
    /// goes on beneath solid — through an arch's opening, into a tunnel's mouth, under a
    /// grotto's roof. A heightfield seen from outside has none: below a surface point is
    /// rock, so no ray passes a step beneath it in the air.
    under: Vec<Vec3>,
}

impl Probe {
    fn of(
        field: &dyn Field,
        guides: &[Arc<Guide>],
        camera: &Camera,
        feature: &Aabb,
        m: &Materials,
    ) -> Self {
        let box_ = feature.dilate(0.02 * feature.radius());
        let margin = 0.05 * feature.radius();
        let depth = depth_image(field, guides, camera);
        let w = camera.width as usize;
        let ray = |k: usize| camera.pixel_ray((k % w) as u32, (k / w) as u32);
        let mut surface = Vec::new();
        let mut under = Vec::new();
        for (k, &t) in depth.iter().enumerate() {
            if t.is_finite() {
                let p = ray(k).at(t);
                if box_.contains(p) && (m.ground.is_none() || m.feature(p) >= 1.0) {
                    surface.push(p);
                }
            }
            // The first pixel above, in the same column, nearer by the margin.
            let above = (0..k / w)
                .rev()
                .map(|j| k % w + j * w)
                .find(|&kk| depth[kk] + margin < t);
            if let Some(kk) = above {
                let q = ray(kk).at(depth[kk]);
                let r = ray(k).at(depth[kk]);
                let d = q - r;
                if box_.contains(q) && box_.contains(r) && d.z > 0.7 * d.length() {
                    under.push(r);
                }
            }
        }
        Probe { surface, under }
    }
}

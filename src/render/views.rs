//! Framing: the box where a field's surface lies, and a close-up camera for each feature.
//!
//! * [`surface_box`]: the support box of a tree is the union of its primitives' compact
//!   supports, often far larger than the surface (an island's falloff reaches well beyond
//!   its rock). Interval bounds over an octree of the support keep only the cells where
//!   the surface can be, and their union frames the image.
//! * [`feature_view`]: a camera outside the terrain looking at a feature — into a
//!   tunnel's mouth, under an arch, at an overhang. Candidate eyes circle the feature's
//!   box; each renders a small depth image, and the one that sees the most *feature
//!   surface* (surface points in the box, away from the ground: [`Materials::cover`])
//!   wins (without a terrain, any surface in the box counts). The camera then aims at the centre of what it saw and moves in until that
//!   fills the frame.

use glam::Vec3;

use super::RenderError;
use super::camera::Camera;
use super::cpu;
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
    // The hits on the image plane at unit distance, and their depths.
    let (right, up, forward, tan_v) = probe.basis();
    let tan_h = tan_v * width as f32 / height as f32;
    let (mut lo, mut hi, mut depth) = (glam::Vec2::MAX, glam::Vec2::MIN, 0.0);
    for p in &seen {
        let d = *p - probe.eye;
        let z = d.dot(forward);
        let uv = glam::Vec2::new(d.dot(right), d.dot(up)) / z;
        (lo, hi, depth) = (lo.min(uv), hi.max(uv), depth + z);
    }
    let depth = depth / seen.len() as f32;
    let c = 0.5 * (lo + hi);
    let target = probe.eye + (forward + right * c.x + up * c.y) * depth;
    let fill = ((hi.x - lo.x) / (2.0 * tan_h)).max((hi.y - lo.y) / (2.0 * tan_v)) / 0.9;
    let back = (probe.eye - target).normalize();
    let eye = target + back * (depth * fill.max(1e-3));
    Camera::look_at(eye, target, fov_y, width, height)
}

/// Side of the square-ish probe images (pixels across) candidate views render.
const PROBE_WIDTH: u32 = 96;
/// Azimuths of the candidate eyes around a feature.
const AZIMUTHS: u32 = 8;
/// Elevations (degrees) of the candidate eyes above the feature's centre.
const ELEVATIONS: [f32; 2] = [6.0, 24.0];
/// Fewest feature pixels of a probe for a view to count.
const MIN_FEATURE_PIXELS: usize = 3;

/// A close-up of a feature whose surface lies in `feature` (a box), or `None` when no
/// candidate eye outside the terrain sees it (a chamber sealed in the rock).
pub fn feature_view(
    field: &dyn Field,
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
    let mut best: Option<(usize, Camera, Vec<Vec3>)> = None;
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
            let seen = feature_points(field, &cam, feature, materials);
            if seen.len() >= MIN_FEATURE_PIXELS && best.as_ref().is_none_or(|b| seen.len() > b.0) {
                best = Some((seen.len(), cam, seen));
            }
        }
    }
    let Some((_, probe, seen)) = best else {
        return Ok(None);
    };
    // Aim at what the best eye saw, and come as close as frames it.
    let target = seen.iter().sum::<Vec3>() / seen.len() as f32;
    let mut spread: Vec<f32> = seen.iter().map(|p| p.distance(target)).collect();
    spread.sort_by(f32::total_cmp);
    let size = spread[spread.len() * 9 / 10].max(1.0);
    let back = (probe.eye - target).normalize();
    let fit = 1.4 * size / (0.5 * fov_y.to_radians()).tan();
    let dist = fit.min(probe.eye.distance(target));
    let eye = target + back * dist;
    let eye = if field.value(eye) < ISO {
        eye
    } else {
        probe.eye
    };
    Camera::look_at(eye, target, fov_y, width, height).map(Some)
}

/// The hit points of `camera`'s rays.
fn hit_points(field: &dyn Field, camera: &Camera) -> Vec<Vec3> {
    let support = field.support();
    let params = TraceParams::for_scene(Method::Segment, 2.0 * support.radius())
        .with_pixel_angle(camera.pixel_angle());
    let (depth, _) = cpu::depth(field, camera, &params);
    depth
        .iter()
        .enumerate()
        .filter(|(_, t)| t.is_finite())
        .map(|(k, &t)| {
            let k = k as u32;
            camera.pixel_ray(k % camera.width, k / camera.width).at(t)
        })
        .collect()
}

/// The hit points of `camera`'s rays that lie on a feature's surface in `feature`.
fn feature_points(field: &dyn Field, camera: &Camera, feature: &Aabb, m: &Materials) -> Vec<Vec3> {
    let box_ = feature.dilate(0.02 * feature.radius());
    hit_points(field, camera)
        .into_iter()
        .filter(|p| box_.contains(*p) && (m.ground.is_none() || m.feature(*p) >= 1.0))
        .collect()
}

//! Feature Curve control points in the viewport: where the points of the scene's inline
//! Feature Volumes are, where they land when dragged, and the `tree set` that moves one.
//!
//! A `Ground(x, y, offset)` point is dragged along the surface (its `x, y` become those
//! of the surface point under the pointer, its offset kept); an `Abs(x, y, z)` point in
//! the plane through it parallel to the image.

use glam::Vec3;

use super::history::Edit;
use crate::dem::HeightfieldField;
use crate::render::{Camera, Frame};
use crate::scene::load::to_ron_text;
use crate::scene::splice::without_attributes;
use crate::scene::{NodeSpec, Scene};
use crate::value::Finite;
use crate::voxel::FeatureSet;
use crate::voxel::spec::{CurveSource, Point};

/// Which point of a [`FeatureSet`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slot {
    /// Point `k` of curve `i`.
    Curve(usize, usize),
    /// Corner `k` of quad `i`.
    Quad(usize, usize),
    /// The centre of disc `i`.
    Disc(usize),
    /// Point `k` of tunnel `i`'s path.
    Tunnel(usize, usize),
    /// The `from` foot of arch `i`.
    ArchFrom(usize),
    /// The `to` foot of arch `i`.
    ArchTo(usize),
}

/// A control point of a Feature Volume.
#[derive(Clone, Debug, PartialEq)]
pub struct Handle {
    /// The Feature Volume's name.
    pub volume: String,
    /// Which of its points.
    pub slot: Slot,
    /// The point as written.
    pub point: Point,
    /// Where it is: `Ground` points on the terrain given.
    pub world: Vec3,
}

/// Mutable access to the point at `slot` of `set`.
fn point_mut(set: &mut FeatureSet, slot: Slot) -> Option<&mut Point> {
    match slot {
        Slot::Curve(i, k) => set.curves.get_mut(i)?.points.get_mut(k),
        Slot::Quad(i, k) => set.quads.get_mut(i)?.corners.get_mut(k),
        Slot::Disc(i) => Some(&mut set.discs.get_mut(i)?.center),
        Slot::Tunnel(i, k) => set.tunnels.get_mut(i)?.path.get_mut(k),
        Slot::ArchFrom(i) => Some(&mut set.arches.get_mut(i)?.from),
        Slot::ArchTo(i) => Some(&mut set.arches.get_mut(i)?.to),
    }
}

/// Every point of `set`, with its slot.
fn slots(set: &FeatureSet) -> Vec<(Slot, Point)> {
    /// The points of each item of `items`, `slot(item, point)` each.
    fn lists<T>(
        v: &mut Vec<(Slot, Point)>,
        items: &[T],
        points: fn(&T) -> &[Point],
        slot: fn(usize, usize) -> Slot,
    ) {
        for (i, item) in items.iter().enumerate() {
            v.extend(
                points(item)
                    .iter()
                    .enumerate()
                    .map(|(k, p)| (slot(i, k), *p)),
            );
        }
    }
    let mut v = Vec::new();
    lists(&mut v, &set.curves, |c| &c.points, Slot::Curve);
    lists(&mut v, &set.quads, |q| &q.corners, Slot::Quad);
    v.extend(
        set.discs
            .iter()
            .enumerate()
            .map(|(i, d)| (Slot::Disc(i), d.center)),
    );
    lists(&mut v, &set.tunnels, |t| &t.path, Slot::Tunnel);
    for (i, a) in set.arches.iter().enumerate() {
        v.push((Slot::ArchFrom(i), a.from));
        v.push((Slot::ArchTo(i), a.to));
    }
    v
}

/// Where `point` is: `Ground` points `offset` above `ground` (`None` without a ground
/// height there).
pub fn resolve(point: Point, ground: Option<&HeightfieldField>) -> Option<Vec3> {
    match point {
        Point::Abs(x, y, z) => Some(Vec3::new(x.0, y.0, z.0)),
        Point::Ground(x, y, off) => {
            let h = ground?.height(glam::Vec2::new(x.0, y.0));
            h.is_finite().then(|| Vec3::new(x.0, y.0, h + off.0))
        }
    }
}

/// The control points of the named Feature Volumes of `scene` whose curves are written
/// in the tree file, placed with `ground`.
pub fn handles(scene: &Scene, ground: Option<&HeightfieldField>) -> Vec<Handle> {
    let mut v = Vec::new();
    for n in scene.all_nodes() {
        let NodeSpec::FeatureVolume(f) = n else {
            continue;
        };
        let (Some(name), CurveSource::Inline(set)) = (&f.name, &f.curves) else {
            continue;
        };
        for (slot, point) in slots(set) {
            if let Some(world) = resolve(point, ground) {
                v.push(Handle {
                    volume: name.clone(),
                    slot,
                    point,
                    world,
                });
            }
        }
    }
    v
}

/// The point `handle` becomes when dragged to `world`: a `Ground` point takes `world`'s
/// `x, y` and keeps its offset; an `Abs` point becomes `world`.
pub fn moved(handle: &Handle, world: Vec3) -> Point {
    match handle.point {
        Point::Abs(..) => Point::Abs(Finite(world.x), Finite(world.y), Finite(world.z)),
        Point::Ground(_, _, off) => Point::Ground(Finite(world.x), Finite(world.y), off),
    }
}

/// The `tree set` that writes `point` in place of `handle`'s point in `scene`: the
/// volume's whole `curves` value with that one point changed.
pub fn edit(scene: &Scene, handle: &Handle, point: Point) -> Option<Edit> {
    let named = scene.named();
    let NodeSpec::FeatureVolume(f) = named.get(handle.volume.as_str())? else {
        return None;
    };
    let CurveSource::Inline(set) = &f.curves else {
        return None;
    };
    let mut set = set.clone();
    *point_mut(&mut set, handle.slot)? = point;
    Some(Edit::Set {
        target: format!("{}.curves", handle.volume),
        value: without_attributes(&to_ron_text(&CurveSource::Inline(set))).to_string(),
    })
}

/// Where `p` is in a picture drawn through `camera`, in pixels from its top-left corner
/// (`None` behind the eye).
pub fn project(camera: &Camera, p: Vec3) -> Option<(f32, f32)> {
    let (right, up, forward, tan) = camera.basis();
    let d = p - camera.eye;
    let z = d.dot(forward);
    if z <= 1e-6 {
        return None;
    }
    let aspect = camera.width as f32 / camera.height as f32;
    let u = d.dot(right) / (z * tan * aspect);
    let v = d.dot(up) / (z * tan);
    Some((
        (u + 1.0) * 0.5 * camera.width as f32,
        (1.0 - v) * 0.5 * camera.height as f32,
    ))
}

/// Where a point dragged from `handle` lands under the pixel position `(x, y)` of
/// `frame` (drawn through `camera`): for a `Ground` point the surface point the tracer
/// hit there (`None` where the ray missed), else the point of the plane through the
/// handle parallel to the image.
pub fn drop_at(handle: &Handle, frame: &Frame, camera: &Camera, x: f32, y: f32) -> Option<Vec3> {
    match handle.point {
        Point::Ground(..) => {
            let (i, j) = (x.floor(), y.floor());
            if i < 0.0 || j < 0.0 {
                return None;
            }
            super::placement::hit(frame, camera, i as u32, j as u32)
        }
        Point::Abs(..) => {
            let ray = camera.ray(x, y);
            let forward = camera.basis().2;
            let den = ray.dir.dot(forward);
            (den > 1e-6).then(|| ray.at((handle.world - ray.origin).dot(forward) / den))
        }
    }
}

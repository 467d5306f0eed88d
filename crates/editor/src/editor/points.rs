//! Feature Curve control points in the viewport: where the points of the scene's inline
//! Feature Volumes are, where they land when dragged, and the `tree set` that moves one.
//!
//! A `Ground(x, y, offset)` point is dragged along the surface (its `x, y` become those
//! of the surface point under the pointer, its offset kept); an `Abs(x, y, z)` point in
//! the plane through it parallel to the image. While it moves, the viewport previews the
//! volume rebuilt with the point where it is, on a coarser grid ([`dragged_scene`]).
//! A point of a curve or a tunnel path can be inserted after another ([`inserted`]) or
//! removed ([`removed`]), down to the two a path needs.

use glam::Vec3;

use super::history::Edit;
use crate::compile::edit::scene_find_mut;
use crate::dem::HeightfieldField;
use crate::render::{Camera, Frame};
use crate::scene::load::to_ron_line;
use crate::scene::{NodeSpec, Scene};
use crate::value::{Finite, Positive};
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

/// The point list `slot` is in and its index there, for the points that can be inserted
/// and removed (a curve's, a tunnel path's: a quad has four corners, a disc one centre,
/// an arch two feet).
fn list_mut(set: &mut FeatureSet, slot: Slot) -> Option<(&mut Vec<Point>, usize)> {
    match slot {
        Slot::Curve(i, k) => Some((&mut set.curves.get_mut(i)?.points, k)),
        Slot::Tunnel(i, k) => Some((&mut set.tunnels.get_mut(i)?.path, k)),
        _ => None,
    }
}

/// The fewest points a curve or a tunnel path takes.
pub const MIN_PATH_POINTS: usize = 2;

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

/// The inline curves of the volume `handle` belongs to in `scene`.
fn inline_set(scene: &Scene, handle: &Handle) -> Option<FeatureSet> {
    let named = scene.named();
    let NodeSpec::FeatureVolume(f) = named.get(handle.volume.as_str())? else {
        return None;
    };
    match &f.curves {
        CurveSource::Inline(set) => Some(set.clone()),
        CurveSource::Path(_) => None,
    }
}

/// The `tree set` that writes `set` as the curves of `handle`'s volume.
fn set_edit(handle: &Handle, set: FeatureSet) -> Edit {
    Edit::Set {
        target: format!("{}.curves", handle.volume),
        value: to_ron_line(&CurveSource::Inline(set)),
    }
}

/// The `tree set` that writes `point` in place of `handle`'s point in `scene`: the
/// volume's whole `curves` value with that one point changed.
pub fn edit(scene: &Scene, handle: &Handle, point: Point) -> Option<Edit> {
    let mut set = inline_set(scene, handle)?;
    *point_mut(&mut set, handle.slot)? = point;
    Some(set_edit(handle, set))
}

/// Halfway between `a` and `b`, written as `a` is: two `Ground` points give a `Ground`
/// point (offsets averaged), two `Abs` points an `Abs` one; a mixed pair keeps `a`'s
/// height (its `z`, or its offset) at the middle of their `x, y`.
pub fn midpoint(a: Point, b: Point) -> Point {
    let mid = |u: Finite, v: Finite| Finite(0.5 * (u.0 + v.0));
    match (a, b) {
        (Point::Abs(x, y, z), Point::Abs(u, v, w)) => Point::Abs(mid(x, u), mid(y, v), mid(z, w)),
        (Point::Ground(x, y, h), Point::Ground(u, v, g)) => {
            Point::Ground(mid(x, u), mid(y, v), mid(h, g))
        }
        (Point::Abs(x, y, z), Point::Ground(u, v, _)) => Point::Abs(mid(x, u), mid(y, v), z),
        (Point::Ground(x, y, h), Point::Abs(u, v, _)) => Point::Ground(mid(x, u), mid(y, v), h),
    }
}

/// The `tree set` that inserts a point after `handle`'s (before it for the last point of
/// its path), halfway to its neighbour ([`midpoint`]); `None` for points that cannot be
/// inserted after (quad corners, disc centres, arch feet).
pub fn inserted(scene: &Scene, handle: &Handle) -> Option<Edit> {
    let mut set = inline_set(scene, handle)?;
    let (list, k) = list_mut(&mut set, handle.slot)?;
    let (at, other) = match list.get(k + 1) {
        Some(next) => (k + 1, *next),
        None => (k, *list.get(k.checked_sub(1)?)?),
    };
    list.insert(at, midpoint(*list.get(k)?, other));
    Some(set_edit(handle, set))
}

/// The `tree set` that removes `handle`'s point, or why it cannot be removed.
pub fn removed(scene: &Scene, handle: &Handle) -> Result<Edit, String> {
    let mut set = inline_set(scene, handle).ok_or("its curves are not in the tree file")?;
    let (list, k) = list_mut(&mut set, handle.slot)
        .ok_or("only points of curves and tunnel paths can be removed")?;
    if list.len() <= MIN_PATH_POINTS {
        return Err(format!(
            "a path keeps at least {MIN_PATH_POINTS} points: this one has {}",
            list.len()
        ));
    }
    list.remove(k);
    Ok(set_edit(handle, set))
}

/// The most voxels a dragged volume's preview grid holds (32³): the grid of its preview is
/// coarsened to stay within it, so that a preview is built in a fraction of a second.
pub const DRAG_VOXELS: f32 = 32_768.0;

/// The preview of a point being dragged: `scene` with `handle`'s point at `point`, its
/// volume's voxel made coarse enough that its domain holds at most [`DRAG_VOXELS`] of
/// them (the file's voxel where it already does).
pub fn dragged_scene(scene: &Scene, handle: &Handle, point: Point) -> Option<Scene> {
    let mut s = scene.clone();
    let NodeSpec::FeatureVolume(f) = scene_find_mut(&mut s, &handle.volume)? else {
        return None;
    };
    let CurveSource::Inline(set) = &mut f.curves else {
        return None;
    };
    *point_mut(set, handle.slot)? = point;
    let size = f.domain.1.0 - f.domain.0.0;
    let coarse = ((size.x * size.y * size.z).abs() / DRAG_VOXELS).cbrt();
    f.voxel = Positive(f.voxel.get().max(coarse));
    Some(s)
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
/// handle parallel to the image (`frame` unused: `camera` may be the view at another
/// size than the frame's, `x, y` in its pixels).
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

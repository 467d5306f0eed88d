//! Placement on the terrain: the surface point under a pixel of the viewport, as the
//! tracer found it, and the nodes placed there.

use glam::Vec3;

use crate::render::{Camera, Frame};
use crate::scene::{NodeSpec, Scene};

/// The surface point the tracer hit through pixel `(i, j)` of `frame`, drawn through
/// `camera`; `None` where the ray missed or outside the image.
pub fn hit(frame: &Frame, camera: &Camera, i: u32, j: u32) -> Option<Vec3> {
    if i >= frame.width || j >= frame.height {
        return None;
    }
    let t = frame.depth[(j * frame.width + i) as usize];
    t.is_finite().then(|| camera.pixel_ray(i, j).at(t))
}

/// A name not yet in `scene`: `stem_1`, `stem_2`, …
pub fn fresh_name(scene: &Scene, stem: &str) -> String {
    let named = scene.named();
    (1..)
        .map(|k| format!("{stem}_{k}"))
        .find(|n| !named.contains_key(n.as_str()))
        .unwrap_or_else(|| stem.to_string())
}

/// Where a new node goes: the selected node when it takes children, else the root when
/// it does.
pub fn parent_for(scene: &Scene, selected: Option<&str>) -> Option<String> {
    let named = scene.named();
    selected
        .and_then(|s| named.get(s).copied())
        .filter(|n| n.takes_children())
        .or(Some(&scene.root).filter(|r| r.takes_children()))
        .and_then(|n| n.name())
        .map(str::to_string)
}

/// An `Anchor` named `name` at the surface point `p` (its `at` is `p`'s x and y) with a
/// `offset` metres above the ground, holding a sphere primitive of `radius` metres.
pub fn anchor_at(name: &str, p: Vec3, offset: f32, radius: f32) -> String {
    format!(
        "Anchor(name: {name:?}, at: ({}, {}), offset: {offset}, child: Primitive(shape: \
         Sphere(center: (0, 0, 0), radius: {radius}), falloff: {}))",
        p.x,
        p.y,
        radius / 3.0
    )
}

/// A sphere primitive named `name` centred on `p`.
pub fn sphere_at(name: &str, p: Vec3, radius: f32) -> String {
    format!(
        "Primitive(name: {name:?}, shape: Sphere(center: ({}, {}, {}), radius: {radius}), \
         falloff: {})",
        p.x,
        p.y,
        p.z,
        radius / 3.0
    )
}

/// `node`'s text with its name replaced by `name` (a duplicate of it).
pub fn renamed(node: &NodeSpec, name: &str) -> Option<String> {
    let text = crate::scene::load::to_ron_text(node);
    crate::scene::splice::set_field(&text, &["name"], &format!("{name:?}")).ok()
}

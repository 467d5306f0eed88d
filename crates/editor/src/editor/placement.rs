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

/// A copy of `node` for `scene`, as DCC tools duplicate: every named node of it renamed
/// `name_k` with the smallest `k` that keeps all names of the scene unique, and the
/// instances inside it that referred to a node of it referring to that node's copy.
/// Returns the copy's name and its text.
pub fn duplicate(scene: &Scene, node: &NodeSpec) -> Option<(String, String)> {
    let named = scene.named();
    let mut names = Vec::new();
    node.walk(&mut |n, _| names.extend(n.name()));
    let k = (1..).find(|k| {
        names
            .iter()
            .all(|n| !named.contains_key(format!("{n}_{k}").as_str()))
    })?;
    fn rename(n: &mut NodeSpec, names: &[&str], k: usize) {
        let fresh = |s: &str| names.contains(&s).then(|| format!("{s}_{k}"));
        if let Some(new) = n.name().and_then(fresh) {
            *n.name_mut() = Some(new);
        }
        if let NodeSpec::Instance(i) = n
            && let Some(new) = fresh(&i.of)
        {
            i.of = new;
        }
        for c in n.children_mut() {
            rename(c, names, k);
        }
    }
    let mut copy = node.clone();
    rename(&mut copy, &names, k);
    let name = copy.name()?.to_string();
    Some((name, crate::scene::load::to_ron_text(&copy)))
}

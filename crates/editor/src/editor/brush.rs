//! Sculpting brushes (Paris et al. 2019 §8.2: users sculpt a terrain with extruding and
//! intruding skeletal primitives): a stroke dragged over the surface becomes one named
//! skeletal primitive of the tree, a tube of the brush's radius around the points the
//! tracer hit under the pointer, that raises the ground or carves it away.
//!
//! * One click is a dab: a `Point` skeleton. A drag is a stroke: a `Polyline` through the
//!   surface points it crossed, one every half radius (at most [`MAX_POINTS`]).
//! * The tube's surface is `radius` from its skeleton: the primitive's falloff `R` is
//!   `radius / x½`, where `x½` is the distance (in units of `R`) at which Wyvill's falloff
//!   falls to the iso-value.
//! * A raise goes into the selected `Blend` or `Union` (else the root, or the base of a
//!   root `Difference`): added to the ground there. A carve goes into the carves of the
//!   selected `Difference` (else the root's), or into a `Blend` with a negative energy,
//!   which subtracts it: the two intrusions of the paper.

use glam::Vec3;

use crate::field::falloff::iso_reach;
use crate::scene::{NodeSpec, Scene};

/// The most skeleton points a stroke keeps: a longer one keeps evenly spaced ones.
pub const MAX_POINTS: usize = 32;

/// Spacing of a stroke's points, in brush radii.
pub const SPACING: f32 = 0.5;

/// What a stroke does to the ground.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Brush {
    /// Adds rock: an extruding primitive.
    Raise,
    /// Removes rock: an intruding primitive.
    Carve,
}

impl Brush {
    /// The stem of the names of its nodes (`raise_1`, `carve_2`).
    pub fn stem(self) -> &'static str {
        match self {
            Brush::Raise => "raise",
            Brush::Carve => "carve",
        }
    }
}

/// A stroke being dragged: the surface points under the pointer, spaced.
#[derive(Clone, Debug, PartialEq)]
pub struct Stroke {
    /// What it does.
    pub brush: Brush,
    /// The tube's radius, metres.
    pub radius: f32,
    /// The skeleton's points so far.
    pub points: Vec<Vec3>,
}

impl Stroke {
    /// A stroke of `brush` with a tube of `radius` metres, starting at `p`.
    pub fn new(brush: Brush, radius: f32, p: Vec3) -> Self {
        Stroke {
            brush,
            radius,
            points: vec![p],
        }
    }

    /// Adds the surface point `p` when it lies [`SPACING`] radii or more from the last.
    pub fn extend(&mut self, p: Vec3) {
        if self
            .points
            .last()
            .is_none_or(|q| q.distance(p) >= SPACING * self.radius)
        {
            self.points.push(p);
        }
    }

    /// The skeleton's points: all of them, or [`MAX_POINTS`] evenly spaced along the list,
    /// the first and the last kept.
    fn skeleton(&self) -> Vec<Vec3> {
        let n = self.points.len();
        if n <= MAX_POINTS {
            return self.points.clone();
        }
        (0..MAX_POINTS)
            .map(|k| self.points[k * (n - 1) / (MAX_POINTS - 1)])
            .collect()
    }

    /// The stroke as a tree node named `name` with `energy` (−1 subtracts it in a
    /// `Blend`): a `Point` skeleton for a dab, a `Polyline` for a stroke; coordinates to
    /// the centimetre.
    pub fn node(&self, name: &str, energy: f32) -> String {
        let xyz = |p: &Vec3| format!("({:.2}, {:.2}, {:.2})", p.x, p.y, p.z);
        let points = self.skeleton();
        let shape = match points.as_slice() {
            [p] => format!("Point(center: {})", xyz(p)),
            ps => format!(
                "Polyline(points: [{}])",
                ps.iter().map(xyz).collect::<Vec<_>>().join(", ")
            ),
        };
        format!(
            "Primitive(name: {name:?}, shape: {shape}, falloff: {:.2}, energy: {energy})",
            self.radius / iso_reach()
        )
    }
}

/// Where a stroke of `brush` goes in `scene` with `selected` selected: the name of the
/// node it is appended to, and its energy; else why it cannot go anywhere, in words.
pub fn target(
    scene: &Scene,
    selected: Option<&str>,
    brush: Brush,
) -> Result<(String, f32), String> {
    let named = scene.named();
    let node = selected
        .and_then(|s| named.get(s).copied())
        .filter(|n| n.takes_children())
        .unwrap_or(&scene.root);
    let named_target = |n: &NodeSpec, energy: f32| {
        n.name().map(|s| (s.to_string(), energy)).ok_or_else(|| {
            format!(
                "the {} a {} goes into has no name: name it in the file",
                n.kind(),
                brush.stem()
            )
        })
    };
    match (brush, node) {
        (Brush::Raise, NodeSpec::Blend(_) | NodeSpec::Union(_)) => named_target(node, 1.0),
        (Brush::Raise, NodeSpec::Difference(d))
            if matches!(*d.base, NodeSpec::Blend(_) | NodeSpec::Union(_)) =>
        {
            named_target(&d.base, 1.0)
        }
        (Brush::Carve, NodeSpec::Difference(_)) => named_target(node, 1.0),
        (Brush::Carve, NodeSpec::Blend(_)) => named_target(node, -1.0),
        (Brush::Raise, _) => Err("select a Blend or Union to raise the ground in".into()),
        (Brush::Carve, _) => Err("select a Difference or Blend to carve the ground in".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_stroke_keeps_its_ends_and_max_points() {
        let mut s = Stroke::new(Brush::Carve, 1.0, Vec3::ZERO);
        for k in 1..=200 {
            s.extend(Vec3::new(k as f32 * 0.5, 0.0, 0.0));
            // Too close to the last point: skipped.
            s.extend(Vec3::new(k as f32 * 0.5 + 0.1, 0.0, 0.0));
        }
        assert_eq!(s.points.len(), 201);
        let k = s.skeleton();
        assert_eq!(k.len(), MAX_POINTS);
        assert_eq!(k[0], Vec3::ZERO);
        assert_eq!(*k.last().unwrap(), Vec3::new(100.0, 0.0, 0.0));
    }
}

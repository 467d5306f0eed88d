//! Feature Curve expansion (Becher 2016 §4.5, optional): each end of every seed Feature Curve
//! is continued by a curve traced through the guidance field of a first run, until it has
//! covered a given length, comes close to another Feature Curve, or reaches the domain's
//! faces; the traced curves join the seeds and the pipeline runs again.
//!
//! As in the thesis, the trace is "a virtual curve similar to a streamline through the
//! guidance fields" (§4.6.1: `c'(s) · N(c(s)) = 0`): it starts along the curve's end
//! tangent and each step keeps the previous direction projected onto the plane normal to
//! the diffused guidance normal N (the straightest continuation perpendicular to N). It
//! does not follow `S = 0` of the first run — beyond a crest's end that surface falls
//! away, while N there still carries the crest's normals — so the continuation extends
//! the feature, which the second run then honours.
//!
//! A traced curve carries the end's Constraint Point: its bitangents (left and right
//! swapped at the start of the curve, where the trace runs backwards) and noise
//! parameters, transported along the trace by the rotation of the tangent, as between the
//! Constraint Points of any Feature Curve (§3.1).

use std::time::{Duration, Instant};

use glam::Vec3;

use super::SField;
use crate::curves::{BSpline, ConstraintPoint, FeatureCurve, Features};
use crate::field::Aabb;

/// How far and how finely curves are expanded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Expansion {
    /// Longest traced continuation of each end (metres).
    pub length: f32,
    /// Distance between the traced curve's control vertices (metres).
    pub step: f32,
    /// A trace stops when it comes this close to another seed primitive (metres).
    pub stop: f32,
}

/// What an expansion added.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Expanded {
    /// The traced curves (seed curves), in the order of the curves and ends they continue.
    pub curves: Vec<FeatureCurve>,
    /// Time spent tracing (the second pipeline run is not included).
    pub trace_time: Duration,
}

/// Traces the continuations of the seed Feature Curves' ends through the guidance normals
/// of `field` (a run with [`super::Params::keep_normals`]; nothing is traced without
/// them). Closed curves (ends within `stop` of each other) are not expanded.
/// Deterministic: the ends are traced in order, and a trace also stops near the curves
/// traced before it.
pub fn expand(features: &Features, field: &SField, e: &Expansion) -> Expanded {
    let clock = Instant::now();
    let mut out = Expanded::default();
    if field.is_empty() || field.guidance_normal(Vec3::ZERO).is_none() || e.length < e.step {
        return out;
    }
    let p = field.params();
    let inner = p.domain.dilate(-(p.falloff + p.voxel));
    let spacing = 0.5 * e.step.min(p.voxel);
    // Samples of every seed primitive, each tagged with the curve it belongs to (user
    // curves by index, everything else with `usize::MAX`).
    let mut others: Vec<(usize, Vec3)> = Vec::new();
    let rest = Features {
        curves: Vec::new(),
        ..features.clone()
    };
    others.extend(
        rest.seed_samples(spacing, 0.0)
            .into_iter()
            .map(|s| (usize::MAX, s.pos)),
    );
    for (k, c) in features.curves.iter().enumerate().filter(|(_, c)| c.seed) {
        others.extend(curve_points(c, spacing).map(|q| (k, q)));
    }
    for (k, c) in features.curves.iter().enumerate().filter(|(_, c)| c.seed) {
        let (a, b) = (c.spline.eval(0.0), c.spline.eval(1.0));
        if a.distance(b) < e.stop {
            continue;
        }
        for t in [0.0, 1.0] {
            let end = c.sample(t);
            // Own samples near this end do not stop the trace.
            let stops = |q: Vec3| {
                others.iter().any(|&(j, s)| {
                    (j != k || s.distance(end.pos) > 2.0 * e.stop) && s.distance(q) < e.stop
                })
            };
            let dir = if t == 0.0 { -end.tangent } else { end.tangent };
            let pts = trace(field, end.pos, dir, e, &inner, &stops);
            if pts.len() < 3 {
                continue;
            }
            let Some(spline) = BSpline::new(pts) else {
                continue;
            };
            // Running away from the curve at its start, left and right swap.
            let (left, right) = if t == 0.0 {
                (end.right, end.left)
            } else {
                (end.left, end.right)
            };
            let curve = FeatureCurve {
                spline,
                constraints: vec![ConstraintPoint {
                    t: 0.0,
                    left,
                    right,
                    amplitude: end.noise.x,
                    roughness: end.noise.y,
                }],
                seed: true,
                ribbon: c.ribbon,
            };
            let idx = features.curves.len() + out.curves.len();
            others.extend(curve_points(&curve, spacing).map(|q| (idx, q)));
            out.curves.push(curve);
        }
    }
    out.trace_time = clock.elapsed();
    out
}

/// Points every `spacing` metres along a curve.
fn curve_points(c: &FeatureCurve, spacing: f32) -> impl Iterator<Item = Vec3> + '_ {
    let n = ((c.spline.length(64) / spacing).ceil() as usize).max(1);
    (0..=n).map(move |i| c.spline.eval(i as f32 / n as f32))
}

/// The vertices of one traced continuation, starting at `start`.
fn trace(
    field: &SField,
    start: Vec3,
    mut dir: Vec3,
    e: &Expansion,
    inner: &Aabb,
    stops: &dyn Fn(Vec3) -> bool,
) -> Vec<Vec3> {
    let mut pts = vec![start];
    let mut p = start;
    let steps = (e.length / e.step).floor() as usize;
    for _ in 0..steps {
        let normal = |q: Vec3| field.guidance_normal(q).and_then(Vec3::try_normalize);
        let Some(n) = normal(p) else { break };
        let Some(d) = dir.reject_from_normalized(n).try_normalize() else {
            break;
        };
        // Midpoint rule: the direction at the half step, perpendicular to N there.
        let Some(n) = normal(p + d * (0.5 * e.step)) else {
            break;
        };
        let Some(d) = d.reject_from_normalized(n).try_normalize() else {
            break;
        };
        let q = p + d * e.step;
        // Stop where N turns against the direction (the guidance folds back).
        if !inner.contains(q) || stops(q) || d.dot(dir) < 0.5 {
            break;
        }
        (dir, p) = (d, q);
        pts.push(q);
    }
    pts
}

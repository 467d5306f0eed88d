//! The thesis's examples (Becher 2016 §7.2) as scenes in `trees/curves/`: each is built by
//! the voxel pipeline and its S field is checked against what the curves ask for.

use crate::curves_util;

use glam::Vec3;
use karstic::curves::{CurveSample, Features};
use karstic::field::{Field, ISO};
use karstic::voxel::FeatureVolumeSpec;
use karstic::voxel::SField;

/// A scene of `trees/curves/`: values come from the compiled tree, parameters and
/// statistics from its S-field leaf.
struct Scene {
    spec: FeatureVolumeSpec,
    features: Features,
    leaf: SField,
    field: Box<dyn Field>,
}

fn scene(name: &str) -> Scene {
    let l = curves_util::load(name);
    Scene {
        spec: l.spec,
        features: l.features,
        leaf: l.leaf,
        field: Box::new(l.tree),
    }
}

impl Scene {
    fn h(&self) -> f32 {
        self.spec.voxel.0
    }

    /// True when `p` is far enough from the domain's faces for the face falloff not to
    /// matter.
    fn inside(&self, p: Vec3) -> bool {
        let d = self.leaf.params().domain;
        let m = self.leaf.params().falloff + 2.0 * self.h();
        p.cmpge(d.min + Vec3::splat(m)).all() && p.cmple(d.max - Vec3::splat(m)).all()
    }

    fn samples(&self) -> Vec<CurveSample> {
        self.features
            .seed_samples(0.5 * self.h(), self.spec.ribbon_width())
            .into_iter()
            .filter(|s| self.inside(s.pos))
            .collect()
    }

    /// Every seed curve sample has the surface within one voxel along its normal, with
    /// the rock behind and the air in front.
    fn assert_surface_through_seeds(&self) {
        let h = self.h();
        let samples = self.samples();
        assert!(samples.len() > 20, "too few samples inside the domain");
        let mut bad = Vec::new();
        for s in &samples {
            let n = (s.left_normal() + s.right_normal()).normalize_or_zero();
            if n == Vec3::ZERO {
                continue;
            }
            let (front, back) = (
                self.field.value(s.pos + n * h),
                self.field.value(s.pos - n * h),
            );
            if !(front < ISO && back > ISO) {
                bad.push((s.pos, front, back));
            }
        }
        assert!(
            bad.is_empty(),
            "{} of {} samples miss the surface: {:?}",
            bad.len(),
            samples.len(),
            &bad[..bad.len().min(8)]
        );
    }

    /// At the Constraint Points of the scene's explicit seed curves, and at the points in
    /// between where their constraints are interpolated, the surface normal one and a
    /// half voxels out on each ribbon is within `deg` degrees of the constrained one.
    fn assert_constraint_normals(&self, deg: f32) {
        let d = 1.5 * self.h();
        let mut worst = (0.0f32, Vec3::ZERO);
        let mut n = 0;
        let seeds: Vec<_> = self.features.curves.iter().filter(|c| c.seed).collect();
        // Where two curves meet their constraints conflict; those points are skipped.
        let near_other = |k: usize, p: Vec3| {
            seeds.iter().enumerate().any(|(j, o)| {
                j != k
                    && (0..=200)
                        .any(|i| o.sample(i as f32 / 200.0).pos.distance(p) < 6.0 * self.h())
            })
        };
        for (k, c) in seeds.iter().enumerate() {
            let ts = c
                .constraints
                .iter()
                .map(|cp| cp.t)
                .chain((0..=40).map(|i| i as f32 / 40.0));
            for t in ts {
                let s = c.sample(t);
                for (b, want) in [(s.left, s.left_normal()), (s.right, s.right_normal())] {
                    let p = s.pos + b * d;
                    if !self.inside(p) || near_other(k, s.pos) {
                        continue;
                    }
                    let got = -self.field.value_grad(p).1.normalize_or_zero();
                    let angle = got.dot(want).clamp(-1.0, 1.0).acos().to_degrees();
                    if angle > worst.0 {
                        worst = (angle, p);
                    }
                    n += 1;
                }
            }
        }
        assert!(n > 0, "no constraint point inside the domain");
        eprintln!("worst normal deviation {:.1}° at {}", worst.0, worst.1);
        assert!(
            worst.0 <= deg,
            "worst normal deviation {:.1}° at {} > {deg}°",
            worst.0,
            worst.1
        );
    }

    /// Number of times the vertical line at `(x, y)` crosses the surface, away from the
    /// domain's top and bottom faces.
    fn crossings(&self, x: f32, y: f32) -> usize {
        let d = self.leaf.params().domain;
        let m = self.leaf.params().falloff + 2.0 * self.h();
        let (top, bottom) = (d.max.z - m, d.min.z + m);
        let steps = ((top - bottom) / (0.25 * self.h())) as usize;
        let mut last = self.field.value(Vec3::new(x, y, top)) > ISO;
        let mut n = 0;
        for i in 0..=steps {
            let z = top - i as f32 * 0.25 * self.h();
            let now = self.field.value(Vec3::new(x, y, z)) > ISO;
            n += (now != last) as usize;
            last = now;
        }
        n
    }

    /// True when the segment `a → b` stays in the air.
    fn clear(&self, a: Vec3, b: Vec3) -> bool {
        let n = (a.distance(b) / (0.25 * self.h())).ceil() as usize;
        (0..=n).all(|i| self.field.value(a.lerp(b, i as f32 / n as f32)) < ISO)
    }
}

#[test]
fn cliff() {
    let s = scene("cliff");
    s.assert_surface_through_seeds();
    s.assert_constraint_normals(20.0);
    // Plateau behind the edge, air in front of the face all the way down.
    assert!(s.field.value(Vec3::new(48.0, 50.0, 30.0)) > ISO);
    assert!(s.clear(Vec3::new(48.0, 15.0, 8.0), Vec3::new(48.0, 15.0, 56.0)));
}

#[test]
fn overhanging_cliff_with_ground() {
    let s = scene("overhang");
    s.assert_surface_through_seeds();
    s.assert_constraint_normals(20.0);
    // Under the lip: air above, rock of the lip, air under the overhang, the ground.
    for x in [24.0, 48.0, 72.0] {
        assert!(
            s.crossings(x, 33.0) >= 3,
            "column x = {x} crosses {} times",
            s.crossings(x, 33.0)
        );
    }
}

#[test]
fn ridge() {
    let s = scene("ridge");
    s.assert_surface_through_seeds();
    s.assert_constraint_normals(20.0);
    assert_eq!(s.crossings(64.0, 64.0), 1);
}

#[test]
fn converging_ridges() {
    let s = scene("ridges");
    s.assert_surface_through_seeds();
    s.assert_constraint_normals(20.0);
}

#[test]
fn riverbed() {
    let s = scene("riverbed");
    s.assert_surface_through_seeds();
    s.assert_constraint_normals(20.0);
    // The river's bottom lies below the land on both sides.
    let top = |y: f32| {
        (0..256)
            .map(|i| 63.0 - i as f32 * 0.25)
            .find(|&z| s.field.value(Vec3::new(64.0, y, z)) > ISO)
            .unwrap()
    };
    assert!(top(64.0) < top(24.0) - 8.0 && top(64.0) < top(104.0) - 8.0);
}

#[test]
fn hill() {
    let s = scene("hill");
    assert_eq!(
        s.leaf.params().interpolation,
        karstic::voxel::Interpolation::Tricubic
    );
    s.assert_surface_through_seeds();
    s.assert_constraint_normals(20.0);
    let top = |x: f32, y: f32| {
        (0..256)
            .map(|i| 63.0 - i as f32 * 0.25)
            .find(|&z| s.field.value(Vec3::new(x, y, z)) > ISO)
            .unwrap()
    };
    eprintln!("hill top {} ground {}", top(64.0, 64.0), top(10.0, 10.0));
    assert!(
        top(64.0, 64.0) > top(10.0, 10.0) + 8.0,
        "the hill rises above the ground"
    );
}

#[test]
fn arch_from_three_curves() {
    let s = scene("arch");
    s.assert_surface_through_seeds();
    // A ray under the span, across it, halfway between the ground and the underside.
    assert!(s.clear(Vec3::new(64.0, 30.0, 26.0), Vec3::new(64.0, 98.0, 26.0)));
    // Over the apex: air, the beam, the hole, the ground.
    assert!(s.crossings(64.0, 64.0) >= 3);
}

/// The artefact of the first version: rock in the domain's top corners, beyond the feet,
/// far from every curve (the beam's top and underside mixed on coarse levels). Above the
/// ground, every solid point is in the slab: inside its tube grown by two voxels.
#[test]
fn arch_has_no_rock_far_from_its_curves() {
    let s = scene("arch");
    let arch = &s.features.arches[0];
    let beam = arch.beam();
    let d = s.leaf.params().domain;
    let ground = arch.from.z;
    let mut far = Vec::new();
    for k in 0..=((d.max.z - ground - 6.0) / 2.0) as i32 {
        for j in 0..=(d.size().y / 2.0) as i32 {
            for i in 0..=(d.size().x / 2.0) as i32 {
                let p = Vec3::new(
                    2.0 * i as f32,
                    2.0 * j as f32,
                    ground + 6.0 + 2.0 * k as f32,
                );
                if s.field.value(p) > ISO && !beam.contains(p, 2.0 * s.h()) {
                    far.push(p);
                }
            }
        }
    }
    assert!(
        far.is_empty(),
        "{} solid points far from the arch, e.g. {:?}",
        far.len(),
        &far[..far.len().min(6)]
    );
    // In particular the top corners of the domain are air.
    for x in [d.min.x + 6.0, d.max.x - 6.0] {
        for y in [d.min.y + 6.0, 64.0, d.max.y - 6.0] {
            assert!(s.field.value(Vec3::new(x, y, d.max.z - 6.0)) < ISO);
        }
    }
}

/// Without its ground curve the arch appears only on the levels fine enough for its
/// beam; the levels before hold air (not rock, as around a tunnel): a lone beam in air.
#[test]
fn arch_without_ground_stands_in_air() {
    let s = scene("arch");
    let mut f = s.features.clone();
    f.arches[0].ground = None;
    let leaf = s.spec.build_features(&f, 7, 1 << 32).unwrap();
    let levels = &leaf.stats().levels;
    assert!(levels[0].seeds == 0 && levels.last().unwrap().seeds > 0);
    // The top of the slab's crown.
    let apex = f.arches[0].beam().path.eval(0.5) + Vec3::Z * 0.5 * f.arches[0].thickness;
    assert!(leaf.value(apex - Vec3::Z * 4.5) > ISO, "rock in the beam");
    assert!(leaf.value(apex + Vec3::Z * 6.0) < ISO, "air above it");
    assert!(leaf.value(apex - Vec3::Z * 20.0) < ISO, "air under it");
    let d = leaf.params().domain;
    for p in [d.min, d.max, Vec3::new(d.min.x, d.max.y, d.max.z)] {
        let q = p + (d.center() - p).signum() * 8.0;
        assert!(leaf.value(q) < ISO, "air at {q}");
    }
}

/// Feature Curve expansion (§4.5): the crest's ends are continued through the first
/// run's guidance field, tangent-continuous, the east one up to the saddle curve and the
/// west one to the domain's face; the second run puts the surface through the
/// continuations, which extends the ridge: where the first run's surface fell away beyond
/// the crest's ends, the continuations were in the air.
#[test]
fn feature_curve_expansion() {
    let s = scene("expansion");
    s.assert_surface_through_seeds();
    let h = s.h();
    let e = s.leaf.expanded().expect("the expansion ran");
    let first = FeatureVolumeSpec {
        expansion: None,
        ..s.spec.clone()
    }
    .build_features(&s.features, 7, 1 << 32)
    .unwrap();
    let (crest, saddle) = (&s.features.curves[0], &s.features.curves[1]);
    let from = |t: f32| {
        let end = crest.sample(t);
        let c = e
            .curves
            .iter()
            .find(|c| c.spline.eval(0.0).distance(end.pos) < 1e-4)
            .expect("both ends of the crest are continued");
        let v = if t == 0.0 { -end.tangent } else { end.tangent };
        let turn = c.spline.tangent(0.0).dot(v).acos().to_degrees();
        assert!(turn < 20.0, "the continuation turns by {turn}°");
        c
    };
    let (west, east) = (from(0.0), from(1.0));
    for c in [west, east] {
        let above = (0..=100)
            .map(|i| first.s_value(c.spline.eval(i as f32 / 100.0)))
            .fold(f32::MIN, f32::max);
        assert!(
            above > 2.0 * h,
            "the first run's surface fell away: {above}"
        );
    }
    for c in &e.curves {
        assert!(c.spline.length(64) <= 60.0 + 2.0 * h);
        for i in 0..=100 {
            let p = c.spline.eval(i as f32 / 100.0);
            assert!(
                s.leaf.s_value(p).abs() < h,
                "the second run misses a continuation at {p}: S = {}",
                s.leaf.s_value(p)
            );
        }
    }
    let saddle_dist = |p: Vec3| {
        (0..=200)
            .map(|i| saddle.spline.eval(i as f32 / 200.0).distance(p))
            .fold(f32::MAX, f32::min)
    };
    let east_end = east.spline.eval(1.0);
    let stop = 4.0 * h;
    assert!(
        saddle_dist(east_end) >= stop && saddle_dist(east_end) < stop + 2.5 * h,
        "the east continuation stops at the saddle: {east_end}, {} m from it",
        saddle_dist(east_end)
    );
    let west_end = west.spline.eval(1.0);
    let inner = s.leaf.params().domain.min.x + s.leaf.params().falloff + h;
    assert!(
        west_end.x < inner + 2.0 * h,
        "the west continuation runs to the domain's face: {west_end}"
    );
    // The continuations are seeds of the second run.
    let seeds = |f: &SField| f.stats().levels.last().unwrap().seeds;
    assert!(seeds(&s.leaf) > seeds(&first));
}

#[test]
fn single_tunnel() {
    let s = scene("tunnel");
    s.assert_surface_through_seeds();
    let path = &s.features.tunnels[0].path;
    // Along the axis from outside the domain to outside the domain: never rock.
    let pts: Vec<Vec3> = (0..=400).map(|i| path.eval(i as f32 / 400.0)).collect();
    assert!(pts.windows(2).all(|w| s.clear(w[0], w[1])));
    // Rock around it.
    assert!(s.field.value(path.eval(0.5) + Vec3::Z * 12.0) > ISO);
    assert!(s.field.value(path.eval(0.5) - Vec3::Z * 12.0) > ISO);
}

#[test]
fn branching_tunnel() {
    let s = scene("branching_tunnel");
    s.assert_surface_through_seeds();
    for t in &s.features.tunnels {
        let pts: Vec<Vec3> = (0..=400).map(|i| t.path.eval(i as f32 / 400.0)).collect();
        assert!(
            pts.windows(2).all(|w| s.clear(w[0], w[1])),
            "a tunnel's axis hits rock"
        );
    }
}

#[test]
fn serpentine_road() {
    let s = scene("serpentine");
    s.assert_surface_through_seeds();
    // Sampled along the whole road, hairpins included.
    s.assert_constraint_normals(20.0);
}

#[test]
fn guidance_curves_alone_create_no_surface() {
    let s = scene("guidance");
    assert!(s.leaf.is_empty());
    for i in 0..1000 {
        let p = Vec3::new(
            (i % 10) as f32 * 6.3,
            ((i / 10) % 10) as f32 * 6.3,
            (i / 100) as f32 * 6.3,
        );
        assert_eq!(s.field.value(p), 0.0);
    }
}

#[test]
fn ridge_with_streamline_propagation() {
    let mut s = scene("ridge");
    s.spec.propagation = karstic::curves::Propagation::Streamline;
    s.leaf = s.spec.build_features(&s.features, 7, 1 << 32).unwrap();
    s.field = Box::new(s.leaf.clone());
    let fine = s.leaf.stats().levels.last().unwrap().clone();
    assert!(fine.streamline_nodes > 0, "streamlines added surface nodes");
    assert!(fine.bitangent_sweeps > 0);
    s.assert_surface_through_seeds();
    assert_eq!(s.crossings(64.0, 64.0), 1);
}

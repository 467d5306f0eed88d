//! Soundness of the compiled tree's operators on random trees (proptest): intervals,
//! Lipschitz bounds, gradients, z-bands, pruning and grid evaluation.
//!
//! The leaves are a minimal exact ball field defined here, so these tests check the tree
//! logic alone; `tests/primitives.rs` checks the real primitives.

use crate::common::Rng;

use std::sync::Arc;

use glam::{Affine3A, Quat, Vec3};
use karstic::field::Erosion;
use karstic::field::falloff::{WYVILL_MAX_SLOPE, wyvill, wyvill_d, wyvill_interval, wyvill_slope};
use karstic::field::skeleton::Point;
use karstic::field::{
    Aabb, Fbm, Field, Grid, ISO, Interval, Line, Node, NodeId, Primitive, PrimitiveSpec, Rect,
    Skeleton, Transition, Tree, TreeBuilder, Warp, ZBands, eval_grid, eval_grid_naive,
};
use karstic::geology::{Geology, GeologySpec};
use karstic::value::ron_options;
use proptest::prelude::*;

/// `energy · g(|p − c| / r)`.
struct Ball {
    c: Vec3,
    r: f32,
    e: f32,
}

impl Ball {
    fn d_range(&self, b: &Aabb) -> Interval {
        let lo = b.distance(self.c);
        let far = b
            .corners()
            .iter()
            .map(|q| (*q - self.c).length())
            .fold(0.0, f32::max);
        Interval::new(lo / self.r, far / self.r)
    }
}

impl Field for Ball {
    fn value(&self, p: Vec3) -> f32 {
        self.e * wyvill((p - self.c).length() / self.r)
    }
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let v = p - self.c;
        let d = v.length();
        let (g, dg) = wyvill_d(d / self.r);
        let dir = if d > 0.0 { v / d } else { Vec3::ZERO };
        (self.e * g, dir * (self.e * dg / self.r))
    }
    fn support(&self) -> Aabb {
        Aabb::around(self.c, self.r)
    }
    fn interval(&self, b: &Aabb) -> Interval {
        wyvill_interval(self.d_range(b)).scale(self.e)
    }
    fn lipschitz(&self) -> f32 {
        self.e.abs() * WYVILL_MAX_SLOPE / self.r
    }
    fn lipschitz_box(&self, b: &Aabb) -> f32 {
        self.e.abs() * wyvill_slope(self.d_range(b)) / self.r
    }
}

#[derive(Clone, Debug)]
enum Shape {
    Ball(Vec3, f32, f32),
    /// A point-skeleton primitive (the leaf a line evaluates from its profile).
    Blob(Vec3, f32, f32),
    Blend(Vec<Shape>),
    Union(Vec<Shape>),
    Inter(Vec<Shape>),
    Diff(Box<Shape>, Vec<Shape>),
    /// The second subtree in place of the first inside a box (corner, size, transition).
    Replace(Box<Shape>, Box<Shape>, Vec3, Vec3, f32),
    Move(Box<Shape>, Vec3, f32, f32),
    Warp(Box<Shape>, f32, u32),
    /// One subtree used twice (a union of it and a moved copy): the tree is a DAG.
    Shared(Box<Shape>, Vec3),
    /// Erosion by a geology inside a box (corner, size, strength, geology seed).
    Erode(Box<Shape>, Vec3, Vec3, f32, u32),
}

/// A geology with every continuous node kind at the scale of these trees: strata (band,
/// layers, noise of the altitude), turbulence, a softening sphere, a fold and a taper.
fn geology(seed: u32) -> Arc<Geology> {
    let text = r#"(root: Blend([
        Turbulence(base: 0.6, noise: (amplitude: 0.2, wavelength: 1.5, octaves: 2)),
        Strata(normal: (0.2, 0, 1), profile: Band(half_width: 0.8, resistance: -0.7)),
        Fold(
            turbulence: (amplitude: 0.6, wavelength: 4, octaves: 2),
            region: (min: (-3, -3, -3), max: (3, 3, 3), falloff: 2),
            child: Strata(point: (0, 0, 0.3), profile: Layers(layers: [
                (thickness: 0.7, resistance: 0.1), (thickness: 1.1, resistance: 0.5)]),
                turbulence: (amplitude: 0.05, wavelength: 1)),
        ),
        Taper(axis: (1, 0.5, 0), from: -4, to: 4, factor: (0.6, 1.8), z0: 1,
              child: Strata(profile: Noise(base: -0.2, noise: (amplitude: 0.3, wavelength: 2)))),
        Local(shape: Sphere(center: (1, -1, 0), radius: 1), falloff: 1.5, energy: -0.5),
    ]))"#;
    let spec: GeologySpec = ron_options().from_str(text).expect("a valid geology");
    Arc::new(Geology::from_spec(&spec, seed))
}

fn shape() -> impl Strategy<Value = Shape> {
    let v = || (-6.0f32..6.0, -6.0f32..6.0, -6.0f32..6.0).prop_map(|(x, y, z)| Vec3::new(x, y, z));
    let leaf = (
        v(),
        1.0f32..5.0,
        prop_oneof![0.6f32..1.6, -1.0f32..-0.3],
        any::<bool>(),
    )
        .prop_map(|(c, r, e, blob)| {
            if blob {
                Shape::Blob(c, r, e)
            } else {
                Shape::Ball(c, r, e)
            }
        });
    leaf.prop_recursive(3, 24, 4, move |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 1..20).prop_map(Shape::Blend),
            prop::collection::vec(inner.clone(), 1..4).prop_map(Shape::Union),
            prop::collection::vec(inner.clone(), 1..3).prop_map(Shape::Inter),
            (inner.clone(), prop::collection::vec(inner.clone(), 1..3))
                .prop_map(|(a, b)| Shape::Diff(Box::new(a), b)),
            (inner.clone(), inner.clone(), v(), v(), 0.2f32..4.0).prop_map(|(a, b, c, s, w)| {
                Shape::Replace(Box::new(a), Box::new(b), c, s.abs() + 1.0, w)
            }),
            (inner.clone(), v(), 0.5f32..2.0, -3.0f32..3.0).prop_map(|(a, t, s, r)| Shape::Move(
                Box::new(a),
                t,
                s,
                r
            )),
            (inner.clone(), 0.1f32..1.0, 0u32..100).prop_map(|(a, amp, seed)| Shape::Warp(
                Box::new(a),
                amp,
                seed
            )),
            (inner.clone(), v()).prop_map(|(a, t)| Shape::Shared(Box::new(a), t)),
            (inner, v(), v(), 0.0f32..0.8, 0u32..100).prop_map(|(a, c, s, k, seed)| {
                Shape::Erode(Box::new(a), c, s.abs() + 1.0, k, seed)
            }),
        ]
    })
}

fn build(s: &Shape, b: &mut TreeBuilder) -> NodeId {
    let all = |v: &[Shape], b: &mut TreeBuilder| v.iter().map(|c| build(c, b)).collect::<Vec<_>>();
    match s {
        Shape::Ball(c, r, e) => b.leaf(
            Arc::new(Ball {
                c: *c,
                r: *r,
                e: *e,
            }),
            None,
        ),
        Shape::Blob(c, r, e) => b.primitive(
            Primitive::new(Skeleton::Point(Point { center: *c }), *r, *e, None).unwrap(),
            None,
        ),
        Shape::Shared(a, t) => {
            let a = build(a, b);
            let moved = b.transform(a, Affine3A::from_translation(*t), None);
            b.union(vec![a, moved], None)
        }
        Shape::Blend(v) => {
            let cs = all(v, b);
            b.blend(cs, None)
        }
        Shape::Union(v) => {
            let cs = all(v, b);
            b.union(cs, None)
        }
        Shape::Inter(v) => {
            let cs = all(v, b);
            b.intersection(cs, None)
        }
        Shape::Diff(a, v) => {
            let a = build(a, b);
            let cs = all(v, b);
            b.difference(a, cs, None)
        }
        Shape::Replace(a, by, corner, size, w) => {
            let (a, by) = (build(a, b), build(by, b));
            let mix = Transition::new(Aabb::new(*corner, *corner + *size), *w);
            b.replace(a, by, mix, None)
        }
        Shape::Move(a, t, s, r) => {
            let a = build(a, b);
            let m = Affine3A::from_scale_rotation_translation(
                Vec3::new(*s, 1.0, 1.0 / s),
                Quat::from_rotation_z(*r),
                *t,
            );
            b.transform(a, m, None)
        }
        Shape::Erode(a, corner, size, strength, seed) => {
            let a = build(a, b);
            let region = Aabb::new(*corner, *corner + *size);
            let erosion = Erosion::new(geology(*seed), region, 0.3 * size.min_element(), *strength);
            b.erode(a, erosion, None)
        }
        Shape::Warp(a, amp, seed) => {
            let a = build(a, b);
            let region = Aabb::new(Vec3::splat(-3.0), Vec3::splat(3.0));
            b.warp(
                a,
                Warp::new(Fbm::with(*seed, 3.0, 2), *seed, *amp, Some((region, 2.0))),
                None,
            )
        }
    }
}

fn tree(s: &Shape) -> Tree {
    let mut b = TreeBuilder::new();
    let root = build(s, &mut b);
    b.build(root)
}

/// Deterministic points in a box: its corners, then uniform ones.
fn points(b: &Aabb, n: usize, seed: u32) -> Vec<Vec3> {
    let mut rng = Rng(u64::from(seed));
    let mut v: Vec<Vec3> = b.corners().to_vec();
    while v.len() < n {
        v.push(rng.in_box(b));
    }
    v
}

fn test_box() -> impl Strategy<Value = Aabb> {
    (-9.0f32..9.0, -9.0f32..9.0, -9.0f32..9.0, 0.05f32..6.0).prop_map(|(x, y, z, s)| {
        Aabb::new(
            Vec3::new(x, y, z),
            Vec3::new(x + s, y + s * 0.7, z + s * 1.3),
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, .. ProptestConfig::default() })]

    #[test]
    fn intervals_contain_samples(s in shape(), b in test_box()) {
        // Every node of the tree, not only the root.
        let t = tree(&s);
        for id in 0..t.nodes().len() as NodeId {
            let n = t.subtree(id);
            let iv = n.interval(&b);
            for p in points(&b, 64, 1) {
                let v = n.value(p);
                prop_assert!(iv.lo - 1e-4 <= v && v <= iv.hi + 1e-4, "{v} not in {iv:?} at {p}");
            }
        }
    }

    #[test]
    fn lipschitz_bounds_hold(s in shape(), b in test_box()) {
        let t = tree(&s);
        let ps = points(&b, 40, 2);
        for id in 0..t.nodes().len() as NodeId {
            let n = t.subtree(id);
            let (lg, lb) = (n.lipschitz(), n.lipschitz_box(&b));
            for w in ps.windows(2) {
                let (p, q) = (w[0], w[1]);
                let df = (n.value(p) - n.value(q)).abs();
                let d = (p - q).length();
                prop_assert!(df <= lb * d + 1e-4, "local: {df} > {lb}·{d}");
                prop_assert!(df <= lg * d + 1e-4, "global: {df} > {lg}·{d}");
            }
            // Along segments: pairs of points on [a, b] obey its segment bound.
            for w in ps.chunks(8) {
                let (a, b) = (w[0], w[w.len() - 1]);
                let ls = n.lipschitz_segment(a, b);
                let on: Vec<Vec3> = (0..=64).map(|i| a.lerp(b, i as f32 / 64.0)).collect();
                for k in 0..on.len() {
                    for j in (k + 1..on.len()).step_by(7) {
                        let df = (n.value(on[k]) - n.value(on[j])).abs();
                        let d = (on[k] - on[j]).length();
                        prop_assert!(df <= ls * d + 1e-4, "segment: {df} > {ls}·{d}");
                    }
                }
            }
        }
    }

    #[test]
    fn support_is_where_the_field_lives(s in shape(), b in test_box()) {
        let t = tree(&s);
        let sup = t.support();
        for p in points(&b, 32, 3) {
            if !sup.contains(p) {
                prop_assert_eq!(t.value(p), 0.0);
            }
        }
    }

    #[test]
    fn z_bands_contain_every_crossing(s in shape(), x in -8.0f32..8.0, y in -8.0f32..8.0, w in 0.1f32..3.0) {
        let t = tree(&s);
        let fp = Rect::new(glam::Vec2::new(x, y), glam::Vec2::new(x + w, y + w));
        let mut bands = ZBands::new();
        t.z_bands(&fp, Interval::new(-20.0, 20.0), &mut bands);
        for (i, j) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.5, 0.5), (1.0, 1.0)] {
            let (px, py) = (x + w * i, y + w * j);
            let mut last = t.value(Vec3::new(px, py, -20.0)) - ISO;
            for k in 1..=800 {
                let z = -20.0 + k as f32 * 0.05;
                let v = t.value(Vec3::new(px, py, z)) - ISO;
                if (v > 0.0) != (last > 0.0) {
                    prop_assert!(bands.contains(z) || bands.contains(z - 0.05), "crossing at z={z} outside {bands:?}");
                }
                last = v;
            }
        }
    }

    #[test]
    fn gradients_match_finite_differences(s in shape(), b in test_box()) {
        let t = tree(&s);
        let h = 1e-3;
        for p in points(&b, 24, 4) {
            let (v, g) = t.value_grad(p);
            prop_assert!((v - t.value(p)).abs() < 1e-5);
            let fd = Vec3::new(
                t.value(p + Vec3::X * h) - t.value(p - Vec3::X * h),
                t.value(p + Vec3::Y * h) - t.value(p - Vec3::Y * h),
                t.value(p + Vec3::Z * h) - t.value(p - Vec3::Z * h),
            ) / (2.0 * h);
            // min/max kinks and the skeleton are non-smooth: skip points where the two
            // one-sided estimates disagree.
            let smooth = (0..3).all(|a| {
                let e = Vec3::AXES[a] * h;
                let fwd = (t.value(p + e) - v) / h;
                let bwd = (v - t.value(p - e)) / h;
                (fwd - bwd).abs() < 1e-2 * (1.0 + t.lipschitz())
            });
            if smooth {
                prop_assert!((g - fd).length() < 2e-2 * (1.0 + t.lipschitz()), "∇ {g} vs FD {fd} at {p}");
            }
        }
    }

    #[test]
    fn pruning_preserves_values(s in shape(), b in test_box()) {
        let t = tree(&s);
        let pruned = t.prune(&b).unwrap();
        for p in points(&b, 48, 5) {
            prop_assert!((t.value(p) - pruned.value(p)).abs() < 1e-5);
        }
    }

    #[test]
    fn grid_evaluation_matches_point_evaluation(s in shape()) {
        let t = tree(&s);
        let grid = Grid { origin: Vec3::new(-9.0, -8.5, -9.3), step: Vec3::new(0.9, 0.8, 0.85), dims: [21, 19, 23] };
        let fast = eval_grid(&t, &grid, None);
        let naive = eval_grid_naive(&t, &grid);
        for (a, b) in fast.iter().zip(&naive) {
            prop_assert!((a - b).abs() < 1e-5, "{a} vs {b}");
        }
    }
}

/// A blend large enough for a BVH, of random subtrees and blobs.
fn crowd() -> impl Strategy<Value = Shape> {
    let v = || (-8.0f32..8.0, -8.0f32..8.0, -8.0f32..8.0).prop_map(|(x, y, z)| Vec3::new(x, y, z));
    let blob = (v(), 0.5f32..3.0, 0.4f32..1.2).prop_map(|(c, r, e)| Shape::Blob(c, r, e));
    (
        prop::collection::vec(shape(), 1..4),
        prop::collection::vec(blob, 16..40),
    )
        .prop_map(|(mut a, b)| {
            a.extend(b);
            Shape::Blend(a)
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 150, .. ProptestConfig::default() })]

    /// Pruning a blend with a BVH (its BVH restricted to the region, not rebuilt) keeps
    /// its values.
    #[test]
    fn pruning_a_crowd_preserves_values(s in crowd(), b in test_box()) {
        let t = tree(&s);
        let pruned = t.prune(&b).unwrap();
        for p in points(&b, 48, 5) {
            prop_assert!((t.value(p) - pruned.value(p)).abs() < 1e-5, "at {}", p);
        }
    }

    /// A line's values and segment bounds are the tree's along the ray, asked in the
    /// order a march asks them (mostly forward, stepping back to refine), and its bounds
    /// hold for pairs on the segment and are never looser than the tree's.
    #[test]
    fn lines_answer_like_the_tree(
        s in crowd(),
        o in (-14.0f32..14.0, -14.0f32..14.0, -14.0f32..14.0),
        to in (-5.0f32..5.0, -5.0f32..5.0, -5.0f32..5.0),
    ) {
        let t = tree(&s);
        let o = Vec3::new(o.0, o.1, o.2);
        let d = (Vec3::new(to.0, to.1, to.2) - o).normalize_or(Vec3::X);
        let span = (0.0, 40.0);
        let mut line = Line::new(&t);
        line.restrict(o, d, span);
        let mut at = 0.0f32;
        let mut k = 0u32;
        while at < span.1 {
            k += 1;
            let len = [0.05f32, 0.7, 3.0, 9.0][k as usize % 4];
            let end = (at + len).min(span.1);
            let (a, b) = (o + d * at, o + d * end);
            let lam = line.lipschitz(at, end);
            prop_assert!(
                lam <= t.lipschitz_segment(a, b) * 1.001 + 1e-5,
                "line bound {lam} above the tree's {}", t.lipschitz_segment(a, b)
            );
            for i in 0..=12 {
                let ti = at + (end - at) * i as f32 / 12.0;
                let (v, w) = (line.value(ti), t.value(o + d * ti));
                prop_assert!((v - w).abs() < 1e-5, "value at t = {ti}: line {v}, tree {w}");
                // Gradients (the hit's normal) too.
                let ((lv, lg), (tv, tg)) = (line.value_grad(ti), t.value_grad(o + d * ti));
                prop_assert!(
                    (lv - tv).abs() < 1e-5 && lg.abs_diff_eq(tg, 1e-4 * (1.0 + tg.length())),
                    "gradient at t = {ti}: line {lv} {lg}, tree {tv} {tg}"
                );
                let df = (v - line.value(at)).abs();
                prop_assert!(df <= lam * (ti - at) * 1.001 + 1e-4, "bound {lam} on [{at}, {end}]: {df}");
            }
            // Step back now and then, as a refinement does.
            at = if k.is_multiple_of(5) { end - 0.5 * (end - at) } else { end };
        }
    }
}

#[test]
fn blend_bvh_answers_like_a_linear_scan() {
    // 400 balls: the blend gets a BVH; compare with the same sum evaluated leaf by leaf.
    let balls: Vec<Ball> = points(&Aabb::new(Vec3::splat(-50.0), Vec3::splat(50.0)), 400, 9)
        .into_iter()
        .map(|c| Ball { c, r: 4.0, e: 1.0 })
        .collect();
    let mut b = TreeBuilder::new();
    let ids: Vec<NodeId> = balls
        .iter()
        .map(|x| {
            b.leaf(
                Arc::new(Ball {
                    c: x.c,
                    r: x.r,
                    e: x.e,
                }),
                None,
            )
        })
        .collect();
    let root = b.blend(ids, None);
    let t = b.build(root);
    // The global bound uses overlap groups: far below the sum of all 400 slopes.
    assert!(t.lipschitz() < 400.0 * balls[0].lipschitz() / 4.0);
    for p in points(&Aabb::new(Vec3::splat(-55.0), Vec3::splat(55.0)), 5000, 10) {
        let direct: f32 = balls.iter().map(|x| x.value(p)).sum();
        assert!((t.value(p) - direct).abs() < 1e-5);
    }
}

/// A blend of thousands of children answers point queries through its point index (round
/// kernels evaluated in the index, other children through their nodes) with exactly the
/// sum, in the BVH's order, of the children whose supports hold the point: on random
/// points, near every child's centre (where it is non-zero, so an index that missed a
/// child would change the value), on the supports' corners and faces, and outside them.
#[test]
fn blend_point_index_sums_like_the_bvh_to_the_bit() {
    let mut rng = Rng(23);
    let mut b = TreeBuilder::new();
    let mut ids = Vec::new();
    let mut centres = Vec::new();
    for i in 0..3000 {
        let c = Vec3::new(
            rng.range(0.0, 400.0),
            rng.range(0.0, 400.0),
            rng.range(0.0, 30.0),
        );
        let (x, y, z) = (c.x, c.y, c.z);
        let shape = match i % 5 {
            0 => format!("Point(center: ({x}, {y}, {z}))"),
            1 => format!("Segment(a: ({x}, {y}, {z}), b: ({}, {y}, {z}))", x + 3.0),
            _ => format!("Sphere(center: ({x}, {y}, {z}), radius: 1.5)"),
        };
        let energy = if i % 7 == 0 { -0.4 } else { 1.0 };
        let spec = format!("(shape: {shape}, falloff: 3, energy: {energy})");
        let spec: PrimitiveSpec = ron::from_str(&spec).unwrap();
        ids.push(match i % 11 {
            // Other leaves go through their nodes.
            3 => b.leaf(Arc::new(Ball { c, r: 4.0, e: 0.7 }), None),
            _ => b.primitive(Primitive::from_spec(&spec, 0), None),
        });
        centres.push(c);
    }
    let root = b.blend(ids.clone(), None);
    let t = b.build(root);
    let Node::Blend { bvh: Some(bvh), .. } = &t.nodes()[root as usize] else {
        panic!("a blend with a BVH");
    };
    let mut points: Vec<Vec3> = centres
        .iter()
        .map(|&c| c + Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 0.5))
        .collect();
    let whole = Aabb::new(Vec3::splat(-20.0), Vec3::new(420.0, 420.0, 50.0));
    points.extend((0..20_000).map(|_| rng.in_box(&whole)));
    for &c in &ids {
        let s = t.info(c).support;
        points.extend([s.min, s.max, Vec3::new(s.min.x, s.center().y, s.max.z)]);
    }
    points.extend([Vec3::new(-500.0, 3.0, 3.0), Vec3::new(200.0, 200.0, 1e3)]);
    // The batch (by blocks through the index) sums as the point query does.
    let mut batch = vec![f32::NAN; points.len()];
    t.values(&points, &mut batch);
    let mut nonzero = 0;
    for (p, v) in points.into_iter().zip(batch) {
        let mut want = 0.0f32;
        bvh.at_point(p, |c| want += t.subtree(c).value(p));
        assert_eq!(t.value(p).to_bits(), want.to_bits(), "at {p}");
        assert_eq!(v.to_bits(), want.to_bits(), "batch at {p}");
        let linear: f32 = ids.iter().map(|&c| t.subtree(c).value(p)).sum();
        assert!((want - linear).abs() < 1e-5, "at {p}: {want} vs {linear}");
        nonzero += (want != 0.0) as usize;
    }
    assert!(
        nonzero > 3000,
        "{nonzero} points where the blend is non-zero"
    );
}

/// Replacing one flat field by another: the whole slope is the transition's, `|f_by −
/// f_base|·g'_max/W`, which the children's own bounds (0 here) do not see.
#[test]
fn replace_bounds_hold_across_the_transition() {
    let mut b = TreeBuilder::new();
    let (base, by) = (b.constant(0.2, None), b.constant(0.9, None));
    let region = Aabb::new(Vec3::new(-2.0, -1.0, -3.0), Vec3::new(4.0, 2.0, 1.0));
    let root = b.replace(base, by, Transition::new(region, 0.5), None);
    let t = b.build(root);
    let mut rng = Rng(3);
    let around = region.dilate(1.0);
    let mut steepest = 0.0f32;
    for _ in 0..4000 {
        let p = rng.in_box(&around);
        let q = p + rng.dir() * 0.05 * rng.f32();
        let (df, d) = ((t.value(p) - t.value(q)).abs(), p.distance(q));
        steepest = steepest.max(df / d.max(1e-9));
        let bx = Aabb::new(p.min(q), p.max(q));
        for l in [
            t.lipschitz(),
            t.lipschitz_box(&bx),
            t.lipschitz_segment(p, q),
        ] {
            assert!(df <= l * d + 1e-5, "{df} > {l}·{d} at {p}");
        }
        let iv = t.interval(&bx);
        assert!(iv.contains(t.value(p)) && iv.contains(t.value(q)));
    }
    // The slope is really there (0.7 · g'_max / W = 2.4): the bound is not vacuous.
    assert!(steepest > 2.0, "{steepest}");
    // Inside the core and outside the region the field is flat and bounded as such.
    let core = Aabb::new(Vec3::new(0.0, 0.0, -1.0), Vec3::new(1.0, 1.0, 0.0));
    let outside = Aabb::new(Vec3::new(6.0, 0.0, 0.0), Vec3::new(7.0, 1.0, 1.0));
    assert_eq!(t.lipschitz_box(&core), 0.0);
    assert_eq!(t.lipschitz_box(&outside), 0.0);
    assert_eq!(t.interval(&core), Interval::point(0.9));
}

/// A replacement whose surface lies above its base's (a ball raised by 3 m): across the
/// transition the mix crosses `T` between the two children's surfaces, in the gap between
/// their own z-bands, and the replace node's bands must hold those crossings too. Where
/// the children agree on the side (inside both balls, above both) the gaps are skipped.
#[test]
fn replace_bands_hold_the_mix_between_its_childrens_surfaces() {
    let mut b = TreeBuilder::new();
    let ball = |c: Vec3| Arc::new(Ball { c, r: 8.0, e: 1.0 });
    let base = b.leaf(ball(Vec3::ZERO), None);
    let by = b.leaf(ball(Vec3::new(0.0, 0.0, 3.0)), None);
    let region = Aabb::new(Vec3::new(-2.0, -10.0, -20.0), Vec3::new(20.0, 10.0, 20.0));
    let root = b.replace(base, by, Transition::new(region, 3.0), None);
    let t = b.build(root);
    let zr = Interval::new(-20.0, 20.0);
    let (mut between, mut crossings) = (0, 0);
    for i in 0..24 {
        // Columns across the transition at the region's −x face and into its core.
        let x = -2.5 + 0.25 * i as f32;
        let fp = Rect::new(glam::Vec2::new(x, 0.0), glam::Vec2::new(x + 0.1, 0.1));
        let bands_of = |id: NodeId| {
            let mut bands = ZBands::new();
            t.z_bands_at(id, &fp, zr, &mut bands);
            bands
        };
        let (bands, own_base, own_by) = (bands_of(root), bands_of(base), bands_of(by));
        let mut last = t.value(Vec3::new(x, 0.0, zr.lo)) - ISO;
        for k in 1..=4000 {
            let z = zr.lo + k as f32 * 0.01;
            let v = t.value(Vec3::new(x, 0.0, z)) - ISO;
            if (v > 0.0) != (last > 0.0) {
                crossings += 1;
                assert!(
                    bands.contains(z) || bands.contains(z - 0.01),
                    "crossing at ({x}, 0, {z}) outside {bands:?}"
                );
                if !own_base.contains(z) && !own_by.contains(z) {
                    between += 1;
                }
            }
            last = v;
        }
    }
    assert!(crossings >= 24, "{crossings}");
    assert!(
        between > 0,
        "no crossing between the children's own bands: the test misses the gaps"
    );
}

//! One conformance suite per node kind, run on all three forms of a field — the compiled
//! tree, its CPU tape and (with an adapter) the GPU — as fidget runs its interval tests on
//! every backend. Each case of the table is a small scene; [`conform`] checks that
//!
//! * its tape uses the ops, shapes and evaluator features the case is about (so a case
//!   cannot drift away from the kind it tests);
//! * the tape equals the tree at points spread over the tree's node supports and on its
//!   surface `f = T`;
//! * the tape's ball bounds are sound (pairs of points in random balls, and on random
//!   segments), and its support lies in the tree's with 0 outside;
//! * the GPU's values and ball bounds equal the CPU tape's at the same points.

use crate::common;

use common::{Rng, assert_probes_match, check_segment_lipschitz, gpu};
use glam::Vec3;
use karstic::field::{Aabb, Field, ISO, Tree, TreeBuilder};
use karstic::tape::format::{flag, op, shape};
use karstic::tape::{FEATURES, Tape, tape_from_tree};

/// What a case's tape must contain.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Uses {
    /// An instruction with this op code.
    Op(u32),
    /// A `PRIM` or `NPRIM` on this shape kind.
    Shape(u32),
    /// An instruction with these flag bits.
    Flag(u32),
    /// This part of the WGSL evaluator ([`FEATURES`]).
    Feature(&'static str),
}

/// A tree file around `root` (a RON node), compiled with `trees/` as its folder (for
/// `data/jacksboro_crop.asc`).
fn scene(root: &str) -> Tree {
    let text = format!("(version: 1, seed: 5, root: {root})");
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("trees");
    let path = dir.join("conformance.ron");
    let sc = karstic::scene::parse_scene(&text, &path).unwrap_or_else(|e| panic!("{e}"));
    karstic::compile::compile_scene(&sc, &path, &dir)
        .unwrap_or_else(|e| panic!("{e}"))
        .tree
}

/// A Wyvill point blob of the tree-file kind (for trees built node by node).
fn blob(b: &mut TreeBuilder, at: Vec3, falloff: f32) -> karstic::field::NodeId {
    let spec = format!(
        "(shape: Point(center: ({}, {}, {})), falloff: {falloff})",
        at.x, at.y, at.z
    );
    let spec: karstic::field::PrimitiveSpec = ron::from_str(&spec).unwrap();
    b.leaf(
        std::sync::Arc::new(karstic::field::Primitive::from_spec(&spec, 1)),
        None,
    )
}

/// The DEM of the scenes in `trees/` (128 × 128 samples, 90 m cells).
const DEM: &str = r#"source: "data/jacksboro_crop.asc", falloff: 30.0"#;

/// A small tunnel through rock (Feature Curves through the voxel pipeline), with `extra`
/// fields of the tunnel and of the volume.
fn tunnel(tunnel_extra: &str, volume_extra: &str) -> Tree {
    scene(&format!(
        "FeatureVolume(curves: Inline(tunnels: [(path: [Abs(-4, 12, 12), Abs(20, 10, 13), \
         Abs(52, 13, 11)], width: Const(8), height: Const(6){tunnel_extra})]), \
         domain: ((0, 0, 0), (47, 23, 23)), voxel: 1.0{volume_extra})"
    ))
}

/// One test per case: `name: [uses…] => tree;`.
macro_rules! conformance {
    ($($name:ident: [$($uses:expr),* $(,)?] => $tree:expr;)*) => {$(
        #[test]
        fn $name() {
            let tree = $tree;
            let tape = tape_from_tree(&tree).unwrap_or_else(|e| panic!("no tape: {e}"));
            conform(stringify!($name), &tree, &tape, &[$($uses),*]);
        }
    )*};
}

use Uses::{Feature, Flag, Op, Shape};

conformance! {
    point: [Op(op::PRIM), Shape(shape::SPHERE)] =>
        scene("Primitive(shape: Point(center: (1, 2, 3)), falloff: 2.5, energy: 1.3)");
    segment: [Shape(shape::CAPSULE)] =>
        scene("Primitive(shape: Segment(a: (-3, 0, 1), b: (4, 2, 3)), falloff: 2)");
    segment_of_zero_length: [Shape(shape::CAPSULE)] =>
        scene("Primitive(shape: Segment(a: (1, 1, 1), b: (1, 1, 1)), falloff: 2)");
    sphere: [Shape(shape::SPHERE)] =>
        scene("Primitive(shape: Sphere(center: (0, 4, 2), radius: 1.5), falloff: 2, energy: 1.3)");
    capsule: [Shape(shape::CAPSULE)] =>
        scene("Primitive(shape: Capsule(a: (-5, -5, 0), b: (-2, -6, 4), radius: 1), falloff: 1.5)");
    axis_aligned_box: [Shape(shape::BOX)] =>
        scene("Primitive(shape: Box(center: (3, -4, 0), half_size: (2, 1, 0.5)), falloff: 1.2)");
    box_turned_by_90_degrees: [Shape(shape::BOX)] =>
        scene("Primitive(shape: Box(center: (3, -4, 0), half_size: (2, 1, 0.5), yaw: 90), falloff: 1.2)");
    polyline: [Op(op::UNION), Op(op::GUARD), Shape(shape::CAPSULE)] =>
        scene("Primitive(shape: Polyline(points: [(-6, 2, 0), (-3, 5, 2), (0, 6, 1), (3, 4, 0), \
               (5, 5, 2), (7, 3, 1)]), falloff: 1.8)");
    curve_carving: [Op(op::INTER), Op(op::GUARD)] => scene(
        "Blend(children: [Primitive(shape: Box(center: (0, 0, 2), half_size: (9, 3, 2)), falloff: 2), \
         Primitive(shape: Curve(points: [(-8, 0, 2), (0, 1, 3), (8, 0, 2)]), falloff: 2, energy: -0.7)])");
    cone: [Shape(shape::CONE), Feature("USE_CONE")] =>
        scene("Primitive(shape: Cone(base: (6, 6, -1), apex: (7, 5, 6), radius: 2.5), falloff: 2, energy: 1.1)");
    cone_upside_down: [Shape(shape::CONE)] =>
        scene("Primitive(shape: Cone(base: (-7, -1, 5), apex: (-6, 1, 0), radius: 1.5), falloff: 1.5)");
    ellipsoid: [Shape(shape::ELLIPSOID), Feature("USE_ELLIPSOID")] =>
        scene("Primitive(shape: Ellipsoid(center: (2, -7, 1), radii: (3, 1.2, 2)), falloff: 1.8, energy: 1.2)");
    ellipsoid_flat: [Shape(shape::ELLIPSOID)] =>
        scene("Primitive(shape: Ellipsoid(center: (-2, 7, 3), radii: (0.6, 2.5, 1)), falloff: 1.2)");
    noisy_point: [Op(op::NPRIM), Shape(shape::SPHERE), Feature("USE_NPRIM")] =>
        scene("Primitive(shape: Point(center: (0, 0, 2)), falloff: 3, energy: 1.2, \
               noise: (amplitude: 1.0, wavelength: 2.5, octaves: 2))");
    noisy_segment: [Op(op::NPRIM), Shape(shape::CAPSULE)] =>
        scene("Primitive(shape: Segment(a: (-6, 3, 1), b: (-1, 6, 3)), falloff: 3, energy: 1.2, \
               noise: (amplitude: 1.3, wavelength: 3.5, octaves: 3, seed_offset: 1))");
    noisy_sphere: [Op(op::NPRIM), Shape(shape::SPHERE)] =>
        scene("Primitive(shape: Sphere(center: (5, 4, 2), radius: 2), falloff: 3, energy: 1.2, \
               noise: (amplitude: 1.6, wavelength: 4.5, octaves: 4, seed_offset: 2))");
    noisy_capsule: [Op(op::NPRIM), Shape(shape::CAPSULE)] =>
        scene("Primitive(shape: Capsule(a: (-7, -5, 0), b: (-3, -6, 3), radius: 1.2), falloff: 3, \
               energy: 1.2, noise: (amplitude: 1.9, wavelength: 5.5, octaves: 5, seed_offset: 3))");
    noisy_box: [Op(op::NPRIM), Shape(shape::BOX)] =>
        scene("Primitive(shape: Box(center: (4, -4, 0), half_size: (2.5, 1.5, 1)), falloff: 3, \
               energy: 1.2, noise: (amplitude: 2.2, wavelength: 6.5, octaves: 2, seed_offset: 4))");
    noisy_cone: [Op(op::NPRIM), Shape(shape::CONE), Feature("USE_CONE")] =>
        scene("Primitive(shape: Cone(base: (8, 0, -1), apex: (9, 1, 6), radius: 2.5), falloff: 3, \
               energy: 1.2, noise: (amplitude: 2.2, wavelength: 7.5, octaves: 3, seed_offset: 5))");
    noisy_ellipsoid: [Op(op::NPRIM), Shape(shape::ELLIPSOID), Feature("USE_ELLIPSOID")] =>
        scene("Primitive(shape: Ellipsoid(center: (-9, 3, 2), radii: (2.5, 1.5, 2)), falloff: 3, \
               energy: 1.2, noise: (amplitude: 2.2, wavelength: 8.5, octaves: 4, seed_offset: 6))");
    noisy_polyline_carving: [Op(op::NPRIM), Op(op::INTER)] => scene(
        "Blend(children: [Primitive(shape: Box(center: (0, 0, 3), half_size: (9, 3, 2)), falloff: 2), \
         Primitive(shape: Polyline(points: [(-8, 0, 3), (0, 1, 4), (8, -1, 3)]), falloff: 2, \
         energy: -0.8, noise: (amplitude: 0.9, wavelength: 3.0, octaves: 3, seed_offset: 9))])");
    heightfield_bilinear: [Op(op::HEIGHT), Shape(shape::PRISM), Feature("USE_HEIGHT")] =>
        scene(&format!("Heightfield({DEM})"));
    heightfield_bicubic: [Op(op::HEIGHT), Flag(flag::BICUBIC), Feature("USE_BICUBIC")] =>
        scene(&format!("Heightfield({DEM}, interpolation: Bicubic)"));
    heightfield_with_detail: [Op(op::HEIGHT), Flag(flag::DETAIL), Feature("USE_HEIGHT_DETAIL")] =>
        scene(&format!("Heightfield({DEM}, interpolation: Bicubic, detail: (noise: (amplitude: 5, \
         wavelength: 40, octaves: 4, seed_offset: 2), steep: 0.6))"));
    heightfield_placed_and_scaled: [Op(op::HEIGHT)] => scene(&format!(
        "Heightfield({DEM}, placement: (-300, 500), vertical_scale: 1.5, vertical_offset: -200, \
         base_depth: 80)"));
    sfield: [Op(op::SFIELD), Feature("USE_SFIELD")] => tunnel("", "");
    sfield_tricubic: [Op(op::SFIELD), Feature("USE_SF_CUBIC")] =>
        tunnel("", ", interpolation: Tricubic");
    sfield_with_displacement_noise: [Op(op::SFIELD), Feature("USE_SF_NOISE")] =>
        tunnel(", amplitude: 1.0, roughness: 0.15", "");
    constant: [Op(op::CONST), Op(op::UNION)] => {
        let mut b = TreeBuilder::new();
        let ball = blob(&mut b, Vec3::ZERO, 6.0);
        let small = blob(&mut b, Vec3::new(1.0, 0.0, 0.0), 2.0);
        let third = b.constant(0.3, None);
        let lifted = b.union(vec![small, third], None);
        let root = b.intersection(vec![lifted, ball], None);
        b.build(root)
    };
    blend: [Op(op::BLEND)] => scene(
        "Blend(children: [Primitive(shape: Point(center: (0, 0, 0)), falloff: 2.5), \
         Primitive(shape: Point(center: (2, 0, 0.5)), falloff: 2.5), \
         Primitive(shape: Segment(a: (0, 2, 0), b: (3, 3, 1)), falloff: 2, energy: 0.8)])");
    blend_under_a_bvh: [Op(op::BLEND), Op(op::GUARD)] => {
        let mut b = TreeBuilder::new();
        let blobs = (0..40)
            .map(|i| {
                let a = i as f32 * 0.7;
                blob(&mut b, Vec3::new(8.0 * a.cos(), 8.0 * a.sin(), 0.2 * i as f32), 2.5)
            })
            .collect();
        let root = b.blend(blobs, None);
        b.build(root)
    };
    union: [Op(op::UNION)] => scene(
        "Union(children: [Primitive(shape: Capsule(a: (-4, 0, 0), b: (4, 0, 0), radius: 1), falloff: 2), \
         Primitive(shape: Capsule(a: (0, -4, 1), b: (0, 4, 1), radius: 1.5), falloff: 2, energy: 1.4)])");
    intersection: [Op(op::INTER)] => scene(
        "Intersection(children: [Primitive(shape: Sphere(center: (0, 0, 0), radius: 3), falloff: 2), \
         Primitive(shape: Box(center: (1, 1, 0), half_size: (3, 2, 2)), falloff: 1.5, energy: 1.2)])");
    difference: [Op(op::DIFF)] => scene(
        "Difference(base: Primitive(shape: Box(center: (0, 0, 0), half_size: (5, 4, 2)), falloff: 2), \
         carves: [Primitive(shape: Sphere(center: (2, 2, 2), radius: 2), falloff: 1.5, energy: 1.4), \
         Primitive(shape: Capsule(a: (-6, 0, 0), b: (6, -1, 0), radius: 0.5), falloff: 1.5)])");
    replace: [Op(op::REPLACE)] => scene(
        "Replace(base: Primitive(shape: Box(center: (0, 0, 0), half_size: (6, 5, 2)), falloff: 2), \
         by: Primitive(shape: Sphere(center: (1, 0, 1), radius: 3), falloff: 2.5, energy: 1.3), \
         region: (min: (-3, -4, -3), max: (5, 3, 4)), blend: 2.5)");
    replace_the_dem_by_a_terrain_aware_volume: [Op(op::REPLACE), Op(op::SFIELD), Op(op::HEIGHT)] =>
        scene(&format!(
            "Replace(base: Heightfield({DEM}), by: FeatureVolume(curves: Inline(tunnels: \
             [(path: [Abs(3700, 4950, 852), Abs(3560, 4958, 860)], width: Const(12), \
             height: Const(10))]), domain: ((3530, 4910, 800), (3720, 5000, 940)), voxel: 2.0, \
             on_terrain: true))"));
    transform: [Op(op::WARP), Op(op::UNWARP)] => scene(
        "Transform(translate: (-9, 9, 2), rotate: (axis: (1, 1, 0.3), degrees: 35), \
         scale: (1.2, 0.7, 1.0), child: Primitive(shape: Box(center: (0, 0, 1), \
         half_size: (4, 3, 2)), falloff: 2))");
    transform_mirroring_a_heightfield: [Op(op::WARP), Op(op::HEIGHT)] => scene(&format!(
        "Intersection(children: [Heightfield({DEM}), Transform(translate: (0, 0, 1450), \
         scale: (1, 1, -1), child: Heightfield({DEM}))])"));
    warp: [Op(op::TWARP), Op(op::UNWARP), Feature("USE_TWARP")] => scene(
        "Warp(turbulence: (amplitude: 0.7, wavelength: 3.0, octaves: 2), \
         child: Primitive(shape: Sphere(center: (0, 0, 0), radius: 2), falloff: 2.5))");
    warp_in_a_region: [Op(op::TWARP)] => scene(
        "Warp(turbulence: (amplitude: 0.8, wavelength: 4.0, octaves: 3, seed_offset: 11), \
         region: (min: (-6, -6, -2), max: (2, 6, 6), falloff: 2.5), \
         child: Blend(children: [Primitive(shape: Capsule(a: (-8, 0, 0), b: (8, 2, 1), radius: 1.5), \
         falloff: 3), Primitive(shape: Box(center: (0, 0, -2), half_size: (9, 7, 1)), falloff: 2)]))");
    anchor: [Op(op::WARP), Op(op::HEIGHT), Shape(shape::ELLIPSOID)] => scene(&format!(
        "Difference(base: Heightfield(name: \"dem\", {DEM}), carves: [Anchor(at: (3690, 5220), \
         offset: -12, child: Primitive(shape: Ellipsoid(center: (-25, 0, 0), radii: (40, 22, 11)), \
         falloff: 6.0))])"));
}

/// The checks of the module's documentation on `tree` and its tape, which must contain
/// `uses`.
pub(crate) fn conform(name: &str, tree: &Tree, tape: &Tape, uses: &[Uses]) {
    for u in uses {
        let found = tape.instrs.iter().any(|i| match *u {
            Uses::Op(code) => i.op == code,
            Uses::Shape(kind) => {
                (i.op == op::PRIM || i.op == op::NPRIM) && i.flags & flag::SHAPE_MASK == kind
            }
            Uses::Flag(bits) => i.flags & bits == bits,
            Uses::Feature(f) => {
                let bit = FEATURES.iter().position(|&x| x == f).expect("a feature");
                tape.features() & (1 << bit) != 0
            }
        });
        assert!(found, "{name}: the tape does not use {u:?}");
    }

    // The tape equals the tree.
    let (pts, surface) = sample_points(tree, 4000, 3);
    assert!(surface >= 40, "{name}: only {surface} surface points");
    let mut between = 0;
    for &p in &pts {
        let (v, t) = (tree.value(p), tape.value(p));
        between += usize::from(v.abs() > 1e-3 && (v - 2.0 * ISO).abs() > 1e-3);
        assert!(
            (v - t).abs() <= 1e-4 * v.abs().max(1.0),
            "{name} at {p}: tree {v}, tape {t}"
        );
    }
    assert!(
        between * 10 >= pts.len(),
        "{name}: only {between} points where the value is not saturated"
    );

    // Its bounds are sound, its support the tree's.
    let support = tree.support();
    check_ball_bounds(name, tape, &support, 4000, 5);
    check_segment_lipschitz(tape, &support, 2000, 6);
    let inner = tape.support();
    assert!(
        support.contains_box(&inner),
        "{name}: tape support {inner:?} ⊄ {support:?}"
    );
    let mut rng = Rng(8);
    for _ in 0..500 {
        let p = inner.center()
            + rng.in_ball(1.0).normalize_or_zero() * inner.radius() * rng.range(1.01, 2.0);
        assert_eq!(
            tape.value(p),
            0.0,
            "{name}: non-zero outside the support at {p}"
        );
    }

    // The GPU evaluates it as the CPU does: values alone and ball bounds.
    let Some(ctx) = gpu() else { return };
    let mut rng = Rng(9);
    let scale = 0.05 * support.radius();
    let probes: Vec<(Vec3, f32)> = pts
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            (
                p,
                if i % 3 == 0 {
                    0.0
                } else {
                    rng.range(0.0, scale)
                },
            )
        })
        .collect();
    assert_probes_match(ctx, tape, &probes);
}

/// For random balls `B(c, r)` in `region`, `λ` the tape's bound over the ball:
/// `|f(a) − f(b)| ≤ λ·|a − b|` (plus float slack) for two random points of the ball, and
/// for two close points along the steepest direction at a random point (where a loose
/// pair would hide a bound that is too small); and `λ` within the global bound.
fn check_ball_bounds(name: &str, tape: &Tape, region: &Aabb, n: usize, seed: u64) {
    let mut rng = Rng(seed);
    let check = |a: Vec3, b: Vec3, lam: f32, c: Vec3, r: f32| {
        let df = (tape.value(a) - tape.value(b)).abs();
        assert!(
            df <= lam * a.distance(b) * 1.001 + 1e-6,
            "{name}: bound {lam} over B({c}, {r}) violated: |Δf| = {df} over {}",
            a.distance(b)
        );
    };
    for _ in 0..n {
        let c = point_in(&mut rng, region);
        let r = region.radius() * (0.2 * rng.f32() * rng.f32() + 1e-3);
        let (_, lam) = tape.eval(c, c, r);
        assert!(
            lam <= tape.lipschitz() * 1.0001 + 1e-6,
            "{name}: local bound {lam} above the global {}",
            tape.lipschitz()
        );
        check(c + rng.in_ball(r), c + rng.in_ball(r), lam, c, r);
        let h = 0.005 * r;
        let a = c + rng.in_ball(r - h);
        let d = |e: Vec3| tape.value(a + e * h) - tape.value(a - e * h);
        let steepest = Vec3::new(d(Vec3::X), d(Vec3::Y), d(Vec3::Z)).normalize_or_zero();
        check(a - steepest * h, a + steepest * h, lam, c, r);
    }
}

pub(crate) fn point_in(rng: &mut Rng, b: &Aabb) -> Vec3 {
    b.min + Vec3::new(rng.f32(), rng.f32(), rng.f32()) * b.size()
}

/// Points spread over the tree: uniform in the root's support and in the supports of
/// random nodes, plus points on the surface `f = T` found by bisecting between samples
/// on either side of it. Returns them and how many are on the surface.
pub(crate) fn sample_points(tree: &Tree, n: usize, seed: u64) -> (Vec<Vec3>, usize) {
    let mut rng = Rng(seed);
    // (A constant's "everywhere" is ±f32::MAX: finite corners, infinite size.)
    let finite = |b: &Aabb| !b.is_empty() && b.size().is_finite();
    let boxes: Vec<Aabb> = (0..tree.nodes().len() as u32)
        .map(|id| tree.info(id).support)
        .filter(finite)
        .collect();
    let root = tree.support();
    assert!(finite(&root), "support {root:?}");
    let mut pts = Vec::with_capacity(n);
    let mut surface = 0;
    while pts.len() < n {
        let b = if rng.f32() < 0.5 {
            root.dilate(0.05 * root.radius())
        } else {
            boxes[(rng.next_u64() % boxes.len() as u64) as usize]
        };
        let (p, q) = (point_in(&mut rng, &b), point_in(&mut rng, &b));
        pts.push(p);
        let (fp, fq) = (tree.value(p) - ISO, tree.value(q) - ISO);
        if fp * fq < 0.0 {
            let (mut a, mut z) = (p, q);
            for _ in 0..30 {
                let m = 0.5 * (a + z);
                if (tree.value(m) - ISO) * fp > 0.0 {
                    a = m;
                } else {
                    z = m;
                }
            }
            pts.push(a);
            surface += 1;
        }
    }
    (pts, surface)
}

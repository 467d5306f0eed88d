//! Elevation trees (Génevaux et al. 2015): the tree's bounds hold on sampled points and
//! pairs, replace is continuous, LoD at level ∞ is the full evaluation, and the 3D leaf
//! over a tree keeps every bound of the field contract (sampled like the raster leaf's).

use crate::common::{Rng, check_z_bands};

use std::path::Path;
use std::sync::Arc;

use glam::{Vec2, Vec3};
use karstic::elevation::{BuildContext, ElevationField, ElevationSpec, ElevationTree, Lod, Node};
use karstic::field::{Aabb, Field, ISO, Rect};
use karstic::io::DEFAULT_MEMORY_BUDGET;

/// A tree with every primitive and operator: blended multifractal discs (one warped), an
/// image patch (a DEM crop), a river curve, a ridge curve added as detail with a size, a
/// lake contour.
const TREE: &str = r#"(
    extent: ((0, 0), (1200, 1000)),
    falloff: 10,
    base_depth: 40,
    tree: Replace(
        base: Replace(
            base: Add(
                base: Blend(base: 80, children: [
                    Warp(turbulence: (amplitude: 40, wavelength: 300, octaves: 2),
                         child: Disc(centre: (300, 700), radius: 500,
                                     elevation: Ridged(base: 100, amplitude: 300, wavelength: 400, octaves: 6))),
                    Disc(centre: (800, 300), radius: 450, elevation: Fbm(base: 90, amplitude: 60, wavelength: 250, octaves: 5)),
                    Disc(centre: (700, 700), radius: 350, elevation: Hybrid(base: 95, amplitude: 80, wavelength: 300, octaves: 5)),
                    Disc(centre: (200, 200), radius: 250, elevation: Constant(120)),
                    Image(source: "data/jacksboro_crop.asc", placement: (900, 600), vertical_scale: 0.2,
                          vertical_offset: -60, falloff: 60, cell_size: 25),
                ]),
                detail: Curve(points: [(100, 900, 260), (500, 850, 300)], width: 60,
                              profile: [(0, 20), (30, 5), (60, 0)]),
                size: 30,
            ),
            by: Curve(points: [(0, 450, 100), (400, 500, 95), (700, 420, 90), (1200, 480, 85)],
                      width: 90, profile: [(0, -5), (10, -4), (25, 0), (90, 3)]),
        ),
        by: Contour(polygon: [(500, 100), (650, 80), (700, 200), (560, 260)], elevation: 88,
                    profile: [(-50, -8), (0, 0), (20, 1)], falloff: 40),
    ),
)"#;

fn spec() -> ElevationSpec {
    karstic::value::ron_options().from_str(TREE).unwrap()
}

fn tree() -> ElevationTree {
    let cx = BuildContext {
        base_dir: &Path::new(env!("CARGO_MANIFEST_DIR")).join("trees"),
        seed: 7,
        budget: DEFAULT_MEMORY_BUDGET,
    };
    spec().build_tree(&cx).unwrap()
}

fn leaf(lod: Lod) -> ElevationField {
    let mut params = spec().params();
    params.lod = lod;
    ElevationField::new(Arc::new(tree()), params).unwrap()
}

/// A random rectangle in (and a little around) the extent, from a metre to most of it.
fn random_rect(rng: &mut Rng) -> Rect {
    let c = Vec2::new(rng.range(-50.0, 1250.0), rng.range(-50.0, 1050.0));
    let half = Vec2::splat(600.0 * rng.f32().powi(3) + 0.5);
    Rect::new(c - half, c + half)
}

fn in_rect(rng: &mut Rng, r: &Rect) -> Vec2 {
    Vec2::new(rng.range(r.min.x, r.max.x), rng.range(r.min.y, r.max.y))
}

#[test]
fn tree_bounds_hold_on_random_points_and_pairs() {
    let t = tree();
    for lod in [Lod::FULL, Lod::new(8.0)] {
        let mut rng = Rng(1);
        let global = t.bounds(&Rect::new(Vec2::ZERO, Vec2::new(1200.0, 1000.0)), &lod);
        let (mut worst, mut local_below) = (0.0f32, 0);
        for _ in 0..3000 {
            let r = random_rect(&mut rng);
            let b = t.bounds(&r, &lod);
            local_below += (b.f.lipschitz < 0.5 * global.f.lipschitz) as usize;
            for _ in 0..10 {
                let (p, q) = (in_rect(&mut rng, &r), in_rect(&mut rng, &r));
                let (sp, sq) = (t.eval(p, &lod), t.eval(q, &lod));
                for s in [sp, sq] {
                    assert!(
                        b.f.range.lo - 1e-3 <= s.f && s.f <= b.f.range.hi + 1e-3,
                        "f = {} not in {:?} over {r:?}",
                        s.f,
                        b.f
                    );
                    assert!(
                        b.a.range.lo - 1e-5 <= s.a && s.a <= b.a.range.hi + 1e-5,
                        "α {} not in {:?}",
                        s.a,
                        b.a
                    );
                }
                let d = p.distance(q);
                if d < 1e-2 {
                    continue;
                }
                let slope = (sp.f - sq.f).abs() / d;
                assert!(
                    slope <= b.f.lipschitz * 1.001 + 1e-4,
                    "slope {slope} > λ_f {} over {r:?} ({p} {q})",
                    b.f.lipschitz
                );
                let slope_a = (sp.a - sq.a).abs() / d;
                assert!(
                    slope_a <= b.a.lipschitz * 1.001 + 1e-5,
                    "α slope {slope_a} > {}",
                    b.a.lipschitz
                );
                worst = worst.max(slope / global.f.lipschitz);
            }
        }
        assert!(
            worst > 0.02,
            "the global bound {} is never approached ({worst})",
            global.f.lipschitz
        );
        assert!(
            local_below > 500,
            "local bounds are no tighter than the global one ({local_below})"
        );
    }
}

#[test]
fn replace_is_continuous_across_the_weight_boundary() {
    let t = tree();
    // Lines across the river's and the lake's support edges, sampled every millimetre:
    // no step may exceed the Lipschitz bound times the spacing.
    let lf = t
        .bounds(
            &Rect::new(Vec2::ZERO, Vec2::new(1200.0, 1000.0)),
            &Lod::FULL,
        )
        .f
        .lipschitz;
    for (a, b) in [
        (Vec2::new(400.0, 560.0), Vec2::new(400.0, 620.0)),
        (Vec2::new(600.0, 230.0), Vec2::new(600.0, 330.0)),
        (Vec2::new(750.0, 150.0), Vec2::new(650.0, 150.0)),
    ] {
        let n = 100_000;
        let mut prev = t.height(a, &Lod::FULL);
        let step = a.distance(b) / n as f32;
        for k in 1..=n {
            let cur = t.height(a.lerp(b, k as f32 / n as f32), &Lod::FULL);
            assert!(
                (cur - prev).abs() <= lf * step + 2e-4,
                "jump {} at {k} of {a} → {b}",
                cur - prev
            );
            prev = cur;
        }
    }
    // The replaced river bed is below the terrain beside it (the replace did something).
    let bed = t.height(Vec2::new(400.0, 500.0), &Lod::FULL);
    let bank = t.height(Vec2::new(400.0, 620.0), &Lod::FULL);
    assert!(bed < 96.0 && bed < bank, "bed {bed}, bank {bank}");
}

#[test]
fn lod_at_level_infinity_is_the_full_evaluation() {
    let t = tree();
    let mut rng = Rng(3);
    let fine = Lod::new(1e-6);
    let coarse = Lod::new(60.0);
    let mut differs = 0;
    for _ in 0..20_000 {
        let p = Vec2::new(rng.range(0.0, 1200.0), rng.range(0.0, 1000.0));
        let full = t.eval(p, &Lod::FULL);
        assert_eq!(t.eval(p, &fine), full, "at {p}");
        differs += (t.height(p, &coarse) != full.f) as usize;
    }
    assert!(differs > 10_000, "coarse LoD changes nothing ({differs})");
    let whole = Rect::new(Vec2::ZERO, Vec2::new(1200.0, 1000.0));
    let (lf_full, lf_coarse) = (
        t.bounds(&whole, &Lod::FULL).f.lipschitz,
        t.bounds(&whole, &coarse).f.lipschitz,
    );
    assert!(
        lf_coarse < 0.5 * lf_full,
        "LoD must shrink the Lipschitz bound: {lf_coarse} vs {lf_full}"
    );
}

#[test]
fn batch_heights_match_point_queries() {
    let t = tree();
    let mut rng = Rng(4);
    let pts: Vec<Vec2> = (0..10_000)
        .map(|_| Vec2::new(rng.range(0.0, 1200.0), rng.range(0.0, 1000.0)))
        .collect();
    let mut out = vec![0.0; pts.len()];
    t.heights(&pts, &Lod::FULL, &mut out);
    for (p, h) in pts.iter().zip(&out) {
        assert_eq!(*h, t.height(*p, &Lod::FULL));
    }
}

/// A blend large enough for its grid index — flat discs, multifractal discs, a nested
/// blend — in batches (four points at a time on SIMD lanes, over the index's cells) is bit
/// for bit the sums over every child in order, at points inside, outside and not finite.
#[test]
fn a_large_blend_in_batches_is_the_sum_over_every_child_bit_for_bit() {
    use karstic::elevation::geometry::rect_contains;
    use karstic::elevation::multifractal::{ElevationFn, Kind, Multifractal};
    use karstic::elevation::primitive::{Disc, Primitive};
    let mut rng = Rng(16);
    let mut disc = |k: u32| {
        let centre = Vec2::new(rng.range(0.0, 1000.0), rng.range(0.0, 1000.0));
        let radius = rng.range(40.0, 160.0);
        let elevation = match k % 5 {
            0 => ElevationFn::Fractal(Multifractal::new(Kind::Fbm, 50.0, 80.0, 90.0, 3, k)),
            1 => ElevationFn::Fractal(Multifractal::new(Kind::Ridged, 60.0, 90.0, 70.0, 5, k)),
            2 => ElevationFn::Fractal(Multifractal::new(Kind::Hybrid, 40.0, 70.0, 80.0, 4, k)),
            _ => ElevationFn::Constant(rng.range(-20.0, 200.0)),
        };
        Node::primitive(Primitive::Disc(Disc {
            centre,
            radius,
            elevation,
        }))
    };
    let mut children: Vec<Node> = (0..60).map(&mut disc).collect();
    children.insert(17, Node::blend(30.0, (60..64).map(&mut disc).collect()));
    let base = 40.0;
    let tree = ElevationTree::new(Node::blend(base, children.clone()));
    let mut pts: Vec<Vec2> = (0..20_000)
        .map(|_| Vec2::new(rng.range(-200.0, 1200.0), rng.range(-200.0, 1200.0)))
        .collect();
    pts.extend([Vec2::NAN, Vec2::new(f32::INFINITY, 5.0), Vec2::splat(1e9)]);
    let mut out = vec![0.0; pts.len()];
    tree.heights(&pts, &Lod::FULL, &mut out);
    let mut weighed = 0;
    for (p, h) in pts.iter().zip(&out) {
        let (mut s, mut fs) = (0.0f32, 0.0f32);
        for c in &children {
            let x = c.eval(*p, &Lod::FULL);
            if rect_contains(&c.support(), *p) && x.a > 0.0 {
                s += x.a;
                fs += x.a * x.f;
            }
        }
        weighed += usize::from(s > 0.0);
        let w = s.max(0.5);
        let f = (fs + (w - s) * base) / w;
        assert_eq!(h.to_bits(), f.to_bits(), "at {p}: {h} vs {f}");
        assert_eq!(tree.height(*p, &Lod::FULL).to_bits(), f.to_bits(), "at {p}");
    }
    assert!(weighed > 10_000, "{weighed} points weighed");
}

/// A random box around the leaf's support: sizes from a fraction of a metre to a large part.
fn random_box(f: &ElevationField, rng: &mut Rng) -> Aabb {
    let s = f.support().dilate(20.0);
    let c = rng.in_box(&s);
    let size = s.size() * rng.f32().powi(3) * 0.3;
    Aabb::new(c - size * 0.5, c + size * 0.5)
}

#[test]
fn leaf_intervals_and_lipschitz_bounds_are_sound() {
    for lod in [Lod::FULL, Lod::new(5.0)] {
        let f = leaf(lod);
        let l = f.lipschitz();
        let mut rng = Rng(5);
        let (mut informative, mut worst) = (0, 0.0f32);
        for _ in 0..3000 {
            let b = random_box(&f, &mut rng);
            let iv = f.interval(&b);
            informative += (iv.width() < 2.0 * ISO) as usize;
            let lb = f.lipschitz_box(&b);
            assert!(lb <= l * 1.0001, "box bound {lb} above the global {l}");
            for _ in 0..8 {
                let (p, q) = (rng.in_box(&b), rng.in_box(&b));
                let (vp, vq) = (f.value(p), f.value(q));
                assert!(
                    iv.lo - 1e-5 <= vp && vp <= iv.hi + 1e-5,
                    "f({p}) = {vp} not in {iv:?}"
                );
                let d = p.distance(q);
                if d < 1e-2 {
                    continue;
                }
                let slope = (vp - vq).abs() / d;
                worst = worst.max(slope / l);
                assert!(
                    slope <= lb * 1.001 + 1e-6,
                    "slope {slope} > box bound {lb} in {b:?}"
                );
            }
        }
        assert!(
            informative > 1000,
            "intervals too loose to prune ({informative})"
        );
        assert!(worst > 0.005, "global bound {l} never approached ({worst})");
    }
}

#[test]
fn leaf_z_bands_contain_every_sampled_crossing() {
    let (crossings, pruned) = check_z_bands("leaf", &leaf(Lod::FULL), 300, 4, 6);
    assert!(crossings > 200, "too few crossings sampled ({crossings})");
    assert!(pruned > 0.5, "bands prune only {:.0}% of z", 100.0 * pruned);
}

#[test]
fn leaf_is_the_elevation_inside_and_vanishes_outside() {
    let f = leaf(Lod::FULL);
    let mut rng = Rng(7);
    let mut answered = 0;
    for _ in 0..2000 {
        let c = Vec2::new(rng.range(-100.0, 1300.0), rng.range(-100.0, 1100.0));
        let fp = Rect::new(c, c + Vec2::splat(rng.range(1.0, 40.0)));
        let xy = in_rect(&mut rng, &fp);
        if let Some(e) = f.elevation(&fp) {
            answered += 1;
            let h = e.source.height(xy);
            assert_eq!(h, f.tree().height(xy, &Lod::FULL));
            for z in [h - 3.0, h + 3.0] {
                if e.z.contains(z) {
                    assert_eq!(f.value(xy.extend(z)) > ISO, z < h, "at {xy}, z {z}, h {h}");
                }
            }
        }
        if !Rect::new(Vec2::ZERO, Vec2::new(1200.0, 1000.0)).contains_rect(&Rect::new(xy, xy)) {
            assert_eq!(f.value(xy.extend(100.0)), 0.0);
        }
    }
    assert!(answered > 1000, "elevation answered only {answered} times");
    // The gradient points down through the surface and matches finite differences there.
    let p = Vec2::new(610.0, 640.0);
    let h = f.height(p);
    let q = p.extend(h + 1.0);
    let (v, g) = f.value_grad(q);
    let e = 0.05;
    for axis in 0..3 {
        let d = Vec3::AXES[axis] * e;
        let fd = (f.value(q + d) - f.value(q - d)) / (2.0 * e);
        assert!(
            (fd - g[axis]).abs() < 2e-3 + 0.05 * fd.abs(),
            "axis {axis}: {fd} vs {}",
            g[axis]
        );
    }
    assert!(v < ISO && g.z < 0.0);
}

#[test]
fn spec_errors_name_the_node_and_field() {
    let bad_points = TREE.replace(
        "points: [(100, 900, 260), (500, 850, 300)]",
        "points: [(100, 900, 260)]",
    );
    let spec: ElevationSpec = karstic::value::ron_options().from_str(&bad_points).unwrap();
    let cx = BuildContext {
        base_dir: &Path::new(env!("CARGO_MANIFEST_DIR")).join("trees"),
        seed: 7,
        budget: DEFAULT_MEMORY_BUDGET,
    };
    let e = spec.build_tree(&cx).unwrap_err().to_string();
    assert!(
        e.contains("tree.base.base.detail (Curve)") && e.contains("`points`"),
        "{e}"
    );
    let unsorted = TREE.replace(
        "profile: [(-50, -8), (0, 0), (20, 1)]",
        "profile: [(0, -8), (-50, 0)]",
    );
    let e = karstic::value::ron_options()
        .from_str::<ElevationSpec>(&unsorted)
        .unwrap_err()
        .to_string();
    assert!(e.contains("increasing distance"), "{e}");
    let unknown = TREE.replace("width: 90,", "width: 90, depth: 3,");
    let e = karstic::value::ron_options()
        .from_str::<ElevationSpec>(&unknown)
        .unwrap_err()
        .to_string();
    assert!(e.contains("depth"), "{e}");
}

#[test]
fn a_blend_of_nothing_is_its_base_and_weighs_nothing() {
    let t = ElevationTree::new(Node::blend(42.0, Vec::new()));
    let s = t.eval(Vec2::new(3.0, 4.0), &Lod::FULL);
    assert_eq!((s.f, s.a), (42.0, 0.0));
}

#[test]
fn the_gpu_tape_names_the_elevation_leaf_and_the_scene_renders_on_the_cpu() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("trees/elevation_valley.ron");
    let compiled = karstic::scene::load(&path).unwrap().compile().unwrap();
    let e = karstic::tape::tape_from_tree(&compiled.tree)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("elevation tree")
            && e.contains("has no GPU encoding")
            && !e.contains("no GPU encoding: elevation"),
        "{e}"
    );
}

/// The compound bounds above are loose (noise octaves at their proven slope, the warp's
/// factor, the blend's weight term) but a primitive's own bound is tight.
#[test]
fn a_curve_alone_reaches_its_bound() {
    // z rises 1 in 10 along the curve, the profile 1 in 1 across it: λ = 0.1 + 1.
    let spec: ElevationSpec = karstic::value::ron_options()
        .from_str(
            "(extent: ((0, 0), (100, 100)), falloff: 5, \
              tree: Curve(points: [(0, 50, 0), (100, 50, 10)], width: 40, profile: [(0, 0), (30, 30)]))",
        )
        .unwrap();
    let cx = BuildContext {
        base_dir: Path::new("."),
        seed: 1,
        budget: DEFAULT_MEMORY_BUDGET,
    };
    let t = spec.build_tree(&cx).unwrap();
    let r = Rect::new(Vec2::ZERO, Vec2::splat(100.0));
    let lf = t.bounds(&r, &Lod::FULL).f.lipschitz;
    assert!((lf - 1.1).abs() < 1e-3, "{lf}");
    let (p, q) = (Vec2::new(50.0, 55.0), Vec2::new(50.0, 65.0));
    let slope = (t.height(p, &Lod::FULL) - t.height(q, &Lod::FULL)).abs() / p.distance(q);
    assert!(slope > 0.9, "{slope} vs {lf}");
}

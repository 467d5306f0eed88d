//! The implicit heightfield leaf (Paris et al. 2019 §5.1): every bound is checked by
//! sampling, on the real UTM DEM (with its nodata edges) and on synthetic grids with
//! polygons and bicubic.

use crate::common::{Rng, check_z_bands, column_crossings_in_bands};

use std::path::Path;

use glam::{Vec2, Vec3};
use karstic::dem::{DetailParams, Heightfield, HeightfieldField, ImplicitParams, Interpolation};
use karstic::field::falloff::sigma;
use karstic::field::{Aabb, Fbm, Field, ISO, Interval, Rect, ZBands};
use karstic::scene::HeightfieldSpec;

fn utm_leaf(r: f32, interp: Interpolation) -> HeightfieldField {
    utm_leaf_with(r, interp, "")
}

/// The UTM DEM with `more` fields appended to its spec.
fn utm_leaf_with(r: f32, interp: Interpolation, more: &str) -> HeightfieldField {
    let ron = format!(
        "(source: \"../shared/data/dem/jacksboro_utm16n_90m.tif\", falloff: {r}, interpolation: {interp:?}, placement: Some((-1000.0, 500.0)){more})"
    );
    let spec: HeightfieldSpec = ron::from_str(&ron).unwrap();
    spec.load(Path::new(env!("CARGO_MANIFEST_DIR"))).unwrap()
}

/// A 40 × 30 grid of rolling hills with a nodata hole, cut by a triangle.
fn synthetic(interp: Interpolation) -> HeightfieldField {
    synthetic_with(interp, None)
}

/// [`synthetic`] with detail amplification.
fn synthetic_with(interp: Interpolation, detail: Option<DetailParams>) -> HeightfieldField {
    let (nx, ny) = (40, 30);
    let z = (0..nx * ny)
        .map(|k| {
            let (i, j) = ((k % nx) as f32, (k / nx) as f32);
            if (i - 25.0).abs() < 2.0 && (j - 12.0).abs() < 2.0 {
                f32::NAN
            } else {
                50.0 + 20.0 * (0.3 * i).sin() * (0.25 * j).cos() + 0.5 * i
            }
        })
        .collect();
    let hf = Heightfield::new(nx, ny, Vec2::ZERO, Vec2::new(10.0, 12.0), z).unwrap();
    let params = ImplicitParams {
        vertical_scale: 1.5,
        vertical_offset: -10.0,
        placement: Vec2::new(100.0, -50.0),
        domain: Some(vec![
            Vec2::new(90.0, -60.0),
            Vec2::new(520.0, -40.0),
            Vec2::new(480.0, 320.0),
            Vec2::new(120.0, 280.0),
        ]),
        interpolation: interp,
        detail,
        ..ImplicitParams::with_falloff(25.0)
    };
    HeightfieldField::new(&hf, &params).unwrap()
}

fn leaves() -> Vec<(&'static str, HeightfieldField)> {
    vec![
        ("utm bilinear", utm_leaf(150.0, Interpolation::Bilinear)),
        ("utm bicubic", utm_leaf(60.0, Interpolation::Bicubic)),
        ("synthetic bilinear", synthetic(Interpolation::Bilinear)),
        ("synthetic bicubic", synthetic(Interpolation::Bicubic)),
        (
            "utm detail",
            utm_leaf_with(
                60.0,
                Interpolation::Bicubic,
                ", detail: Some((noise: (amplitude: 5, wavelength: 40, octaves: 4), steep: 0.6))",
            ),
        ),
        (
            "utm amplified",
            utm_leaf_with(
                60.0,
                Interpolation::Bicubic,
                ", amplify: Some((region: Some(((12000, 14000), (12900, 14700))), cell: Some(10), steps: 12))",
            ),
        ),
        (
            "synthetic detail",
            synthetic_with(
                Interpolation::Bilinear,
                Some(DetailParams {
                    noise: Fbm::with(3, 60.0, 3),
                    amplitude: 2.0,
                    flat: 0.3,
                    steep: 0.5,
                    altitude: 0.5,
                }),
            ),
        ),
    ]
}

/// The detail's largest displacement (0 without detail).
fn reach(f: &HeightfieldField) -> f32 {
    f.detail().map_or(0.0, |d| d.reach_total())
}

/// A random box around the support: sizes from a fraction of a cell to a large part.
fn random_box(f: &HeightfieldField, rng: &mut Rng) -> Aabb {
    let s = f.support().dilate(20.0);
    let c = rng.in_box(&s);
    let size = s.size() * rng.f32().powi(3) * 0.3;
    Aabb::new(c - size * 0.5, c + size * 0.5)
}

#[test]
fn intervals_contain_sampled_values() {
    for (name, f) in leaves() {
        let mut rng = Rng(1);
        let mut informative = 0;
        for _ in 0..1500 {
            let b = random_box(&f, &mut rng);
            let iv = f.interval(&b);
            informative += (iv.width() < 2.0 * ISO) as usize;
            for _ in 0..20 {
                let p = rng.in_box(&b);
                let v = f.value(p);
                assert!(
                    iv.lo - 1e-5 <= v && v <= iv.hi + 1e-5,
                    "{name}: f({p}) = {v} not in {iv:?} for {b:?}"
                );
            }
        }
        assert!(
            informative > 500,
            "{name}: intervals are too loose to prune ({informative})"
        );
    }
}

#[test]
fn lipschitz_bounds_hold_on_random_pairs() {
    for (name, f) in leaves() {
        let l = f.lipschitz();
        let mut rng = Rng(2);
        let mut worst = 0.0f32;
        for _ in 0..20000 {
            let b = random_box(&f, &mut rng);
            let lb = f.lipschitz_box(&b);
            assert!(
                lb <= l * 1.0001,
                "{name}: box bound {lb} above the global {l}"
            );
            let (p, q) = (rng.in_box(&b), rng.in_box(&b));
            let d = p.distance(q);
            if d < 1e-2 {
                continue;
            }
            let slope = (f.value(p) - f.value(q)).abs() / d;
            worst = worst.max(slope / l);
            assert!(
                slope <= lb * 1.001 + 1e-6,
                "{name}: slope {slope} > box bound {lb} in {b:?}"
            );
        }
        assert!(
            worst > 0.05,
            "{name}: global bound {l} never approached ({worst})"
        );
    }
}

#[test]
fn gradients_match_finite_differences() {
    for (name, f) in leaves() {
        let mut rng = Rng(3);
        let s = f.support();
        let mut checked = 0;
        while checked < 400 {
            // points near the surface, where the gradient matters
            let mut p = rng.in_box(&s);
            let h = f
                .heightfield()
                .sample(p.truncate(), f.params().interpolation);
            if h.is_nan() {
                continue;
            }
            p.z = h + rng.range(-40.0, 40.0);
            let (v, g) = f.value_grad(p);
            assert!((v - f.value(p)).abs() < 1e-6, "{name}");
            let e = 1e-2;
            let fd = |e: f32| {
                Vec3::new(
                    f.value(p + Vec3::X * e) - f.value(p - Vec3::X * e),
                    f.value(p + Vec3::Y * e) - f.value(p - Vec3::Y * e),
                    f.value(p + Vec3::Z * e) - f.value(p - Vec3::Z * e),
                ) / (2.0 * e)
            };
            let (a, b) = (fd(e), fd(2.0 * e));
            if (a - b).length() > 1e-4 * (1.0 + a.length()) {
                continue; // a kink (min, cell edge) under the stencil
            }
            assert!(
                (a - g).length() <= 2e-3 * (1.0 + g.length()),
                "{name}: at {p}: {g} vs {a}"
            );
            checked += 1;
        }
    }
}

#[test]
fn z_bands_contain_every_sampled_crossing() {
    for (name, f) in leaves() {
        let (crossings, pruned) = check_z_bands(name, &f, 600, 6, 4);
        assert!(
            crossings > 300,
            "{name}: too few crossings sampled ({crossings})"
        );
        assert!(
            pruned > 0.5,
            "{name}: bands prune only {:.0}% of z",
            100.0 * pruned
        );
    }
}

#[test]
fn elevation_answers_only_where_the_field_is_the_heightfield() {
    for (name, f) in leaves() {
        let mut rng = Rng(5);
        let s = f.support();
        let (mut some, mut none) = (0, 0);
        for _ in 0..3000 {
            let c = rng.in_box(&s).truncate();
            let half = Vec2::splat(rng.range(1.0, 200.0));
            let fp = Rect::new(c - half, c + half);
            let Some(e) = f.elevation(&fp) else {
                none += 1;
                continue;
            };
            some += 1;
            for _ in 0..10 {
                let xy = Vec2::new(rng.range(fp.min.x, fp.max.x), rng.range(fp.min.y, fp.max.y));
                let h = e.source.height(xy);
                assert!(
                    h.is_finite(),
                    "{name}: no elevation at {xy} inside an elevation footprint"
                );
                let z = rng.range(e.z.lo, e.z.hi);
                let v = f.value(xy.extend(z));
                if f.detail().is_none() {
                    assert_eq!(
                        v,
                        sigma(h - z, f.params().falloff),
                        "{name}: f is not σ(h − z) at {xy}, {z}"
                    );
                }
                // with detail, h is found by iteration: a hair of tolerance at the surface
                if (z - h).abs() > 1e-3 * (1.0 + h.abs()) * reach(&f).min(1.0) {
                    assert_eq!(v > ISO, z < h, "{name}: at {xy}, {z}, surface {h}");
                }
            }
        }
        assert!(some > 100 && none > 100, "{name}: {some} Some, {none} None");
    }
}

#[test]
fn field_vanishes_outside_the_support_and_the_domain() {
    for (name, f) in leaves() {
        let mut rng = Rng(6);
        let s = f.support();
        let big = s.dilate(500.0);
        for _ in 0..20000 {
            let p = rng.in_box(&big);
            let v = f.value(p);
            assert!((0.0..=2.0 * ISO).contains(&v), "{name}: {v}");
            if !s.contains(p) {
                assert_eq!(v, 0.0, "{name}: f({p}) = {v} outside the support {s:?}");
            }
            let xy = p.truncate();
            if f.heightfield()
                .sample(xy, f.params().interpolation)
                .is_nan()
            {
                assert_eq!(v, 0.0, "{name}: f({p}) = {v} where h is undefined");
            }
        }
    }
}

#[test]
fn solid_is_the_terrain_inside_and_closed_by_walls() {
    let f = utm_leaf(150.0, Interpolation::Bilinear);
    let hf = f.heightfield();
    // centre of the DEM: solid below the terrain, empty above
    let xy = hf.origin() + Vec2::new(170.0, 180.0) * hf.cell();
    let h = f.height(xy);
    assert!(f.value(xy.extend(h - 1.0)) > ISO && f.value(xy.extend(h + 1.0)) < ISO);
    assert!((f.value(xy.extend(h)) - ISO).abs() < 1e-6);
    // far below the prism floor: empty again (the block has a bottom)
    let dz = f.prism_z();
    assert!(f.value(xy.extend(dz.lo - 100.0)) < ISO && f.value(xy.extend(dz.lo - 10.0)) > ISO);
}

#[test]
fn eval_block_matches_value() {
    for (name, f) in leaves() {
        let s = f.support();
        let dims = [17, 13, 29];
        let step = s.size() / Vec3::new(16.0, 12.0, 28.0);
        let mut out = vec![0.0; 17 * 13 * 29];
        f.eval_block(s.min, step, dims, &mut out);
        for k in 0..29 {
            for j in 0..13 {
                for i in 0..17 {
                    let p = s.min + Vec3::new(i as f32, j as f32, k as f32) * step;
                    assert_eq!(out[i + 17 * (j + 13 * k)], f.value(p), "{name} at {p}");
                }
            }
        }
    }
}

/// A vertical line's values in one call are the points' values bit for bit, inside and
/// outside the domain and the support, above, in and below the detail's band.
#[test]
fn eval_column_matches_value() {
    let mut rng = Rng(29);
    for (name, f) in leaves() {
        let s = f.support().dilate(20.0);
        for _ in 0..200 {
            let xy = Vec2::new(rng.range(s.min.x, s.max.x), rng.range(s.min.y, s.max.y));
            let h = f.base_height(xy);
            let centre = if h.is_nan() { s.center().z } else { h };
            let mut zs: Vec<f32> = (0..40)
                .map(|k| centre - 60.0 + 3.0 * k as f32 + rng.range(0.0, 3.0))
                .collect();
            zs.push(s.min.z - 1.0);
            zs.push(s.max.z + 1.0);
            let mut out = vec![f32::NAN; zs.len()];
            assert!(
                f.eval_column(xy, &zs, &mut out),
                "{name}: shares the column"
            );
            for (&z, &v) in zs.iter().zip(&out) {
                let p = xy.extend(z);
                assert_eq!(v.to_bits(), f.value(p).to_bits(), "{name} at {p}");
            }
        }
    }
}

#[test]
fn spec_errors_carry_positions_and_paths() {
    let e =
        ron::from_str::<HeightfieldSpec>("(\n source: \"x.tif\",\n falloff: -3.0)").unwrap_err();
    assert_eq!(e.span.start.line, 3, "{e}");
    assert!(e.to_string().contains("> 0"), "{e}");
    let e = ron::from_str::<HeightfieldSpec>("(source: \"x.tif\", falloff: 3.0, colour: 1)")
        .unwrap_err();
    assert!(e.to_string().contains("colour"), "{e}");
    let spec = HeightfieldSpec::new("missing.tif", 10.0);
    let e = spec.load(Path::new("/nonexistent-dir")).unwrap_err();
    assert!(
        e.to_string().contains("/nonexistent-dir/missing.tif"),
        "{e}"
    );
    // a round trip keeps the spec
    let mut spec = HeightfieldSpec::new("a.tif", 12.5);
    spec.interpolation = Interpolation::Bicubic;
    let text = ron::to_string(&spec).unwrap();
    assert_eq!(
        ron::from_str::<HeightfieldSpec>(&text).unwrap(),
        spec,
        "{text}"
    );
}

#[test]
fn tree_frame_maps_back_to_utm() {
    let f = utm_leaf(150.0, Interpolation::Bilinear);
    // placement (-1000, 500): the south-west sample centre, GDAL's corner + 45 m
    let sw = f.tree_to_crs(Vec2::new(-1000.0, 500.0)).unwrap();
    assert!(
        (sw[0] - 730_984.219_465_799).abs() < 1e-6 && (sw[1] - 4_036_601.162_225_269).abs() < 1e-6,
        "{sw:?}"
    );
    let p = f.crs_to_tree([sw[0] + 900.0, sw[1] + 90.0]).unwrap();
    assert!(p.distance(Vec2::new(-100.0, 590.0)) < 1e-3, "{p}");
}

#[test]
fn dem_cache_shares_decoded_files() {
    let base = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut cache = karstic::scene::DemCache::new(1 << 30);
    let a = HeightfieldSpec::new("../shared/data/dem/jacksboro_int16.tif", 100.0);
    let mut b = a.clone();
    b.vertical_scale = karstic::value::Finite(-1.0);
    let fa = a.load_with(base, &mut cache, 0, None).unwrap();
    let fb = b.load_with(base, &mut cache, 0, None).unwrap();
    assert_eq!(
        cache.notices().len(),
        1,
        "one decode, one notice: {:?}",
        cache.notices()
    );
    let xy = Vec2::new(5000.0, 5000.0);
    assert_eq!(fa.height(xy), -fb.height(xy));
}

/// Small boxes hugging the terrain — what a tracer's candidate segments look like near the
/// surface. Their bounds must stay sound (sampled values inside the interval, sampled slopes
/// under the box bound) and be sharp: a box 8 to 40 m above the ground at its centre and a
/// few metres wide must be known to lie outside the solid, even though the cells under it
/// (90 m on the UTM DEM) span more than that in height.
#[test]
fn small_boxes_near_the_terrain_have_sound_and_sharp_bounds() {
    for (name, f) in leaves() {
        let interp = f.params().interpolation;
        let mut rng = Rng(6);
        let s = f.support();
        let (mut above, mut known) = (0, 0);
        let mut checked = 0;
        while checked < 3000 {
            let c = rng.in_box(&s);
            let h = f.heightfield().sample(c.truncate(), interp);
            if h.is_nan() {
                continue;
            }
            checked += 1;
            let lift = rng.range(-40.0, 40.0);
            let c = c.truncate().extend(h + lift);
            let half = Vec3::new(
                rng.range(0.1, 4.0),
                rng.range(0.1, 4.0),
                rng.range(0.1, 4.0),
            );
            let b = Aabb::new(c - half, c + half);
            let iv = f.interval(&b);
            let lb = f.lipschitz_box(&b);
            for _ in 0..20 {
                let (p, q) = (rng.in_box(&b), rng.in_box(&b));
                let (vp, vq) = (f.value(p), f.value(q));
                assert!(
                    iv.lo - 1e-5 <= vp && vp <= iv.hi + 1e-5,
                    "{name}: f({p}) = {vp} not in {iv:?} for {b:?}"
                );
                let d = p.distance(q);
                if d > 1e-2 {
                    let slope = (vp - vq).abs() / d;
                    assert!(
                        slope <= lb * 1.001 + 1e-6,
                        "{name}: slope {slope} > box bound {lb} in {b:?}"
                    );
                }
            }
            // (with detail, steep ground is no graph of an elevation: its boxes count too)
            let inside = f.elevation(&b.footprint()).is_some()
                || (f.detail().is_some() && f.value(c.truncate().extend(h - 1.0)) > ISO);
            if lift > 8.0 + reach(&f) && inside {
                above += 1;
                known += (iv.hi < ISO) as usize;
            }
        }
        assert!(
            above > 300,
            "{name}: too few boxes above the ground ({above})"
        );
        assert!(
            known * 10 >= above * 9,
            "{name}: only {known} of {above} boxes above the ground are known to be air"
        );
    }
}

/// Segment bounds (what the tracer asks): along a segment only the slope of `h + d − z`
/// in its direction counts, and in the air above the terrain's band the field is 0. Rays
/// grazing the ground (nearly level, a few metres to tens of metres above it) and steep
/// ones: every sampled pair obeys the bound, and along level segments the bound is below
/// the box's (which takes every direction) — the directional bound is what is checked.
#[test]
fn segment_bounds_are_sound_along_grazing_rays() {
    for (name, f) in leaves() {
        let interp = f.params().interpolation;
        let mut rng = Rng(9);
        let s = f.support();
        let (mut checked, mut level, mut sharper) = (0, 0, 0);
        while checked < 4000 {
            let c = rng.in_box(&s);
            let h = f.heightfield().sample(c.truncate(), interp);
            if h.is_nan() {
                continue;
            }
            checked += 1;
            let a = c.truncate().extend(h + rng.range(-10.0, 60.0));
            let steep = checked % 4 == 0;
            let dz = if steep {
                rng.range(-1.0, 1.0)
            } else {
                rng.range(-0.15, 0.15)
            };
            let heading = rng.range(0.0, std::f32::consts::TAU);
            let u = Vec3::new(heading.cos(), heading.sin(), dz).normalize();
            let b = a + u * rng.range(0.2, 40.0) * rng.f32();
            let lam = f.lipschitz_segment(a, b);
            assert!(
                lam <= f.lipschitz() * 1.0001 + 1e-6,
                "{name}: segment bound {lam} above the global one"
            );
            // p and q are rounded to f32 (millimetres at these coordinates), which moves
            // them off the segment's line: the global bound covers that sideways offset
            let off = 2.0 * f.lipschitz() * a.abs().max_element() * f32::EPSILON;
            for _ in 0..12 {
                let (p, q) = (a.lerp(b, rng.f32()), a.lerp(b, rng.f32()));
                let d = p.distance(q);
                if d < 1e-2 {
                    continue;
                }
                let df = (f.value(p) - f.value(q)).abs();
                assert!(
                    df <= lam * d * 1.001 + 1e-6 + off,
                    "{name}: |Δf| = {df} over {d} m > bound {lam} on [{a}, {b}]"
                );
            }
            if !steep {
                let lb = f.lipschitz_box(&Aabb::new(a, b));
                level += (lb > 0.0) as usize;
                sharper += (lam < lb * 0.98) as usize;
            }
        }
        assert!(
            sharper * 2 > level,
            "{name}: level segments' bounds are no sharper than their boxes' ({sharper} of {level})"
        );
    }
}

/// Footprints of a mesh column (half a metre to two metres across) inside the domain:
/// their terrain band holds every sampled crossing and is about as tall as the detail's
/// reach plus the relief across the footprint — not as the relief of the DEM cells under
/// it (90 m cells on the UTM DEM), since the tile mesher evaluates every sample of it.
#[test]
fn column_bands_are_sound_and_as_tall_as_the_local_relief() {
    for (name, f) in leaves() {
        let mut rng = Rng(8);
        let s = f.support();
        let (a, r) = (reach(&f), f.params().falloff);
        let mut bands = ZBands::new();
        let (mut checked, mut sharp, mut crossings) = (0, 0, 0);
        while checked < 400 {
            let c = rng.in_box(&s).truncate();
            let half = Vec2::new(rng.range(0.25, 1.0), rng.range(0.25, 1.0));
            let fp = Rect::new(c - half, c + half);
            let corners = [
                fp.min,
                fp.max,
                Vec2::new(fp.min.x, fp.max.y),
                Vec2::new(fp.max.x, fp.min.y),
            ];
            // inside the eroded domain: the prism is whole under every corner
            let inside = corners.iter().all(|&q| {
                let h = f.base_height(q);
                h.is_finite() && f.value(q.extend(h - a - r)) >= 2.0 * ISO
            });
            if !inside {
                continue;
            }
            checked += 1;
            let hc = f.base_height(c);
            bands.clear();
            f.z_bands(
                &fp,
                Interval::new(hc - 3.0 * (a + r), hc + 3.0 * (a + r)),
                &mut bands,
            );
            let terrain = bands.as_slice().iter().find(|b| b.contains(hc));
            let Some(terrain) = terrain else {
                panic!(
                    "{name}: no band holds h = {hc} over {fp:?}: {:?}",
                    bands.as_slice()
                );
            };
            // the relief across the footprint, from the DEM's samples at its corners
            let relief = corners
                .iter()
                .map(|&q| (f.base_height(q) - hc).abs())
                .fold(0.0, f32::max);
            sharp += (terrain.width() <= 2.0 * (a + 2.0 * relief) + 2.0) as usize;
            for _ in 0..3 {
                let xy = Vec2::new(rng.range(fp.min.x, fp.max.x), rng.range(fp.min.y, fp.max.y));
                let zr = Interval::new(hc - 2.0 * (a + r), hc + 2.0 * (a + r));
                crossings += column_crossings_in_bands(name, &f, xy, zr, 400, &bands);
            }
        }
        assert!(
            crossings >= 1000,
            "{name}: too few crossings sampled ({crossings})"
        );
        assert!(
            sharp * 10 >= checked * 9,
            "{name}: only {sharp} of {checked} column bands are as tall as the local relief"
        );
    }
}

/// With detail, `height` is the top of the detailed terrain: solid just below it, empty
/// just above it and all the way up past the detail's reach.
#[test]
fn detailed_height_is_the_top_of_the_surface() {
    for (name, f) in leaves().into_iter().filter(|(_, f)| f.detail().is_some()) {
        let mut rng = Rng(7);
        let s = f.support();
        let (r, a) = (f.params().falloff, reach(&f));
        let mut checked = 0;
        let mut moved = 0.0f32;
        while checked < 2000 {
            let xy = rng.in_box(&s).truncate();
            if f.elevation(&Rect::new(xy, xy)).is_none()
                && f.value(xy.extend(f.base_height(xy) - a - 1.0)) <= ISO
            {
                continue; // outside the eroded domain
            }
            let h = f.height(xy);
            if h.is_nan() {
                continue;
            }
            checked += 1;
            moved = moved.max((h - f.base_height(xy)).abs());
            let eps = 0.02;
            assert!(
                f.value(xy.extend(h - eps)) > ISO,
                "{name}: not solid under {h} at {xy}"
            );
            for k in 1..40 {
                let z = h + eps + (a + r) * k as f32 / 40.0;
                assert!(
                    f.value(xy.extend(z)) < ISO,
                    "{name}: solid at {z} over the top {h} at {xy}"
                );
            }
        }
        assert!(
            moved > 0.3 * a,
            "{name}: the detail moved the surface by only {moved} m"
        );
    }
}

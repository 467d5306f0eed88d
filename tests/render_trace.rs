//! The CPU tracer against independent ground truths, and segment vs sphere tracing.

use crate::common;

use common::{
    Blobs, Rng, SigmaSphere, Terrain, check_segment_lipschitz, depth_agreement, uv_sphere,
};
use glam::{Vec2, Vec3};
use indicatif::ProgressBar;
use karstic::field::falloff::{sigma, sigma_interval, sigma_max_slope};
use karstic::field::{Aabb, Field, Interval};
use karstic::render::camera::Ray;
use karstic::render::cpu::{self, RenderSettings};
use karstic::render::raycast::MeshRaycaster;
use karstic::render::trace::{Method, TraceParams, occluded, trace};
use karstic::render::{Camera, render};

#[test]
fn sigma_sphere_depth_matches_the_analytic_intersection() {
    let s = SigmaSphere {
        center: Vec3::new(3.0, -2.0, 5.0),
        radius: 4.0,
        falloff: 1.5,
    };
    let cam = Camera::look_at(Vec3::new(20.0, -25.0, 15.0), s.center, 30.0, 96, 80).unwrap();
    let truth: Vec<f32> = (0..96 * 80)
        .map(|k| {
            let r = cam.pixel_ray(k % 96, k / 96);
            s.intersect(r.origin, r.dir).unwrap_or(f32::INFINITY)
        })
        .collect();
    let cell = 0.01 * s.radius;
    for method in [Method::Segment, Method::Sphere] {
        let params = TraceParams::for_scene(method, 2.0 * s.support().radius());
        let (depth, _) = cpu::depth(&s, &cam, &params);
        let (frac, hits) = depth_agreement(&truth, &depth, cell);
        assert!(hits > 1000, "the sphere fills part of the image");
        assert!(
            frac >= 0.99,
            "{method:?}: only {:.2}% of hit pixels agree",
            frac * 100.0
        );
    }
}

/// First crossing of `z = h(x, y)` by dense marching on the elevation itself (not on the
/// field), refined by bisection: independent of every Lipschitz bound.
fn terrain_truth(t: &Terrain, ray: &Ray) -> f32 {
    let Some((t0, t1)) = ray.clip(&t.bounds) else {
        return f32::INFINITY;
    };
    let below = |s: f32| {
        let p = ray.at(s);
        p.z < t.height(Vec2::new(p.x, p.y))
    };
    let h = 0.002 * t.wavelength;
    let mut a = t0;
    if below(a) {
        return a;
    }
    while a < t1 {
        let b = (a + h).min(t1);
        if below(b) {
            let (mut lo, mut hi) = (a, b);
            for _ in 0..30 {
                let m = 0.5 * (lo + hi);
                if below(m) { hi = m } else { lo = m }
            }
            return 0.5 * (lo + hi);
        }
        a = b;
    }
    f32::INFINITY
}

#[test]
fn terrain_depth_matches_marching_the_elevation() {
    let terrain = Terrain::new(100.0, 12.0, 4.0);
    let cam = Camera::frame(&terrain.support(), 40.0, 160, 120).unwrap();
    let truth: Vec<f32> = (0..160 * 120)
        .map(|k| terrain_truth(&terrain, &cam.pixel_ray(k % 160, k / 160)))
        .collect();
    let params = TraceParams::for_scene(Method::Segment, 2.0 * terrain.support().radius());
    let (depth, _) = cpu::depth(&terrain, &cam, &params);
    // The prism's σ-rounded edges make the chunk's sides differ from the bare elevation:
    // compare where the truth hits the top surface away from the sides.
    let inner = terrain.bounds.dilate(-2.0 * terrain.falloff);
    let (mut ok, mut n) = (0, 0);
    for k in 0..truth.len() {
        let r = cam.pixel_ray(k as u32 % 160, k as u32 / 160);
        let p = r.at(truth[k]);
        if truth[k].is_finite() && inner.contains(Vec3::new(p.x, p.y, inner.center().z)) {
            n += 1;
            ok += usize::from((depth[k] - truth[k]).abs() <= 0.01 * terrain.wavelength);
        }
    }
    assert!(n > 2000, "enough terrain pixels: {n}");
    assert!(
        ok as f64 >= 0.99 * n as f64,
        "{ok} of {n} terrain pixels agree"
    );
}

fn small_blobs() -> Blobs {
    Blobs::in_ball(60, 6.0, 2.0, 1.0, 7)
}

#[test]
fn blob_field_bounds_are_sound() {
    let b = small_blobs();
    let region = b.support().dilate(1.0);
    check_segment_lipschitz(&b, &region, 20_000, 1);
    // Short segments near the blobs, where the directional per-blob bounds are used.
    for (k, c) in b.centers.iter().take(20).enumerate() {
        check_segment_lipschitz(&b, &Aabb::around(*c, 1.2 * b.radius), 2_000, 100 + k as u64);
    }
    let mut rng = Rng(3);
    for _ in 0..2000 {
        let p = region.min + Vec3::new(rng.f32(), rng.f32(), rng.f32()) * region.size();
        assert!((b.value(p) - b.value_brute(p)).abs() < 1e-5);
    }
    let s = SigmaSphere {
        center: Vec3::ZERO,
        radius: 3.0,
        falloff: 1.0,
    };
    check_segment_lipschitz(&s, &s.support().dilate(1.0), 20_000, 2);
    let t = Terrain::new(50.0, 6.0, 2.0);
    check_segment_lipschitz(&t, &t.support().dilate(1.0), 20_000, 4);
}

#[test]
fn blob_depth_matches_a_dense_march_and_both_methods_agree() {
    let b = small_blobs();
    let cam = Camera::frame(&b.support(), 35.0, 120, 90).unwrap();
    // Dense fixed-step march on the brute-force value, refined by bisection.
    let truth: Vec<f32> = (0..120 * 90)
        .map(|k| {
            let r = cam.pixel_ray(k % 120, k / 120);
            let Some((t0, t1)) = r.clip(&b.support()) else {
                return f32::INFINITY;
            };
            let inside = |t: f32| b.value_brute(r.at(t)) > 0.5;
            let mut a = t0;
            while a < t1 {
                let c = a + 0.01;
                if inside(c) {
                    let (mut lo, mut hi) = (a, c);
                    for _ in 0..20 {
                        let m = 0.5 * (lo + hi);
                        if inside(m) { hi = m } else { lo = m }
                    }
                    return lo;
                }
                a = c;
            }
            f32::INFINITY
        })
        .collect();
    let mut depths = Vec::new();
    let mut mean_steps = Vec::new();
    for method in [Method::Segment, Method::Sphere] {
        let params = TraceParams::for_scene(method, 2.0 * b.support().radius());
        let (depth, steps) = cpu::depth(&b, &cam, &params);
        let (frac, hits) = depth_agreement(&truth, &depth, 0.02);
        assert!(hits > 500);
        assert!(
            frac >= 0.99,
            "{method:?} vs dense march: {:.2}%",
            frac * 100.0
        );
        mean_steps.push(steps.iter().map(|&s| s as f64).sum::<f64>() / steps.len() as f64);
        depths.push(depth);
    }
    let (frac, _) = depth_agreement(&depths[0], &depths[1], 0.02);
    assert!(frac >= 0.99, "segment vs sphere: {:.2}%", frac * 100.0);
    assert!(
        mean_steps[0] * 5.0 < mean_steps[1],
        "segment tracing should take far fewer steps: {mean_steps:?}"
    );
}

#[test]
fn segment_and_sphere_images_match() {
    let b = small_blobs();
    let cam = Camera::frame(&b.support(), 35.0, 64, 48).unwrap();
    let frames: Vec<_> = [Method::Segment, Method::Sphere]
        .iter()
        .map(|&m| {
            render(
                &b,
                &cam,
                &RenderSettings::for_scene(&b.support(), &cam, m),
                &ProgressBar::hidden(),
            )
        })
        .collect();
    let close = frames[0]
        .rgba
        .chunks(4)
        .zip(frames[1].rgba.chunks(4))
        .filter(|(a, c)| a.iter().zip(c.iter()).all(|(x, y)| x.abs_diff(*y) <= 6))
        .count();
    assert!(
        close as f64 >= 0.99 * (64.0 * 48.0),
        "{close} of {} pixels match",
        64 * 48
    );
}

#[test]
fn shadows_fall_where_the_sun_is_blocked() {
    // A ball floating above a slab of terrain: the point under the ball (towards the sun's
    // opposite) is in shadow, a point far away is lit.
    let ball = SigmaSphere {
        center: Vec3::new(0.0, 0.0, 10.0),
        radius: 3.0,
        falloff: 1.0,
    };
    let params = TraceParams::for_scene(Method::Segment, 40.0);
    let sun = Vec3::new(0.3, 0.2, 1.0).normalize();
    let support = ball.support();
    let shadowed = |origin: Vec3| {
        let ray = Ray { origin, dir: sun };
        ray.clip(&support)
            .is_some_and(|span| occluded(&ball, &ray, span, &params))
    };
    assert!(
        shadowed(ball.center - sun * 10.0),
        "straight under the ball along the sun"
    );
    assert!(!shadowed(Vec3::new(8.0, 0.0, 0.0)));
    // A ray leaving the surface outwards is not shadowed by the surface itself.
    let on = ball.center + sun * ball.radius;
    assert!(!shadowed(on + sun * 1e-3));
}

/// Adaptive supersampling touches the edge pixels alone, and softens them: a ball against
/// the sky, with and without it. Away from the edges the two pictures are the same pixel
/// for pixel; on the silhouette, pixels take levels between the sky's and the ball's
/// that the single-sample picture does not have (its silhouette steps from one to the
/// other); and the picture is the same on one thread and on many.
#[test]
fn antialiasing_softens_edges_and_leaves_the_rest() {
    let ball = SigmaSphere {
        center: Vec3::ZERO,
        radius: 4.0,
        falloff: 1.0,
    };
    let cam = Camera::frame(&ball.support(), 35.0, 64, 48).unwrap();
    let plain = RenderSettings::for_scene(&ball.support(), &cam, Method::Segment);
    let smooth = RenderSettings {
        antialias: true,
        ..plain.clone()
    };
    let a = render(&ball, &cam, &plain, &ProgressBar::hidden());
    let b = render(&ball, &cam, &smooth, &ProgressBar::hidden());
    let (w, h) = (64usize, 48usize);
    let hit = |k: usize| a.depth[k].is_finite();
    let silhouette = |k: usize| {
        let (i, j) = (k % w, k / w);
        [(1i32, 0i32), (-1, 0), (0, 1), (0, -1)]
            .iter()
            .any(|&(di, dj)| {
                let (x, y) = (i as i32 + di, j as i32 + dj);
                x >= 0
                    && y >= 0
                    && (x as usize) < w
                    && (y as usize) < h
                    && hit(x as usize + w * y as usize) != hit(k)
            })
    };
    let edges: Vec<usize> = (0..w * h).filter(|&k| silhouette(k)).collect();
    assert!(edges.len() > 40, "{} silhouette pixels", edges.len());
    let changed = edges
        .iter()
        .filter(|&&k| a.rgba[4 * k..4 * k + 3] != b.rgba[4 * k..4 * k + 3])
        .count();
    // (On the sky's side of the silhouette a pixel's sub-samples may all miss too.)
    assert!(
        changed * 3 > edges.len(),
        "{changed} of {} silhouette pixels softened",
        edges.len()
    );
    // Far from every edge (two pixels from any pixel that differs from a neighbour by the
    // edge contrast), nothing changed.
    let differs = |k: usize, m: usize| {
        hit(k) != hit(m)
            || (0..3).any(|c| a.rgba[4 * k + c].abs_diff(a.rgba[4 * m + c]) > cpu::EDGE_CONTRAST)
    };
    let near_edge = |k: usize| {
        let (i, j) = ((k % w) as i32, (k / w) as i32);
        (-2..=2).any(|dj| {
            (-2..=2).any(|di| {
                let (x, y) = (i + di, j + dj);
                x >= 1 && y >= 1 && (x as usize) < w - 1 && (y as usize) < h - 1 && {
                    let m = x as usize + w * y as usize;
                    [m + 1, m - 1, m + w, m - w].iter().any(|&n| differs(m, n))
                }
            })
        })
    };
    for k in (0..w * h).filter(|&k| !near_edge(k)) {
        assert_eq!(
            a.rgba[4 * k..4 * k + 4],
            b.rgba[4 * k..4 * k + 4],
            "pixel {k} changed away from the edges"
        );
        assert_eq!(a.depth[k].to_bits(), b.depth[k].to_bits());
    }
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    assert_eq!(
        one.install(|| render(&ball, &cam, &smooth, &ProgressBar::hidden())),
        b
    );
}

#[test]
fn rays_starting_inside_find_the_way_out() {
    let s = SigmaSphere {
        center: Vec3::ZERO,
        radius: 4.0,
        falloff: 1.0,
    };
    let ray = Ray {
        origin: Vec3::ZERO,
        dir: Vec3::new(1.0, 2.0, 0.5).normalize(),
    };
    let params = TraceParams::for_scene(Method::Segment, 10.0);
    let tr = trace(&s, &ray, ray.clip(&s.support()).unwrap(), &params);
    assert!((tr.t - 4.0).abs() < 0.01, "{tr:?}");
}

#[test]
fn rendering_is_deterministic_across_thread_counts() {
    let t = Terrain::new(60.0, 8.0, 3.0);
    let cam = Camera::frame(&t.support(), 40.0, 50, 40).unwrap();
    let s = RenderSettings::for_scene(&t.support(), &cam, Method::Segment);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let a = one.install(|| render(&t, &cam, &s, &ProgressBar::hidden()));
    let b = render(&t, &cam, &s, &ProgressBar::hidden());
    assert_eq!(a, b.clone());
    assert!(b.hits() > 400, "{}", b.hits());
}

#[test]
fn traced_depth_matches_ray_casting_a_mesh_of_the_surface() {
    // The pattern of the Marching Cubes comparison: a triangle mesh of the surface, ray
    // cast through an obvhs BVH, against the traced depth, within one "cell" (here the
    // mesh's chord error bound, 0.2% of the radius, plus the tracer's tolerance).
    let s = SigmaSphere {
        center: Vec3::new(-2.0, 1.0, 4.0),
        radius: 5.0,
        falloff: 2.0,
    };
    let (pos, faces) = uv_sphere(s.center, s.radius, 128);
    let mesh = MeshRaycaster::new(&pos, &faces);
    let cam = Camera::look_at(
        s.center + Vec3::new(18.0, -20.0, 12.0),
        s.center,
        35.0,
        120,
        90,
    )
    .unwrap();
    let truth = mesh.depth(&cam);
    let params = TraceParams::for_scene(Method::Segment, 2.0 * s.support().radius())
        .with_pixel_angle(cam.pixel_angle());
    let (depth, _) = cpu::depth(&s, &cam, &params);
    let (frac, hits) = depth_agreement(&truth, &depth, 0.01 * s.radius);
    assert!(hits > 1500, "{hits}");
    assert!(frac >= 0.99, "{:.2}% of hit pixels agree", frac * 100.0);
    // And the mesh agrees with the analytic sphere, so the comparison means something
    // (a few rays slip between triangles: obvhs's Möller–Trumbore is not watertight).
    let (mut facing_hits, mut bad) = (0, 0);
    for (k, d) in truth.iter().enumerate() {
        let r = cam.pixel_ray(k as u32 % 120, k as u32 / 120);
        let Some(t) = s.intersect(r.origin, r.dir) else {
            continue;
        };
        if (r.at(t) - s.center).normalize().dot(-r.dir) > 0.3 {
            facing_hits += 1;
            bad += usize::from((d - t).abs() >= 0.01 * s.radius);
        }
    }
    assert!(
        bad * 200 <= facing_hits,
        "{bad} of {facing_hits} mesh depths off the sphere"
    );
}

/// Ground (a thick slab, top at `z = 0`) and a floating slab above it: the union of two
/// boxes through `σ_R` of their signed distances, for the shadow tests.
struct Overhang {
    ground: Aabb,
    slab: Aabb,
    falloff: f32,
}

fn box_sd(b: &Aabb, p: Vec3) -> f32 {
    let q = (p - b.center()).abs() - b.size() * 0.5;
    q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
}

impl Overhang {
    /// `min` of the two boxes' signed distances: 1-Lipschitz.
    fn sd(&self, p: Vec3) -> f32 {
        box_sd(&self.ground, p).min(box_sd(&self.slab, p))
    }
}

impl Field for Overhang {
    fn value(&self, p: Vec3) -> f32 {
        sigma(-self.sd(p), self.falloff)
    }
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let e = 1e-3;
        let g = Vec3::new(
            self.value(p + Vec3::X * e) - self.value(p - Vec3::X * e),
            self.value(p + Vec3::Y * e) - self.value(p - Vec3::Y * e),
            self.value(p + Vec3::Z * e) - self.value(p - Vec3::Z * e),
        ) / (2.0 * e);
        (self.value(p), g)
    }
    fn support(&self) -> Aabb {
        self.ground.union(self.slab).dilate(self.falloff)
    }
    fn interval(&self, b: &Aabb) -> Interval {
        let (d, r) = (self.sd(b.center()), b.radius());
        sigma_interval(Interval::new(-d - r, -d + r), self.falloff)
    }
    fn lipschitz(&self) -> f32 {
        sigma_max_slope(self.falloff)
    }
    fn lipschitz_box(&self, _b: &Aabb) -> f32 {
        self.lipschitz()
    }
}

/// Whether the ray from `o` along `d` crosses `b` over more than `depth` metres of its
/// length (negative `depth`: passes within `−depth` of it, roughly, by growing the box).
fn crosses(b: &Aabb, o: Vec3, d: Vec3, depth: f32) -> bool {
    let g = b.dilate((-depth).max(0.0));
    let inv = d.recip();
    let (a, c) = ((g.min - o) * inv, (g.max - o) * inv);
    let t0 = a.min(c).max_element().max(0.0);
    let t1 = a.max(c).min_element();
    t1 - t0 > depth.max(0.0)
}

#[test]
fn soft_shadows_darken_what_the_sun_disk_ray_of_each_pixel_meets() {
    // A slab floating over open ground, seen from above: each ground pixel whose own ray
    // towards the sun's disk (Shading::sun_towards) runs through the slab is in shadow,
    // each whose ray clears it is lit — under the overhang and on the open plain alike.
    // The penumbra — pixels the render darkens though the sun's centre is in view —
    // widens with the slab's height.
    let penumbra_px = |height: f32, thick: f32| {
        let f = Overhang {
            ground: Aabb::new(Vec3::new(-60.0, -60.0, -10.0), Vec3::new(60.0, 60.0, 0.0)),
            slab: Aabb::new(
                Vec3::new(-8.0, -8.0, height),
                Vec3::new(8.0, 8.0, height + thick),
            ),
            falloff: 0.5,
        };
        let cam = Camera::look_at(
            Vec3::new(12.0, -25.0, 70.0),
            Vec3::new(12.0, 8.0, 0.0),
            50.0,
            160,
            120,
        )
        .unwrap();
        let mut s = RenderSettings::for_scene(&f.support(), &cam, Method::Segment);
        s.shading.ao_radius = 0.0;
        s.shading.haze = f32::INFINITY;
        // A sun of 5.7° radius (five times the default's), so that its penumbra spans
        // pixels.
        s.shading.sun_radius = 0.1;
        let bar = ProgressBar::hidden();
        let shaded = render(&f, &cam, &s, &bar);
        s.shading.shadows = false;
        let open = render(&f, &cam, &s, &bar);
        let (mut dark, mut lit, mut penumbra) = (0, 0, 0);
        for j in 0..cam.height {
            for i in 0..cam.width {
                let at = (i + j * cam.width) as usize;
                let p = cam.pixel_ray(i, j).at(shaded.depth[at]);
                if !shaded.depth[at].is_finite() || p.z.abs() >= 0.05 {
                    continue; // not the ground's top
                }
                let sun = s.shading.sun_towards(i, j);
                let (a, b) = (shaded.rgba[4 * at], open.rgba[4 * at]);
                // Beyond the shadow ray's tolerance (steps may cross a thinner chord): the
                // pixel's footprint at the hit, grown by the pixel's cone up to the slab's
                // top.
                let t = &s.trace;
                let reach = (height + thick) / sun.z;
                let tol = t.epsilon + t.cone * (shaded.depth[at] + reach);
                let margin = 1.5 * tol;
                // The shadow ray starts two footprints above the ground.
                let o = p + Vec3::Z * (2.0 * (t.epsilon + t.cone * shaded.depth[at]));
                if crosses(&f.slab, o, sun, margin) {
                    assert!(
                        a + 40 < b,
                        "pixel ({i}, {j}) under the slab is lit: {a} vs {b}"
                    );
                    dark += 1;
                } else if !crosses(&f.slab, o, sun, -margin) {
                    assert_eq!(a, b, "pixel ({i}, {j}) in the open is shadowed");
                    lit += 1;
                }
                // Partly hidden disk (the rim's rays disagree): the render darkens some of
                // these pixels though the ray to the sun's centre clears the slab, which
                // only a shadow of the whole disk does.
                let (u, v) = s.shading.sun_disk();
                let rim = [u, -u, v, -v]
                    .map(|w| crosses(&f.slab, p, (s.shading.sun + w).normalize(), 0.0));
                let partly = rim.iter().any(|&x| x) && !rim.iter().all(|&x| x);
                if partly && a + 40 < b && !crosses(&f.slab, o, s.shading.sun, 0.0) {
                    penumbra += 1;
                }
            }
        }
        assert!(dark > 200 && lit > 2000, "{dark} dark, {lit} lit pixels");
        penumbra
    };
    let (low, high) = (penumbra_px(4.0, 3.0), penumbra_px(16.0, 3.0));
    // A thin roof hides the sun's disk as well as a thick one: its shadow is checked
    // pixel by pixel alike (a tolerance grown by the penumbra stepped through it).
    penumbra_px(16.0, 1.5);
    assert!(
        low > 0 && high > low + low / 2,
        "penumbra: {low} pixels at 4 m, {high} at 16 m"
    );
}

//! The test fields encoded as GPU tapes.

use glam::{Vec2, Vec3};
use karstic::dem::Interpolation;
use karstic::field::Aabb;
use karstic::tape::{Combine, HeightGrid, Profile, Shape, Tape, TapeBuilder};

use super::dem::Dem;
use super::{Blobs, SigmaSphere, Terrain};

/// The blobs as a blend under a BVH of guards.
pub fn blobs(b: &Blobs) -> Tape {
    let mut t = TapeBuilder::new();
    let boxes: Vec<Aabb> = b
        .centers
        .iter()
        .map(|c| Aabb::around(*c, b.radius))
        .collect();
    t.combine_bvh(Combine::Blend, &boxes, &mut |t, i| {
        t.primitive(
            Shape::Point(b.centers[i]),
            Profile::Wyvill {
                radius: b.radius,
                energy: b.energy,
            },
        );
        Ok(())
    })
    .unwrap();
    t.finish().unwrap()
}

/// A σ-sphere.
pub fn sigma_sphere(s: &SigmaSphere) -> Tape {
    let mut t = TapeBuilder::new();
    t.primitive(
        Shape::Sphere {
            center: s.center,
            radius: s.radius,
        },
        Profile::Sigma { radius: s.falloff },
    );
    t.finish().unwrap()
}

/// A DEM as `σ(h − z)` inside a σ box prism (Paris et al. 2019 §5.1) with a tunnel carved by
/// a σ capsule through the middle at the median elevation.
pub fn dem_with_cave(d: &Dem) -> Tape {
    let falloff = 2.0 * d.cell;
    let size = Vec3::new((d.nx - 1) as f32 * d.cell, (d.ny - 1) as f32 * d.cell, 0.0);
    let (lo, hi) =
        d.z.iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &z| (a.min(z), b.max(z)));
    let mut sorted = d.z.clone();
    sorted.sort_by(f32::total_cmp);
    let median = sorted[sorted.len() / 2];
    let mut t = TapeBuilder::new();
    t.heightfield(
        &HeightGrid {
            origin: Vec2::ZERO,
            cell: d.cell,
            nx: d.nx,
            ny: d.ny,
            z: &d.z,
            interpolation: Interpolation::Bilinear,
            detail: None,
        },
        falloff,
    )
    .unwrap();
    let floor = lo - 200.0;
    t.primitive(
        Shape::Box {
            center: Vec3::new(0.5 * size.x, 0.5 * size.y, 0.5 * (floor + hi)),
            half: Vec3::new(0.5 * size.x, 0.5 * size.y, 0.5 * (hi - floor)),
        },
        Profile::Sigma { radius: falloff },
    );
    t.combine(Combine::Intersection).unwrap();
    t.primitive(
        Shape::Capsule {
            a: Vec3::new(0.1 * size.x, 0.3 * size.y, median),
            b: Vec3::new(0.9 * size.x, 0.6 * size.y, median + 100.0),
            radius: 250.0,
        },
        Profile::Sigma { radius: falloff },
    );
    t.combine(Combine::Difference).unwrap();
    t.finish().unwrap()
}

/// The terrain sampled on an `n × n` grid, intersected with a σ box prism.
pub fn terrain(tr: &Terrain, n: usize) -> Tape {
    let lo = tr.bounds.min.truncate();
    let cell = (tr.bounds.max.x - lo.x) / (n - 1) as f32;
    let z: Vec<f32> = (0..n * n)
        .map(|k| tr.height(lo + Vec2::new((k % n) as f32, (k / n) as f32) * cell))
        .collect();
    let mut t = TapeBuilder::new();
    t.heightfield(
        &HeightGrid {
            origin: lo,
            cell,
            nx: n,
            ny: n,
            z: &z,
            interpolation: Interpolation::Bilinear,
            detail: None,
        },
        tr.falloff,
    )
    .unwrap();
    t.primitive(
        Shape::Box {
            center: tr.bounds.center(),
            half: tr.bounds.size() * 0.5,
        },
        Profile::Sigma { radius: tr.falloff },
    );
    t.combine(Combine::Intersection).unwrap();
    t.finish().unwrap()
}

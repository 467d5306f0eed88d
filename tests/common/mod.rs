//! Small test fields for the renderer's tests and benches: a σ-sphere (analytic ground
//! truth), a sum of many Wyvill point blobs with local Lipschitz bounds from a grid, and a
//! heightfield-like terrain chunk `min(σ(h(x, y) − z), σ(−d_box))`.
#![allow(dead_code)]

use glam::{Vec2, Vec3};
use karstic::field::falloff::{
    WYVILL_MAX_SLOPE, sigma, sigma_d, sigma_interval, sigma_max_slope, sigma_slope, wyvill,
    wyvill_d, wyvill_slope,
};
use karstic::field::{Aabb, Field, Interval, T};

/// `σ(r − |p − c|, R)`: a ball of radius `r` whose surface is exactly the sphere.
pub struct SigmaSphere {
    pub center: Vec3,
    pub radius: f32,
    pub falloff: f32,
}

impl SigmaSphere {
    /// The analytic first intersection of a ray with the sphere `|p − c| = r`.
    pub fn intersect(&self, o: Vec3, d: Vec3) -> Option<f32> {
        let oc = o - self.center;
        let b = oc.dot(d);
        let c = oc.length_squared() - self.radius * self.radius;
        let disc = b * b - c;
        if disc < 0.0 {
            return None;
        }
        let t = -b - disc.sqrt();
        (t >= 0.0).then_some(t)
    }

    fn dist_range(&self, b: &Aabb) -> Interval {
        let lo = b.distance(self.center);
        let hi = b
            .corners()
            .iter()
            .map(|q| q.distance(self.center))
            .fold(0.0, f32::max);
        Interval::new(lo, hi)
    }
}

impl Field for SigmaSphere {
    fn value(&self, p: Vec3) -> f32 {
        sigma(self.radius - p.distance(self.center), self.falloff)
    }
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let d = p - self.center;
        let l = d.length();
        let (v, s) = sigma_d(self.radius - l, self.falloff);
        (v, if l > 0.0 { -s * d / l } else { Vec3::ZERO })
    }
    fn support(&self) -> Aabb {
        // Outside the ball of radius r + R the field is 0.
        Aabb::around(self.center, self.radius + self.falloff)
    }
    fn interval(&self, b: &Aabb) -> Interval {
        let d = self.dist_range(b);
        sigma_interval(
            Interval::new(self.radius - d.hi, self.radius - d.lo),
            self.falloff,
        )
    }
    fn lipschitz(&self) -> f32 {
        sigma_max_slope(self.falloff)
    }
    fn lipschitz_box(&self, b: &Aabb) -> f32 {
        let d = self.dist_range(b);
        sigma_slope(
            Interval::new(self.radius - d.hi, self.radius - d.lo),
            self.falloff,
        )
    }
}

/// `Σ e · g(|p − c_i| / R)` with a uniform grid of cell size `R`: each cell lists the
/// blobs whose support overlaps it (for values) and the blobs centred in it (for segment
/// bounds), and holds a bound of `|∇f|` inside it (for long segments and boxes).
pub struct Blobs {
    pub centers: Vec<Vec3>,
    pub energy: f32,
    pub radius: f32,
    origin: Vec3,
    dims: [i32; 3],
    starts: Vec<u32>,
    items: Vec<Vec3>,
    centered_starts: Vec<u32>,
    centered: Vec<Vec3>,
    slope: Vec<f32>,
}

/// A deterministic generator (SplitMix64) so tests need no RNG crate.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `[0, 1)`.
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    /// Uniform in `[a, b)`.
    pub fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.f32()
    }
    /// Uniform in the ball of radius `r`.
    pub fn in_ball(&mut self, r: f32) -> Vec3 {
        loop {
            let p = Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            if p.length_squared() <= 1.0 {
                return p * r;
            }
        }
    }
}

impl Blobs {
    /// `n` blobs scattered uniformly in a ball of radius `ball`, each `energy · g(d / radius)`.
    pub fn in_ball(n: usize, ball: f32, radius: f32, energy: f32, seed: u64) -> Self {
        let mut rng = Rng(seed);
        let centers = (0..n).map(|_| rng.in_ball(ball)).collect();
        Blobs::new(centers, radius, energy)
    }

    pub fn new(centers: Vec<Vec3>, radius: f32, energy: f32) -> Self {
        assert!(energy > 0.0 && radius > 0.0);
        let b = Aabb::from_points(centers.iter().copied()).dilate(radius);
        let dims = ((b.size() / radius).ceil().as_ivec3().max(glam::IVec3::ONE)).to_array();
        let ncell = (dims[0] * dims[1] * dims[2]) as usize;
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); ncell];
        let mut slope = vec![0.0f32; ncell];
        let k = energy / radius;
        for (i, c) in centers.iter().enumerate() {
            let lo = ((*c - radius - b.min) / radius)
                .floor()
                .as_ivec3()
                .max(glam::IVec3::ZERO);
            let hi = ((*c + radius - b.min) / radius)
                .floor()
                .as_ivec3()
                .min(glam::IVec3::from(dims) - 1);
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let cell_min = b.min + Vec3::new(x as f32, y as f32, z as f32) * radius;
                        let cell = Aabb::new(cell_min, cell_min + radius);
                        let dlo = cell.distance(*c);
                        if dlo >= radius {
                            continue;
                        }
                        let dhi = cell
                            .corners()
                            .iter()
                            .map(|q| q.distance(*c))
                            .fold(0.0, f32::max);
                        let at = (x + dims[0] * (y + dims[1] * z)) as usize;
                        lists[at].push(i as u32);
                        slope[at] += k * wyvill_slope(Interval::new(dlo / radius, dhi / radius));
                    }
                }
            }
        }
        let csr = |lists: &[Vec<u32>]| {
            let mut starts = Vec::with_capacity(lists.len() + 1);
            let mut items = Vec::new();
            for l in lists {
                starts.push(items.len() as u32);
                items.extend(l.iter().map(|&i| centers[i as usize]));
            }
            starts.push(items.len() as u32);
            (starts, items)
        };
        let mut by_center: Vec<Vec<u32>> = vec![Vec::new(); ncell];
        for (i, c) in centers.iter().enumerate() {
            let q = ((*c - b.min) / radius)
                .floor()
                .as_ivec3()
                .clamp(glam::IVec3::ZERO, glam::IVec3::from(dims) - 1);
            by_center[(q.x + dims[0] * (q.y + dims[1] * q.z)) as usize].push(i as u32);
        }
        let (starts, items) = csr(&lists);
        let (centered_starts, centered) = csr(&by_center);
        Blobs {
            centers,
            energy,
            radius,
            origin: b.min,
            dims,
            starts,
            items,
            centered_starts,
            centered,
            slope,
        }
    }

    fn cell_of(&self, p: Vec3) -> Option<usize> {
        let q = (p - self.origin) / self.radius;
        if q.min_element() < 0.0 {
            return None;
        }
        // Non-negative: truncation is the floor (and avoids a libm call).
        let c = q.as_ivec3();
        let d = self.dims;
        if c.x >= d[0] || c.y >= d[1] || c.z >= d[2] {
            return None;
        }
        Some((c.x + d[0] * (c.y + d[1] * c.z)) as usize)
    }

    fn blobs_at(&self, p: Vec3) -> &[Vec3] {
        match self.cell_of(p) {
            Some(c) => &self.items[self.starts[c] as usize..self.starts[c + 1] as usize],
            None => &[],
        }
    }

    /// The value by brute force over every blob (the grid-free reference).
    pub fn value_brute(&self, p: Vec3) -> f32 {
        self.centers
            .iter()
            .map(|c| self.energy * wyvill(p.distance(*c) / self.radius))
            .sum()
    }

    fn cell_range(&self, b: &Aabb) -> Option<(glam::IVec3, glam::IVec3)> {
        let hi_cell = glam::IVec3::from(self.dims) - 1;
        let lo = ((b.min - self.origin) / self.radius).floor().as_ivec3();
        let hi = ((b.max - self.origin) / self.radius).floor().as_ivec3();
        if hi.cmplt(glam::IVec3::ZERO).any() || lo.cmpgt(hi_cell).any() {
            return None;
        }
        Some((lo.max(glam::IVec3::ZERO), hi.min(hi_cell)))
    }
}

impl Field for Blobs {
    fn value(&self, p: Vec3) -> f32 {
        let r2 = self.radius * self.radius;
        let mut v = 0.0;
        for c in self.blobs_at(p) {
            let d2 = p.distance_squared(*c);
            if d2 < r2 {
                let s = 1.0 - d2 / r2;
                v += s * s * s;
            }
        }
        self.energy * v
    }
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let (mut v, mut g) = (0.0, Vec3::ZERO);
        for c in self.blobs_at(p) {
            let d = p - *c;
            let l = d.length();
            let (w, dw) = wyvill_d(l / self.radius);
            v += w;
            if l > 0.0 {
                g += d / l * (dw / self.radius);
            }
        }
        (self.energy * v, self.energy * g)
    }
    fn support(&self) -> Aabb {
        Aabb::from_points(self.centers.iter().copied()).dilate(self.radius)
    }
    fn interval(&self, b: &Aabb) -> Interval {
        let hi = self
            .centers
            .iter()
            .map(|c| wyvill(b.distance(*c) / self.radius))
            .sum::<f32>();
        Interval::new(0.0, self.energy * hi)
    }
    /// What a blend node reports: the sum of its children's global bounds.
    fn lipschitz(&self) -> f32 {
        self.centers.len() as f32 * self.energy * WYVILL_MAX_SLOPE / self.radius
    }
    fn lipschitz_box(&self, b: &Aabb) -> f32 {
        let Some((lo, hi)) = self.cell_range(b) else {
            return 0.0;
        };
        let mut m = 0.0f32;
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    m = m.max(self.slope[(x + self.dims[0] * (y + self.dims[1] * z)) as usize]);
                }
            }
        }
        m
    }
    /// Short segments (up to `2R`): the sum over the blobs within reach of each blob's
    /// directional slope bound along the segment. Longer ones: the largest cell bound
    /// along the segment (pieces no longer than a cell, each covered by the cells its box
    /// overlaps).
    fn lipschitz_segment(&self, a: Vec3, b: Vec3) -> f32 {
        let r = self.radius;
        let ab = b - a;
        let len2 = ab.length_squared();
        let (r2, inv_r) = (r * r, 1.0 / r);
        // Along the segment a blob is φ(s) = g(√((s − s₀)² + h²) / R) (h: distance from
        // the blob's centre to the line), so |φ'| = |g'(x)|·√(1 − k²/x²)/R with k = h/R:
        // 6(1 − y)²√(y − k²)/R in y = x², unimodal with its peak at y* = (1 + 4k²)/5. Its
        // maximum over the segment's range of y is a directional Lipschitz bound, which is
        // all the contract asks for pairs of points on the segment.
        let slope_on_segment = |c: Vec3| {
            let ac = c - a;
            let t = if len2 > 0.0 { ac.dot(ab) / len2 } else { 0.0 };
            let near2 = (ac - ab * t.clamp(0.0, 1.0)).length_squared();
            if near2 >= r2 {
                return 0.0;
            }
            let k2 = (ac - ab * t).length_squared() * inv_r * inv_r;
            let far2 = ac.length_squared().max((c - b).length_squared());
            let y = ((1.0 + 4.0 * k2) * 0.2)
                .clamp(near2 * inv_r * inv_r, (far2 * inv_r * inv_r).min(1.0));
            6.0 * (1.0 - y) * (1.0 - y) * (y - k2).max(0.0).sqrt()
        };
        let (ca, cb) = (self.cell_of(a), self.cell_of(b));
        if ca.is_some() && ca == cb {
            // Both ends in one (convex) cell: the blobs overlapping it are all that reach.
            let c = ca.unwrap_or_default();
            let list = &self.items[self.starts[c] as usize..self.starts[c + 1] as usize];
            return self.energy * inv_r * list.iter().map(|&c| slope_on_segment(c)).sum::<f32>();
        }
        if len2 <= 4.0 * r * r {
            let Some((lo, hi)) = self.cell_range(&Aabb::new(a, b).dilate(r)) else {
                return 0.0;
            };
            let mut sum = 0.0;
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    let row = self.dims[0] * (y + self.dims[1] * z);
                    let (s, e) = (
                        self.centered_starts[(row + lo.x) as usize] as usize,
                        self.centered_starts[(row + hi.x + 1) as usize] as usize,
                    );
                    for &c in &self.centered[s..e] {
                        sum += slope_on_segment(c);
                    }
                }
            }
            return self.energy * inv_r * sum;
        }
        let n = (ab.abs().max_element() / r).ceil().max(1.0) as usize;
        let mut m = 0.0f32;
        let mut p = a;
        for i in 1..=n {
            let q = a.lerp(b, i as f32 / n as f32);
            m = m.max(self.lipschitz_box(&Aabb::new(p, q)));
            p = q;
        }
        m
    }
}

/// A terrain chunk: `min(σ(h(x, y) − z, R), σ(−d_box(p), R))`, solid under the
/// heightfield `h` and inside `bounds`.
pub struct Terrain {
    pub bounds: Aabb,
    pub falloff: f32,
    pub amplitude: f32,
    pub wavelength: f32,
}

impl Terrain {
    pub fn new(size: f32, amplitude: f32, falloff: f32) -> Self {
        Terrain {
            bounds: Aabb::new(
                Vec3::new(-size, -size, -amplitude * 2.0),
                Vec3::new(size, size, amplitude * 2.5),
            ),
            falloff,
            amplitude,
            wavelength: size / 3.0,
        }
    }

    /// `h(x, y)`: two octaves of sines, a high ridge in the middle.
    pub fn height(&self, xy: Vec2) -> f32 {
        let (a, l) = (self.amplitude, self.wavelength);
        let ridge = 1.2 * a * (-(xy.length_squared()) / (2.0 * l * l)).exp();
        ridge
            + a * (xy.x / l).sin() * (0.7 * xy.y / l).cos()
            + 0.3 * a * ((xy.x + 2.0 * xy.y) / (0.31 * l)).sin()
    }

    /// A bound of `|∇h|`.
    pub fn slope(&self) -> f32 {
        let (a, l) = (self.amplitude, self.wavelength);
        // Gaussian ridge: max |∇| = 1.2 a / (l √e); sines: a/l·(1, 0.7); detail: 0.3 a/(0.31 l)·(1, 2).
        let gx = 1.2 * a / (l * 1.6487) + a / l + 0.3 * a / (0.31 * l);
        let gy = 1.2 * a / (l * 1.6487) + 0.7 * a / l + 0.6 * a / (0.31 * l);
        (gx * gx + gy * gy).sqrt()
    }

    fn box_sd(&self, p: Vec3) -> f32 {
        let c = self.bounds.center();
        let h = self.bounds.size() * 0.5;
        let q = (p - c).abs() - h;
        q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
    }
}

impl Field for Terrain {
    fn value(&self, p: Vec3) -> f32 {
        let a = sigma(self.height(p.truncate()) - p.z, self.falloff);
        let b = sigma(-self.box_sd(p), self.falloff);
        a.min(b)
    }
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let e = 1e-3 * self.wavelength;
        let v = self.value(p);
        let g = Vec3::new(
            self.value(p + Vec3::X * e) - self.value(p - Vec3::X * e),
            self.value(p + Vec3::Y * e) - self.value(p - Vec3::Y * e),
            self.value(p + Vec3::Z * e) - self.value(p - Vec3::Z * e),
        ) / (2.0 * e);
        (v, g)
    }
    fn support(&self) -> Aabb {
        self.bounds.dilate(self.falloff)
    }
    fn interval(&self, b: &Aabb) -> Interval {
        let _ = b;
        Interval::new(0.0, 2.0 * T)
    }
    fn lipschitz(&self) -> f32 {
        sigma_max_slope(self.falloff) * (1.0 + self.slope() * self.slope()).sqrt()
    }
    fn lipschitz_box(&self, b: &Aabb) -> f32 {
        let c = b.center();
        let half_xy = (b.size().truncate() * 0.5).length();
        let h = self.height(c.truncate());
        let hz = Interval::new(
            h - self.slope() * half_xy - b.max.z,
            h + self.slope() * half_xy - b.min.z,
        );
        let terrain = sigma_slope(hz, self.falloff) * (1.0 + self.slope() * self.slope()).sqrt();
        let r = b.radius();
        let d = self.box_sd(c);
        let edge = sigma_slope(Interval::new(-d - r, -d + r), self.falloff);
        terrain.max(edge)
    }
}

/// Samples random pairs on random segments inside `region` and checks
/// `|f(a) − f(b)| ≤ λ_seg · |a − b|` (plus a float slack). Returns the pairs checked.
pub fn check_segment_lipschitz(f: &dyn Field, region: &Aabb, n: usize, seed: u64) -> usize {
    let mut rng = Rng(seed);
    let s = region.size();
    let pick =
        |rng: &mut Rng| region.min + Vec3::new(rng.f32() * s.x, rng.f32() * s.y, rng.f32() * s.z);
    for _ in 0..n {
        let a = pick(&mut rng);
        let b = a + (pick(&mut rng) - a) * rng.f32() * rng.f32();
        let lam = f.lipschitz_segment(a, b);
        let (u, v) = (rng.f32(), rng.f32());
        let (p, q) = (a.lerp(b, u), a.lerp(b, v));
        let df = (f.value(p) - f.value(q)).abs();
        assert!(
            df <= lam * p.distance(q) * 1.001 + 1e-5,
            "Lipschitz bound {lam} violated on [{a}, {b}]: |Δf| = {df} over {}",
            p.distance(q)
        );
        assert!(
            lam <= f.lipschitz() * 1.0001 + 1e-6,
            "local bound above the global one"
        );
    }
    n
}

pub mod tapes {
    //! The same scenes encoded as GPU tapes.
    use super::*;
    use karstic::dem::Interpolation;
    use karstic::tape::{Combine, HeightGrid, Profile, Shape, Tape, TapeBuilder};

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

    /// A DEM as `σ(h − z)` inside a σ box prism (seed 002 §5.1) with a tunnel carved by
    /// a σ capsule through the middle at the median elevation.
    pub fn dem_with_cave(d: &super::dem::Dem) -> Tape {
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
}

pub mod dem {
    //! The Jacksboro DEM (UTM 16N, 90 m cells) from `../shared/data/dem`, read with a
    //! minimal ESRI ASCII parser and cropped to the largest centred window without
    //! no-data cells; elevations in metres, x east and y north from the window's
    //! south-west sample.
    use std::path::Path;

    pub struct Dem {
        pub nx: usize,
        pub ny: usize,
        pub cell: f32,
        /// `z[i + nx·j]`, `j = 0` the southern row.
        pub z: Vec<f32>,
    }

    pub fn jacksboro() -> Dem {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../shared/data/dem/jacksboro_utm16n_90m.asc");
        let text =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut head = std::collections::HashMap::new();
        let mut values = Vec::new();
        for line in text.lines() {
            let mut it = line.split_whitespace();
            match it.next() {
                Some(k) if k.chars().next().is_some_and(|c| c.is_ascii_alphabetic()) => {
                    head.insert(
                        k.to_ascii_lowercase(),
                        it.next().unwrap().parse::<f64>().unwrap(),
                    );
                }
                Some(first) => {
                    values.push(first.parse::<f32>().unwrap());
                    values.extend(it.map(|v| v.parse::<f32>().unwrap()));
                }
                None => {}
            }
        }
        let (cols, rows) = (head["ncols"] as usize, head["nrows"] as usize);
        let nodata = head["nodata_value"] as f32;
        assert_eq!(values.len(), cols * rows);
        let at = |c: usize, r: usize| values[c + cols * r];
        let clean = |m: usize| (m..rows - m).all(|r| (m..cols - m).all(|c| at(c, r) != nodata));
        let m = (0..rows.min(cols) / 2)
            .find(|&m| clean(m))
            .expect("some clean window");
        let (nx, ny) = (cols - 2 * m, rows - 2 * m);
        let z = (0..nx * ny)
            .map(|k| at(m + k % nx, rows - 1 - m - k / nx))
            .collect();
        Dem {
            nx,
            ny,
            cell: head["cellsize"] as f32,
            z,
        }
    }
}

/// A UV sphere of radius `r` with `n` segments around and `n / 2` rings: its chords lie
/// within `r(1 − cos(π/n))` of the sphere.
pub fn uv_sphere(c: Vec3, r: f32, n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let rings = n / 2;
    let mut pos = Vec::new();
    for i in 0..=rings {
        let th = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..n {
            let ph = std::f32::consts::TAU * j as f32 / n as f32;
            pos.push(c + r * Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()));
        }
    }
    let mut faces = Vec::new();
    for i in 0..rings {
        for j in 0..n {
            let (a, b) = (i * n + j, i * n + (j + 1) % n);
            faces.push([a, a + n, b]);
            faces.push([b, a + n, b + n]);
        }
    }
    (pos, faces)
}

/// Fraction of pixels where both images agree on hit/miss and, on hits, on depth within
/// `tol`. `None` in the first image counts as a miss.
pub fn depth_agreement(a: &[f32], b: &[f32], tol: f32) -> (f64, usize) {
    let mut ok = 0;
    let mut hits = 0;
    for (x, y) in a.iter().zip(b) {
        hits += usize::from(x.is_finite() || y.is_finite());
        let same = match (x.is_finite(), y.is_finite()) {
            (true, true) => (x - y).abs() <= tol,
            (false, false) => true,
            _ => false,
        };
        ok += usize::from(same && (x.is_finite() || y.is_finite()));
    }
    (ok as f64 / hits.max(1) as f64, hits)
}

/// The shared GPU context of a test binary, `None` (after printing a notice) when there is
/// no adapter; panics when an adapter exists but the tracer cannot run on it.
pub fn gpu() -> Option<&'static karstic::render::gpu::GpuContext> {
    use karstic::render::gpu::{GpuContext, GpuError};
    static CTX: std::sync::OnceLock<Option<GpuContext>> = std::sync::OnceLock::new();
    CTX.get_or_init(|| match GpuContext::new() {
        Ok(c) => {
            eprintln!("GPU tests on {}", c.adapter);
            Some(c)
        }
        Err(e @ GpuError::NoAdapter(_)) => {
            eprintln!("NOTICE: skipping the GPU comparison: {e}");
            None
        }
        Err(e) => panic!("the GPU adapter exists but the tracer cannot run on it: {e}"),
    })
    .as_ref()
}

/// Asserts that the GPU's probes of `tape` (value and Lipschitz bound over a ball of
/// radius `r` at each point) equal the CPU tape's within float rounding.
pub fn assert_probes_match(
    ctx: &karstic::render::gpu::GpuContext,
    tape: &karstic::tape::Tape,
    pts: &[(Vec3, f32)],
) {
    let got = ctx.probe(tape, pts).unwrap();
    for (&(p, r), &(v, l)) in pts.iter().zip(&got) {
        let (cv, cl) = tape.eval(p, p, r);
        assert!(
            (v - cv).abs() <= 1e-4 * (1.0 + cv.abs()),
            "value at {p}: GPU {v}, CPU {cv}"
        );
        assert!(
            (l - cl).abs() <= 1e-3 * (1.0 + cl.abs()),
            "bound at {p}, r {r}: GPU {l}, CPU {cl}"
        );
    }
}

/// Asserts that two renders of the same scene agree: on ≥ 99 % of pixels every colour
/// channel within 6 levels, and on ≥ 99 % of pixels the same hit/miss.
pub fn assert_frames_match(name: &str, a: &karstic::render::Frame, b: &karstic::render::Frame) {
    let n = a.depth.len();
    assert_eq!(n, b.depth.len(), "{name}: frame sizes differ");
    let close = (0..n)
        .filter(|&k| (0..3).all(|c| a.rgba[4 * k + c].abs_diff(b.rgba[4 * k + c]) <= 6))
        .count();
    let hits_agree = (0..n)
        .filter(|&k| a.depth[k].is_finite() == b.depth[k].is_finite())
        .count();
    assert!(
        close as f64 >= 0.99 * n as f64,
        "{name}: {close} of {n} pixels match"
    );
    assert!(
        hits_agree as f64 >= 0.99 * n as f64,
        "{name}: hit masks differ on {} pixels",
        n - hits_agree
    );
}

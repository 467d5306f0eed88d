//! Small exact fields for the mesher's tests and benches: a sphere, a torus, a gyroid
//! clipped by a box, Wyvill blob sums, a heightfield `σ(h(x, y) − z)` that answers
//! `elevation()`, and that heightfield carved by caves. Their bounds are sound by
//! construction (distance fields are 1-Lipschitz; Lipschitz bounds of `h` are explicit).
#![allow(dead_code)]

use glam::{Vec2, Vec3};
use karstic::field::falloff::{
    WYVILL_MAX_SLOPE, sigma, sigma_d, sigma_interval, sigma_max_slope, sigma_slope, wyvill,
    wyvill_d, wyvill_interval,
};
use karstic::field::{Aabb, Elevation, ElevationSource, Field, ISO, Interval, Rect, ZBands};

/// Range of `|p − c|` over a box.
fn dist_range(b: &Aabb, c: Vec3) -> Interval {
    let far = b
        .corners()
        .iter()
        .map(|&q| (q - c).length())
        .fold(0.0, f32::max);
    Interval::new(b.distance(c), far)
}

/// `σ_R(r − |p − c|)`: a ball of radius `r`, exact surface.
pub struct Sphere {
    pub c: Vec3,
    pub r: f32,
    pub falloff: f32,
}

impl Field for Sphere {
    fn value(&self, p: Vec3) -> f32 {
        sigma(self.r - (p - self.c).length(), self.falloff)
    }
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let d = p - self.c;
        let l = d.length();
        let (v, s) = sigma_d(self.r - l, self.falloff);
        (v, if l > 0.0 { -s * d / l } else { Vec3::ZERO })
    }
    fn support(&self) -> Aabb {
        Aabb::around(self.c, self.r + self.falloff)
    }
    fn interval(&self, b: &Aabb) -> Interval {
        let d = dist_range(b, self.c);
        sigma_interval(Interval::new(self.r - d.hi, self.r - d.lo), self.falloff)
    }
    fn lipschitz(&self) -> f32 {
        sigma_max_slope(self.falloff)
    }
    fn lipschitz_box(&self, b: &Aabb) -> f32 {
        let d = dist_range(b, self.c);
        sigma_slope(Interval::new(self.r - d.hi, self.r - d.lo), self.falloff)
    }
}

/// A torus around the z axis through `c`: major radius `big`, minor radius `small`.
pub struct Torus {
    pub c: Vec3,
    pub big: f32,
    pub small: f32,
    pub falloff: f32,
}

impl Torus {
    fn dist(&self, p: Vec3) -> f32 {
        let q = p - self.c;
        Vec2::new(q.truncate().length() - self.big, q.z).length() - self.small
    }
}

impl Field for Torus {
    fn value(&self, p: Vec3) -> f32 {
        sigma(-self.dist(p), self.falloff)
    }
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let q = p - self.c;
        let rxy = q.truncate().length();
        let w = Vec2::new(rxy - self.big, q.z);
        let wl = w.length();
        let (v, s) = sigma_d(-(wl - self.small), self.falloff);
        if rxy == 0.0 || wl == 0.0 {
            return (v, Vec3::ZERO);
        }
        let radial = q.truncate() / rxy;
        let dd = Vec3::new(radial.x * w.x, radial.y * w.x, w.y) / wl;
        (v, -s * dd)
    }
    fn support(&self) -> Aabb {
        let e = self.big + self.small + self.falloff;
        Aabb::new(
            self.c - Vec3::new(e, e, self.small + self.falloff),
            self.c + Vec3::new(e, e, self.small + self.falloff),
        )
    }
    fn interval(&self, b: &Aabb) -> Interval {
        let d = self.dist(b.center());
        let r = b.radius();
        sigma_interval(Interval::new(-(d + r), -(d - r)), self.falloff)
    }
    fn lipschitz(&self) -> f32 {
        sigma_max_slope(self.falloff)
    }
    fn lipschitz_box(&self, b: &Aabb) -> f32 {
        let d = self.dist(b.center());
        let r = b.radius();
        sigma_slope(Interval::new(-(d + r), -(d - r)), self.falloff)
    }
}

/// `min(T + a·gyroid(w·p), σ(box))`: a dense triply periodic surface clipped by a box.
pub struct Gyroid {
    pub freq: f32,
    pub amp: f32,
    pub clip: Aabb,
    pub falloff: f32,
}

impl Gyroid {
    fn g(&self, p: Vec3) -> (f32, Vec3) {
        let q = p * self.freq;
        let (sx, cx) = q.x.sin_cos();
        let (sy, cy) = q.y.sin_cos();
        let (sz, cz) = q.z.sin_cos();
        let v = sx * cy + sy * cz + sz * cx;
        let d = Vec3::new(cx * cy - sz * sx, -sx * sy + cy * cz, -sy * sz + cz * cx) * self.freq;
        (ISO + self.amp * v, self.amp * d)
    }
    /// Signed distance to the clip box, positive inside (exact outside, a bound inside).
    fn inside(&self, p: Vec3) -> (f32, Vec3) {
        let c = self.clip.center();
        let h = self.clip.size() * 0.5;
        let q = (p - c).abs() - h;
        if q.max_element() > 0.0 {
            let o = q.max(Vec3::ZERO);
            let l = o.length();
            (-l, -(o / l) * (p - c).signum())
        } else {
            let m = q.max_element();
            let axis = if q.x == m {
                Vec3::X
            } else if q.y == m {
                Vec3::Y
            } else {
                Vec3::Z
            };
            (-m, -axis * (p - c).signum())
        }
    }
}

impl Field for Gyroid {
    fn value(&self, p: Vec3) -> f32 {
        self.g(p).0.min(sigma(self.inside(p).0, self.falloff))
    }
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let (g, dg) = self.g(p);
        let (s, ds) = self.inside(p);
        let (b, db) = sigma_d(s, self.falloff);
        if g <= b { (g, dg) } else { (b, db * ds) }
    }
    fn support(&self) -> Aabb {
        self.clip.dilate(self.falloff)
    }
    fn interval(&self, b: &Aabb) -> Interval {
        let (g, _) = self.g(b.center());
        let lg = self.amp * self.freq * 2.0 * 3f32.sqrt();
        let r = b.radius();
        let gi = Interval::new(
            (g - lg * r).max(ISO - 1.5 * self.amp),
            (g + lg * r).min(ISO + 1.5 * self.amp),
        );
        let s = self.inside(b.center()).0;
        gi.min(sigma_interval(Interval::new(s - r, s + r), self.falloff))
    }
    fn lipschitz(&self) -> f32 {
        (self.amp * self.freq * 2.0 * 3f32.sqrt()).max(sigma_max_slope(self.falloff))
    }
    fn lipschitz_box(&self, _b: &Aabb) -> f32 {
        self.lipschitz()
    }
}

/// `Σ e_i · g(|p − c_i| / R_i)` with positive energies.
pub struct Blobs(pub Vec<(Vec3, f32, f32)>);

impl Field for Blobs {
    fn value(&self, p: Vec3) -> f32 {
        self.0
            .iter()
            .map(|&(c, r, e)| e * wyvill((p - c).length() / r))
            .sum()
    }
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        self.0.iter().fold((0.0, Vec3::ZERO), |(v, g), &(c, r, e)| {
            let d = p - c;
            let l = d.length();
            let (w, dw) = wyvill_d(l / r);
            let gd = if l > 0.0 {
                e * dw / r * d / l
            } else {
                Vec3::ZERO
            };
            (v + e * w, g + gd)
        })
    }
    fn support(&self) -> Aabb {
        self.0
            .iter()
            .fold(Aabb::EMPTY, |b, &(c, r, _)| b.union(Aabb::around(c, r)))
    }
    fn interval(&self, b: &Aabb) -> Interval {
        self.0.iter().fold(Interval::ZERO, |acc, &(c, r, e)| {
            let d = dist_range(b, c);
            acc + wyvill_interval(Interval::new(d.lo / r, d.hi / r)).scale(e)
        })
    }
    fn lipschitz(&self) -> f32 {
        self.0
            .iter()
            .map(|&(_, r, e)| e * WYVILL_MAX_SLOPE / r)
            .sum()
    }
    fn lipschitz_box(&self, _b: &Aabb) -> f32 {
        self.lipschitz()
    }
}

/// `h(x, y) = base + a·sin(kx·x)·cos(ky·y) + b·x`: a smooth synthetic DEM.
pub struct Hills {
    pub base: f32,
    pub a: f32,
    pub k: Vec2,
    pub slope: f32,
}

impl Hills {
    /// A bound of `|∇h|`.
    pub fn lipschitz(&self) -> f32 {
        self.a * self.k.length() + self.slope.abs()
    }
    /// `[min h, max h]` over a rectangle.
    pub fn range(&self, fp: &Rect) -> Interval {
        let c = (fp.min + fp.max) * 0.5;
        let r = (fp.max - fp.min).length() * 0.5;
        let h = self.height(c);
        Interval::new(h - self.lipschitz() * r, h + self.lipschitz() * r)
    }
}

impl ElevationSource for Hills {
    fn height(&self, xy: Vec2) -> f32 {
        self.base + self.a * (self.k.x * xy.x).sin() * (self.k.y * xy.y).cos() + self.slope * xy.x
    }
}

/// The heightfield leaf `σ_R(h(x, y) − z)`. It is solid all the way down, so `support()`
/// only reports `domain`, the box the tests mesh.
pub struct Heightfield {
    pub h: Hills,
    pub falloff: f32,
    pub domain: Aabb,
}

impl Heightfield {
    fn grad_h(&self, xy: Vec2) -> Vec2 {
        let h = &self.h;
        let (sx, cx) = (h.k.x * xy.x).sin_cos();
        let (sy, cy) = (h.k.y * xy.y).sin_cos();
        Vec2::new(h.a * h.k.x * cx * cy + h.slope, -h.a * h.k.y * sx * sy)
    }
}

impl Field for Heightfield {
    fn value(&self, p: Vec3) -> f32 {
        sigma(self.h.height(p.truncate()) - p.z, self.falloff)
    }
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let (v, s) = sigma_d(self.h.height(p.truncate()) - p.z, self.falloff);
        let g = self.grad_h(p.truncate());
        (v, s * Vec3::new(g.x, g.y, -1.0))
    }
    fn support(&self) -> Aabb {
        self.domain
    }
    fn interval(&self, b: &Aabb) -> Interval {
        let h = self.h.range(&b.footprint());
        sigma_interval(Interval::new(h.lo - b.max.z, h.hi - b.min.z), self.falloff)
    }
    fn lipschitz(&self) -> f32 {
        sigma_max_slope(self.falloff) * (1.0 + self.h.lipschitz())
    }
    fn lipschitz_box(&self, _b: &Aabb) -> f32 {
        self.lipschitz()
    }
    fn z_bands(&self, fp: &Rect, z: Interval, out: &mut ZBands) {
        out.push(self.h.range(fp).intersect(z));
    }
    fn elevation(&self, _fp: &Rect) -> Option<Elevation<'_>> {
        Some(Elevation {
            source: &self.h,
            z: Interval::new(-1e6, 1e6),
        })
    }
}

/// A heightfield carved by spherical caves: `hf(p) − Σ g(|p − c_i| / R_i)`. It answers
/// `elevation()` only over footprints no cave reaches.
pub struct CavedTerrain {
    pub ground: Heightfield,
    pub caves: Vec<(Vec3, f32)>,
}

impl CavedTerrain {
    fn cave_boxes<'s>(&'s self, fp: &'s Rect) -> impl Iterator<Item = Aabb> + 's {
        self.caves
            .iter()
            .map(|&(c, r)| Aabb::around(c, r))
            .filter(move |b| b.footprint().overlaps(fp))
    }
}

impl Field for CavedTerrain {
    fn value(&self, p: Vec3) -> f32 {
        self.caves.iter().fold(self.ground.value(p), |v, &(c, r)| {
            v - wyvill((p - c).length() / r)
        })
    }
    fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        self.caves
            .iter()
            .fold(self.ground.value_grad(p), |(v, g), &(c, r)| {
                let d = p - c;
                let l = d.length();
                let (w, dw) = wyvill_d(l / r);
                (v - w, if l > 0.0 { g - dw / r * d / l } else { g })
            })
    }
    fn support(&self) -> Aabb {
        self.ground.support()
    }
    fn interval(&self, b: &Aabb) -> Interval {
        self.caves
            .iter()
            .fold(self.ground.interval(b), |acc, &(c, r)| {
                let d = dist_range(b, c);
                acc + wyvill_interval(Interval::new(d.lo / r, d.hi / r)).scale(-1.0)
            })
    }
    fn lipschitz(&self) -> f32 {
        self.ground.lipschitz()
            + self
                .caves
                .iter()
                .map(|&(_, r)| WYVILL_MAX_SLOPE / r)
                .sum::<f32>()
    }
    fn lipschitz_box(&self, _b: &Aabb) -> f32 {
        self.lipschitz()
    }
    fn z_bands(&self, fp: &Rect, z: Interval, out: &mut ZBands) {
        self.ground.z_bands(fp, z, out);
        for b in self.cave_boxes(fp) {
            out.push(b.z().intersect(z));
        }
    }
    fn elevation(&self, fp: &Rect) -> Option<Elevation<'_>> {
        if self.cave_boxes(fp).next().is_some() {
            None
        } else {
            self.ground.elevation(fp)
        }
    }
}

/// The standard test sphere: radius 1 at the origin.
pub fn unit_sphere() -> Sphere {
    Sphere {
        c: Vec3::ZERO,
        r: 1.0,
        falloff: 0.5,
    }
}

/// A 400 m × 400 m hilly terrain with `n` caves under its surface.
pub fn caved_terrain(n: usize) -> CavedTerrain {
    let ground = Heightfield {
        h: Hills {
            base: 20.0,
            a: 12.0,
            k: Vec2::new(0.021, 0.017),
            slope: 0.05,
        },
        falloff: 4.0,
        domain: Aabb::new(Vec3::new(0.0, 0.0, -40.0), Vec3::new(400.0, 400.0, 80.0)),
    };
    let caves = (0..n)
        .map(|i| {
            let x = 40.0 + (i as f32 * 97.0) % 320.0;
            let y = 40.0 + (i as f32 * 61.0 + 30.0) % 320.0;
            let z = ground.h.height(Vec2::new(x, y)) - 2.0;
            (Vec3::new(x, y, z), 9.0 + (i % 3) as f32 * 3.0)
        })
        .collect();
    CavedTerrain { ground, caves }
}

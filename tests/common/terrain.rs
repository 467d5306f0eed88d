//! A heightfield-like terrain chunk `min(σ(h(x, y) − z), σ(−d_box))`.

use glam::{Vec2, Vec3};
use karstic::field::falloff::{sigma, sigma_max_slope, sigma_slope};
use karstic::field::{Aabb, Field, ISO, Interval};

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
        Interval::new(0.0, 2.0 * ISO)
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

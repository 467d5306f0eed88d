//! A σ-sphere: a field with an analytic ground truth for the tracers.

use glam::Vec3;
use karstic::field::falloff::{sigma, sigma_d, sigma_interval, sigma_max_slope, sigma_slope};
use karstic::field::{Aabb, Field, Interval};

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

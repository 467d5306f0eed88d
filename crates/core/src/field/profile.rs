//! A point blob seen along a line: the one-dimensional polynomial that segment tracing
//! evaluates and bounds (Galin et al. 2020 §4).
//!
//! Along `o + t·d`, the squared distance to the centre `c` is `|d|²(t − t_c)² + h²`, with
//! `t_c` the foot of the perpendicular and `h` the clearance. In the normalized abscissa
//! `w = (t − t_c)|d|/R`, Wyvill's falloff is `E·(k − w²)³` where positive, `k = 1 − h²/R²`:
//! no square root per evaluation. Its slope `|dg/dw| = 6|w|(k − w²)²` is zero at the foot,
//! peaks at `|w| = √(k/5)` with `k^{5/2}·max|g'|`, and falls to zero where the line leaves
//! the support (`w² = k`): the directional derivative, which segment tracing bounds, is
//! much smaller than the gradient's norm for a line passing beside the blob (half of it at
//! half the radius).

use glam::Vec3;

use super::falloff::{WYVILL_MAX_SLOPE, WYVILL_PEAK_X};

/// `E·g(|p − c| / R)` restricted to the line `o + t·d`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineProfile {
    /// `t_c`, the parameter of the foot of the perpendicular from the centre.
    foot: f32,
    /// `|d| / R`: `w = (t − t_c)·scale`.
    scale: f32,
    /// `1 − h²/R²`: the line meets the support where `k > 0`.
    k: f32,
    /// `√k` (0 when `k < 0`): the slope peaks at `|w| = √(k/5)`.
    sqrt_k: f32,
    /// `|E|/R · k^{5/2}·max|g'|`, the peak slope per unit of arc length.
    peak: f32,
    energy: f32,
    inv_radius: f32,
}

impl LineProfile {
    /// The blob of centre `c`, radius `1 / inv_radius` and energy `e` along `o + t·d`
    /// (`d ≠ 0`).
    #[inline]
    pub fn new(c: Vec3, inv_radius: f32, e: f32, o: Vec3, d: Vec3) -> Self {
        let co = c - o;
        let d2 = d.length_squared();
        let foot = co.dot(d) / d2;
        let k = 1.0 - (co - d * foot).length_squared() * inv_radius * inv_radius;
        let sk = k.max(0.0).sqrt();
        LineProfile {
            foot,
            scale: d2.sqrt() * inv_radius,
            k,
            sqrt_k: sk,
            peak: e.abs() * inv_radius * WYVILL_MAX_SLOPE * k * k * sk,
            energy: e,
            inv_radius,
        }
    }

    /// The parameter range where the field is non-zero along the line (`w² < k`), or
    /// `None` when the line misses the support ball.
    #[inline]
    pub fn reach(&self) -> Option<(f32, f32)> {
        (self.k > 0.0).then(|| {
            let half = self.sqrt_k / self.scale;
            (self.foot - half, self.foot + half)
        })
    }

    /// The field at parameter `t`.
    #[inline]
    pub fn value(&self, t: f32) -> f32 {
        let w = (t - self.foot) * self.scale;
        let u = (self.k - w * w).max(0.0);
        self.energy * u * u * u
    }

    /// The largest `|∂f/∂s|` over `t ∈ [t0, t1]` (`t0 ≤ t1`), `s` the arc length along
    /// the line: a Lipschitz bound of the field on that segment, exact up to rounding.
    #[inline]
    pub fn lipschitz(&self, t0: f32, t1: f32) -> f32 {
        if self.k <= 0.0 {
            return 0.0;
        }
        let (w0, w1) = ((t0 - self.foot) * self.scale, (t1 - self.foot) * self.scale);
        // The range of |w| over the segment.
        let (lo, hi) = if w0 <= 0.0 && 0.0 <= w1 {
            (0.0, (-w0).max(w1))
        } else {
            (w0.abs().min(w1.abs()), w0.abs().max(w1.abs()))
        };
        let peak_w = self.sqrt_k * WYVILL_PEAK_X;
        if lo <= peak_w && peak_w <= hi {
            return self.peak;
        }
        let slope = |w: f32| {
            let s = (self.k - w * w).max(0.0);
            6.0 * w * s * s
        };
        self.energy.abs() * self.inv_radius * slope(lo).max(slope(hi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::falloff::wyvill;

    /// Along lines at every clearance, the bound is the largest slope over the segment
    /// (finite differences, within rounding, and never 1% looser), and never above the
    /// gradient's bound.
    #[test]
    fn line_slope_is_the_directional_maximum() {
        let (r, e) = (2.0, 1.5);
        for ih in 0..12 {
            let h = ih as f32 * 0.09 * r;
            let c = Vec3::new(0.3, h, -0.2);
            let p = LineProfile::new(c, 1.0 / r, e, Vec3::new(-5.0, 0.0, -0.2), Vec3::X);
            let f = |t: f32| e * wyvill((Vec3::new(-5.0 + t, 0.0, -0.2) - c).length() / r);
            for (t0, t1) in [(0.0, 10.0), (5.3, 5.5), (5.6, 6.0), (6.2, 7.2), (8.5, 9.5)] {
                let n = 4000;
                let mut best = 0.0f32;
                for i in 0..=n {
                    let t = t0 + (t1 - t0) * i as f32 / n as f32;
                    let dt = 1e-3;
                    best = best.max((f(t + dt) - f(t - dt)).abs() / (2.0 * dt));
                    assert!((p.value(t) - f(t)).abs() < 1e-5, "value at {t}");
                }
                let s = p.lipschitz(t0, t1);
                assert!(best <= s * 1.001 + 1e-4, "h {h} [{t0}, {t1}]: {best} > {s}");
                assert!(
                    s <= best * 1.01 + 1e-3,
                    "h {h} [{t0}, {t1}]: {s} loose vs {best}"
                );
                assert!(s <= e / r * WYVILL_MAX_SLOPE * 1.000_01);
            }
        }
    }
}

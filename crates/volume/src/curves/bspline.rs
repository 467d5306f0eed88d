//! Cubic B-splines with end-point interpolation (Becher 2016, definition 3.1.1).
//!
//! The knot vector is clamped (multiplicity `n + 1` at both ends) and uniform inside, so
//! the curve starts at the first control vertex and ends at the last. The parameter runs
//! over `[0, 1]`. With fewer than four control vertices the degree drops to
//! `vertices − 1` (two vertices give a segment, three a parabola).

use glam::Vec3;

/// A clamped uniform B-spline of degree `min(3, m)` through `m + 1 ≥ 2` control vertices.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BSpline {
    ctrl: Vec<Vec3>,
    knots: Vec<f32>,
    degree: usize,
}

/// Offset in parameter space of the finite-difference tangent (§3.1).
const TANGENT_EPS: f32 = 1e-3;

impl BSpline {
    /// The spline through `ctrl`; `None` with fewer than two vertices.
    pub fn new(ctrl: Vec<Vec3>) -> Option<Self> {
        if ctrl.len() < 2 {
            return None;
        }
        let degree = (ctrl.len() - 1).min(3);
        let m = ctrl.len() - 1;
        // m + degree + 2 knots: degree + 1 zeros, the inner ones, degree + 1 ones.
        let inner = m - degree; // number of inner knots
        let mut knots = vec![0.0; degree + 1];
        for i in 1..=inner {
            knots.push(i as f32 / (inner + 1) as f32);
        }
        knots.extend(std::iter::repeat_n(1.0, degree + 1));
        Some(BSpline {
            ctrl,
            knots,
            degree,
        })
    }

    /// The control vertices.
    pub fn control(&self) -> &[Vec3] {
        &self.ctrl
    }

    /// The degree (3 unless there are fewer than four vertices).
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// `B(t)` for `t` in `[0, 1]` (clamped), by de Boor's algorithm.
    pub fn eval(&self, t: f32) -> Vec3 {
        let p = self.degree;
        let t = t.clamp(0.0, 1.0);
        // Knot span k with knots[k] <= t < knots[k + 1], the last span for t = 1.
        let last = self.ctrl.len() - 1;
        let k = if t >= 1.0 {
            last
        } else {
            (self.knots.partition_point(|&u| u <= t) - 1).clamp(p, last)
        };
        let mut d = [Vec3::ZERO; 4];
        for (j, dj) in d.iter_mut().enumerate().take(p + 1) {
            *dj = self.ctrl[j + k - p];
        }
        for r in 1..=p {
            for j in (r..=p).rev() {
                let i = j + k - p;
                let den = self.knots[i + 1 + p - r] - self.knots[i];
                let a = if den > 0.0 {
                    (t - self.knots[i]) / den
                } else {
                    0.0
                };
                d[j] = d[j - 1] * (1.0 - a) + d[j] * a;
            }
        }
        d[p]
    }

    /// The unit tangent by the central difference of §3.1 (one-sided at the ends).
    /// Falls back to the chord direction where the curve stalls.
    pub fn tangent(&self, t: f32) -> Vec3 {
        let a = (t - TANGENT_EPS).max(0.0);
        let b = (t + TANGENT_EPS).min(1.0);
        let d = self.eval(b) - self.eval(a);
        if d.length_squared() > 1e-14 {
            return d.normalize();
        }
        (self.ctrl[self.ctrl.len() - 1] - self.ctrl[0]).normalize_or(Vec3::X)
    }

    /// Polyline length with `n` segments (an estimate of the arc length).
    pub fn length(&self, n: usize) -> f32 {
        let n = n.max(1);
        (0..n)
            .map(|i| {
                (self.eval((i + 1) as f32 / n as f32) - self.eval(i as f32 / n as f32)).length()
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_end_points_and_degenerates_gracefully() {
        let c = vec![
            Vec3::ZERO,
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(3.0, 2.0, 1.0),
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(6.0, 1.0, 2.0),
        ];
        let s = BSpline::new(c.clone()).unwrap();
        assert_eq!(s.degree(), 3);
        assert!((s.eval(0.0) - c[0]).length() < 1e-6);
        assert!((s.eval(1.0) - c[4]).length() < 1e-6);
        // The curve lies in the convex hull: every coordinate within the control range.
        for i in 0..=100 {
            let p = s.eval(i as f32 / 100.0);
            assert!(p.x >= -1e-5 && p.x <= 6.0 + 1e-5 && p.y >= -1e-5 && p.y <= 2.0 + 1e-5);
        }
        let line = BSpline::new(vec![Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0)]).unwrap();
        assert!((line.eval(0.25) - Vec3::new(0.5, 0.0, 0.0)).length() < 1e-6);
        assert!((line.tangent(0.5) - Vec3::X).length() < 1e-5);
        assert!(BSpline::new(vec![Vec3::ZERO]).is_none());
    }

    #[test]
    fn cubic_reproduces_a_straight_line_uniformly() {
        // Collinear, evenly spaced control vertices: a clamped cubic stays on the line and its
        // ends interpolate; the tangent is the line direction everywhere.
        let c: Vec<Vec3> = (0..6).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
        let s = BSpline::new(c).unwrap();
        for i in 0..=50 {
            let t = i as f32 / 50.0;
            let p = s.eval(t);
            assert!(p.y.abs() < 1e-6 && p.z.abs() < 1e-6);
            assert!((s.tangent(t) - Vec3::X).length() < 1e-4);
        }
        // Monotone in t.
        let xs: Vec<f32> = (0..=50).map(|i| s.eval(i as f32 / 50.0).x).collect();
        assert!(xs.windows(2).all(|w| w[1] >= w[0]));
    }
}

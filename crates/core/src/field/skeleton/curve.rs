//! Flattening of the curve skeleton: a centripetal Catmull-Rom spline through the
//! control points (Barry–Goldman evaluation), cut into [`SEGMENTS_PER_SPAN`] segments per
//! span at compile time. The skeleton *is* that polyline, so its distance is exact (and
//! 1-Lipschitz); it differs from the spline by the chord error of the flattening.
//!
//! Centripetal parametrisation (knot gaps `‖Pᵢ₊₁ − Pᵢ‖^½`) never makes cusps or loops
//! inside a span, unlike the uniform one, whatever the spacing of the control points.
//! The end tangents come from mirrored phantom points `2P₀ − P₁` and `2Pₙ − Pₙ₋₁`.

use glam::Vec3;

/// Segments each span between two control points is cut into.
pub const SEGMENTS_PER_SPAN: usize = 16;

/// The flattened spline through `control` (consecutive duplicates dropped): the first
/// point, then [`SEGMENTS_PER_SPAN`] points per span, the last being the next control
/// point.
pub fn catmull_rom(control: &[Vec3]) -> Vec<Vec3> {
    let mut pts: Vec<Vec3> = Vec::with_capacity(control.len());
    for &p in control {
        if pts.last() != Some(&p) {
            pts.push(p);
        }
    }
    if pts.len() < 3 {
        return pts;
    }
    let n = pts.len();
    let at = |i: isize| -> Vec3 {
        if i < 0 {
            2.0 * pts[0] - pts[1]
        } else if i as usize >= n {
            2.0 * pts[n - 1] - pts[n - 2]
        } else {
            pts[i as usize]
        }
    };
    let mut out = Vec::with_capacity((n - 1) * SEGMENTS_PER_SPAN + 1);
    out.push(pts[0]);
    for i in 0..n as isize - 1 {
        let p = [at(i - 1), at(i), at(i + 1), at(i + 2)];
        let mut t = [0.0f32; 4];
        for k in 1..4 {
            t[k] = t[k - 1] + (p[k] - p[k - 1]).length().sqrt();
        }
        for s in 1..=SEGMENTS_PER_SPAN {
            let u = t[1] + (t[2] - t[1]) * s as f32 / SEGMENTS_PER_SPAN as f32;
            out.push(if s == SEGMENTS_PER_SPAN {
                p[2]
            } else {
                barry_goldman(&p, &t, u)
            });
        }
    }
    out
}

/// The Barry–Goldman pyramid: the Catmull-Rom point at knot value `u ∈ [t₁, t₂]`.
fn barry_goldman(p: &[Vec3; 4], t: &[f32; 4], u: f32) -> Vec3 {
    let lerp = |a: Vec3, b: Vec3, t0: f32, t1: f32| {
        a * ((t1 - u) / (t1 - t0)) + b * ((u - t0) / (t1 - t0))
    };
    let a1 = lerp(p[0], p[1], t[0], t[1]);
    let a2 = lerp(p[1], p[2], t[1], t[2]);
    let a3 = lerp(p[2], p[3], t[2], t[3]);
    let b1 = lerp(a1, a2, t[0], t[2]);
    let b2 = lerp(a2, a3, t[1], t[3]);
    lerp(b1, b2, t[1], t[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_through_its_control_points_smoothly() {
        let c = [
            Vec3::ZERO,
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(10.0, 1.0, 0.0),
            Vec3::new(20.0, 5.0, 3.0),
        ];
        let pts = catmull_rom(&c);
        assert_eq!(pts.len(), 3 * SEGMENTS_PER_SPAN + 1);
        for (i, cp) in c.iter().enumerate() {
            assert_eq!(pts[i * SEGMENTS_PER_SPAN], *cp);
        }
        // No segment longer than the span it belongs to (no loops or overshoot blow-up),
        // and turning angles between consecutive segments stay below 60°.
        for w in pts.windows(3) {
            let (a, b) = ((w[1] - w[0]).normalize(), (w[2] - w[1]).normalize());
            assert!(a.dot(b) > 0.5, "sharp turn {a} {b}");
        }
        assert_eq!(
            catmull_rom(&[Vec3::ZERO, Vec3::ZERO, Vec3::X]),
            vec![Vec3::ZERO, Vec3::X]
        );
    }
}

//! Constraint Points and Feature Curves (Becher 2016, definitions 3.1.2 and 3.1.3).
//!
//! A Feature Curve is a B-spline with Constraint Points `(b_l, b_r, α, β, t)` attached.
//! Between two Constraint Points the noise parameters are interpolated linearly in `t`;
//! the bitangents are first carried along the curve by the rotation that maps the
//! Constraint Point's tangent onto the tangent at `t` (so they follow the curve's shape),
//! then blended linearly and projected back onto the plane normal to the tangent (§3.1).
//! Where the two tangents are nearly opposite the rotation is not unique; the reference
//! point is then moved towards `t` in steps (the thesis's fix), which composes small,
//! well-defined rotations.
//!
//! Surface normals follow from the bitangents and the tangent `v`:
//! `n_left = v × b_l`, `n_right = b_r × v`. With `z` up and a curve running along `+x`,
//! the left side is `+y`, and two horizontal bitangents give an upward normal on both
//! sides: normals point *out of the solid, into the air*.

use glam::{Quat, Vec2, Vec3};

use super::bspline::BSpline;

/// A Constraint Point (definition 3.1.2): bitangents to both sides, noise amplitude and
/// roughness, and its position `t` on the curve.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ConstraintPoint {
    /// Curve parameter in `[0, 1]`.
    pub t: f32,
    /// Left-hand bitangent (unit, perpendicular to the tangent at `t`).
    pub left: Vec3,
    /// Right-hand bitangent.
    pub right: Vec3,
    /// Noise amplitude `α` (metres).
    pub amplitude: f32,
    /// Noise roughness `β`: the noise's base frequency (1/m).
    pub roughness: f32,
}

/// The attributes of a Feature Curve at one parameter value.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct CurveSample {
    /// `B(t)`.
    pub pos: Vec3,
    /// Unit tangent.
    pub tangent: Vec3,
    /// Interpolated left bitangent (unit, ⟂ tangent).
    pub left: Vec3,
    /// Interpolated right bitangent.
    pub right: Vec3,
    /// `(α, β)`.
    pub noise: Vec2,
}

impl CurveSample {
    /// Surface normal of the left ribbon, `v × b_l`.
    pub fn left_normal(&self) -> Vec3 {
        self.tangent.cross(self.left).normalize_or_zero()
    }

    /// Surface normal of the right ribbon, `b_r × v`.
    pub fn right_normal(&self) -> Vec3 {
        self.right.cross(self.tangent).normalize_or_zero()
    }
}

/// A Feature Curve (definition 3.1.3): spline, Constraint Points, seed flag.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FeatureCurve {
    /// The shape.
    pub spline: BSpline,
    /// Constraint Points sorted by `t` (at least one).
    pub constraints: Vec<ConstraintPoint>,
    /// A seed curve puts the surface through itself; a guidance curve only steers normals.
    pub seed: bool,
    /// Ribbon width in metres, when set; the pipeline's default otherwise.
    pub ribbon: Option<f32>,
}

/// Beyond this angle between two tangents the direct rotation is ambiguous (§3.1).
const MAX_DIRECT_ANGLE: f32 = 150.0 * std::f32::consts::PI / 180.0;

impl FeatureCurve {
    /// The curve's attributes at `t` (clamped to `[0, 1]`).
    pub fn sample(&self, t: f32) -> CurveSample {
        let t = t.clamp(0.0, 1.0);
        let v = self.spline.tangent(t);
        let cs = &self.constraints;
        let i = cs.partition_point(|c| c.t <= t);
        let (p0, p1, a) = if i == 0 {
            (cs[0], cs[0], 0.0)
        } else if i == cs.len() {
            (cs[i - 1], cs[i - 1], 0.0)
        } else {
            let (p0, p1) = (cs[i - 1], cs[i]);
            let span = p1.t - p0.t;
            (p0, p1, if span > 0.0 { (t - p0.t) / span } else { 0.0 })
        };
        let carry = |b: Vec3, from: f32| self.transport(b, from, t);
        let blend = |b0: Vec3, b1: Vec3| {
            let b = carry(b0, p0.t) * (1.0 - a) + carry(b1, p1.t) * a;
            reproject(b, v)
        };
        CurveSample {
            pos: self.spline.eval(t),
            tangent: v,
            left: blend(p0.left, p1.left),
            right: blend(p0.right, p1.right),
            noise: Vec2::new(p0.amplitude, p0.roughness)
                .lerp(Vec2::new(p1.amplitude, p1.roughness), a),
        }
    }

    /// Carries `b` from parameter `from` to `to` by the rotation mapping the tangents.
    fn transport(&self, b: Vec3, from: f32, to: f32) -> Vec3 {
        self.transport_rec(b, from, to, 12)
    }

    fn transport_rec(&self, b: Vec3, from: f32, to: f32, depth: u32) -> Vec3 {
        let (v0, v1) = (self.spline.tangent(from), self.spline.tangent(to));
        if v0.dot(v1).clamp(-1.0, 1.0).acos() <= MAX_DIRECT_ANGLE || depth == 0 {
            return Quat::from_rotation_arc(v0, v1) * b;
        }
        // Move the reference point half-way towards `to` and go on from there.
        let mid = 0.5 * (from + to);
        let b_mid = self.transport_rec(b, from, mid, depth - 1);
        self.transport_rec(b_mid, mid, to, depth - 1)
    }
}

/// The bitangent of a slope: the horizontal direction perpendicular to the tangent on
/// that side (`left = ẑ × v`, `right = −left`), turned downward by `degrees` about the
/// tangent. 0° is flat, 90° points straight down (a cliff face), more than 90° tucks under
/// (an overhang), 180° folds back over the curve (a ceiling), −90° points straight up.
/// `None` when the tangent is vertical (the horizontal direction is undefined).
pub fn slope_bitangent(tangent: Vec3, left: bool, degrees: f32) -> Option<Vec3> {
    let side = Vec3::Z.cross(tangent);
    if side.length_squared() < 1e-6 {
        return None;
    }
    let l = side.normalize();
    let up = tangent.cross(l).normalize();
    let h = if left { l } else { -l };
    let a = degrees.to_radians();
    Some(h * a.cos() - up * a.sin())
}

/// `b` projected onto the plane normal to the unit vector `v`, normalised; any
/// perpendicular unit vector when `b` is (nearly) parallel to `v`.
pub fn reproject(b: Vec3, v: Vec3) -> Vec3 {
    let p = b - v * v.dot(b);
    if p.length_squared() > 1e-12 {
        p.normalize()
    } else {
        v.any_orthonormal_vector()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cp(t: f32, left: Vec3, right: Vec3) -> ConstraintPoint {
        ConstraintPoint {
            t,
            left,
            right,
            amplitude: t,
            roughness: 1.0,
        }
    }

    #[test]
    fn bitangents_follow_the_curve_and_stay_perpendicular() {
        // A quarter circle in the xy plane; constraint bitangents pointing up at both ends.
        let spline = BSpline::new(vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(5.0, 0.0, 0.0),
            Vec3::new(10.0, 5.0, 0.0),
            Vec3::new(10.0, 10.0, 0.0),
        ])
        .unwrap();
        let left = Vec3::new(0.0, 1.0, 0.0);
        let curve = FeatureCurve {
            spline,
            constraints: vec![
                cp(0.0, left, -left),
                cp(1.0, Vec3::new(-1.0, 0.0, 0.0), Vec3::X),
            ],
            seed: true,
            ribbon: None,
        };
        for i in 0..=20 {
            let s = curve.sample(i as f32 / 20.0);
            assert!(s.left.dot(s.tangent).abs() < 1e-4 && s.right.dot(s.tangent).abs() < 1e-4);
            assert!((s.left.length() - 1.0).abs() < 1e-4);
            // Horizontal left bitangents on a horizontal curve: the normal is +z all along.
            assert!(s.left_normal().z > 0.999, "{s:?}");
            assert!(s.right_normal().z > 0.999, "{s:?}");
            assert!((s.noise.x - i as f32 / 20.0).abs() < 1e-5);
        }
    }

    #[test]
    fn slopes_give_the_documented_normals() {
        let v = Vec3::X;
        let s = |l: f32, r: f32| CurveSample {
            pos: Vec3::ZERO,
            tangent: v,
            left: slope_bitangent(v, true, l).unwrap(),
            right: slope_bitangent(v, false, r).unwrap(),
            noise: Vec2::ZERO,
        };
        let flat = s(0.0, 0.0);
        assert!(
            (flat.left - Vec3::Y).length() < 1e-6 && (flat.left_normal() - Vec3::Z).length() < 1e-6
        );
        assert!((flat.right_normal() - Vec3::Z).length() < 1e-6);
        let cliff = s(0.0, 90.0);
        assert!((cliff.right - -Vec3::Z).length() < 1e-6);
        assert!(
            (cliff.right_normal() - -Vec3::Y).length() < 1e-6,
            "the face looks out to the right"
        );
        let ceiling = s(180.0, 180.0);
        assert!((ceiling.left_normal() - -Vec3::Z).length() < 1e-6);
        assert!((ceiling.right_normal() - -Vec3::Z).length() < 1e-6);
        let over = s(0.0, 110.0);
        assert!(
            over.right_normal().z < -0.3,
            "an overhanging face looks down"
        );
        assert!(slope_bitangent(Vec3::Z, true, 0.0).is_none());
    }

    #[test]
    fn near_180_degree_turn_is_unambiguous() {
        // A hairpin: the tangent turns by ~180° between the two Constraint Points. The
        // left bitangent is +z at the start, so carried along it must stay +z (the turn is
        // about z); a direct rotation between opposite tangents could pick any axis.
        let spline = BSpline::new(vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(10.0, 4.0, 0.0),
            Vec3::new(0.0, 4.0, 0.0),
        ])
        .unwrap();
        let curve = FeatureCurve {
            spline,
            constraints: vec![cp(0.0, Vec3::Z, -Vec3::Z)],
            seed: true,
            ribbon: None,
        };
        let end = curve.sample(1.0);
        assert!(end.tangent.x < -0.9);
        assert!(end.left.z > 0.99, "{end:?}");
        assert!(end.right.z < -0.99, "{end:?}");
    }
}

//! Compound primitives that place several Feature Curves themselves (Becher (thesis)
//! §7.2), built on one shape, a [`Tube`]: Feature Curves around a path, on an elliptic
//! section of varying width and height, with normals into the tube (a tunnel: the air is
//! inside) or out of it (an arch's beam: the rock is inside).
//!
//! * A tunnel is a tube with inward normals; tunnels sharing a node branch (each
//!   tunnel's curves leave out the parts inside the others).
//! * A natural arch is a rock slab: a tube with outward normals along an arc from foot to
//!   foot, wider than thick, thinnest at the crown and thickening towards the abutments,
//!   and optionally (the thesis's Figure 7.6) a ground curve under the apex.
//!
//! On a terrain (a Feature Volume with terrain boundary conditions) the compounds keep
//! only what is on their side of the ground: a tunnel its underground part, an arch its
//! part above ground; the terrain's own samples fill in the rest (see
//! [`super::terrain`]).

use glam::{Vec2, Vec3};

use super::bspline::BSpline;
use super::constraint::{ConstraintPoint, FeatureCurve};
use super::ribbon::{ProxyMesh, curve_ribbon};

/// A piecewise-linear profile over the path parameter `t ∈ [0, 1]`: `(t, value)` keys
/// sorted by `t`, held constant beyond the first and last key.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Profile(pub Vec<(f32, f32)>);

impl Profile {
    /// A constant profile.
    pub fn constant(v: f32) -> Self {
        Profile(vec![(0.0, v)])
    }

    /// The value at `t`.
    pub fn at(&self, t: f32) -> f32 {
        let k = &self.0;
        let i = k.partition_point(|&(kt, _)| kt <= t);
        if i == 0 {
            k[0].1
        } else if i == k.len() {
            k[i - 1].1
        } else {
            let ((t0, v0), (t1, v1)) = (k[i - 1], k[i]);
            v0 + (v1 - v0) * ((t - t0) / (t1 - t0).max(1e-9))
        }
    }

    /// The largest value.
    pub fn max(&self) -> f32 {
        self.0.iter().map(|k| k.1).fold(f32::MIN, f32::max)
    }

    /// The smallest value.
    pub fn min(&self) -> f32 {
        self.0.iter().map(|k| k.1).fold(f32::MAX, f32::min)
    }
}

/// Curves placed around a tube's section: every eighth of a turn, so the section is
/// round rather than the diamond four curves leave between them.
const CURVES_AROUND: usize = 8;

/// Feature Curves around `path` on an elliptic section `width × height`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Tube {
    /// The axis.
    pub path: BSpline,
    /// Full width (metres) along the path, horizontal.
    pub width: Profile,
    /// Full height (metres) along the path, perpendicular to it in the vertical plane.
    pub height: Profile,
    /// Noise `(α, β)` on the tube's surface.
    pub noise: Vec2,
    /// Normals into the tube (air inside: a tunnel) or out of it (rock inside).
    pub inward: bool,
}

/// A tunnel: a tube with the air inside.
pub type Tunnel = Tube;

/// The local frame of a path: tangent, horizontal left, up (perpendicular to the tangent).
fn frame(path: &BSpline, t: f32) -> (Vec3, Vec3, Vec3) {
    let v = path.tangent(t);
    let l = Vec3::Z.cross(v).normalize_or(v.any_orthonormal_vector());
    (v, l, v.cross(l))
}

/// Number of sections placed along a path: enough to follow its bends.
fn sections(path: &BSpline, spacing: f32) -> usize {
    ((path.length(64) / spacing).ceil() as usize).clamp(4 * path.control().len(), 4096)
}

/// A curve through `points` (as control vertices) with one Constraint Point per point.
fn curve_through(points: Vec<Vec3>, bitangents: Vec<(Vec3, Vec3)>, noise: Vec2) -> FeatureCurve {
    let n = points.len();
    let constraints = bitangents
        .into_iter()
        .enumerate()
        .map(|(i, (left, right))| ConstraintPoint {
            t: i as f32 / (n - 1) as f32,
            left,
            right,
            amplitude: noise.x,
            roughness: noise.y,
        })
        .collect();
    FeatureCurve {
        spline: BSpline::new(points).expect("at least two sections"),
        constraints,
        seed: true,
        ribbon: None,
    }
}

impl Tube {
    /// The curves around the tube, starting at the floor (the bottom of the section) and
    /// turning through the left side. Sections every eighth of the smaller of width and
    /// height become their control vertices. Each curve's ribbons lie along the section's
    /// outline, its normal is the outline's (into or out of the tube).
    pub fn curves(&self) -> [FeatureCurve; CURVES_AROUND] {
        let spacing = 0.125 * self.width.max().min(self.height.max());
        let n = sections(&self.path, spacing);
        let mut pts: [Vec<Vec3>; CURVES_AROUND] = Default::default();
        let mut bts: [Vec<(Vec3, Vec3)>; CURVES_AROUND] = Default::default();
        for i in 0..=n {
            let t = i as f32 / n as f32;
            let p = self.path.eval(t);
            let (v, l, u) = frame(&self.path, t);
            let (hw, hh) = (0.5 * self.width.at(t), 0.5 * self.height.at(t));
            for k in 0..CURVES_AROUND {
                let a = std::f32::consts::TAU * k as f32 / CURVES_AROUND as f32
                    - std::f32::consts::FRAC_PI_2;
                let (s, c) = a.sin_cos();
                let q = p + l * (hw * c) + u * (hh * s);
                let out = (l * (c / hw) + u * (s / hh)).normalize();
                let n = if self.inward { -out } else { out };
                // Normals: left `v × b_l`, right `b_r × v`; so `b_l = n × v`, `b_r = −b_l`.
                let b = n.cross(v).normalize();
                pts[k].push(q);
                bts[k].push((b, -b));
            }
        }
        let mut it = pts.into_iter().zip(bts);
        std::array::from_fn(|_| {
            let (p, b) = it.next().expect("a curve per angle");
            curve_through(p, b, self.noise)
        })
    }

    /// The smallest width or height along the path.
    pub fn section(&self) -> f32 {
        self.width.min().min(self.height.min())
    }

    /// The parameter of the path point nearest `p` (by sampling).
    fn nearest_t(&self, p: Vec3) -> f32 {
        let n = 128;
        let (mut best, mut best_t) = (f32::INFINITY, 0.0);
        for i in 0..=n {
            let t = i as f32 / n as f32;
            let d = self.path.eval(t).distance_squared(p);
            if d < best {
                (best, best_t) = (d, t);
            }
        }
        best_t
    }

    /// True when `p` lies inside the tube grown by `margin`.
    pub fn contains(&self, p: Vec3, margin: f32) -> bool {
        let t = self.nearest_t(p);
        let (v, l, u) = frame(&self.path, t);
        let d = p - self.path.eval(t);
        let along_ok = (t > 0.0 && t < 1.0) || d.dot(v).abs() < margin;
        let a = d.dot(l) / (0.5 * self.width.at(t) + margin);
        let b = d.dot(u) / (0.5 * self.height.at(t) + margin);
        along_ok && a * a + b * b < 1.0
    }

    /// Samples of the axis every `step` metres with the section's half-size there:
    /// `(point, radius)` balls that cover the tube.
    pub fn balls(&self, step: f32) -> Vec<(Vec3, f32)> {
        let n = ((self.path.length(64) / step).ceil() as usize).clamp(1, 1 << 16);
        (0..=n)
            .map(|i| {
                let t = i as f32 / n as f32;
                let r = 0.5 * self.width.at(t).max(self.height.at(t));
                (self.path.eval(t), r)
            })
            .collect()
    }
}

/// True when `p` is outside every tunnel of `tunnels` but the `i`-th (grown by `margin`):
/// where tunnel `i`'s curves are kept, so that branches open into each other.
pub fn outside_others(tunnels: &[Tube], i: usize, p: Vec3, margin: f32) -> bool {
    !tunnels
        .iter()
        .enumerate()
        .any(|(j, t)| j != i && t.contains(p, margin))
}

/// The ribbon width used for a tube: no wider than a quarter of its section, so the
/// ribbons around it do not cross.
pub fn tube_ribbon(tube: &Tube, ribbon: f32) -> f32 {
    ribbon.min(0.25 * tube.width.max().min(tube.height.max()))
}

/// The proxy meshes of a set of tunnels: each tunnel's curves leave out the segments
/// inside the other tunnels, so tunnels sharing a node open into each other, and those
/// where `keep` fails. Ribbons and guidance extensions are capped at a quarter of the
/// section.
pub fn tunnel_proxies(
    tunnels: &[Tube],
    ribbon: f32,
    guide: f32,
    segment: f32,
    keep: &dyn Fn(Vec3) -> bool,
) -> ProxyMesh {
    let mut mesh = ProxyMesh::default();
    for (i, tunnel) in tunnels.iter().enumerate() {
        let keep = |p: Vec3| keep(p) && outside_others(tunnels, i, p, ribbon);
        mesh.append(&tube_proxy(tunnel, ribbon, guide, segment, &keep));
    }
    mesh
}

/// The proxy mesh of one tube's curves, segments failing `keep` left out.
pub fn tube_proxy(
    tube: &Tube,
    ribbon: f32,
    guide: f32,
    segment: f32,
    keep: &dyn Fn(Vec3) -> bool,
) -> ProxyMesh {
    let (w, g) = (tube_ribbon(tube, ribbon), tube_ribbon(tube, guide));
    let mut mesh = ProxyMesh::default();
    for c in tube.curves() {
        mesh.append(&curve_ribbon(&c, w, g, segment, keep));
    }
    mesh
}

/// A natural arch: a rock slab along an arc from `from` to `to` (its feet) whose top
/// rises `height` above the feet. At the crown the slab is `thickness` thick and `width`
/// wide; both grow towards the feet (the abutments), the thickness to `abutment`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Arch {
    /// One foot (the centre of the slab's end).
    pub from: Vec3,
    /// The other foot.
    pub to: Vec3,
    /// Height of the top at the apex above the feet's mean elevation.
    pub height: f32,
    /// Thickness at the crown (perpendicular to the arc, in its vertical plane).
    pub thickness: f32,
    /// Width at the crown (horizontal, across the span).
    pub width: f32,
    /// Thickness at the feet.
    pub abutment: f32,
    /// Half-length of a ground curve under the apex, across the span; none if `None`.
    pub ground: Option<f32>,
    /// Noise `(α, β)`.
    pub noise: Vec2,
}

/// How much wider than at the crown an arch is at its feet.
const ABUTMENT_WIDENING: f32 = 1.5;

impl Arch {
    /// The slab: a tube with outward normals along the arc through the feet. The arc is a
    /// cubic Bézier with its inner control vertices straight above the feet, so the legs
    /// leave the ground vertically; the section grows from the crown to the feet as
    /// `|2t − 1|` (linearly in the parameter).
    pub fn beam(&self) -> Tube {
        let base = 0.5 * (self.from.z + self.to.z);
        let crown = self.height - 0.5 * self.thickness;
        // A cubic Bézier rises to 3/4 of its control height at the middle.
        let lift = |p: Vec3| Vec3::new(p.x, p.y, base + crown * 4.0 / 3.0);
        let path = BSpline::new(vec![self.from, lift(self.from), lift(self.to), self.to])
            .expect("four vertices");
        let keys = |at_crown: f32, at_feet: f32| {
            Profile(
                (0..=8)
                    .map(|i| {
                        let t = i as f32 / 8.0;
                        (t, at_crown + (at_feet - at_crown) * (2.0 * t - 1.0).abs())
                    })
                    .collect(),
            )
        };
        Tube {
            path,
            width: keys(self.width, self.width * ABUTMENT_WIDENING),
            height: keys(self.thickness, self.abutment),
            noise: self.noise,
            inward: false,
        }
    }

    /// Horizontal direction from `from` to `to`, and the horizontal side (`ẑ × dir`).
    fn frame(&self) -> (Vec3, Vec3) {
        let span = self.to - self.from;
        let dir = Vec3::new(span.x, span.y, 0.0).normalize_or(Vec3::X);
        (dir, Vec3::Z.cross(dir))
    }

    /// The ground curve under the apex, across the span, if any.
    pub fn ground_curve(&self) -> Option<FeatureCurve> {
        let g = self.ground?;
        let (dir, side) = self.frame();
        let mid = 0.5 * (self.from + self.to);
        // Running along `side`, its horizontal left is `-dir`.
        Some(curve_through(
            vec![mid - side * g, mid + side * g],
            vec![(-dir, dir); 2],
            self.noise,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn straight(len: f32) -> BSpline {
        BSpline::new(vec![Vec3::ZERO, Vec3::new(len, 0.0, 0.0)]).unwrap()
    }

    #[test]
    fn tunnel_normals_point_inside() {
        let t = Tube {
            path: straight(40.0),
            width: Profile::constant(8.0),
            height: Profile(vec![(0.0, 6.0), (1.0, 10.0)]),
            noise: Vec2::ZERO,
            inward: true,
        };
        let curves = t.curves();
        for c in &curves {
            for i in 0..=10 {
                let s = c.sample(i as f32 / 10.0);
                // The axis is the x axis; the normal of an ellipse points along
                // (y / a², z / b²), here inwards.
                let (a, b) = (4.0, 0.5 * (6.0 + 4.0 * i as f32 / 10.0));
                let inward = -Vec3::new(0.0, s.pos.y / (a * a), s.pos.z / (b * b)).normalize();
                assert!(s.left_normal().dot(inward) > 0.99, "{s:?}");
                assert!(s.right_normal().dot(inward) > 0.99, "{s:?}");
            }
        }
        // The floor is first and flat; the ceiling (halfway round) is 3 m above the axis
        // at the start, 5 m at the end.
        let floor = curves[0].sample(0.5);
        assert!(floor.left_normal().z > 0.99 && floor.pos.z < -3.5);
        let ceiling = &curves[CURVES_AROUND / 2];
        assert!((ceiling.sample(0.0).pos.z - 3.0).abs() < 1e-4);
        assert!((ceiling.sample(1.0).pos.z - 5.0).abs() < 1e-4);
        assert!(t.contains(Vec3::new(20.0, 0.0, 0.0), 0.0));
        assert!(!t.contains(Vec3::new(20.0, 5.0, 0.0), 0.5));
        // Outward normals for rock inside.
        let rock = Tube { inward: false, ..t };
        assert!(rock.curves()[0].sample(0.5).left_normal().z < -0.99);
    }

    #[test]
    fn branches_open_into_each_other() {
        let main = Tube {
            path: straight(60.0),
            width: Profile::constant(8.0),
            height: Profile::constant(8.0),
            noise: Vec2::ZERO,
            inward: true,
        };
        let branch = Tube {
            path: BSpline::new(vec![Vec3::new(30.0, 0.0, 0.0), Vec3::new(30.0, 40.0, 0.0)])
                .unwrap(),
            ..main.clone()
        };
        let mesh = tunnel_proxies(&[main, branch], 1.0, 1.0, 1.0, &|_| true);
        // No ribbon of either tunnel inside the junction: the main tunnel's left wall is
        // open where the branch leaves, the branch has no walls inside the main tunnel.
        for v in &mesh.vertices {
            let p = v.pos;
            assert!(
                !(p.y > 0.0 && p.y < 3.0 && (p.x - 30.0).abs() < 2.5 && p.z.abs() < 2.0),
                "{p}"
            );
        }
        assert!(
            mesh.vertices.iter().any(|v| v.pos.y > 10.0),
            "the branch has walls"
        );
    }

    #[test]
    fn arch_is_a_slab_thinnest_at_the_crown() {
        let a = Arch {
            from: Vec3::new(0.0, 0.0, 0.0),
            to: Vec3::new(40.0, 0.0, 0.0),
            height: 20.0,
            thickness: 4.0,
            width: 8.0,
            abutment: 10.0,
            ground: Some(15.0),
            noise: Vec2::ZERO,
        };
        let beam = a.beam();
        assert!(!beam.inward);
        // The top of the crown is `height` above the feet, its underside `thickness` lower.
        let top = beam.curves()[CURVES_AROUND / 2].sample(0.5);
        let under = beam.curves()[0].sample(0.5);
        assert!(
            (top.pos - Vec3::new(20.0, 0.0, 20.0)).length() < 0.1,
            "{top:?}"
        );
        assert!((under.pos.z - 16.0).abs() < 0.1, "{under:?}");
        assert!(top.left_normal().z > 0.99 && under.left_normal().z < -0.99);
        // Wider than thick; thicker and wider at the feet.
        assert_eq!((beam.width.at(0.5), beam.height.at(0.5)), (8.0, 4.0));
        assert_eq!((beam.width.at(0.0), beam.height.at(1.0)), (12.0, 10.0));
        // The legs leave the feet vertically.
        assert!(beam.path.tangent(0.0).z > 0.99 && beam.path.tangent(1.0).z < -0.99);
        let g = a.ground_curve().unwrap().sample(0.5);
        assert!(g.left_normal().z > 0.99 && g.pos.z.abs() < 1e-6);
    }
}

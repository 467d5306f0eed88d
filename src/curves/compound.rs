//! Compound primitives that place several Feature Curves themselves (seed 000 §7.2):
//! a `Tunnel` (floor, ceiling and two walls along a path, with width and height
//! profiles; tunnels sharing a node branch) and an `Arch` (the top, the underside and
//! the ground below, from the span's end points, height and thickness).

use glam::{Vec2, Vec3};

use super::bspline::BSpline;
use super::constraint::{ConstraintPoint, FeatureCurve};
use super::ribbon::{ProxyMesh, curve_ribbon};

/// A piecewise-linear profile over the path parameter `t ∈ [0, 1]`: `(t, value)` keys
/// sorted by `t`, held constant beyond the first and last key.
#[derive(Clone, Debug, PartialEq)]
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
}

/// A tunnel: an elliptic tube of `width × height` around `path` (its axis). It places a
/// floor, a ceiling and two wall curves; all normals point into the tunnel (the air).
#[derive(Clone, Debug, PartialEq)]
pub struct Tunnel {
    /// The axis.
    pub path: BSpline,
    /// Full width (metres) along the path.
    pub width: Profile,
    /// Full height (metres) along the path.
    pub height: Profile,
    /// Noise `(α, β)` on the tunnel's walls.
    pub noise: Vec2,
}

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

impl Tunnel {
    /// The four curves: floor, ceiling, left wall, right wall. Sections every eighth of
    /// the smaller of width and height become their control vertices.
    pub fn curves(&self) -> [FeatureCurve; 4] {
        let spacing = 0.125 * self.width.max().min(self.height.max());
        let n = sections(&self.path, spacing);
        let mut pts: [Vec<Vec3>; 4] = Default::default();
        let mut bts: [Vec<(Vec3, Vec3)>; 4] = Default::default();
        for i in 0..=n {
            let t = i as f32 / n as f32;
            let p = self.path.eval(t);
            let (_, l, u) = frame(&self.path, t);
            let (hw, hh) = (0.5 * self.width.at(t), 0.5 * self.height.at(t));
            // floor: flat both sides; ceiling: folded over (normal down); walls: vertical,
            // left wall looking right (−l), right wall looking left (+l).
            let placed = [
                (p - u * hh, (l, -l)),
                (p + u * hh, (-l, l)),
                (p + l * hw, (u, -u)),
                (p - l * hw, (-u, u)),
            ];
            for (k, (q, b)) in placed.into_iter().enumerate() {
                pts[k].push(q);
                bts[k].push(b);
            }
        }
        let mut it = pts.into_iter().zip(bts);
        std::array::from_fn(|_| {
            let (p, b) = it.next().expect("four curves");
            curve_through(p, b, self.noise)
        })
    }

    /// The smallest width or height along the path.
    pub fn section(&self) -> f32 {
        self.width
            .0
            .iter()
            .chain(&self.height.0)
            .map(|k| k.1)
            .fold(f32::INFINITY, f32::min)
    }

    /// True when `p` lies inside the tube grown by `margin`.
    pub fn contains(&self, p: Vec3, margin: f32) -> bool {
        let n = 128;
        let (mut best, mut best_t) = (f32::INFINITY, 0.0);
        for i in 0..=n {
            let t = i as f32 / n as f32;
            let d = self.path.eval(t).distance_squared(p);
            if d < best {
                (best, best_t) = (d, t);
            }
        }
        let (v, l, u) = frame(&self.path, best_t);
        let d = p - self.path.eval(best_t);
        let along_ok = (best_t > 0.0 && best_t < 1.0) || d.dot(v).abs() < margin;
        let a = d.dot(l) / (0.5 * self.width.at(best_t) + margin);
        let b = d.dot(u) / (0.5 * self.height.at(best_t) + margin);
        along_ok && a * a + b * b < 1.0
    }
}

/// True when `p` is outside every tunnel of `tunnels` but the `i`-th (grown by `margin`):
/// where tunnel `i`'s curves are kept, so that branches open into each other.
pub fn outside_others(tunnels: &[Tunnel], i: usize, p: Vec3, margin: f32) -> bool {
    !tunnels
        .iter()
        .enumerate()
        .any(|(j, t)| j != i && t.contains(p, margin))
}

/// The ribbon width used for a tunnel: no wider than a quarter of its section, so the
/// four ribbons do not cross.
pub fn tunnel_ribbon(tunnel: &Tunnel, ribbon: f32) -> f32 {
    ribbon.min(0.25 * tunnel.width.max().min(tunnel.height.max()))
}

/// The proxy meshes of a set of tunnels: each tunnel's curves leave out the segments
/// inside the other tunnels, so tunnels sharing a node open into each other. Ribbons and
/// guidance extensions are capped at a quarter of the section.
pub fn tunnel_proxies(tunnels: &[Tunnel], ribbon: f32, guide: f32, segment: f32) -> ProxyMesh {
    let mut mesh = ProxyMesh::default();
    for (i, tunnel) in tunnels.iter().enumerate() {
        let keep = |p: Vec3| outside_others(tunnels, i, p, ribbon);
        let (w, g) = (tunnel_ribbon(tunnel, ribbon), tunnel_ribbon(tunnel, guide));
        for c in tunnel.curves() {
            mesh.append(&curve_ribbon(&c, w, g, segment, &keep));
        }
    }
    mesh
}

/// A natural arch: a beam from `from` to `to` (its feet) rising to `height` above the
/// feet, `thickness` thick at the apex, with flanks sloping at `flank` degrees, and
/// optionally a ground curve under it, across the span.
#[derive(Clone, Debug, PartialEq)]
pub struct Arch {
    /// One foot.
    pub from: Vec3,
    /// The other foot.
    pub to: Vec3,
    /// Height of the top at the apex above the feet's mean elevation.
    pub height: f32,
    /// Vertical thickness at the apex.
    pub thickness: f32,
    /// Slope of the beam's flanks below the horizontal (degrees).
    pub flank: f32,
    /// Half-length of the ground curve under the apex, across the span; none if `None`.
    pub ground: Option<f32>,
    /// Noise `(α, β)`.
    pub noise: Vec2,
}

impl Arch {
    /// The top, the underside and (optionally) the ground curve (§7.2, Figure 7.6).
    pub fn curves(&self) -> Vec<FeatureCurve> {
        self.curves_at(0.0)
    }

    /// [`Arch::curves`] on a grid level whose cells are about `min_thickness / 3`: the
    /// beam's two curves only when the beam is at least `min_thickness` thick. On coarser
    /// levels one cell would hold the top and the underside, their opposite normals would
    /// mix, and the normal field diffused from them would turn the air around the arch
    /// into rock; the ground curve (if any) is always kept.
    pub fn curves_at(&self, min_thickness: f32) -> Vec<FeatureCurve> {
        let mut out = Vec::with_capacity(3);
        if self.thickness >= min_thickness {
            out.extend(self.beam());
        }
        out.extend(self.ground_curve());
        out
    }

    /// The top and the underside of the beam.
    fn beam(&self) -> [FeatureCurve; 2] {
        let (dir, side) = self.frame();
        let base = 0.5 * (self.from.z + self.to.z);
        // A cubic Bézier rises to 3/4 of its control height at the middle.
        let arc = |a: Vec3, b: Vec3, apex: f32| {
            let lift = |p: Vec3| Vec3::new(p.x, p.y, base + (apex - base) * 4.0 / 3.0);
            BSpline::new(vec![a, lift(a), lift(b), b]).expect("four vertices")
        };
        let inset = dir * self.thickness;
        let top = arc(self.from, self.to, base + self.height);
        let under = arc(
            self.from + inset,
            self.to - inset,
            base + self.height - self.thickness,
        );
        let (c, s) = (self.flank.to_radians().cos(), self.flank.to_radians().sin());
        let along = |spline: BSpline, upper: bool| {
            let n = 24;
            let constraints = (0..=n)
                .map(|i| {
                    let t = i as f32 / n as f32;
                    let v = spline.tangent(t);
                    let out = v.cross(side).normalize_or(Vec3::Z); // away from the hole
                    let (left, right) = if upper {
                        (side * c - out * s, -side * c - out * s)
                    } else {
                        (-side * c + out * s, side * c + out * s)
                    };
                    ConstraintPoint {
                        t,
                        left,
                        right,
                        amplitude: self.noise.x,
                        roughness: self.noise.y,
                    }
                })
                .collect();
            FeatureCurve {
                spline,
                constraints,
                seed: true,
                ribbon: None,
            }
        };
        [along(top, true), along(under, false)]
    }

    /// Horizontal direction from `from` to `to`, and the horizontal side (`ẑ × dir`).
    fn frame(&self) -> (Vec3, Vec3) {
        let span = self.to - self.from;
        let dir = Vec3::new(span.x, span.y, 0.0).normalize_or(Vec3::X);
        (dir, Vec3::Z.cross(dir))
    }

    /// The ground curve under the apex, across the span, if any.
    fn ground_curve(&self) -> Option<FeatureCurve> {
        let g = self.ground?;
        let (dir, side) = self.frame();
        let mid = Vec3::new(
            0.5 * (self.from.x + self.to.x),
            0.5 * (self.from.y + self.to.y),
            0.5 * (self.from.z + self.to.z),
        );
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
        let t = Tunnel {
            path: straight(40.0),
            width: Profile::constant(8.0),
            height: Profile(vec![(0.0, 6.0), (1.0, 10.0)]),
            noise: Vec2::ZERO,
        };
        let curves = t.curves();
        for c in &curves {
            for i in 0..=10 {
                let s = c.sample(i as f32 / 10.0);
                // The axis is the x axis; the floor and ceiling tilt with the height profile.
                let inward = Vec3::new(0.0, -s.pos.y, -s.pos.z).normalize();
                assert!(s.left_normal().dot(inward) > 0.995, "{s:?}");
                assert!(s.right_normal().dot(inward) > 0.995, "{s:?}");
            }
        }
        // Height profile: the ceiling is 3 m above the axis at the start, 5 m at the end.
        assert!((curves[1].sample(0.0).pos.z - 3.0).abs() < 1e-4);
        assert!((curves[1].sample(1.0).pos.z - 5.0).abs() < 1e-4);
        assert!(t.contains(Vec3::new(20.0, 0.0, 0.0), 0.0));
        assert!(!t.contains(Vec3::new(20.0, 5.0, 0.0), 0.5));
    }

    #[test]
    fn branches_open_into_each_other() {
        let main = Tunnel {
            path: straight(60.0),
            width: Profile::constant(8.0),
            height: Profile::constant(8.0),
            noise: Vec2::ZERO,
        };
        let branch = Tunnel {
            path: BSpline::new(vec![Vec3::new(30.0, 0.0, 0.0), Vec3::new(30.0, 40.0, 0.0)])
                .unwrap(),
            ..main.clone()
        };
        let mesh = tunnel_proxies(&[main, branch], 1.0, 1.0, 1.0);
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
    fn arch_curves_frame_a_hole() {
        let a = Arch {
            from: Vec3::new(0.0, 0.0, 0.0),
            to: Vec3::new(40.0, 0.0, 0.0),
            height: 20.0,
            thickness: 5.0,
            flank: 45.0,
            ground: Some(15.0),
            noise: Vec2::ZERO,
        };
        let c = a.curves();
        assert_eq!(c.len(), 3);
        let top = c[0].sample(0.5);
        assert!(
            (top.pos - Vec3::new(20.0, 0.0, 20.0)).length() < 1e-3,
            "{top:?}"
        );
        assert!(top.left_normal().z > 0.5 && top.right_normal().z > 0.5);
        let under = c[1].sample(0.5);
        assert!((under.pos.z - 15.0).abs() < 1e-3);
        assert!(under.left_normal().z < -0.5 && under.right_normal().z < -0.5);
        let g = c[2].sample(0.5);
        assert!(g.left_normal().z > 0.99 && g.pos.z.abs() < 1e-6);
        // Levels too coarse for the beam get only the ground curve.
        assert_eq!(a.curves_at(5.0), c);
        assert_eq!(a.curves_at(6.0), c[2..]);
        assert!(Arch { ground: None, ..a }.curves_at(6.0).is_empty());
    }
}

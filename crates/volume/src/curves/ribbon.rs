//! Proxy ribbon meshes (Becher 2016 §3.3): the common triangle representation of every
//! modelling primitive, and the input of the voxel pipeline.
//!
//! A Feature Curve is cut into short segments; each segment gets two quads, one swept
//! along the left bitangent and one along the right. Vertices carry the ribbon normal,
//! the bitangent and the noise parameters `(α, β)`; triangles carry the ribbon side (for
//! the sign-invariant bitangent pairing of §4.2.1) and the seed flag. Any triangle mesh
//! with normals can be fed to the pipeline the same way.

use glam::{Vec2, Vec3};

use super::constraint::FeatureCurve;

/// Which ribbon a triangle belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Side {
    /// The left-hand ribbon of a curve.
    Left,
    /// The right-hand ribbon of a curve.
    Right,
    /// A shape or a generic mesh: its bitangent is gathered with the left ones.
    Face,
}

/// A vertex of a proxy mesh.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ProxyVertex {
    /// Position (metres).
    pub pos: Vec3,
    /// Unit surface normal, pointing into the air.
    pub normal: Vec3,
    /// Unit bitangent (the direction the ribbon extends in).
    pub bitangent: Vec3,
    /// Noise amplitude and roughness `(α, β)`.
    pub noise: Vec2,
}

/// A triangle of a proxy mesh.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ProxyTriangle {
    /// Vertex indices.
    pub v: [u32; 3],
    /// Ribbon side.
    pub side: Side,
    /// Seed triangles put the surface through themselves (S = 0); others only guide.
    pub seed: bool,
}

/// A triangle mesh with the attributes the pipeline gathers.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct ProxyMesh {
    /// Vertices.
    pub vertices: Vec<ProxyVertex>,
    /// Triangles.
    pub triangles: Vec<ProxyTriangle>,
}

impl ProxyMesh {
    /// Appends `other`'s triangles.
    pub fn append(&mut self, other: &ProxyMesh) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.triangles
            .extend(other.triangles.iter().map(|t| ProxyTriangle {
                v: t.v.map(|i| i + base),
                ..*t
            }));
    }

    /// Adds the quad `a b c d` (in order around it) as two triangles.
    pub fn push_quad(&mut self, quad: [ProxyVertex; 4], side: Side, seed: bool) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&quad);
        for v in [[0, 1, 2], [0, 2, 3]] {
            self.triangles.push(ProxyTriangle {
                v: v.map(|i| base + i),
                side,
                seed,
            });
        }
    }

    /// The three vertices of triangle `i`.
    pub fn triangle(&self, i: usize) -> [&ProxyVertex; 3] {
        self.triangles[i].v.map(|k| &self.vertices[k as usize])
    }

    /// True when there is at least one seed triangle.
    pub fn has_seed(&self) -> bool {
        self.triangles.iter().any(|t| t.seed)
    }

    /// Writes the mesh as Wavefront OBJ (positions and normals), for inspection.
    pub fn write_obj(&self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        for v in &self.vertices {
            writeln!(w, "v {} {} {}", v.pos.x, v.pos.y, v.pos.z)?;
        }
        for v in &self.vertices {
            writeln!(w, "vn {} {} {}", v.normal.x, v.normal.y, v.normal.z)?;
        }
        for t in &self.triangles {
            let [a, b, c] = t.v.map(|i| i + 1);
            writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
        }
        Ok(())
    }
}

/// The proxy ribbons of a curve: segments no longer than `max_segment`, each ribbon
/// `width` metres wide, continued up to `guide` metres by guidance triangles (normals
/// only, no surface) when `guide > width` — coarse levels of the pipeline use that so a
/// curve's two sides stay distinct in cells larger than its ribbons. Segments whose both
/// end points fail `keep` are left out (used by tunnels to open junctions).
pub fn curve_ribbon(
    curve: &FeatureCurve,
    width: f32,
    guide: f32,
    max_segment: f32,
    keep: &dyn Fn(Vec3) -> bool,
) -> ProxyMesh {
    let len = curve.spline.length(64);
    let n = ((len / max_segment).ceil() as usize).clamp(1, 1 << 16);
    let samples: Vec<_> = (0..=n).map(|i| curve.sample(i as f32 / n as f32)).collect();
    let mut mesh = ProxyMesh::default();
    for w in samples.windows(2) {
        let (s0, s1) = (&w[0], &w[1]);
        if !keep(s0.pos) && !keep(s1.pos) {
            continue;
        }
        let vert = |s: &super::constraint::CurveSample, b: Vec3, n: Vec3, out: f32| ProxyVertex {
            pos: s.pos + b * out,
            normal: n,
            bitangent: b,
            noise: s.noise,
        };
        // Left ribbons: inner0, inner1, outer1, outer0 — counter-clockwise seen from the
        // normal side, so the geometric normal agrees with the vertex normals.
        let (l0, l1) = (s0.left_normal(), s1.left_normal());
        let (r0, r1) = (s0.right_normal(), s1.right_normal());
        for (from, to, seed) in [(0.0, width, curve.seed), (width, guide, false)] {
            if to <= from {
                continue;
            }
            mesh.push_quad(
                [
                    vert(s0, s0.left, l0, from),
                    vert(s1, s1.left, l1, from),
                    vert(s1, s1.left, l1, to),
                    vert(s0, s0.left, l0, to),
                ],
                Side::Left,
                seed,
            );
            mesh.push_quad(
                [
                    vert(s0, s0.right, r0, from),
                    vert(s0, s0.right, r0, to),
                    vert(s1, s1.right, r1, to),
                    vert(s1, s1.right, r1, from),
                ],
                Side::Right,
                seed,
            );
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curves::bspline::BSpline;
    use crate::curves::constraint::ConstraintPoint;

    #[test]
    fn ridge_ribbons_have_outward_normals_and_consistent_winding() {
        let s = 0.5f32;
        let curve = FeatureCurve {
            spline: BSpline::new(vec![Vec3::ZERO, Vec3::new(10.0, 0.0, 0.0)]).unwrap(),
            constraints: vec![ConstraintPoint {
                t: 0.0,
                left: Vec3::new(0.0, 1.0, -s).normalize(),
                right: Vec3::new(0.0, -1.0, -s).normalize(),
                amplitude: 0.0,
                roughness: 0.0,
            }],
            seed: true,
            ribbon: None,
        };
        let mesh = curve_ribbon(&curve, 2.0, 2.0, 1.0, &|_| true);
        assert_eq!(mesh.triangles.len(), 10 * 4);
        for (i, t) in mesh.triangles.iter().enumerate() {
            let [a, b, c] = mesh.triangle(i);
            let geo = (b.pos - a.pos).cross(c.pos - a.pos).normalize();
            assert!(geo.dot(a.normal) > 0.99, "winding agrees with the normal");
            assert!(a.normal.z > 0.8, "ridge normals point up");
            let expect_y = if t.side == Side::Left { 1.0 } else { -1.0 };
            assert!(a.normal.y * expect_y > 0.3, "and away from the crest");
        }
        let none = curve_ribbon(&curve, 2.0, 2.0, 1.0, &|p| p.x > 20.0);
        let guided = curve_ribbon(&curve, 2.0, 5.0, 1.0, &|_| true);
        assert_eq!(guided.triangles.iter().filter(|t| !t.seed).count(), 10 * 4);
        assert!(none.triangles.is_empty());
    }
}

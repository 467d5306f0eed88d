//! Simple shapes (Becher 2016 §3.2): a quad of two triangles and a disc (triangle fan) that
//! enforce a normal, a bitangent orientation and noise parameters locally — to close a
//! tunnel, level a plateau or set noise over a flat area.

use glam::{Vec2, Vec3};

use super::ribbon::{ProxyMesh, ProxyTriangle, ProxyVertex, Side};

/// A planar quad; its normal follows the corners' order (counter-clockwise seen from the
/// air side).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Quad {
    /// The corners, in order around the quad.
    pub corners: [Vec3; 4],
    /// Seed (surface goes through it) or guidance.
    pub seed: bool,
    /// Noise `(α, β)`.
    pub noise: Vec2,
}

/// A flat disc.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Disc {
    /// Centre.
    pub center: Vec3,
    /// Unit normal, pointing into the air.
    pub normal: Vec3,
    /// Radius (metres).
    pub radius: f32,
    /// Seed or guidance.
    pub seed: bool,
    /// Noise `(α, β)`.
    pub noise: Vec2,
}

impl Quad {
    /// The unit normal of the corners' winding (zero for a degenerate quad).
    pub fn normal(&self) -> Vec3 {
        let [a, b, c, d] = self.corners;
        (c - a).cross(d - b).normalize_or_zero()
    }

    /// Its proxy mesh: two triangles, bitangent along the first edge.
    pub fn proxy(&self) -> ProxyMesh {
        let n = self.normal();
        let [a, b, ..] = self.corners;
        let bt = (b - a)
            .reject_from(n)
            .normalize_or(n.any_orthonormal_vector());
        let mut mesh = ProxyMesh::default();
        mesh.push_quad(
            self.corners.map(|pos| ProxyVertex {
                pos,
                normal: n,
                bitangent: bt,
                noise: self.noise,
            }),
            Side::Face,
            self.seed,
        );
        mesh
    }
}

impl Disc {
    /// Its proxy mesh: a fan whose rim chords are at most `max_segment` long; radial
    /// bitangents.
    pub fn proxy(&self, max_segment: f32) -> ProxyMesh {
        let n = self.normal.normalize();
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        let k =
            ((std::f32::consts::TAU * self.radius / max_segment).ceil() as usize).clamp(8, 4096);
        let mut mesh = ProxyMesh::default();
        mesh.vertices.push(ProxyVertex {
            pos: self.center,
            normal: n,
            bitangent: u,
            noise: self.noise,
        });
        for i in 0..k {
            let a = i as f32 / k as f32 * std::f32::consts::TAU;
            let r = u * a.cos() + v * a.sin();
            mesh.vertices.push(ProxyVertex {
                pos: self.center + r * self.radius,
                normal: n,
                bitangent: r,
                noise: self.noise,
            });
        }
        for i in 0..k as u32 {
            mesh.triangles.push(ProxyTriangle {
                v: [0, 1 + i, 1 + (i + 1) % k as u32],
                side: Side::Face,
                seed: self.seed,
            });
        }
        mesh
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_wind_with_their_normals() {
        let q = Quad {
            corners: [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            seed: true,
            noise: Vec2::ZERO,
        };
        assert!((q.normal() - Vec3::Z).length() < 1e-6);
        let d = Disc {
            center: Vec3::ZERO,
            normal: -Vec3::Z,
            radius: 3.0,
            seed: false,
            noise: Vec2::ZERO,
        };
        for m in [q.proxy(), d.proxy(0.5)] {
            for i in 0..m.triangles.len() {
                let [a, b, c] = m.triangle(i);
                let geo = (b.pos - a.pos).cross(c.pos - a.pos).normalize();
                assert!(geo.dot(a.normal) > 0.999);
                assert!(a.bitangent.dot(a.normal).abs() < 1e-5);
            }
        }
        assert!(d.proxy(0.5).triangles.len() >= 37);
    }
}

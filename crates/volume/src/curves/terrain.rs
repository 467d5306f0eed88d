//! The terrain under a Feature Volume as boundary conditions of the voxel pipeline.
//!
//! A feature put on a terrain must change it only near itself. The thesis (Becher
//! §4.2–4.6) builds S from seed primitives alone, so a lone arch's S has no opinion about
//! the ground around it, and whatever it says there shows up as terraces and walls. Here
//! the terrain's surface becomes seed primitives too: the ground is sampled on a grid
//! over the domain's footprint, every grid cell becomes two seed triangles carrying the
//! terrain's normal (into the air) and no noise, and the triangles near the user's
//! features are left out — the features take over there, and the diffusion of normals
//! (§4.3) and the surface propagation (§4.6) join them to the ground smoothly. S then
//! reproduces the terrain away from the features, so the volume can *replace* the terrain
//! inside its domain (the tree's `Replace` node) without a seam.

use glam::{Vec2, Vec3};

use super::ribbon::{ProxyMesh, ProxyTriangle, ProxyVertex, Side};
use super::room::Room;
use crate::field::{Aabb, Interval};

/// The terrain's heights on a grid over a volume's footprint, and the seed triangles made
/// of them (those left after the features took their room).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TerrainSurface {
    /// Position of sample `(0, 0)`.
    origin: Vec2,
    /// Grid spacing (metres).
    spacing: f32,
    /// Samples along x and y.
    dims: [usize; 2],
    /// Heights, x fastest; NaN where the ground is unknown.
    heights: Vec<f32>,
    /// The domain's z-range: ground outside it makes no triangle.
    z: Interval,
    /// The distance features keep from the ground.
    clearance: f32,
    /// The noise roughness the ground's triangles carry.
    beta: f32,
    /// The seed triangles of the ground, without those near the features.
    mesh: ProxyMesh,
}

impl TerrainSurface {
    /// Samples `ground` every `spacing` metres over `domain`'s footprint. It has no
    /// triangles until [`TerrainSurface::make_room`] makes them: every cell whose corners
    /// lie in the domain's z-range and outside the features' room becomes two.
    ///
    /// The features on the terrain keep `clearance` metres from the ground: their curves
    /// stop that far above (an arch) or below it (a tunnel), and the ground's triangles
    /// give way that far around them, so the pipeline has room to round the junction
    /// (a fillet at an arch's feet, a flared portal at a tunnel's mouth) instead of
    /// meeting the ground edge to edge, which leaves a notch.
    ///
    /// The ground's triangles carry no noise amplitude (α = 0: the terrain stays as it
    /// is) but the features' roughness `beta`: the noise is evaluated at `β(p)·p`, and a
    /// β falling to 0 across the transition would compress the noise's pattern there.
    pub fn new(
        ground: &dyn Fn(Vec2) -> Option<f32>,
        domain: &Aabb,
        spacing: f32,
        clearance: f32,
        beta: f32,
    ) -> Self {
        let fp = domain.footprint();
        let n = ((fp.max - fp.min) / spacing).ceil().as_uvec2() + 1;
        let dims = [n.x as usize, n.y as usize];
        let origin = fp.min;
        let heights = (0..dims[0] * dims[1])
            .map(|i| {
                let xy = origin + Vec2::new((i % dims[0]) as f32, (i / dims[0]) as f32) * spacing;
                ground(xy).filter(|h| h.is_finite()).unwrap_or(f32::NAN)
            })
            .collect();
        TerrainSurface {
            origin,
            spacing,
            dims,
            heights,
            z: domain.z(),
            clearance,
            beta,
            mesh: ProxyMesh::default(),
        }
    }

    /// Makes the seed triangles, leaving out those whose cell centre lies in a ball of
    /// `room`: there the features take over.
    pub fn make_room(&mut self, room: &Room) {
        self.mesh = self.triangles(room);
    }

    /// The ground height at `xy`, bilinear between the samples; `None` off the grid or
    /// where a sample is unknown.
    pub fn height(&self, xy: Vec2) -> Option<f32> {
        let g = (xy - self.origin) / self.spacing;
        let [nx, ny] = self.dims;
        if !(g.x >= 0.0 && g.y >= 0.0 && g.x <= (nx - 1) as f32 && g.y <= (ny - 1) as f32) {
            return None;
        }
        let (i, j) = ((g.x as usize).min(nx - 2), (g.y as usize).min(ny - 2));
        let (fx, fy) = (g.x - i as f32, g.y - j as f32);
        let h = |a: usize, b: usize| self.heights[a + nx * b];
        let v = (h(i, j) * (1.0 - fx) + h(i + 1, j) * fx) * (1.0 - fy)
            + (h(i, j + 1) * (1.0 - fx) + h(i + 1, j + 1) * fx) * fy;
        v.is_finite().then_some(v)
    }

    /// True when `p` is more than `margin` below the ground (false where the ground is
    /// unknown).
    pub fn below(&self, p: Vec3, margin: f32) -> bool {
        self.height(p.truncate()).is_some_and(|h| p.z < h - margin)
    }

    /// True when `p` is more than `margin` above the ground (false where the ground is
    /// unknown).
    pub fn above(&self, p: Vec3, margin: f32) -> bool {
        self.height(p.truncate()).is_some_and(|h| p.z > h + margin)
    }

    /// How far from the ground the features' own curves stop (see
    /// [`crate::curves::Features::room`]).
    pub fn clearance(&self) -> f32 {
        self.clearance
    }

    /// The seed triangles of the ground.
    pub fn mesh(&self) -> &ProxyMesh {
        &self.mesh
    }

    /// Grid sample `(i, j)` as a point, with the normal from central differences.
    fn vertex(&self, i: usize, j: usize) -> Option<ProxyVertex> {
        let [nx, ny] = self.dims;
        let h = |a: usize, b: usize| self.heights[a + nx * b];
        let z = h(i, j);
        let (i0, i1, j0, j1) = (
            i.saturating_sub(1),
            (i + 1).min(nx - 1),
            j.saturating_sub(1),
            (j + 1).min(ny - 1),
        );
        let dx = (h(i1, j) - h(i0, j)) / ((i1 - i0) as f32 * self.spacing);
        let dy = (h(i, j1) - h(i, j0)) / ((j1 - j0) as f32 * self.spacing);
        if !(z.is_finite() && dx.is_finite() && dy.is_finite()) {
            return None;
        }
        let normal = Vec3::new(-dx, -dy, 1.0).normalize();
        Some(ProxyVertex {
            pos: (self.origin + Vec2::new(i as f32, j as f32) * self.spacing).extend(z),
            normal,
            bitangent: Vec3::X.reject_from_normalized(normal).normalize(),
            noise: Vec2::new(0.0, self.beta),
        })
    }

    /// Two seed triangles per grid cell whose corners are known, lie in `z` and are not
    /// inside the features' room.
    fn triangles(&self, room: &Room) -> ProxyMesh {
        let z = self.z;
        let [nx, ny] = self.dims;
        let mut index = vec![u32::MAX; nx * ny];
        let mut mesh = ProxyMesh::default();
        for j in 0..ny {
            for i in 0..nx {
                if let Some(v) = self.vertex(i, j).filter(|v| z.contains(v.pos.z)) {
                    index[i + nx * j] = mesh.vertices.len() as u32;
                    mesh.vertices.push(v);
                }
            }
        }
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let c = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
                    .map(|(a, b)| index[a + nx * b]);
                if c.contains(&u32::MAX) {
                    continue;
                }
                let centre = c
                    .iter()
                    .map(|&k| mesh.vertices[k as usize].pos)
                    .sum::<Vec3>()
                    / 4.0;
                if room.contains(centre) {
                    continue;
                }
                // Counter-clockwise seen from above: the geometric normal points up.
                for v in [[c[0], c[1], c[2]], [c[0], c[2], c[3]]] {
                    mesh.triangles.push(ProxyTriangle {
                        v,
                        side: Side::Face,
                        seed: true,
                    });
                }
            }
        }
        mesh
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ground_becomes_upward_seed_triangles_with_room_for_features() {
        let ground = |xy: Vec2| Some(10.0 + 0.25 * xy.x);
        let domain = Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(40.0, 20.0, 30.0));
        let ball = (Vec3::new(20.0, 10.0, 15.0), 5.0);
        let mut s = TerrainSurface::new(&ground, &domain, 2.0, 1.0, 0.1);
        assert!(s.mesh().triangles.is_empty());
        s.make_room(&Room::default());
        let full = s.mesh().triangles.len();
        s.make_room(&Room::new(vec![ball]));
        assert!(s.mesh().triangles.len() < full);
        assert_eq!(s.dims, [21, 11]);
        assert!((s.height(Vec2::new(13.0, 7.0)).unwrap() - 13.25).abs() < 1e-5);
        assert!(s.height(Vec2::new(41.0, 7.0)).is_none());
        assert!(
            s.below(Vec3::new(13.0, 7.0, 13.0), 0.0) && s.above(Vec3::new(13.0, 7.0, 13.5), 0.0)
        );
        assert!(
            !s.below(Vec3::new(13.0, 7.0, 13.0), 0.5) && s.above(Vec3::new(13.0, 7.0, 13.5), 0.1)
        );
        let m = s.mesh();
        assert!(!m.triangles.is_empty());
        let expect = Vec3::new(-0.25, 0.0, 1.0).normalize();
        for (i, t) in m.triangles.iter().enumerate() {
            let [a, b, c] = m.triangle(i);
            let geo = (b.pos - a.pos).cross(c.pos - a.pos).normalize();
            assert!(geo.dot(expect) > 0.999 && a.normal.dot(expect) > 0.999);
            assert!(t.seed && a.noise == Vec2::new(0.0, 0.1));
            let centre = (a.pos + b.pos + c.pos) / 3.0;
            assert!(centre.distance(ball.0) > 3.0, "{centre}");
        }
        // Triangles only where the ground is inside the domain's z-range: x ≤ 80 here.
        let lower = Aabb::new(Vec3::ZERO, Vec3::new(40.0, 20.0, 15.0));
        let mut s = TerrainSurface::new(&ground, &lower, 2.0, 1.0, 0.1);
        s.make_room(&Room::default());
        assert!(s.mesh().vertices.iter().all(|v| v.pos.z <= 15.0));
        assert!(s.mesh().vertices.iter().any(|v| v.pos.x >= 18.0));
    }
}

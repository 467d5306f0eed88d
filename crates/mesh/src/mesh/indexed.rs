//! The indexed triangle mesh the extractors produce, its measures and topology checks.

use glam::Vec3;
use rayon::prelude::*;

use crate::field::Aabb;

/// A per-vertex scalar attribute (exported to glTF as `_NAME`, e.g. `_AMPLITUDE`).
#[derive(Clone, Debug, PartialEq)]
pub struct Attribute {
    /// Upper-case name without the leading underscore, e.g. `AMPLITUDE`.
    pub name: String,
    /// One value per vertex.
    pub values: Vec<f32>,
}

/// An indexed triangle mesh in the tree's frame (Z up, metres). Triangles are wound
/// counter-clockwise seen from outside the solid; normals point out of it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals.
    pub normals: Vec<[f32; 3]>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// Extra per-vertex data.
    pub attributes: Vec<Attribute>,
}

/// A topology defect found by [`Mesh::check_topology`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TopologyError {
    /// A triangle repeats a vertex or has no area.
    #[error("triangle {0} is degenerate")]
    Degenerate(usize),
    /// An edge is used more than twice, or twice in the same direction.
    #[error("edge ({0}, {1}) is not 2-manifold or is inconsistently oriented")]
    NonManifold(u32, u32),
    /// An edge used once lies inside the allowed box, not on its faces.
    #[error("boundary edge ({0}, {1}) is not on the box faces")]
    Boundary(u32, u32),
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {0} refers to a missing vertex")]
    Index(usize),
}

/// Counts from a successful [`Mesh::check_topology`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Topology {
    /// Vertices referenced by triangles.
    pub vertices: usize,
    /// Distinct undirected edges.
    pub edges: usize,
    /// Triangles.
    pub faces: usize,
    /// Edges used by one triangle only.
    pub boundary_edges: usize,
}

impl Topology {
    /// `V − E + F`.
    pub fn euler_characteristic(&self) -> i64 {
        self.vertices as i64 - self.edges as i64 + self.faces as i64
    }
}

impl Mesh {
    /// The connected component of each triangle (triangles sharing a vertex are
    /// connected), numbered `0..count` in the order of their first triangles, and `count`.
    pub fn components(&self) -> (Vec<u32>, usize) {
        let mut parent: Vec<u32> = (0..self.positions.len() as u32).collect();
        fn root(parent: &mut [u32], mut v: u32) -> u32 {
            while parent[v as usize] != v {
                parent[v as usize] = parent[parent[v as usize] as usize];
                v = parent[v as usize];
            }
            v
        }
        for t in &self.triangles {
            let a = root(&mut parent, t[0]);
            for &v in &t[1..] {
                let b = root(&mut parent, v);
                parent[b as usize] = a;
            }
        }
        let mut number = vec![u32::MAX; self.positions.len()];
        let mut count = 0;
        let labels = self
            .triangles
            .iter()
            .map(|t| {
                let r = root(&mut parent, t[0]) as usize;
                if number[r] == u32::MAX {
                    number[r] = count;
                    count += 1;
                }
                number[r]
            })
            .collect();
        (labels, count as usize)
    }

    /// The face count of each connected component, largest first: floating debris shows
    /// up as small components.
    pub fn component_sizes(&self) -> Vec<usize> {
        let (labels, count) = self.components();
        let mut sizes = vec![0usize; count];
        for l in labels {
            sizes[l as usize] += 1;
        }
        sizes.sort_unstable_by(|a, b| b.cmp(a));
        sizes
    }

    /// Removes the connected components of at most `max_faces` triangles, and the
    /// vertices only they used; returns how many components went. A closed piece of 8
    /// faces is one sample of the field on the other side of `T` from all its neighbours:
    /// solid (or air) smaller than a cell, which the mesh can only draw as a speck.
    pub fn drop_specks(&mut self, max_faces: usize) -> usize {
        let (labels, count) = self.components();
        let mut sizes = vec![0usize; count];
        for &l in &labels {
            sizes[l as usize] += 1;
        }
        let dropped = sizes.iter().filter(|&&n| n <= max_faces).count();
        if dropped == 0 {
            return 0;
        }
        let mut kept = Vec::with_capacity(self.triangles.len());
        for (t, &l) in self.triangles.iter().zip(&labels) {
            if sizes[l as usize] > max_faces {
                kept.push(*t);
            }
        }
        // Renumber the vertices the kept triangles use, in their old order.
        let mut used = vec![false; self.positions.len()];
        for t in &kept {
            for &v in t {
                used[v as usize] = true;
            }
        }
        let mut index = vec![u32::MAX; used.len()];
        let mut next = 0u32;
        for (i, &u) in used.iter().enumerate() {
            if u {
                index[i] = next;
                next += 1;
            }
        }
        let keep = |v: &Vec<[f32; 3]>| -> Vec<[f32; 3]> {
            v.iter()
                .zip(&used)
                .filter(|(_, u)| **u)
                .map(|(p, _)| *p)
                .collect()
        };
        self.positions = keep(&self.positions);
        self.normals = keep(&self.normals);
        for a in &mut self.attributes {
            a.values = a
                .values
                .iter()
                .zip(&used)
                .filter(|(_, u)| **u)
                .map(|(x, _)| *x)
                .collect();
        }
        self.triangles = kept
            .into_iter()
            .map(|t| t.map(|v| index[v as usize]))
            .collect();
        dropped
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Vertex `i` as a vector.
    #[inline]
    pub fn position(&self, i: u32) -> Vec3 {
        Vec3::from(self.positions[i as usize])
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| self.triangle_normal(t).length() as f64 * 0.5)
            .sum()
    }

    /// Signed enclosed volume (divergence theorem); positive for a closed surface wound
    /// counter-clockwise from outside.
    pub fn volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|&[a, b, c]| {
                let (a, b, c) = (self.position(a), self.position(b), self.position(c));
                a.as_dvec3().dot(b.as_dvec3().cross(c.as_dvec3())) / 6.0
            })
            .sum()
    }

    /// Bounding box of the vertices.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.positions.iter().map(|&p| Vec3::from(p)))
    }

    /// Twice-area normal `(b − a) × (c − a)` of a triangle.
    #[inline]
    pub fn triangle_normal(&self, &[a, b, c]: &[u32; 3]) -> Vec3 {
        let (a, b, c) = (self.position(a), self.position(b), self.position(c));
        (b - a).cross(c - a)
    }

    /// Replaces every normal that is not a finite unit vector by the area-weighted
    /// average of its triangles' normals (or +Z if that is zero too).
    pub fn repair_normals(&mut self) {
        let is_bad = |n: &[f32; 3]| {
            let l = Vec3::from(*n).length();
            !(l.is_finite() && (l - 1.0).abs() < 1e-3)
        };
        if !self.normals.par_iter().any(is_bad) {
            return;
        }
        let bad: Vec<bool> = self.normals.iter().map(is_bad).collect();
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        for t in &self.triangles {
            let n = self.triangle_normal(t);
            for &v in t {
                if bad[v as usize] {
                    acc[v as usize] += n;
                }
            }
        }
        for (i, n) in self.normals.iter_mut().enumerate() {
            if bad[i] {
                *n = acc[i].try_normalize().unwrap_or(Vec3::Z).into();
            }
        }
    }

    /// Checks that the mesh is a consistently oriented 2-manifold: no degenerate triangle,
    /// every edge shared by exactly two triangles in opposite directions, except edges
    /// used once, which must lie on a face of `open_faces` (within `tol`) — pass `None`
    /// to require a closed surface.
    pub fn check_topology(
        &self,
        open_faces: Option<(&Aabb, f32)>,
    ) -> Result<Topology, TopologyError> {
        let nv = self.positions.len() as u32;
        let mut edges: Vec<(u32, u32, bool)> = Vec::with_capacity(self.triangles.len() * 3);
        for (i, t) in self.triangles.iter().enumerate() {
            if t.iter().any(|&v| v >= nv) {
                return Err(TopologyError::Index(i));
            }
            if t[0] == t[1]
                || t[1] == t[2]
                || t[0] == t[2]
                || self.triangle_normal(t).length() == 0.0
            {
                return Err(TopologyError::Degenerate(i));
            }
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edges.push((a.min(b), a.max(b), a < b));
            }
        }
        edges.sort_unstable();
        let on_faces = |p: Vec3, b: &Aabb, tol: f32| {
            (0..3).any(|k| (p[k] - b.min[k]).abs() <= tol || (p[k] - b.max[k]).abs() <= tol)
        };
        let mut unique = 0;
        let mut boundary = 0;
        let mut i = 0;
        while i < edges.len() {
            let (a, b, dir) = edges[i];
            let mut j = i + 1;
            while j < edges.len() && edges[j].0 == a && edges[j].1 == b {
                j += 1;
            }
            match j - i {
                1 => {
                    let (pa, pb) = (self.position(a), self.position(b));
                    match open_faces {
                        Some((bx, tol)) if on_faces(pa, bx, tol) && on_faces(pb, bx, tol) => {
                            boundary += 1
                        }
                        _ => return Err(TopologyError::Boundary(a, b)),
                    }
                }
                2 if edges[i + 1].2 != dir => {}
                _ => return Err(TopologyError::NonManifold(a, b)),
            }
            unique += 1;
            i = j;
        }
        let mut used = vec![false; self.positions.len()];
        for t in &self.triangles {
            for &v in t {
                used[v as usize] = true;
            }
        }
        Ok(Topology {
            vertices: used.iter().filter(|&&u| u).count(),
            edges: unique,
            faces: self.triangles.len(),
            boundary_edges: boundary,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> Mesh {
        Mesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            normals: vec![[0.0, 0.0, 1.0]; 4],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            attributes: vec![],
        }
    }

    /// A tetrahedron of 4 faces beside one of 12 (three tetrahedra sharing a vertex), each
    /// vertex tagged with its old index: the small piece goes, the other stays whole.
    #[test]
    fn specks_are_dropped_and_the_rest_renumbered() {
        let shifted = |m: &Mesh, d: f32, base: u32| -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
            (
                m.positions.iter().map(|p| [p[0] + d, p[1], p[2]]).collect(),
                m.triangles.iter().map(|t| t.map(|v| v + base)).collect(),
            )
        };
        let t = tetra();
        let mut mesh = Mesh::default();
        for (k, d) in [0.0, 5.0, 5.0, 5.0].into_iter().enumerate() {
            let base = mesh.positions.len() as u32;
            let (p, tr) = shifted(&t, d + k as f32 * 0.01, base);
            mesh.positions.extend(p);
            mesh.triangles.extend(tr);
        }
        // Tie the three tetrahedra at x ≈ 5 into one piece through shared vertices.
        for tr in &mut mesh.triangles[8..] {
            for v in tr.iter_mut() {
                if *v % 4 == 0 {
                    *v = 4;
                }
            }
        }
        mesh.normals = vec![[0.0, 0.0, 1.0]; mesh.positions.len()];
        mesh.attributes = vec![Attribute {
            name: "OLD".into(),
            values: (0..mesh.positions.len()).map(|i| i as f32).collect(),
        }];
        assert_eq!(mesh.component_sizes(), vec![12, 4]);
        assert_eq!(mesh.drop_specks(8), 1);
        assert_eq!(mesh.component_sizes(), vec![12]);
        // Vertices 0–3 (the speck) and the three merged away (8 and 12) are gone; the
        // others keep their order, positions and attributes.
        let old: Vec<usize> = mesh.attributes[0]
            .values
            .iter()
            .map(|&v| v as usize)
            .collect();
        assert_eq!(old, vec![4, 5, 6, 7, 9, 10, 11, 13, 14, 15]);
        for (i, &o) in old.iter().enumerate() {
            assert!(mesh.positions[i][0] >= 5.0, "vertex {o} moved to {i}");
        }
        assert!(
            mesh.triangles
                .iter()
                .flatten()
                .all(|&v| (v as usize) < old.len())
        );
        assert_eq!(mesh.drop_specks(8), 0, "nothing more to drop");
    }

    #[test]
    fn tetrahedron_measures() {
        let m = tetra();
        assert!((m.volume() - 1.0 / 6.0).abs() < 1e-9);
        let t = m.check_topology(None).unwrap();
        assert_eq!(t.euler_characteristic(), 2);
    }

    #[test]
    fn flipped_triangle_is_caught() {
        let mut m = tetra();
        m.triangles[3] = [1, 3, 2];
        assert!(matches!(
            m.check_topology(None),
            Err(TopologyError::NonManifold(..))
        ));
        let mut m = tetra();
        m.triangles.pop();
        assert!(matches!(
            m.check_topology(None),
            Err(TopologyError::Boundary(..))
        ));
    }

    #[test]
    fn components_count_faces_of_connected_pieces() {
        let mut m = tetra();
        // A second, smaller piece: one triangle away from the tetrahedron.
        m.positions
            .extend([[5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [5.0, 1.0, 0.0]]);
        m.normals.extend([[0.0, 0.0, 1.0]; 3]);
        m.triangles.push([4, 5, 6]);
        assert_eq!(m.component_sizes(), vec![4, 1]);
        assert_eq!(tetra().component_sizes(), vec![4]);
    }
}

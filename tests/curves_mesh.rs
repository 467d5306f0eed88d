//! The Marching Cubes surface of the S-field leaf (`SField::extract`, what `karstic curves
//! build -o mesh.glb` writes), not only the field: closed, through the seed curves, and
//! in one piece, with the through-holes of the arch and the tunnels.

use crate::curves_util;

use std::collections::HashMap;

use glam::{IVec3, Vec3};
use karstic::mesh::{Mesh, MeshOptions};
use karstic::voxel::voxelize::closest_on_triangle;

/// The leaf of `trees/curves/NAME.ron` meshed at its voxel size, and the scene.
fn meshed(name: &str) -> (Mesh, curves_util::Loaded) {
    let l = curves_util::load(name);
    let (mesh, _) = l.leaf.extract(None, &MeshOptions::default()).unwrap();
    (mesh, l)
}

/// A connected component of a mesh.
#[derive(Debug)]
struct Component {
    triangles: usize,
    /// `V − E + F`.
    euler: i64,
    /// Enclosed volume (divergence theorem; the mesh is closed).
    volume: f32,
}

/// Connected components (by shared vertices, [`Mesh::components`]), largest first.
fn components(m: &Mesh) -> Vec<Component> {
    let (labels, count) = m.components();
    // (vertices, edges, faces, volume) per component.
    let mut per = vec![(0i64, 0i64, 0i64, 0f32); count];
    let mut edges = Vec::new();
    let mut seen = vec![false; m.positions.len()];
    for (t, &l) in m.triangles.iter().zip(&labels) {
        let c = &mut per[l as usize];
        c.2 += 1;
        let [a, b, cc] = t.map(|v| m.position(v));
        c.3 += a.dot(b.cross(cc)) / 6.0;
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.push((a.min(b), a.max(b), l));
            if !seen[a as usize] {
                seen[a as usize] = true;
                c.0 += 1;
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    for (_, _, l) in edges {
        per[l as usize].1 += 1;
    }
    let mut out: Vec<Component> = per
        .into_iter()
        .map(|(v, e, f, volume)| Component {
            triangles: f as usize,
            euler: v - e + f,
            volume,
        })
        .collect();
    out.sort_unstable_by_key(|m| std::cmp::Reverse(m.triangles));
    out
}

/// Genus of a closed mesh that is one piece (no spurious blob of rock or air), up to
/// flat specks enclosing under a hundredth of a voxel (where a seed curve runs along a
/// row of grid nodes on a sharp edge, S is 0 up to rounding there, and Marching Cubes
/// can close a sliver around a node).
fn genus(m: &Mesh, h: f32) -> i64 {
    m.check_topology(None)
        .expect("the mesh is closed and manifold");
    let comps = components(m);
    let pieces: Vec<&Component> = comps
        .iter()
        .filter(|c| c.volume.abs() > 0.01 * h * h * h)
        .collect();
    assert_eq!(
        pieces.len(),
        1,
        "one piece, not {:?}",
        &comps[..comps.len().min(6)]
    );
    (2 - pieces[0].euler) / 2
}

/// Triangles bucketed in cubes of side `cell`, for nearest-triangle queries.
struct Buckets<'m> {
    mesh: &'m Mesh,
    cell: f32,
    map: HashMap<IVec3, Vec<usize>>,
}

impl<'m> Buckets<'m> {
    fn new(mesh: &'m Mesh, cell: f32) -> Self {
        let mut map: HashMap<IVec3, Vec<usize>> = HashMap::new();
        for (i, t) in mesh.triangles.iter().enumerate() {
            let ps = t.map(|v| mesh.position(v));
            let lo = (ps[0].min(ps[1]).min(ps[2]) / cell).floor().as_ivec3();
            let hi = (ps[0].max(ps[1]).max(ps[2]) / cell).floor().as_ivec3();
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        map.entry(IVec3::new(x, y, z)).or_default().push(i);
                    }
                }
            }
        }
        Buckets { mesh, cell, map }
    }

    /// Distance from `p` to the mesh, or `cell` when it is farther than that.
    fn distance(&self, p: Vec3) -> f32 {
        let c = (p / self.cell).floor().as_ivec3();
        let mut best = self.cell;
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    for &i in self
                        .map
                        .get(&(c + IVec3::new(dx, dy, dz)))
                        .into_iter()
                        .flatten()
                    {
                        let [a, b, cc] = self.mesh.triangles[i].map(|v| self.mesh.position(v));
                        best = best.min(p.distance(closest_on_triangle(p, [a, b, cc])));
                    }
                }
            }
        }
        best
    }
}

/// Every seed curve sample away from the domain's faces lies within one voxel of the mesh.
fn assert_mesh_through_seeds(mesh: &Mesh, l: &curves_util::Loaded) {
    let h = l.spec.voxel.0;
    let d = l.leaf.params().domain;
    let m = l.leaf.params().falloff + 2.0 * h;
    let buckets = Buckets::new(mesh, 2.0 * h);
    let samples: Vec<Vec3> = l
        .features
        .seed_samples(0.5 * h, l.spec.ribbon_width())
        .into_iter()
        .map(|s| s.pos)
        .filter(|p| p.cmpge(d.min + m).all() && p.cmple(d.max - m).all())
        .collect();
    assert!(samples.len() > 20);
    let far: Vec<(Vec3, f32)> = samples
        .iter()
        .map(|&p| (p, buckets.distance(p)))
        .filter(|&(_, dist)| dist > h)
        .collect();
    assert!(
        far.is_empty(),
        "{} of {} seed samples are more than a voxel from the mesh: {:?}",
        far.len(),
        samples.len(),
        &far[..far.len().min(8)]
    );
}

/// True when the segment `p → q` crosses a triangle (Möller–Trumbore).
fn segment_hits(mesh: &Mesh, p: Vec3, q: Vec3) -> bool {
    let dir = q - p;
    mesh.triangles.iter().any(|t| {
        let [a, b, c] = t.map(|v| mesh.position(v));
        let (e1, e2) = (b - a, c - a);
        let pv = dir.cross(e2);
        let det = e1.dot(pv);
        if det.abs() < 1e-12 {
            return false;
        }
        let inv = 1.0 / det;
        let tv = p - a;
        let u = tv.dot(pv) * inv;
        let qv = tv.cross(e1);
        let v = dir.dot(qv) * inv;
        let s = e2.dot(qv) * inv;
        (0.0..=1.0).contains(&u) && v >= 0.0 && u + v <= 1.0 && (0.0..=1.0).contains(&s)
    })
}

#[test]
fn arch_mesh_has_a_hole_under_the_span() {
    let (mesh, l) = meshed("arch");
    assert!(mesh.triangles.len() > 1000);
    assert_eq!(
        genus(&mesh, l.spec.voxel.0),
        1,
        "the arch's surface has one handle"
    );
    assert!(
        !segment_hits(
            &mesh,
            Vec3::new(64.0, 30.0, 26.0),
            Vec3::new(64.0, 98.0, 26.0)
        ),
        "a ray under the span, across it, crosses no triangle"
    );
    assert_mesh_through_seeds(&mesh, &l);
}

#[test]
fn tunnel_meshes_are_pierced_along_their_axes() {
    for (name, handles) in [("tunnel", 1), ("branching_tunnel", 2)] {
        let (mesh, l) = meshed(name);
        assert_eq!(genus(&mesh, l.spec.voxel.0), handles, "{name}: handles");
        let d = l.leaf.params().domain;
        for t in &l.features.tunnels {
            let pts: Vec<Vec3> = (0..=200)
                .map(|i| t.path.eval(i as f32 / 200.0))
                .filter(|p| d.contains(*p))
                .collect();
            assert!(
                pts.windows(2).all(|w| !segment_hits(&mesh, w[0], w[1])),
                "{name}: the axis crosses the surface"
            );
        }
        assert_mesh_through_seeds(&mesh, &l);
    }
}

/// The other scenes: closed, one piece, no handle (they are terrains), and through their
/// seed curves.
#[test]
fn every_scene_meshes_to_one_closed_piece() {
    for name in [
        "cliff",
        "overhang",
        "ridge",
        "ridges",
        "riverbed",
        "hill",
        "serpentine",
        "expansion",
    ] {
        let (mesh, l) = meshed(name);
        assert_eq!(genus(&mesh, l.spec.voxel.0), 0, "{name}");
        assert_mesh_through_seeds(&mesh, &l);
    }
}

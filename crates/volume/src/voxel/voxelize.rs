//! Voxelization (Becher 2016 §4.2): every node whose cell (the cube of side `h` centred on
//! it) intersects a proxy triangle gathers the triangle's normal, bitangent (left and
//! right separately) and noise parameters; the gathered values are then averaged, with
//! the sign-invariant bitangent pairing of §4.2.1. Nodes touched by seed triangles get
//! a surface value: the signed distance to the plane of the *nearest* seed triangle (the
//! thesis writes 0; the distance keeps sub-voxel precision and is 0 on the triangle).
//!
//! The averages are weighted by `1 / (d + h/4)²`, `d` the node's distance to the
//! triangle: equal weights where ribbons meet on a curve's spine (the thesis's average),
//! but on coarse levels, where one cell may hold a tunnel's floor *and* ceiling, the
//! nearest triangle dominates instead of cancelling out.
//!
//! Triangles are processed in parallel; contributions are sorted by node and triangle
//! before they are summed, so the result does not depend on the thread count.

use glam::{IVec3, Vec2, Vec3};
use rayon::prelude::*;

use super::sparse::LevelGeom;
use crate::curves::{ProxyMesh, Side};

/// The averaged constraints of one node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Constraint {
    /// Node coordinates.
    pub node: IVec3,
    /// Unit normal (zero when the gathered normals cancel out).
    pub normal: Vec3,
    /// Unit bitangent (sign-invariant average; zero if none).
    pub bitangent: Vec3,
    /// Mean `(α, β)`.
    pub noise: Vec2,
    /// Signed distance to the seed triangles' planes, when a seed triangle touches it.
    pub seed: Option<f32>,
}

#[derive(Clone, Copy, Default)]
struct Gather {
    normal: Vec3,
    left: Vec3,
    right: Vec3,
    noise: Vec2,
    weight: f32,
    /// Distance to the nearest seed triangle (infinite when none) and its plane distance.
    seed_dist: f32,
    seed: f32,
}

/// The point of triangle `t` closest to `p` (Ericson, Real-Time Collision Detection 5.1.5).
pub fn closest_on_triangle(p: Vec3, t: [Vec3; 3]) -> Vec3 {
    let [a, b, c] = t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let den = 1.0 / (va + vb + vc);
    a + ab * (vb * den) + ac * (vc * den)
}

/// Triangle–box overlap by the separating axis theorem (Akenine-Möller): box centred at
/// `c` with half-size `e`.
pub fn tri_box(c: Vec3, e: f32, tri: [Vec3; 3]) -> bool {
    let v = tri.map(|p| p - c);
    let f = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    // Nine edge cross-product axes.
    for fe in f {
        for a in [
            Vec3::new(0.0, -fe.z, fe.y),
            Vec3::new(fe.z, 0.0, -fe.x),
            Vec3::new(-fe.y, fe.x, 0.0),
        ] {
            let p = v.map(|x| x.dot(a));
            let r = e * (a.x.abs() + a.y.abs() + a.z.abs());
            let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
            if lo > r || hi < -r {
                return false;
            }
        }
    }
    // The box's face normals.
    let (lo3, hi3) = (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]));
    for (lo, hi) in lo3.to_array().into_iter().zip(hi3.to_array()) {
        if lo > e || hi < -e {
            return false;
        }
    }
    // The triangle's plane.
    let n = f[0].cross(f[1]);
    let d = n.dot(v[0]);
    let r = e * (n.x.abs() + n.y.abs() + n.z.abs());
    d.abs() <= r
}

/// Gathers and averages the mesh's attributes on the nodes of `geom`, sorted by node
/// `(z, y, x)`.
pub fn voxelize(mesh: &ProxyMesh, geom: &LevelGeom) -> Vec<Constraint> {
    let h = geom.h;
    let mut contrib: Vec<(u64, u32, Gather)> = (0..mesh.triangles.len())
        .into_par_iter()
        .flat_map_iter(|ti| {
            let t = mesh.triangles[ti];
            let [a, b, c] = mesh.triangle(ti);
            let tri = [a.pos, b.pos, c.pos];
            let mut out = Vec::new();
            let vn = (a.normal + b.normal + c.normal).normalize_or_zero();
            let mut geo = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero();
            if geo.dot(vn) < 0.0 {
                geo = -geo;
            }
            if geo == Vec3::ZERO {
                geo = vn;
            }
            let bt = (a.bitangent + b.bitangent + c.bitangent).normalize_or_zero();
            let noise = (a.noise + b.noise + c.noise) / 3.0;
            let lo = tri[0].min(tri[1]).min(tri[2]);
            let hi = tri[0].max(tri[1]).max(tri[2]);
            let glo = (((lo - geom.origin) / h - 0.5).ceil().as_ivec3()).max(IVec3::ZERO);
            let ghi =
                (((hi - geom.origin) / h + 0.5).floor().as_ivec3()).min(geom.dims - IVec3::ONE);
            for z in glo.z..=ghi.z {
                for y in glo.y..=ghi.y {
                    for x in glo.x..=ghi.x {
                        let g = IVec3::new(x, y, z);
                        let p = geom.pos(g);
                        // A hair over h/2 so a triangle on a cell face touches both cells.
                        if !tri_box(p, 0.5 * h * 1.0001, tri) {
                            continue;
                        }
                        let d = p.distance(closest_on_triangle(p, tri));
                        let w = 1.0 / ((d + 0.25 * h) * (d + 0.25 * h));
                        let mut gth = Gather {
                            normal: vn * w,
                            noise: noise * w,
                            weight: w,
                            seed_dist: f32::INFINITY,
                            ..Default::default()
                        };
                        match t.side {
                            Side::Left | Side::Face => gth.left = bt * w,
                            Side::Right => gth.right = bt * w,
                        }
                        if t.seed {
                            gth.seed = (p - tri[0]).dot(geo);
                            gth.seed_dist = d;
                        }
                        let key = x as u64
                            + geom.dims.x as u64 * (y as u64 + geom.dims.y as u64 * z as u64);
                        out.push((key, ti as u32, gth));
                    }
                }
            }
            out.into_iter()
        })
        .collect();
    contrib.par_sort_unstable_by_key(|&(k, t, _)| (k, t));
    let mut out = Vec::new();
    let mut i = 0;
    while i < contrib.len() {
        let key = contrib[i].0;
        let mut s = Gather {
            seed_dist: f32::INFINITY,
            ..Default::default()
        };
        while i < contrib.len() && contrib[i].0 == key {
            let g = &contrib[i].2;
            s.normal += g.normal;
            s.left += g.left;
            s.right += g.right;
            s.noise += g.noise;
            s.weight += g.weight;
            if g.seed_dist < s.seed_dist {
                (s.seed_dist, s.seed) = (g.seed_dist, g.seed);
            }
            i += 1;
        }
        let (dx, dy) = (geom.dims.x as u64, geom.dims.y as u64);
        let node = IVec3::new(
            (key % dx) as i32,
            ((key / dx) % dy) as i32,
            (key / (dx * dy)) as i32,
        );
        out.push(Constraint {
            node,
            normal: s.normal.normalize_or_zero(),
            bitangent: pair_bitangents(s.left.normalize_or_zero(), s.right.normalize_or_zero()),
            noise: s.noise / s.weight,
            seed: s.seed_dist.is_finite().then_some(s.seed),
        });
    }
    out
}

/// The sign-invariant average of a left and a right bitangent (§4.2.1): their sum, or
/// their difference when they are more than 90° apart.
pub fn pair_bitangents(left: Vec3, right: Vec3) -> Vec3 {
    if left.dot(right) < 0.0 {
        (left - right).normalize_or_zero()
    } else {
        (left + right).normalize_or_zero()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curves::{ProxyMesh, Quad};

    #[test]
    fn tri_box_agrees_with_sampling() {
        let tri = [
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(2.3, 0.4, 1.1),
            Vec3::new(0.5, 1.9, -0.7),
        ];
        for i in 0..2000 {
            let c = Vec3::new(
                (i % 13) as f32 * 0.25 - 0.5,
                ((i / 13) % 13) as f32 * 0.25 - 0.5,
                (i / 169) as f32 * 0.25 - 1.0,
            );
            let hit = tri_box(c, 0.125, tri);
            // A sampled point of the triangle inside the box proves overlap.
            let mut sampled = false;
            for a in 0..=40 {
                for b in 0..=(40 - a) {
                    let p = tri[0]
                        + (tri[1] - tri[0]) * (a as f32 / 40.0)
                        + (tri[2] - tri[0]) * (b as f32 / 40.0);
                    sampled |= ((p - c).abs().max_element()) <= 0.125;
                }
            }
            if sampled {
                assert!(hit, "missed overlap at {c}");
            }
        }
    }

    #[test]
    fn closest_point_agrees_with_sampling() {
        let tri = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(3.0, 0.5, 0.2),
            Vec3::new(0.7, 2.0, -0.4),
        ];
        for i in 0..300 {
            let p = Vec3::new(
                (i as f32 * 0.37).sin() * 4.0,
                (i as f32 * 0.91).cos() * 4.0,
                (i % 9) as f32 - 4.0,
            );
            let d = p.distance(closest_on_triangle(p, tri));
            let mut best = f32::INFINITY;
            for a in 0..=60 {
                for b in 0..=(60 - a) {
                    let q = tri[0]
                        + (tri[1] - tri[0]) * (a as f32 / 60.0)
                        + (tri[2] - tri[0]) * (b as f32 / 60.0);
                    best = best.min(p.distance(q));
                }
            }
            assert!(d <= best + 1e-4 && d >= best - 0.05, "{d} vs {best}");
        }
    }

    #[test]
    fn the_nearest_seed_wins_where_sheets_share_a_cell() {
        // A floor at z = 0.1 (normal up) and a ceiling at z = 0.7 (normal down) in the
        // same cell of size 2: the node at z = 0 is below the floor, in the rock.
        let quad = |z: f32, up: bool| {
            let mut c = [
                Vec3::new(-3.0, -3.0, z),
                Vec3::new(3.0, -3.0, z),
                Vec3::new(3.0, 3.0, z),
                Vec3::new(-3.0, 3.0, z),
            ];
            if !up {
                c.reverse();
            }
            Quad {
                corners: c,
                seed: true,
                noise: Vec2::ZERO,
            }
            .proxy()
        };
        let mut mesh = quad(0.1, true);
        mesh.append(&quad(0.7, false));
        let geom = LevelGeom {
            origin: Vec3::splat(-4.0),
            h: 2.0,
            dims: IVec3::splat(5),
        };
        let c = voxelize(&mesh, &geom);
        let centre = c.iter().find(|k| k.node == IVec3::splat(2)).unwrap();
        assert!((centre.seed.unwrap() - -0.1).abs() < 1e-5);
        assert!(
            centre.normal.z > 0.5,
            "the nearer floor dominates: {}",
            centre.normal
        );
    }

    #[test]
    fn a_flat_quad_marks_one_layer_with_plane_distances() {
        let mut mesh = ProxyMesh::default();
        mesh.append(
            &Quad {
                corners: [
                    Vec3::new(0.0, 0.0, 2.3),
                    Vec3::new(6.0, 0.0, 2.3),
                    Vec3::new(6.0, 6.0, 2.3),
                    Vec3::new(0.0, 6.0, 2.3),
                ],
                seed: true,
                noise: Vec2::new(1.0, 0.5),
            }
            .proxy(),
        );
        let geom = LevelGeom {
            origin: Vec3::ZERO,
            h: 1.0,
            dims: IVec3::splat(8),
        };
        let c = voxelize(&mesh, &geom);
        assert_eq!(c.len(), 7 * 7, "one layer of nodes: z = 2 (cell 1.5..2.5)");
        for k in &c {
            assert_eq!(k.node.z, 2);
            assert!((k.seed.unwrap() - (-0.3)).abs() < 1e-5);
            assert_eq!(k.normal, Vec3::Z);
            assert_eq!(k.noise, Vec2::new(1.0, 0.5));
        }
        assert!(
            c.windows(2).all(|w| (w[0].node.z, w[0].node.y, w[0].node.x)
                < (w[1].node.z, w[1].node.y, w[1].node.x))
        );
    }
}

//! Marching Cubes case tables, generated once from the cube's geometry.
//!
//! Instead of the classic hand-written 256-entry table (whose complementary cases crack
//! across shared faces), the triangulation of every case is *derived*: on each of the six
//! faces the corner signs give one or two iso-segments, the segments chain into closed
//! loops on the cube's surface, and each loop is triangulated without a diagonal inside a
//! face (see [`triangulate`]). A face with four
//! crossings (two diagonal solid corners) is ambiguous; the caller decides it with the
//! asymptotic decider ([`crate::mesh::cell::ambiguity_mask`]) and passes one bit per
//! ambiguous face, so every case has `2^n` variants for its `n ≤ 6` ambiguous faces.
//! Because a face's segments depend only on that face's four corner values, the two cells
//! sharing a face always cut it the same way and the mesh cannot crack. Inside a cell,
//! loops are capped by discs (no tunnels through a cell, unlike MC33's interior tests),
//! which keeps the surface a 2-manifold.
//!
//! Corner `c` of a cell sits at offset `(c & 1, c >> 1 & 1, c >> 2 & 1)`; bit `c` of the
//! case index is set when corner `c` is solid (`f > T`). Triangles are wound
//! counter-clockwise seen from outside the solid.

use std::sync::LazyLock;

/// Corner pair of each of the 12 edges: x-edges 0–3, y-edges 4–7, z-edges 8–11.
pub const EDGE_CORNERS: [[u8; 2]; 12] = [
    [0, 1],
    [2, 3],
    [4, 5],
    [6, 7],
    [0, 2],
    [1, 3],
    [4, 6],
    [5, 7],
    [0, 4],
    [1, 5],
    [2, 6],
    [3, 7],
];

/// Axis of each edge (0 = x, 1 = y, 2 = z).
pub const EDGE_AXIS: [u8; 12] = [0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2];

/// The four corners of each face `2·axis + side`, in increasing index order, i.e. at local
/// face coordinates `(0,0), (1,0), (0,1), (1,1)` along the face's two other axes in
/// increasing axis order. Both cells sharing a face list the same grid points in the same
/// order, which keeps floating-point decisions on the face identical.
pub const FACE_CORNERS: [[u8; 4]; 6] = face_corners();

const fn face_corners() -> [[u8; 4]; 6] {
    let mut out = [[0u8; 4]; 6];
    let mut f = 0;
    while f < 6 {
        let (axis, side) = (f / 2, (f % 2) as u8);
        let mut n = 0;
        let mut c = 0u8;
        while c < 8 {
            if (c >> axis) & 1 == side {
                out[f][n] = c;
                n += 1;
            }
            c += 1;
        }
        f += 1;
    }
    out
}

/// One case of the table: which faces are ambiguous and where its variants start.
#[derive(Clone, Copy, Debug, Default)]
pub struct Case {
    /// Bit `e` set when edge `e` is crossed.
    pub edges: u16,
    /// Number of ambiguous faces.
    pub n_ambiguous: u8,
    /// The ambiguous faces, in increasing face order.
    pub ambiguous: [u8; 6],
    /// Index of variant 0 in [`Tables::variants`].
    pub first_variant: u32,
}

/// The generated tables.
pub struct Tables {
    /// One entry per case index.
    pub cases: [Case; 256],
    /// `(start, count)` into [`Tables::triangles`] per (case, ambiguity mask).
    pub variants: Vec<(u32, u32)>,
    /// Triangles as edge triples.
    pub triangles: Vec<[u8; 3]>,
}

impl Tables {
    /// The triangles of `case` when its ambiguous faces are decided by `mask`
    /// (bit `n` set: the solid corners of the `n`-th ambiguous face are connected).
    #[inline]
    pub fn triangles(&self, case: usize, mask: usize) -> &[[u8; 3]] {
        let (s, n) = self.variants[self.cases[case].first_variant as usize + mask];
        &self.triangles[s as usize..(s + n) as usize]
    }
}

/// The tables, built on first use.
pub static TABLES: LazyLock<Tables> = LazyLock::new(build);

fn corner_pos(c: u8) -> [f32; 3] {
    [(c & 1) as f32, ((c >> 1) & 1) as f32, ((c >> 2) & 1) as f32]
}

fn edge_mid(e: u8) -> [f32; 3] {
    let [a, b] = EDGE_CORNERS[e as usize];
    let (p, q) = (corner_pos(a), corner_pos(b));
    [
        (p[0] + q[0]) / 2.0,
        (p[1] + q[1]) / 2.0,
        (p[2] + q[2]) / 2.0,
    ]
}

fn edge_between(a: u8, b: u8) -> u8 {
    EDGE_CORNERS
        .iter()
        .position(|&[p, q]| (p, q) == (a, b) || (p, q) == (b, a))
        .expect("corners of a face edge") as u8
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The oriented iso-segments of face `f` for `case`: `n × (to − from)` points away from
/// the solid side, where `n` is the face's outward normal. Chained around the cube this
/// winds every loop counter-clockwise seen from outside the solid.
fn face_segments(case: usize, f: usize, connected: bool, out: &mut Vec<(u8, u8)>) {
    let q = FACE_CORNERS[f];
    let cyc = [q[0], q[1], q[3], q[2]];
    let solid = |c: u8| case >> c & 1 == 1;
    let s: Vec<bool> = cyc.iter().map(|&c| solid(c)).collect();
    let fe: Vec<u8> = (0..4)
        .map(|i| edge_between(cyc[i], cyc[(i + 1) % 4]))
        .collect();
    let (axis, side) = (f / 2, f % 2);
    let mut n = [0.0; 3];
    n[axis] = if side == 1 { 1.0 } else { -1.0 };
    let center = {
        let p = q.map(corner_pos);
        [0, 1, 2].map(|k| p.iter().map(|v| v[k]).sum::<f32>() / 4.0)
    };
    let n_solid = s.iter().filter(|&&b| b).count();
    let crossings = (0..4).filter(|&i| s[i] != s[(i + 1) % 4]).count();
    // Each segment cuts the corner `i` off the face between edges fe[i-1] and fe[i], or
    // (2–2 adjacent split) joins two opposite edges; `reference` lies on the solid side.
    let mut push = |a: u8, b: u8, reference: [f32; 3]| {
        let (pa, pb) = (edge_mid(a), edge_mid(b));
        let side_dir = cross(n, sub(pb, pa));
        if dot(side_dir, sub(reference, pa)) > 0.0 {
            out.push((b, a));
        } else {
            out.push((a, b));
        }
    };
    match crossings {
        0 => {}
        2 => {
            let cut: Vec<usize> = (0..4).filter(|&i| s[i] != s[(i + 1) % 4]).collect();
            let (a, b) = (fe[cut[0]], fe[cut[1]]);
            let reference = match n_solid {
                1 => corner_pos(cyc[(0..4).find(|&i| s[i]).unwrap()]),
                3 => center,
                _ => {
                    let p: Vec<[f32; 3]> = (0..4)
                        .filter(|&i| s[i])
                        .map(|i| corner_pos(cyc[i]))
                        .collect();
                    [0, 1, 2].map(|k| (p[0][k] + p[1][k]) / 2.0)
                }
            };
            push(a, b, reference);
        }
        4 => {
            // Connected solid: cut the empty corners off; separated: cut the solid ones.
            for i in 0..4 {
                if s[i] != connected {
                    let reference = if s[i] { corner_pos(cyc[i]) } else { center };
                    push(fe[(i + 3) % 4], fe[i], reference);
                }
            }
        }
        _ => unreachable!("a face has an even number of crossings"),
    }
}

fn variant_triangles(case: usize, ambiguous: &[u8], mask: usize) -> Vec<[u8; 3]> {
    let mut segments = Vec::new();
    for f in 0..6 {
        let connected = ambiguous
            .iter()
            .position(|&a| a as usize == f)
            .is_some_and(|n| mask >> n & 1 == 1);
        face_segments(case, f, connected, &mut segments);
    }
    let mut next = [u8::MAX; 12];
    let mut incoming = [0u8; 12];
    for &(a, b) in &segments {
        assert_eq!(
            next[a as usize],
            u8::MAX,
            "case {case}: edge {a} starts two segments"
        );
        next[a as usize] = b;
        incoming[b as usize] += 1;
    }
    let ambiguous_faces = ambiguous.iter().fold(0u8, |m, &f| m | 1 << f);
    let mut tris = Vec::new();
    let mut seen = [false; 12];
    for start in 0..12u8 {
        if next[start as usize] == u8::MAX || seen[start as usize] {
            continue;
        }
        let mut lp = vec![start];
        seen[start as usize] = true;
        let mut e = next[start as usize];
        while e != start {
            assert!(
                incoming[e as usize] == 1 && !seen[e as usize],
                "case {case}: broken loop"
            );
            seen[e as usize] = true;
            lp.push(e);
            e = next[e as usize];
        }
        if !triangulate(&lp, ambiguous_faces, &mut tris) {
            panic!("case {case} mask {mask}: loop {lp:?} has no triangulation off the faces");
        }
    }
    tris
}

/// Bit `f` set when edge `e` lies on face `f`.
fn edge_faces(e: u8) -> u8 {
    let [a, b] = EDGE_CORNERS[e as usize];
    (0..6)
        .filter(|&f| FACE_CORNERS[f].contains(&a) && FACE_CORNERS[f].contains(&b))
        .fold(0, |m, f| m | 1 << f)
}

/// True when a diagonal joining the vertices on edges `a` and `b` may be drawn inside a cell,
/// given its faces with four crossings (`ambiguous`, a face mask).
///
/// Two vertices of one face are either a loop segment (the face has two crossings) or, on
/// a face with four crossings, may be joined by a diagonal lying in that face. If the
/// cells on both sides of the face drew the same diagonal, its edge would have four
/// triangles (a non-manifold mesh: seen on a noisy carve, where a plain fan ran the same
/// diagonal across a face from both cells). So the diagonals of a face are split between
/// its two cells: the cell below the face (for which it is an upper face) draws those
/// that touch the face's first edge (between its corners 0 and 1 of [`FACE_CORNERS`],
/// the same grid edge seen from both cells), the cell above draws the others.
fn diagonal_allowed(a: u8, b: u8, ambiguous: u8) -> bool {
    let shared = edge_faces(a) & edge_faces(b) & ambiguous;
    if shared == 0 {
        return true;
    }
    let f = shared.trailing_zeros() as usize;
    let [c0, c1, ..] = FACE_CORNERS[f];
    let first = edge_between(c0, c1);
    let touches_first = a == first || b == first;
    let upper = f % 2 == 1;
    touches_first == upper
}

/// Triangulates the loop `lp` (edge ids, in order) into `out` with diagonals allowed by
/// [`diagonal_allowed`]. Returns false when there is no such triangulation (never, for
/// the cube's loops: the tests build every variant).
fn triangulate(lp: &[u8], ambiguous: u8, out: &mut Vec<[u8; 3]>) -> bool {
    let n = lp.len();
    // `ok(i, j)`: `lp[i]`–`lp[j]` may be a triangle side (a loop segment or a diagonal off
    // the faces).
    let ok = |i: usize, j: usize| {
        let d = i.abs_diff(j);
        d == 1 || d == n - 1 || diagonal_allowed(lp[i], lp[j], ambiguous)
    };
    // Triangulates the sub-polygon `lp[i..=j]` closed by the side `i`–`j`.
    fn sub(
        lp: &[u8],
        i: usize,
        j: usize,
        ok: &dyn Fn(usize, usize) -> bool,
        out: &mut Vec<[u8; 3]>,
    ) -> bool {
        if j - i < 2 {
            return true;
        }
        let mark = out.len();
        for k in i + 1..j {
            if ok(i, k) && ok(k, j) {
                out.push([lp[i], lp[k], lp[j]]);
                if sub(lp, i, k, ok, out) && sub(lp, k, j, ok, out) {
                    return true;
                }
                out.truncate(mark);
            }
        }
        false
    }
    sub(lp, 0, n - 1, &ok, out)
}

fn build() -> Tables {
    let mut cases = [Case::default(); 256];
    let mut variants = Vec::new();
    let mut triangles = Vec::new();
    for (case, entry) in cases.iter_mut().enumerate() {
        let solid = |c: u8| case >> c & 1 == 1;
        let mut edges = 0u16;
        for (e, &[a, b]) in EDGE_CORNERS.iter().enumerate() {
            if solid(a) != solid(b) {
                edges |= 1 << e;
            }
        }
        let mut ambiguous = [0u8; 6];
        let mut n = 0;
        for (f, q) in FACE_CORNERS.iter().enumerate() {
            let s = q.map(solid);
            if s[0] == s[3] && s[1] == s[2] && s[0] != s[1] {
                ambiguous[n] = f as u8;
                n += 1;
            }
        }
        *entry = Case {
            edges,
            n_ambiguous: n as u8,
            ambiguous,
            first_variant: variants.len() as u32,
        };
        for mask in 0..1usize << n {
            let tris = variant_triangles(case, &ambiguous[..n], mask);
            variants.push((triangles.len() as u32, tris.len() as u32));
            triangles.extend(tris);
        }
    }
    Tables {
        cases,
        variants,
        triangles,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_and_full_cells_have_no_triangles() {
        assert!(TABLES.triangles(0, 0).is_empty());
        assert!(TABLES.triangles(255, 0).is_empty());
    }

    #[test]
    fn single_corner_is_one_outward_triangle() {
        // Corner 0 solid: the triangle must face away from the origin (+x+y+z).
        let t = TABLES.triangles(1, 0);
        assert_eq!(t.len(), 1);
        let [a, b, c] = t[0].map(edge_mid);
        let nrm = cross(sub(b, a), sub(c, a));
        assert!(dot(nrm, [1.0, 1.0, 1.0]) > 0.0, "{t:?}");
    }

    #[test]
    fn every_variant_uses_each_crossed_edge_and_only_those() {
        for case in 0..256 {
            let c = TABLES.cases[case];
            for mask in 0..1 << c.n_ambiguous {
                let mut used = 0u16;
                for t in TABLES.triangles(case, mask) {
                    assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
                    for &e in t {
                        used |= 1 << e;
                    }
                }
                assert_eq!(used, c.edges, "case {case} mask {mask}");
            }
        }
    }

    /// Sides drawn by two triangles of `case`/`mask` (diagonals) with both ends on face
    /// `f`, as pairs of the face's local corner indices `(i, j)` of [`FACE_CORNERS`].
    fn face_diagonals(case: usize, mask: usize, f: usize) -> Vec<[(usize, usize); 2]> {
        let local = |e: u8| {
            let [a, b] = EDGE_CORNERS[e as usize];
            let q = FACE_CORNERS[f];
            let (i, j) = (
                q.iter().position(|&c| c == a),
                q.iter().position(|&c| c == b),
            );
            i.zip(j).map(|(i, j)| (i.min(j), i.max(j)))
        };
        let tris = TABLES.triangles(case, mask);
        let sides: Vec<(u8, u8)> = tris
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .map(|(a, b)| (a.min(b), a.max(b)))
            .collect();
        let mut out: Vec<[(usize, usize); 2]> = sides
            .iter()
            .filter(|&&s| sides.iter().filter(|&&t| t == s).count() == 2)
            .filter_map(|&(a, b)| Some([local(a)?, local(b)?]))
            .map(|mut d| {
                d.sort();
                d
            })
            .collect();
        out.dedup();
        out
    }

    #[test]
    fn cells_sharing_a_face_never_draw_the_same_diagonal_in_it() {
        let solid = |case: usize, c: u8| case >> c & 1 == 1;
        let mut shared_ambiguous = 0;
        for axis in 0..3 {
            let (up, down) = (2 * axis + 1, 2 * axis);
            for a in 0..256 {
                for b in 0..256 {
                    let same = (0..4)
                        .all(|i| solid(a, FACE_CORNERS[up][i]) == solid(b, FACE_CORNERS[down][i]));
                    let (ca, cb) = (TABLES.cases[a], TABLES.cases[b]);
                    let slot = |c: Case, f: usize| {
                        c.ambiguous[..c.n_ambiguous as usize]
                            .iter()
                            .position(|&g| g as usize == f)
                    };
                    let (Some(sa), Some(sb)) = (slot(ca, up), slot(cb, down)) else {
                        continue;
                    };
                    if !same {
                        continue;
                    }
                    shared_ambiguous += 1;
                    for ma in 0..1usize << ca.n_ambiguous {
                        for mb in 0..1usize << cb.n_ambiguous {
                            // Both cells decide the shared face the same way.
                            if (ma >> sa & 1) != (mb >> sb & 1) {
                                continue;
                            }
                            let (da, db) = (face_diagonals(a, ma, up), face_diagonals(b, mb, down));
                            assert!(
                                da.iter().all(|d| !db.contains(d)),
                                "cases {a}/{b} masks {ma}/{mb}: both draw {da:?} / {db:?}"
                            );
                        }
                    }
                }
            }
        }
        assert!(shared_ambiguous > 0);
    }

    #[test]
    fn complement_cases_reverse_winding_with_flipped_decisions() {
        // Swapping solid and empty flips orientation; deciding "connected" for the old
        // solid corners is deciding "separated" for the new ones.
        for case in 0..256usize {
            let c = TABLES.cases[case];
            let all = (1usize << c.n_ambiguous) - 1;
            for mask in 0..=all {
                let mut a: Vec<[u8; 3]> = TABLES.triangles(case, mask).to_vec();
                let mut b: Vec<[u8; 3]> = TABLES
                    .triangles(255 - case, all ^ mask)
                    .iter()
                    .map(|t| [t[0], t[2], t[1]])
                    .collect();
                let edges = |v: &mut Vec<[u8; 3]>| {
                    let mut e: Vec<(u8, u8)> = v
                        .iter()
                        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
                        .collect();
                    e.sort();
                    e
                };
                // Same boundary loops, reversed: compare directed boundary edges of the fans.
                let (ea, eb) = (edges(&mut a), edges(&mut b));
                let boundary = |e: &[(u8, u8)]| -> Vec<(u8, u8)> {
                    e.iter()
                        .copied()
                        .filter(|&(x, y)| !e.contains(&(y, x)))
                        .collect()
                };
                assert_eq!(boundary(&ea), boundary(&eb), "case {case} mask {mask}");
            }
        }
    }
}

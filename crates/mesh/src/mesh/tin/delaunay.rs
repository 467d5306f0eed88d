//! A Delaunay triangulation of grid points in flat half-edge arrays, grown by inserting
//! points into known triangles and legalising the edges around them by flips (Lawson's
//! incremental algorithm, as Garland & Heckbert 1995 use it).
//!
//! Triangle `t` owns half-edges `4t`, `4t + 1` and `4t + 2`, counter-clockwise; a
//! half-edge has an origin vertex and a twin (the same edge in the neighbouring triangle,
//! [`NONE`] on the boundary). A triangle's corners, twins and its owner's two words of
//! data fill one 32-byte record: an insertion's reads of a triangle and its neighbours
//! take a cache line each. Triangles are never deleted: an insertion rewrites the
//! triangle it lands in (and, on an edge, the neighbour across) and appends the rest, and
//! a flip rewrites its two triangles in place, so every slot is a live triangle.

/// The twin of a boundary half-edge.
const NONE: u32 = u32::MAX;

/// The next half-edge of the same triangle.
fn next(e: u32) -> u32 {
    if e & 3 == 2 { e - 2 } else { e + 1 }
}

/// A triangle: its half-edges' origins and twins, and two words of the owner's.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct Tri {
    start: [u32; 3],
    /// The owner's word (the greedy insertion: the worst grid point's index).
    pub a: u32,
    twin: [u32; 3],
    /// The owner's other word (the greedy insertion: the worst grid point's height, as
    /// f32 bits).
    pub b: u32,
}

impl Tri {
    const EMPTY: Tri = Tri {
        start: [NONE; 3],
        a: 0,
        twin: [NONE; 3],
        b: 0,
    };
}

/// A vertex: a grid point and its height, together so that the scans of the triangles
/// an insertion made find their corners' heights where the insertion read their
/// coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    /// Grid column.
    pub i: i32,
    /// Grid row.
    pub j: i32,
    /// Height, metres.
    pub z: f32,
}

impl Vertex {
    /// The grid coordinates.
    pub fn ij(self) -> [i64; 2] {
        [i64::from(self.i), i64::from(self.j)]
    }
}

/// A triangulation of a rectangle of grid points.
pub struct Triangulation {
    /// The vertices, in insertion order.
    pub vertices: Vec<Vertex>,
    /// The triangles.
    pub tris: Vec<Tri>,
    /// Whether the incircle determinant is exact in f64 (coordinates below 4096).
    exact_f64: bool,
    /// Half-edges to legalise: each is a triangle's first half-edge, the one facing the
    /// inserted vertex.
    stack: Vec<u32>,
}

impl Triangulation {
    /// The two triangles of the rectangle `[0, w] × [0, h]` (`1 ≤ w, h < 2³¹`) with
    /// heights `z` at its corners `(0, 0)`, `(w, 0)`, `(w, h)`, `(0, h)`.
    pub fn rectangle(w: i32, h: i32, z: [f32; 4]) -> Triangulation {
        let mut t = Triangulation {
            vertices: Vec::new(),
            tris: Vec::new(),
            exact_f64: w.max(h) < 4096,
            stack: Vec::new(),
        };
        let corners = [[0, 0], [w, 0], [w, h], [0, h]];
        t.vertices.extend((0..4).map(|k| Vertex {
            i: corners[k][0],
            j: corners[k][1],
            z: z[k],
        }));
        // (0, 1, 2) and (0, 2, 3), sharing the diagonal 2 → 0 / 0 → 2.
        t.tris.extend([
            Tri {
                start: [0, 1, 2],
                twin: [NONE, NONE, 4],
                ..Tri::EMPTY
            },
            Tri {
                start: [0, 2, 3],
                twin: [2, NONE, NONE],
                ..Tri::EMPTY
            },
        ]);
        t
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// Half-edge `e`'s origin.
    fn start(&self, e: u32) -> u32 {
        self.tris[(e >> 2) as usize].start[(e & 3) as usize]
    }

    /// Half-edge `e`'s twin.
    fn twin(&self, e: u32) -> u32 {
        self.tris[(e >> 2) as usize].twin[(e & 3) as usize]
    }

    /// Sets half-edge `e`'s origin.
    fn set_start(&mut self, e: u32, v: u32) {
        self.tris[(e >> 2) as usize].start[(e & 3) as usize] = v;
    }

    /// Sets half-edge `e`'s twin.
    fn set_twin(&mut self, e: u32, f: u32) {
        self.tris[(e >> 2) as usize].twin[(e & 3) as usize] = f;
    }

    /// The vertices of triangle `t`, counter-clockwise.
    pub fn triangle(&self, t: usize) -> [u32; 3] {
        self.tris[t].start
    }

    /// The corners of triangle `t`, counter-clockwise.
    pub fn corners(&self, t: usize) -> [Vertex; 3] {
        // Written out: `array::map` is not always inlined, and its result then goes
        // through memory (a store-forwarding stall).
        let [a, b, c] = self.triangle(t);
        let v = &self.vertices;
        [v[a as usize], v[b as usize], v[c as usize]]
    }

    /// Inserts vertex `p`, whose grid point lies in triangle `t` (inside it or on one of its
    /// edges, not at a corner), keeps the triangulation Delaunay, and appends to `changed`
    /// every triangle that now has `p` as a corner (the new and the rewritten ones).
    pub fn insert(&mut self, t: u32, p: Vertex, changed: &mut Vec<u32>) {
        let v = self.vertices.len() as u32;
        self.vertices.push(p);
        let p = p.ij();
        let Tri {
            start: vs,
            twin: outer,
            ..
        } = self.tris[t as usize];
        // The neighbours' records are read by the fan and the legalisation: asked for now.
        for &f in &outer {
            if f != NONE {
                crate::cache::prefetch(&self.tris[(f >> 2) as usize]);
            }
        }
        let c = vs.map(|u| self.vertices[u as usize].ij());
        let new = self.len() as u32;
        // The edge p lies on, if any: orient(c[k], c[k+1], p) = 0.
        let on = (0..3).find(|&k| orient(c[k], c[(k + 1) % 3], p) == 0);
        match on {
            None => {
                // Inside: the fan (a, b, p), (b, c, p), (c, a, p).
                self.fan(v, &[t, new, new + 1], &vs, &outer, true, changed);
            }
            Some(k) => {
                let (a, b, c) = (vs[k], vs[(k + 1) % 3], vs[(k + 2) % 3]);
                let (o1, o2) = (outer[(k + 1) % 3], outer[(k + 2) % 3]);
                let f = outer[k];
                if f == NONE {
                    // On the boundary: (b, c, p), (c, a, p).
                    self.fan(v, &[t, new], &[b, c, a], &[o1, o2], false, changed);
                } else {
                    // On an inner edge a → b, whose twin b → a has d across:
                    // (b, c, p), (c, a, p), (a, d, p), (d, b, p).
                    let (m1, m2) = (next(f), next(next(f)));
                    let d = self.start(m2);
                    let (q1, q2) = (self.twin(m1), self.twin(m2));
                    let u = f >> 2;
                    self.fan(
                        v,
                        &[t, new, u, new + 1],
                        &[b, c, a, d],
                        &[o1, o2, q1, q2],
                        true,
                        changed,
                    );
                }
            }
        }
        self.legalise(changed);
    }

    /// Writes the fan of triangles `(ring[i], ring[i + 1], v)` into `slots` (appending the
    /// ones past the end), the first edge of each linked to `outer[i]`, the edges between
    /// consecutive triangles linked, the last to the first when `closed`; queues the outer
    /// edges for legalisation.
    fn fan(
        &mut self,
        v: u32,
        slots: &[u32],
        ring: &[u32],
        outer: &[u32],
        closed: bool,
        changed: &mut Vec<u32>,
    ) {
        let n = slots.len();
        let grow = slots.iter().map(|&s| s as usize + 1).max().unwrap_or(0);
        if grow > self.tris.len() {
            self.tris.resize(grow, Tri::EMPTY);
        }
        for i in 0..n {
            let e = 4 * slots[i];
            let (x, y) = (ring[i], ring[(i + 1) % ring.len()]);
            self.tris[slots[i] as usize].start = [x, y, v];
            self.link(e, outer[i]);
            if i + 1 < n {
                self.link(e + 1, 4 * slots[i + 1] + 2);
            } else if closed {
                self.link(e + 1, 4 * slots[0] + 2);
            } else {
                self.set_twin(e + 1, NONE);
                self.set_twin(4 * slots[0] + 2, NONE);
            }
            self.stack.push(e);
            changed.push(slots[i]);
        }
        // The legalisation reads the vertex across each outer edge: asked for now, the
        // misses overlap rather than come one after the other.
        for &f in outer {
            if f != NONE {
                crate::cache::prefetch(&self.vertices[self.start(next(next(f))) as usize]);
            }
        }
    }

    /// Makes `e` and `f` twins (`f` may be [`NONE`]).
    fn link(&mut self, e: u32, f: u32) {
        self.set_twin(e, f);
        if f != NONE {
            self.set_twin(f, e);
        }
    }

    /// Flips the queued edges whose far vertex lies inside the circumcircle of their
    /// triangle, queueing the edges a flip exposes, until none is left.
    fn legalise(&mut self, changed: &mut Vec<u32>) {
        while let Some(e) = self.stack.pop() {
            let f = self.twin(e);
            if f == NONE {
                continue;
            }
            // Triangle (a, b, p) with e = a → b; across it (b, a, d).
            let n1 = e + 1;
            let (m1, m2) = (next(f), next(next(f)));
            let [a, b, p] = self.tris[(e >> 2) as usize].start;
            let d = self.start(m2);
            let [pa, pb, pp, pd] = [a, b, p, d].map(|u| self.vertices[u as usize].ij());
            if !self.in_circle(pa, pb, pp, pd) {
                continue;
            }
            // The edge becomes p–d: (a, d, p) in e's triangle (its p → a is kept), (d, b, p)
            // in f's.
            let (ad, db, bp) = (self.twin(m1), self.twin(m2), self.twin(n1));
            let u = f & !3;
            self.set_start(n1, d);
            self.tris[(f >> 2) as usize].start = [d, b, p];
            self.link(e, ad);
            self.link(u, db);
            self.link(u + 1, bp);
            self.link(n1, u + 2);
            self.stack.extend([e, u]);
            changed.push(f >> 2);
        }
    }

    /// Whether `d` lies strictly inside the circle through `a`, `b`, `c`
    /// (counter-clockwise), exactly.
    fn in_circle(&self, a: [i64; 2], b: [i64; 2], c: [i64; 2], d: [i64; 2]) -> bool {
        let [ax, ay, bx, by, cx, cy] = [
            a[0] - d[0],
            a[1] - d[1],
            b[0] - d[0],
            b[1] - d[1],
            c[0] - d[0],
            c[1] - d[1],
        ];
        if self.exact_f64 {
            // |coordinate differences| < 2¹², so every term below is an integer under 2⁵³.
            let f = |v: i64| v as f64;
            let (ax, ay, bx, by, cx, cy) = (f(ax), f(ay), f(bx), f(by), f(cx), f(cy));
            let (la, lb, lc) = (ax * ax + ay * ay, bx * bx + by * by, cx * cx + cy * cy);
            ax * (by * lc - cy * lb) - ay * (bx * lc - cx * lb) + la * (bx * cy - cx * by) > 0.0
        } else {
            let f = i128::from;
            let (ax, ay, bx, by, cx, cy) = (f(ax), f(ay), f(bx), f(by), f(cx), f(cy));
            let (la, lb, lc) = (ax * ax + ay * ay, bx * bx + by * by, cx * cx + cy * cy);
            ax * (by * lc - cy * lb) - ay * (bx * lc - cx * lb) + la * (bx * cy - cx * by) > 0
        }
    }
}

/// Twice the signed area of `(a, b, c)`: positive counter-clockwise.
fn orient(a: [i64; 2], b: [i64; 2], c: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Checks the half-edge links, the orientation, the covered area and that every
    /// inner edge is locally Delaunay.
    fn check(t: &Triangulation, w: i64, h: i64) {
        let mut area2 = 0;
        for e in (0..4 * t.len() as u32).filter(|e| e & 3 != 3) {
            let f = t.twin(e);
            if f == NONE {
                // Boundary half-edges lie on the rectangle's sides.
                let [p, q] = [e, next(e)].map(|k| t.vertices[t.start(k) as usize].ij());
                assert!(
                    (p[0] == q[0] && (p[0] == 0 || p[0] == w))
                        || (p[1] == q[1] && (p[1] == 0 || p[1] == h)),
                    "{p:?} → {q:?} is on no side"
                );
                continue;
            }
            assert_eq!(t.twin(f), e);
            assert_eq!(t.start(f), t.start(next(e)));
            assert_eq!(t.start(next(f)), t.start(e));
            // The far vertex of f's triangle is not inside e's circumcircle.
            let [a, b, c, d] = [e, next(e), next(next(e)), next(next(f))]
                .map(|k| t.vertices[t.start(k) as usize].ij());
            assert!(
                !t.in_circle(a, b, c, d),
                "{a:?} {b:?} {c:?} has {d:?} inside"
            );
        }
        for k in 0..t.len() {
            let [a, b, c] = t.corners(k).map(Vertex::ij);
            let o = orient(a, b, c);
            assert!(o > 0, "triangle {k} is not counter-clockwise");
            area2 += o;
        }
        assert_eq!(area2, 2 * w * h);
    }

    #[test]
    fn insertions_inside_on_edges_and_on_the_boundary_keep_it_delaunay() {
        for (w, h, exact_f64) in [(40, 23, true), (40, 23, false), (5000, 3, true)] {
            let mut t = Triangulation::rectangle(w as i32, h as i32, [0.0; 4]);
            t.exact_f64 = exact_f64 && w.max(h) < 4096;
            // A deterministic sequence of grid points, many of them on lines through
            // others (grid-aligned and diagonal edges, cocircular quadruples).
            let mut s = 12345u64;
            let mut seen = std::collections::HashSet::from([[0, 0], [w, 0], [w, h], [0, h]]);
            let mut changed = Vec::new();
            for _ in 0..400 {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let p = [
                    ((s >> 33) % (w as u64 + 1)) as i64,
                    ((s >> 17) % (h as u64 + 1)) as i64,
                ];
                if !seen.insert(p) {
                    continue;
                }
                let k = (0..t.len())
                    .find(|&k| {
                        let [a, b, c] = t.corners(k).map(Vertex::ij);
                        orient(a, b, p) >= 0 && orient(b, c, p) >= 0 && orient(c, a, p) >= 0
                    })
                    .unwrap();
                changed.clear();
                let z = (p[0] * p[1]) as f32;
                t.insert(
                    k as u32,
                    Vertex {
                        i: p[0] as i32,
                        j: p[1] as i32,
                        z,
                    },
                    &mut changed,
                );
                assert_eq!(t.vertices.last().map(|v| v.z), Some(z));
                // Exactly the triangles with p as a corner are reported, once each.
                let v = t.vertices.len() as u32 - 1;
                let mut star: Vec<u32> = (0..t.len() as u32)
                    .filter(|&k| t.triangle(k as usize).contains(&v))
                    .collect();
                changed.sort_unstable();
                star.sort_unstable();
                assert_eq!(changed, star);
                check(&t, w, h);
            }
            assert!(t.vertices.len() > 300);
        }
    }
}

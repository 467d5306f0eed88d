//! The grid points of one TIN triangle and the worst of them: a scan of the triangle's
//! rows, each row's span (from the edges' `x` at that row, stepped exactly in integers:
//! vertices sit on grid points) compared with the triangle's plane.

/// The grid point of a triangle farthest (vertically) from the triangle's plane.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Worst {
    /// `|plane − h|` there, metres; 0 when the triangle holds no grid point but its corners.
    pub error: f64,
    /// Its grid index `i + nx·j`.
    pub at: u32,
    /// Its height, metres (kept here: the sample is long out of cache when the point is
    /// inserted).
    pub z: f32,
}

/// Rows whose spans are found (and first samples touched) before they are scanned.
const ROWS: usize = 32;

/// An edge's `x` at successive rows, exactly: `x + r/dy` with `0 ≤ r < dy`, stepped by
/// `dx/dy` (a digital differential analyser on integers).
struct Edge {
    x: i64,
    r: i64,
    q: i64,
    rs: i64,
    dy: i64,
}

impl Edge {
    /// The edge from grid point `p` up to `q` (`q` not below `p`), at `p`'s row.
    fn new(p: [i64; 2], q: [i64; 2]) -> Edge {
        let (dx, dy) = (q[0] - p[0], (q[1] - p[1]).max(1));
        Edge {
            x: p[0],
            r: 0,
            q: dx.div_euclid(dy),
            rs: dx.rem_euclid(dy),
            dy,
        }
    }

    /// Moves to the next row.
    fn step(&mut self) {
        self.x += self.q;
        self.r += self.rs;
        if self.r >= self.dy {
            self.x += 1;
            self.r -= self.dy;
        }
    }

    /// The smallest grid column at or right of the edge.
    fn ceil(&self) -> i64 {
        self.x + i64::from(self.r > 0)
    }

    /// The largest grid column at or left of the edge.
    fn floor(&self) -> i64 {
        self.x
    }
}

/// The grid point of the triangle with grid corners `t` (any orientation) over the
/// samples `h` (row-major, `nx` per row, fewer than 2³² in all) farthest from the plane
/// through `z`, its corners excluded.
pub fn worst_point(t: [[i64; 2]; 3], z: [f64; 3], h: &[f32], nx: usize) -> Worst {
    let [a, mut b, mut c] = t;
    let [za, mut zb, mut zc] = z;
    let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    if cross == 0 {
        return Worst::default();
    }
    if cross < 0 {
        std::mem::swap(&mut b, &mut c);
        std::mem::swap(&mut zb, &mut zc);
    }
    let det = cross.abs() as f64;
    // The plane z = za + gx·(x − ax) + gy·(y − ay).
    let (ux, uy, vx, vy) = (
        (b[0] - a[0]) as f64,
        (b[1] - a[1]) as f64,
        (c[0] - a[0]) as f64,
        (c[1] - a[1]) as f64,
    );
    let (dzb, dzc) = (zb - za, zc - za);
    let gx = (dzb * vy - dzc * uy) / det;
    let gy = (dzc * ux - dzb * vx) / det;

    // The rows from the lowest corner v0 to the highest v2: the long edge v0 → v2 bounds
    // every row on one side, v0 → v1 then v1 → v2 on the other.
    let mut v = [a, b, c];
    v.sort_unstable_by_key(|p| p[1]);
    let [v0, v1, v2] = v;
    let long_left = (v2[0] - v0[0]) * (v1[1] - v0[1]) - (v2[1] - v0[1]) * (v1[0] - v0[0]) < 0;
    let mut long = Edge::new(v0, v2);
    let mut short = Edge::new(v0, v1);
    let mut worst = Worst::default();
    let mut spans = [(0i64, 0i64); ROWS];
    let mut y = v0[1];
    while y <= v2[1] {
        // A batch of rows' spans, each row's first samples touched so that the rows'
        // cache misses overlap instead of stalling the scan one after the other.
        let rows = ((v2[1] - y + 1) as usize).min(ROWS);
        for (k, span) in spans[..rows].iter_mut().enumerate() {
            let yk = y + k as i64;
            if yk == v1[1] {
                short = Edge::new(v1, v2);
            }
            *span = if long_left {
                (long.ceil(), short.floor())
            } else {
                (short.ceil(), long.floor())
            };
            long.step();
            short.step();
            if span.0 <= span.1 {
                std::hint::black_box(h[yk as usize * nx + span.0 as usize]);
            }
        }
        for (k, &(lo, hi)) in spans[..rows].iter().enumerate() {
            if lo > hi {
                continue;
            }
            let y = y + k as i64;
            let fy = y as f64;
            let (lo, hi) = (lo as usize, hi as usize);
            let row = y as usize * nx;
            let base = za + gx * (lo as f64 - a[0] as f64) + gy * (fy - a[1] as f64);
            let span = &h[row + lo..=row + hi];
            // First the row's largest error in f32 (four lanes, vectorised), then — only
            // where that can beat the worst so far — exact errors in f64 and where they are.
            if row_max_f32(base, gx, span) <= worst.error {
                continue;
            }
            let err = |k: usize, s: f32| (base + gx * k as f64 - f64::from(s)).abs();
            let corner_row = y == a[1] || y == b[1] || y == c[1];
            for (k, &s) in span.iter().enumerate() {
                let e = err(k, s);
                if e > worst.error && !(corner_row && [a, b, c].contains(&[(lo + k) as i64, y])) {
                    worst = Worst {
                        error: e,
                        at: (row + lo + k) as u32,
                        z: s,
                    };
                }
            }
        }
        y += rows as i64;
    }
    worst
}

/// An upper bound of `max_k |base + gx·k − span[k]|`, computed in f32: the f32 maximum
/// plus a bound of its rounding error.
fn row_max_f32(base: f64, gx: f64, span: &[f32]) -> f64 {
    let (b, g) = (base as f32, gx as f32);
    let mut m = [0.0f32; 4];
    let chunks = span.chunks_exact(4);
    let rest = chunks.remainder();
    for (c, q) in chunks.enumerate() {
        for l in 0..4 {
            let e = (b + g * (4 * c + l) as f32 - q[l]).abs();
            m[l] = if e > m[l] { e } else { m[l] };
        }
    }
    let at = span.len() - rest.len();
    for (l, &s) in rest.iter().enumerate() {
        let e = (b + g * (at + l) as f32 - s).abs();
        m[l] = if e > m[l] { e } else { m[l] };
    }
    let most = f64::from(m[0].max(m[1]).max(m[2]).max(m[3]));
    // Each of the plane's roundings (its base and slope to f32, the product, the sum) and
    // the difference's is at most ε times the magnitudes involved.
    let scale = base.abs() + gx.abs() * span.len() as f64 + most;
    most + 8.0 * f64::from(f32::EPSILON) * scale
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every grid point inside (or on) a triangle, by brute force over its bounding box.
    fn inside(t: [[i64; 2]; 3], n: i64) -> Vec<[i64; 2]> {
        let [a, b, c] = t;
        let o = |p: [i64; 2], q: [i64; 2], r: [i64; 2]| {
            (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
        };
        let s = o(a, b, c).signum();
        let mut v = Vec::new();
        for y in 0..n {
            for x in 0..n {
                let r = [x, y];
                if o(a, b, r) * s >= 0 && o(b, c, r) * s >= 0 && o(c, a, r) * s >= 0 {
                    v.push(r);
                }
            }
        }
        v
    }

    #[test]
    fn finds_the_worst_point_of_any_triangle_either_way_round() {
        let n = 17usize;
        // A bumpy surface whose maximum inside each triangle is unique enough.
        let h: Vec<f32> = (0..n * n)
            .map(|k| {
                let (x, y) = ((k % n) as f32, (k / n) as f32);
                (x * 0.37).sin() * 5.0 + (y * 0.23 + x * 0.11).cos() * 3.0 + 0.01 * k as f32
            })
            .collect();
        let tris = [
            [[0, 0], [16, 0], [0, 16]],
            [[3, 1], [15, 9], [7, 14]],
            [[2, 2], [3, 15], [16, 16]],
            [[5, 5], [6, 6], [12, 5]],
        ];
        for t in tris {
            for t in [t, [t[0], t[2], t[1]]] {
                let z = t.map(|p| f64::from(h[p[0] as usize + n * p[1] as usize]));
                let w = worst_point(t, z, &h, n);
                // The same maximum by brute force, corners excluded.
                let det = {
                    let [a, b, c] = t;
                    ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) as f64
                };
                let mut best = 0.0f64;
                for r in inside(t, n as i64) {
                    if t.contains(&r) {
                        continue;
                    }
                    let [a, b, c] = t;
                    let l1 = ((r[0] - a[0]) * (c[1] - a[1]) - (r[1] - a[1]) * (c[0] - a[0])) as f64
                        / det;
                    let l2 = ((b[0] - a[0]) * (r[1] - a[1]) - (b[1] - a[1]) * (r[0] - a[0])) as f64
                        / det;
                    let p = z[0] + l1 * (z[1] - z[0]) + l2 * (z[2] - z[0]);
                    best = best.max((p - f64::from(h[r[0] as usize + n * r[1] as usize])).abs());
                }
                assert!(
                    (w.error - best).abs() < 1e-9,
                    "{t:?}: {} vs {best}",
                    w.error
                );
                assert!(best == 0.0 || w.z == h[w.at as usize]);
                assert!(
                    best == 0.0
                        || inside(t, n as i64)
                            .contains(&[(w.at as usize % n) as i64, (w.at as usize / n) as i64])
                );
            }
        }
    }
}

//! The grid points of one TIN triangle and the worst of them: a scan of the triangle's
//! rows, each row's span (from the edges' `x` at that row, stepped exactly in integers:
//! vertices sit on grid points) compared with the triangle's plane. Two passes: every
//! row's largest error in f32 (four lanes at once) with a bound of its rounding, then the
//! exact errors in f64 only in the rows that may hold the largest — about one a triangle.

use glam::Vec4;

/// The grid point of a triangle farthest (vertically) from the triangle's plane.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Worst {
    /// `|plane − h|` there, metres; 0 when the triangle holds no grid point but its corners.
    pub error: f64,
    /// Its grid index `i + nx·j`.
    pub at: u32,
}

/// Rows ahead of the scan whose first samples are prefetched.
const AHEAD: usize = 16;

/// The rows of a triangle scan, kept from scan to scan.
#[derive(Default)]
pub struct Scanner {
    /// Each row's first grid column, its corner left out.
    lo: Vec<i64>,
    /// Each row's last grid column, its corner left out.
    hi: Vec<i64>,
    /// Each row's largest errors from the f32 pass, lane by lane (−1 for an empty row).
    most: Vec<Vec4>,
}

/// Writes the `x` of the edge from grid point `p` up to `q` at successive rows from `p`'s
/// into `out`, rounded up to a grid column when `up`, down otherwise — exactly, by a
/// digital differential analyser on integers: `x + r/dy` with `0 ≤ r < dy`, stepped by
/// `dx/dy`, where rounding up is rounding down `x + (r + dy − 1)/dy`.
fn trace(p: [i64; 2], q: [i64; 2], up: bool, out: &mut [i64]) {
    let (dx, dy) = (q[0] - p[0], (q[1] - p[1]).max(1));
    let (step, rs) = (dx.div_euclid(dy), dx.rem_euclid(dy));
    let (mut x, mut r) = (p[0], if up { dy - 1 } else { 0 });
    for o in out {
        *o = x;
        r += rs;
        let carry = i64::from(r >= dy);
        x += step + carry;
        r -= carry * dy;
    }
}

impl Scanner {
    /// The grid point of the triangle with grid corners `t` (any orientation) over the
    /// samples `h` (row-major, `nx` per row, fewer than 2³² in all) farthest from the
    /// plane through `z`, its corners excluded. Inlined into its one caller: passed
    /// through memory, the arrays were stored in pieces and loaded whole, a store-forwarding
    /// stall at every scan.
    #[inline(always)]
    pub fn worst_point(&mut self, t: [[i64; 2]; 3], z: [f64; 3], h: &[f32], nx: usize) -> Worst {
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

        // The rows from the lowest corner v0 to the highest v2: the long edge v0 → v2
        // bounds every row on one side, v0 → v1 then v1 → v2 on the other.
        let [v0, v1, v2] = by_row([a, b, c]);
        let long_left = (v2[0] - v0[0]) * (v1[1] - v0[1]) - (v2[1] - v0[1]) * (v1[0] - v0[0]) < 0;
        let rows = (v2[1] - v0[1] + 1) as usize;
        let mid = (v1[1] - v0[1]) as usize;
        if self.lo.len() < rows {
            self.lo.resize(rows, 0);
            self.hi.resize(rows, 0);
            self.most.resize(rows, Vec4::ZERO);
        }
        let (lo, hi) = (&mut self.lo[..rows], &mut self.hi[..rows]);
        let (long, short) = if long_left {
            (&mut *lo, &mut *hi)
        } else {
            (&mut *hi, &mut *lo)
        };
        trace(v0, v2, long_left, long);
        trace(v0, v1, !long_left, &mut short[..mid]);
        trace(v1, v2, !long_left, &mut short[mid..]);
        // A corner is always at one end of its row's span.
        for p in [v0, v1, v2] {
            let k = (p[1] - v0[1]) as usize;
            if lo[k] == p[0] {
                lo[k] += 1;
            } else if hi[k] == p[0] {
                hi[k] -= 1;
            }
        }
        // The f32 pass: each row's largest errors, lane by lane; the rows' first samples
        // prefetched ahead so that their cache misses overlap.
        let first = |k: usize| (v0[1] as usize + k) * nx + lo[k] as usize;
        for k in 0..rows.min(AHEAD) {
            prefetch(h, first(k));
        }
        let mut top = Vec4::ZERO;
        for k in 0..rows {
            if k + AHEAD < rows {
                prefetch(h, first(k + AHEAD));
            }
            if lo[k] > hi[k] {
                self.most[k] = Vec4::NEG_ONE;
                continue;
            }
            let y = (v0[1] + k as i64) as f64;
            let base = za + gx * (lo[k] as f64 - a[0] as f64) + gy * (y - a[1] as f64);
            let m = row_max_f32(base, gx, h, first(k), (hi[k] - lo[k] + 1) as usize);
            self.most[k] = m;
            top = top.max(m);
        }
        // Each of the plane's roundings (its base and slope to f32, the product, the sum)
        // and the difference's is at most ε times the magnitudes involved — the plane's
        // value at a grid point of the triangle is at most its largest corner's, and `k` at
        // most the triangle's width —, so every f32 error is within `slack` of the f64 one.
        let top = f64::from(top.max_element());
        let high = za.abs().max(zb.abs()).max(zc.abs());
        let wide = (v0[0].max(v1[0]).max(v2[0]) - v0[0].min(v1[0]).min(v2[0]) + 1) as f64;
        let slack = 8.0 * f64::from(f32::EPSILON) * (high + gx.abs() * wide + top);
        // The exact pass, in f64, only over rows that may hold the largest error: none
        // whose f32 errors are all more than twice the slack below the largest (a third
        // slack covers the threshold's own rounding to f32), nor any whose largest is
        // within the slack of the worst so far.
        let floor = Vec4::splat((top - 3.0 * slack) as f32);
        let mut worst = Worst::default();
        for k in 0..rows {
            let m = self.most[k];
            // A row the triangle misses holds no point (its `most` is only a marker).
            if hi[k] < lo[k]
                || !m.cmpge(floor).any()
                || f64::from(m.max_element()) + slack <= worst.error
            {
                continue;
            }
            let y = (v0[1] + k as i64) as f64;
            let base = za + gx * (lo[k] as f64 - a[0] as f64) + gy * (y - a[1] as f64);
            let at = first(k);
            for (i, &s) in h[at..=at + (hi[k] - lo[k]) as usize].iter().enumerate() {
                let e = (base + gx * i as f64 - f64::from(s)).abs();
                if e > worst.error {
                    worst = Worst {
                        error: e,
                        at: (at + i) as u32,
                    };
                }
            }
        }
        worst
    }
}

/// The points `v` by row, stably, in registers (a slice sort went through memory).
fn by_row(v: [[i64; 2]; 3]) -> [[i64; 2]; 3] {
    let [mut p, mut q, mut r] = v;
    if p[1] > q[1] {
        std::mem::swap(&mut p, &mut q);
    }
    if q[1] > r[1] {
        std::mem::swap(&mut q, &mut r);
    }
    if p[1] > q[1] {
        std::mem::swap(&mut p, &mut q);
    }
    [p, q, r]
}

/// Most rows of a triangle whose samples [`prefetch_rows`] asks for.
const PREFETCH_ROWS: i64 = 32;

/// Asks for the cache lines at both ends of each row of the bounding box of the triangle
/// with grid corners `t` (its first [`PREFETCH_ROWS`]), over the samples `h` (row-major,
/// `nx` per row).
pub fn prefetch_rows(t: [[i64; 2]; 3], h: &[f32], nx: usize) {
    let [a, b, c] = t;
    let (x0, x1) = (a[0].min(b[0]).min(c[0]), a[0].max(b[0]).max(c[0]));
    let (y0, y1) = (a[1].min(b[1]).min(c[1]), a[1].max(b[1]).max(c[1]));
    for y in y0..=y1.min(y0 + PREFETCH_ROWS - 1) {
        let row = y as usize * nx;
        prefetch(h, row + x0 as usize);
        prefetch(h, row + x1 as usize);
    }
}

/// Asks for the cache line of `h[at]`, so that its miss overlaps the work before the scan
/// reaches it.
fn prefetch(h: &[f32], at: usize) {
    if let Some(s) = h.get(at) {
        crate::cache::prefetch(s);
    }
}

/// `|base + gx·k − h[at + k]|` for `k < len`, computed in f32, the largest of each lane.
#[inline(always)]
fn row_max_f32(base: f64, gx: f64, h: &[f32], at: usize, len: usize) -> Vec4 {
    let (b, g) = (Vec4::splat(base as f32), Vec4::splat(gx as f32));
    let err = |k: usize| {
        let q = Vec4::from_slice(&h[at + k..at + k + 4]);
        (b + g * (Vec4::new(0.0, 1.0, 2.0, 3.0) + Vec4::splat(k as f32)) - q).abs()
    };
    if len >= 4 {
        // Chunks of four, the last one ending at the span's end (overlapping the one
        // before: the maximum does not mind).
        let mut m = err(len - 4);
        let mut k = 0;
        while k + 4 < len {
            m = m.max(err(k));
            k += 4;
        }
        m
    } else if at + 4 <= h.len() {
        // One chunk, the lanes past the span masked.
        let inside = Vec4::new(0.0, 1.0, 2.0, 3.0).cmplt(Vec4::splat(len as f32));
        Vec4::select(inside, err(0), Vec4::ZERO)
    } else {
        let e = |k: usize| (base as f32 + gx as f32 * k as f32 - h[at + k]).abs();
        Vec4::new(
            e(0),
            if len > 1 { e(1) } else { 0.0 },
            if len > 2 { e(2) } else { 0.0 },
            0.0,
        )
    }
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
                let w = Scanner::default().worst_point(t, z, &h, n);
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
                assert!(
                    best == 0.0
                        || inside(t, n as i64)
                            .contains(&[(w.at as usize % n) as i64, (w.at as usize / n) as i64])
                );
            }
        }
    }
}

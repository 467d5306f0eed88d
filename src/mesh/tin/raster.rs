//! The grid points of one TIN triangle and the worst of them: a scan of the triangle's
//! rows with exact integer edge tests (vertices sit on grid points), each row's span
//! compared with the triangle's plane.

/// The grid point of a triangle farthest (vertically) from the triangle's plane.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Worst {
    /// `|plane − h|` there, metres; 0 when the triangle holds no grid point but its corners.
    pub error: f64,
    /// Its grid index `i + nx·j`.
    pub at: usize,
}

/// Row range of `x` where `a·x + k ≥ 0`, intersected with `lo..=hi` (integers).
#[inline]
fn half_plane(a: i64, k: i64, lo: i64, hi: i64) -> (i64, i64) {
    if a > 0 {
        // x ≥ −k / a, rounded up
        (lo.max(-(k.div_euclid(a))), hi)
    } else if a < 0 {
        // x ≤ k / (−a), rounded down
        (lo, hi.min(k.div_euclid(-a)))
    } else if k >= 0 {
        (lo, hi)
    } else {
        (1, 0)
    }
}

/// The worst grid point of the triangle with grid corners `t` (any orientation, not
/// degenerate) over the samples `h` (row-major, `nx` per row), its corners excluded.
pub fn worst_point(t: [[i64; 2]; 3], z: [f64; 3], h: &[f32], nx: usize) -> Worst {
    let [a, mut b, mut c] = t;
    let [za, mut zb, mut zc] = z;
    let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    if cross < 0 {
        std::mem::swap(&mut b, &mut c);
        std::mem::swap(&mut zb, &mut zc);
    }
    let det = cross.abs() as f64;
    if det == 0.0 {
        return Worst::default();
    }
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

    // Edge p → q of a counter-clockwise triangle: r is inside when
    // (qx − px)(ry − py) − (qy − py)(rx − px) ≥ 0, i.e. A·rx + K(ry) ≥ 0.
    let edges = [(a, b), (b, c), (c, a)];
    let y0 = a[1].min(b[1]).min(c[1]);
    let y1 = a[1].max(b[1]).max(c[1]);
    let xlo = a[0].min(b[0]).min(c[0]);
    let xhi = a[0].max(b[0]).max(c[0]);
    let mut worst = Worst::default();
    for y in y0..=y1 {
        let (mut lo, mut hi) = (xlo, xhi);
        for (p, q) in edges {
            let ea = -(q[1] - p[1]);
            let k = (q[0] - p[0]) * (y - p[1]) + (q[1] - p[1]) * p[0];
            (lo, hi) = half_plane(ea, k, lo, hi);
        }
        if lo > hi {
            continue;
        }
        let row = y as usize * nx;
        let base = za + gx * (lo - a[0]) as f64 + gy * (y - a[1]) as f64;
        let span = &h[row + lo as usize..=row + hi as usize];
        let corner_row = y == a[1] || y == b[1] || y == c[1];
        let mut best = (worst.error, usize::MAX);
        for (k, &s) in span.iter().enumerate() {
            let e = (base + gx * k as f64 - f64::from(s)).abs();
            if e > best.0 {
                let x = lo + k as i64;
                if corner_row && [a, b, c].contains(&[x, y]) {
                    continue;
                }
                best = (e, k);
            }
        }
        if best.1 != usize::MAX {
            worst = Worst {
                error: best.0,
                at: row + lo as usize + best.1,
            };
        }
    }
    worst
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
                assert!(
                    best == 0.0
                        || inside(t, n as i64).contains(&[(w.at % n) as i64, (w.at / n) as i64])
                );
            }
        }
    }
}

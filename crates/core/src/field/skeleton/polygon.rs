//! Simple 2D polygons for the prism skeleton: validation, inside test, closest boundary
//! point and ear-clipping triangulation. Predicates run in f64.

use glam::{DVec2, Vec2};

/// `(b − a) × (c − a)`: positive when `a, b, c` turn counter-clockwise.
fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// True when the closed segments `[a, b]` and `[c, d]` share a point.
fn segments_meet(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    let on = |p: DVec2, q: DVec2, r: DVec2| {
        r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y)
    };
    if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
        return true;
    }
    (o1 == 0.0 && on(a, b, c))
        || (o2 == 0.0 && on(a, b, d))
        || (o3 == 0.0 && on(c, d, a))
        || (o4 == 0.0 && on(c, d, b))
}

/// Checks that `points` is a simple polygon with non-zero area and returns its vertices
/// counter-clockwise, with repeated points (including a closing copy of the first) and
/// vertices in the middle of straight edges removed. Errors name the offending vertex or
/// edges by their index in `points`.
pub fn validate_polygon(points: &[Vec2]) -> Result<Vec<Vec2>, String> {
    // (index in `points`, position), consecutive duplicates dropped.
    let mut v: Vec<(usize, DVec2)> = Vec::with_capacity(points.len());
    for (i, p) in points.iter().enumerate() {
        let p = p.as_dvec2();
        if v.last().is_none_or(|l| l.1 != p) {
            v.push((i, p));
        }
    }
    while v.len() > 1 && v[0].1 == v[v.len() - 1].1 {
        v.pop();
    }
    if v.len() < 3 {
        return Err(format!(
            "a polygon needs at least 3 distinct vertices, found {}",
            v.len()
        ));
    }
    let (p0, p1) = (v[0].1, v[1].1);
    if v.iter().all(|q| orient(p0, p1, q.1) == 0.0) {
        return Err("the polygon has zero area (all its vertices are on a line)".into());
    }
    // Drop vertices where the boundary goes straight on; refuse spikes.
    let mut i = 0;
    while i < v.len() && v.len() >= 3 {
        let n = v.len();
        let (a, b, c) = (v[(i + n - 1) % n].1, v[i].1, v[(i + 1) % n].1);
        if orient(a, b, c) == 0.0 {
            if (b - a).dot(c - b) < 0.0 {
                return Err(format!(
                    "the polygon doubles back on itself at vertex {}",
                    v[i].0
                ));
            }
            v.remove(i);
            i = i.saturating_sub(1);
        } else {
            i += 1;
        }
    }
    if v.len() < 3 {
        return Err("the polygon has zero area (all its vertices are on a line)".into());
    }
    let n = v.len();
    for i in 0..n {
        for j in i + 1..n {
            let adjacent = j == i + 1 || (i == 0 && j == n - 1);
            if adjacent {
                continue;
            }
            let (a, b) = (v[i].1, v[(i + 1) % n].1);
            let (c, d) = (v[j].1, v[(j + 1) % n].1);
            if segments_meet(a, b, c, d) {
                return Err(format!(
                    "polygon edges {}–{} and {}–{} intersect: the polygon must be simple",
                    v[i].0,
                    v[(i + 1) % n].0,
                    v[j].0,
                    v[(j + 1) % n].0
                ));
            }
        }
    }
    let area2: f64 = (0..n).map(|i| v[i].1.perp_dot(v[(i + 1) % n].1)).sum();
    let mut out: Vec<Vec2> = v.iter().map(|(_, p)| p.as_vec2()).collect();
    if area2 < 0.0 {
        out.reverse();
    }
    Ok(out)
}

/// True when `p` is inside the polygon (crossing number; boundary points may go either
/// way, which does not matter for a distance that is 0 on the boundary).
pub fn contains(poly: &[Vec2], p: Vec2) -> bool {
    let mut inside = false;
    let mut j = poly.len() - 1;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[j]);
        if (a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// The closest point of the polygon's boundary to `p`.
pub fn closest_on_boundary(poly: &[Vec2], p: Vec2) -> Vec2 {
    let mut best = f32::INFINITY;
    let mut at = poly[0];
    let mut j = poly.len() - 1;
    for i in 0..poly.len() {
        let (a, b) = (poly[j], poly[i]);
        let ab = b - a;
        let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
        let q = a + ab * t;
        let d2 = (p - q).length_squared();
        if d2 < best {
            best = d2;
            at = q;
        }
        j = i;
    }
    at
}

/// Ear-clipping triangulation of a counter-clockwise simple polygon: `n − 2` triangles,
/// each counter-clockwise.
pub fn triangulate(poly: &[Vec2]) -> Vec<[Vec2; 3]> {
    let pts: Vec<DVec2> = poly.iter().map(|p| p.as_dvec2()).collect();
    let mut idx: Vec<usize> = (0..pts.len()).collect();
    let mut tris = Vec::with_capacity(pts.len().saturating_sub(2));
    while idx.len() > 3 {
        let n = idx.len();
        let is_ear = |k: usize| {
            let (a, b, c) = (
                pts[idx[(k + n - 1) % n]],
                pts[idx[k]],
                pts[idx[(k + 1) % n]],
            );
            orient(a, b, c) > 0.0
                && idx.iter().all(|&m| {
                    let q = pts[m];
                    q == a
                        || q == b
                        || q == c
                        || orient(a, b, q) < 0.0
                        || orient(b, c, q) < 0.0
                        || orient(c, a, q) < 0.0
                })
        };
        // A simple polygon always has an ear; rounding may hide it, then clip the most
        // convex corner so the loop always ends.
        let k = (0..n).find(|&k| is_ear(k)).unwrap_or_else(|| {
            (0..n)
                .max_by(|&x, &y| {
                    let o = |k: usize| {
                        orient(
                            pts[idx[(k + n - 1) % n]],
                            pts[idx[k]],
                            pts[idx[(k + 1) % n]],
                        )
                    };
                    o(x).total_cmp(&o(y))
                })
                .unwrap_or(0)
        });
        tris.push([idx[(k + n - 1) % n], idx[k], idx[(k + 1) % n]].map(|i| poly[i]));
        idx.remove(k);
    }
    tris.push([poly[idx[0]], poly[idx[1]], poly[idx[2]]]);
    tris
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(p: &[(f32, f32)]) -> Vec<Vec2> {
        p.iter().map(|&(x, y)| Vec2::new(x, y)).collect()
    }

    #[test]
    fn validation() {
        let sq = v(&[(0.0, 0.0), (0.0, 1.0), (1.0, 1.0), (1.0, 0.0), (0.0, 0.0)]);
        let ok = validate_polygon(&sq).unwrap();
        assert_eq!(ok.len(), 4);
        let area2: f32 = (0..4).map(|i| ok[i].perp_dot(ok[(i + 1) % 4])).sum();
        assert!(area2 > 0.0, "made counter-clockwise");
        let mid = v(&[(0.0, 0.0), (0.5, 0.0), (1.0, 0.0), (1.0, 1.0)]);
        assert_eq!(validate_polygon(&mid).unwrap().len(), 3);
        let e = validate_polygon(&v(&[(0.0, 0.0), (1.0, 1.0)])).unwrap_err();
        assert!(e.contains("at least 3"), "{e}");
        let e = validate_polygon(&v(&[(0.0, 0.0), (1.0, 1.0), (2.0, 2.0)])).unwrap_err();
        assert!(e.contains("zero area"), "{e}");
        let bow = v(&[(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)]);
        let e = validate_polygon(&bow).unwrap_err();
        assert!(e.contains("intersect"), "{e}");
        let spike = v(&[(0.0, 0.0), (2.0, 0.0), (1.0, 0.0), (1.0, 1.0)]);
        assert!(validate_polygon(&spike).is_err());
    }

    #[test]
    fn triangulation_covers_the_polygon() {
        // An L-shape (non-convex) and a comb.
        let l = validate_polygon(&v(&[
            (0.0, 0.0),
            (3.0, 0.0),
            (3.0, 1.0),
            (1.0, 1.0),
            (1.0, 3.0),
            (0.0, 3.0),
        ]))
        .unwrap();
        let comb = validate_polygon(&v(&[
            (0.0, 0.0),
            (5.0, 0.0),
            (5.0, 3.0),
            (4.0, 3.0),
            (4.0, 1.0),
            (3.0, 1.0),
            (3.0, 3.0),
            (2.0, 3.0),
            (2.0, 1.0),
            (1.0, 1.0),
            (1.0, 3.0),
            (0.0, 3.0),
        ]))
        .unwrap();
        for poly in [l, comb] {
            let tris = triangulate(&poly);
            assert_eq!(tris.len(), poly.len() - 2);
            let area = |t: &[Vec2; 3]| (t[1] - t[0]).perp_dot(t[2] - t[0]) * 0.5;
            let total: f32 = tris.iter().map(area).sum();
            let poly_area: f32 = (0..poly.len())
                .map(|i| poly[i].perp_dot(poly[(i + 1) % poly.len()]))
                .sum::<f32>()
                * 0.5;
            assert!((total - poly_area).abs() < 1e-4 && tris.iter().all(|t| area(t) > 0.0));
            for i in 0..50 {
                for j in 0..50 {
                    let p = Vec2::new(i as f32 * 0.1 + 0.05, j as f32 * 0.06 + 0.01);
                    let in_tri = tris
                        .iter()
                        .any(|t| (0..3).all(|k| (t[(k + 1) % 3] - t[k]).perp_dot(p - t[k]) >= 0.0));
                    assert_eq!(in_tri, contains(&poly, p), "at {p}");
                }
            }
        }
    }
}

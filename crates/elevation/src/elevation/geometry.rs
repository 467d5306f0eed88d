//! Planar distances the primitives and the leaf share: to a segment, to a polygon (signed),
//! and the clearance of a rectangle.

use glam::Vec2;

use crate::field::{Interval, Rect};

/// The rectangle holding nothing (`min = +∞`, `max = −∞`).
pub const EMPTY_RECT: Rect = Rect {
    min: Vec2::INFINITY,
    max: Vec2::NEG_INFINITY,
};

/// True when `p` lies in `r` (borders included).
#[inline]
pub fn rect_contains(r: &Rect, p: Vec2) -> bool {
    r.min.cmple(p).all() && p.cmple(r.max).all()
}

/// The smallest rectangle holding `a` and `b`.
pub fn rect_union(a: &Rect, b: &Rect) -> Rect {
    Rect {
        min: a.min.min(b.min),
        max: a.max.max(b.max),
    }
}

/// Half the diagonal of `r` and its centre.
#[inline]
pub fn rect_centre(r: &Rect) -> (Vec2, f32) {
    let c = (r.min + r.max) * 0.5;
    (c, (r.max - c).length())
}

/// Clearance of `p` in `r`: the distance to the nearest side, negative outside. It is
/// 1-Lipschitz and concave.
#[inline]
pub fn clearance(r: &Rect, p: Vec2) -> f32 {
    (p.x - r.min.x)
        .min(r.max.x - p.x)
        .min(p.y - r.min.y)
        .min(r.max.y - p.y)
}

/// `(clearance, its gradient)` (the inward normal of the nearest side).
pub fn clearance_grad(r: &Rect, p: Vec2) -> (f32, Vec2) {
    [
        (p.x - r.min.x, Vec2::X),
        (r.max.x - p.x, -Vec2::X),
        (p.y - r.min.y, Vec2::Y),
        (r.max.y - p.y, -Vec2::Y),
    ]
    .into_iter()
    .fold(
        (f32::INFINITY, Vec2::ZERO),
        |a, b| if b.0 < a.0 { b } else { a },
    )
}

/// The exact range of [`clearance`] over the footprint `fp`: `e = min(e_x(x), e_y(y))` is
/// separable and concave, so its minimum is at a corner and its maximum at the point of
/// `fp` nearest the centre of `r` on each axis.
pub fn clearance_range(r: &Rect, fp: &Rect) -> Interval {
    let lo = [
        fp.min,
        fp.max,
        Vec2::new(fp.min.x, fp.max.y),
        Vec2::new(fp.max.x, fp.min.y),
    ]
    .into_iter()
    .map(|p| clearance(r, p))
    .fold(f32::INFINITY, f32::min);
    let c = (r.min + r.max) * 0.5;
    let hi = clearance(r, c.clamp(fp.min, fp.max));
    Interval::new(lo, hi)
}

/// `(distance from p to the segment [a, b], parameter t ∈ [0, 1] of the nearest point)`.
#[inline]
pub fn segment_distance(p: Vec2, a: Vec2, b: Vec2) -> (f32, f32) {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((p - (a + ab * t)).length(), t)
}

/// Signed distance from `p` to the closed polygon `poly`: negative inside (even-odd rule).
/// It is 1-Lipschitz.
pub fn polygon_signed_distance(poly: &[Vec2], p: Vec2) -> f32 {
    let mut d = f32::INFINITY;
    let mut inside = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        d = d.min(segment_distance(p, a, b).0);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
    }
    if inside { -d } else { d }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clearance_range_holds_samples() {
        let r = Rect::new(Vec2::ZERO, Vec2::new(10.0, 4.0));
        let fp = Rect::new(Vec2::new(3.0, -1.0), Vec2::new(12.0, 1.5));
        let e = clearance_range(&r, &fp);
        for i in 0..=20 {
            for j in 0..=20 {
                let p = fp.min + (fp.max - fp.min) * Vec2::new(i as f32, j as f32) / 20.0;
                let v = clearance(&r, p);
                assert!(e.lo <= v && v <= e.hi, "{p}: {v} not in {e:?}");
            }
        }
        assert_eq!(e.hi, 1.5);
    }

    #[test]
    fn polygon_sign() {
        let sq = [
            Vec2::ZERO,
            Vec2::new(2.0, 0.0),
            Vec2::new(2.0, 2.0),
            Vec2::new(0.0, 2.0),
        ];
        assert_eq!(polygon_signed_distance(&sq, Vec2::new(1.0, 1.0)), -1.0);
        assert_eq!(polygon_signed_distance(&sq, Vec2::new(3.0, 1.0)), 1.0);
    }
}

//! The horizontal domain Ω of an implicitized heightfield and its *clearance*
//! `e(x) = distance from x to the complement of Ω` (0 outside Ω).
//!
//! Ω is the grid extent, minus the cells without a surface (nodata in their stencil),
//! intersected with an optional user polygon. `e = min(e_rect, e_mask, e_polygon)`: the
//! distance to a union of complements is the minimum of the distances. `e_rect` and
//! `e_polygon` are exact Euclidean distances (1-Lipschitz); `e_mask` is the bilinear
//! interpolant of the exact distance from each grid node to the nearest node of an invalid
//! cell (a Felzenszwalb–Huttenlocher distance transform), which vanishes on every invalid
//! cell and whose Lipschitz bound is read off its samples (≤ √2).

use glam::Vec2;

use super::DemError;
use super::grid::{Heightfield, Interpolation};
use super::pyramid::MinMaxPyramid;
use crate::field::{Interval, Rect};

/// Ω and its clearance function.
#[derive(Clone, Debug)]
pub(crate) struct Domain {
    rect: Rect,
    mask: Option<Mask>,
    polygon: Option<Polygon>,
    lipschitz: f32,
}

#[derive(Clone, Debug)]
struct Mask {
    e: Heightfield,
    ranges: MinMaxPyramid,
}

#[derive(Clone, Debug)]
struct Polygon {
    pts: Vec<Vec2>,
    bbox: Rect,
}

impl Domain {
    /// The domain of `hf` (already placed in the leaf's frame), cut by `polygon`.
    pub(crate) fn new(
        hf: &Heightfield,
        interp: Interpolation,
        polygon: Option<&[Vec2]>,
    ) -> Result<Domain, DemError> {
        let mask = Mask::new(hf, interp);
        let polygon = polygon.map(Polygon::new).transpose()?;
        let lipschitz = mask
            .as_ref()
            .map_or(1.0, |m| m.e.lipschitz(Interpolation::Bilinear).max(1.0));
        Ok(Domain {
            rect: hf.extent(),
            mask,
            polygon,
            lipschitz,
        })
    }

    /// Lipschitz bound of the clearance.
    pub(crate) fn lipschitz(&self) -> f32 {
        self.lipschitz
    }

    /// The bounding rectangle of Ω.
    pub(crate) fn bounds(&self) -> Rect {
        match &self.polygon {
            Some(p) => Rect {
                min: self.rect.min.max(p.bbox.min),
                max: self.rect.max.min(p.bbox.max),
            },
            None => self.rect,
        }
    }

    /// `e(xy)`.
    #[inline]
    pub(crate) fn clearance(&self, xy: Vec2) -> f32 {
        let r = &self.rect;
        let mut e = (xy.x - r.min.x)
            .min(r.max.x - xy.x)
            .min(xy.y - r.min.y)
            .min(r.max.y - xy.y);
        if e <= 0.0 {
            return 0.0;
        }
        if let Some(m) = &self.mask {
            e = e.min(m.e.sample(xy, Interpolation::Bilinear));
        }
        if let Some(p) = &self.polygon
            && e > 0.0
        {
            e = e.min(p.clearance(xy).0);
        }
        e.max(0.0)
    }

    /// `(e(xy), ∇e(xy))` (the gradient of the active term).
    #[inline]
    pub(crate) fn clearance_grad(&self, xy: Vec2) -> (f32, Vec2) {
        let r = &self.rect;
        let sides = [
            (xy.x - r.min.x, Vec2::X),
            (r.max.x - xy.x, -Vec2::X),
            (xy.y - r.min.y, Vec2::Y),
            (r.max.y - xy.y, -Vec2::Y),
        ];
        let mut best =
            sides.into_iter().fold(
                (f32::INFINITY, Vec2::ZERO),
                |a, b| if b.0 < a.0 { b } else { a },
            );
        if best.0 <= 0.0 {
            return (0.0, Vec2::ZERO);
        }
        if let Some(m) = &self.mask {
            let c = m.e.sample_grad(xy, Interpolation::Bilinear);
            if c.0 < best.0 {
                best = c;
            }
        }
        if let Some(p) = &self.polygon {
            let c = p.clearance(xy);
            if c.0 < best.0 {
                best = c;
            }
        }
        if best.0 <= 0.0 {
            (0.0, Vec2::ZERO)
        } else {
            best
        }
    }

    /// A range containing `e` over the footprint `fp`.
    pub(crate) fn clearance_range(&self, fp: &Rect) -> Interval {
        let r = &self.rect;
        let lo = (fp.min.x - r.min.x)
            .min(r.max.x - fp.max.x)
            .min(fp.min.y - r.min.y)
            .min(r.max.y - fp.max.y);
        let hi = (fp.max.x - r.min.x)
            .min(r.max.x - fp.min.x)
            .min(fp.max.y - r.min.y)
            .min(r.max.y - fp.min.y);
        let mut range = Interval::new(lo.max(0.0), hi.max(0.0));
        if let Some(m) = &self.mask {
            if let Some((i0, i1, j0, j1)) = m.e.cells_overlapping(fp) {
                let q = m.ranges.query_interval(i0, i1, j0, j1);
                range = range.min(Interval::new(q.lo.max(0.0), q.hi.max(0.0)));
            } else {
                return Interval::ZERO;
            }
        }
        if let Some(p) = &self.polygon {
            let c = (fp.min + fp.max) * 0.5;
            let rad = (fp.max - fp.min).length() * 0.5;
            let e = p.clearance(c).0;
            range = range.min(Interval::new((e - rad).max(0.0), e + rad));
        }
        range
    }
}

impl Mask {
    /// The clearance of the invalid cells, `None` when every cell is valid.
    fn new(hf: &Heightfield, interp: Interpolation) -> Option<Mask> {
        let (nx, ny) = (hf.nx(), hf.ny());
        let mut feature = vec![false; nx * ny];
        let mut any = false;
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                if !hf.cell_valid(i, j, interp) {
                    any = true;
                    for (a, b) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        feature[i + a + nx * (j + b)] = true;
                    }
                }
            }
        }
        if !any {
            return None;
        }
        let c = hf.cell();
        let d2 = edt(&feature, nx, ny, f64::from(c.x), f64::from(c.y));
        let e: Vec<f32> = d2.iter().map(|&d| d.sqrt() as f32).collect();
        let e = Heightfield::new(nx, ny, hf.origin(), c, e)
            .expect("same geometry as a valid heightfield");
        let (cx, cy) = e.cells();
        let ranges = MinMaxPyramid::new(cx, cy, e.cell_ranges(Interpolation::Bilinear));
        Some(Mask { e, ranges })
    }
}

/// Squared Euclidean distance from each node to the nearest `feature` node, with node
/// spacing `(sx, sy)` (Felzenszwalb & Huttenlocher 2012, separable lower envelopes).
pub fn edt(feature: &[bool], nx: usize, ny: usize, sx: f64, sy: f64) -> Vec<f64> {
    const INF: f64 = 1e300;
    let mut d: Vec<f64> = feature.iter().map(|&f| if f { 0.0 } else { INF }).collect();
    let n = nx.max(ny);
    let (mut f, mut out, mut v, mut z) = (
        vec![0.0; n],
        vec![0.0; n],
        vec![0usize; n],
        vec![0.0; n + 1],
    );
    for j in 0..ny {
        f[..nx].copy_from_slice(&d[j * nx..(j + 1) * nx]);
        envelope(&f[..nx], sx, &mut out[..nx], &mut v, &mut z);
        d[j * nx..(j + 1) * nx].copy_from_slice(&out[..nx]);
    }
    for i in 0..nx {
        for j in 0..ny {
            f[j] = d[i + nx * j];
        }
        envelope(&f[..ny], sy, &mut out[..ny], &mut v, &mut z);
        for j in 0..ny {
            d[i + nx * j] = out[j];
        }
    }
    d
}

/// 1D squared distance transform of `f` with sample spacing `s`.
fn envelope(f: &[f64], s: f64, out: &mut [f64], v: &mut [usize], z: &mut [f64]) {
    const INF: f64 = 1e300;
    let n = f.len();
    let s2 = s * s;
    let mut k = 0usize;
    // only finite parabolas take part; all-INF rows stay INF
    let Some(first) = f.iter().position(|&x| x < INF) else {
        out.fill(INF);
        return;
    };
    v[0] = first;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in first + 1..n {
        if f[q] >= INF {
            continue;
        }
        loop {
            let p = v[k];
            let sx = ((f[q] + s2 * (q * q) as f64) - (f[p] + s2 * (p * p) as f64))
                / (2.0 * s2 * (q as f64 - p as f64));
            if sx <= z[k] && k > 0 {
                k -= 1;
            } else {
                k += 1;
                v[k] = q;
                z[k] = sx;
                z[k + 1] = f64::INFINITY;
                break;
            }
        }
    }
    k = 0;
    for (q, o) in out.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let p = v[k];
        let dq = q as f64 - p as f64;
        *o = s2 * dq * dq + f[p];
    }
}

impl Polygon {
    fn new(pts: &[Vec2]) -> Result<Polygon, DemError> {
        let invalid = |what: String| Err(DemError::Invalid { what });
        if pts.len() < 3 {
            return invalid(format!(
                "a domain polygon needs at least 3 vertices, got {}",
                pts.len()
            ));
        }
        let area: f32 = pts
            .iter()
            .zip(pts.iter().cycle().skip(1))
            .map(|(a, b)| a.perp_dot(*b))
            .sum::<f32>()
            * 0.5;
        if area.is_nan() || area == 0.0 {
            return invalid("the domain polygon has no area".into());
        }
        let bbox = pts.iter().fold(Rect::new(pts[0], pts[0]), |r, p| Rect {
            min: r.min.min(*p),
            max: r.max.max(*p),
        });
        Ok(Polygon {
            pts: pts.to_vec(),
            bbox,
        })
    }

    /// Distance to the boundary when inside (0 outside) and its gradient.
    fn clearance(&self, x: Vec2) -> (f32, Vec2) {
        let mut inside = false;
        let mut best = (f32::INFINITY, Vec2::ZERO);
        let n = self.pts.len();
        for k in 0..n {
            let (a, b) = (self.pts[k], self.pts[(k + 1) % n]);
            if (a.y > x.y) != (b.y > x.y) && x.x < a.x + (x.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                inside = !inside;
            }
            let ab = b - a;
            let t = ((x - a).dot(ab) / ab.length_squared().max(f32::MIN_POSITIVE)).clamp(0.0, 1.0);
            let d = x - (a + ab * t);
            let l2 = d.length_squared();
            if l2 < best.0 {
                best = (l2, d);
            }
        }
        if !inside {
            return (0.0, Vec2::ZERO);
        }
        let d = best.0.sqrt();
        (d, if d > 0.0 { best.1 / d } else { Vec2::ZERO })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edt_matches_brute_force() {
        let (nx, ny) = (23, 17);
        let feature: Vec<bool> = (0..nx * ny).map(|k| k % 37 == 3 || k % 53 == 0).collect();
        let d = edt(&feature, nx, ny, 2.0, 3.0);
        for j in 0..ny {
            for i in 0..nx {
                let mut best = f64::INFINITY;
                for (k, _) in feature.iter().enumerate().filter(|f| *f.1) {
                    let (a, b) = ((k % nx) as f64 - i as f64, (k / nx) as f64 - j as f64);
                    best = best.min(4.0 * a * a + 9.0 * b * b);
                }
                assert!(
                    (d[i + nx * j] - best).abs() < 1e-9,
                    "{i} {j}: {} vs {best}",
                    d[i + nx * j]
                );
            }
        }
    }

    fn grid_with_hole() -> Heightfield {
        let (nx, ny) = (30, 20);
        let z = (0..nx * ny)
            .map(|k| {
                if (k % nx, k / nx) == (10, 8) {
                    f32::NAN
                } else {
                    (k % 7) as f32
                }
            })
            .collect();
        Heightfield::new(nx, ny, Vec2::new(5.0, -4.0), Vec2::new(2.0, 1.5), z).unwrap()
    }

    #[test]
    fn clearance_is_zero_outside_and_lipschitz() {
        let hf = grid_with_hole();
        let poly = [
            Vec2::new(6.0, -3.0),
            Vec2::new(60.0, -3.0),
            Vec2::new(30.0, 20.0),
        ];
        let d = Domain::new(&hf, Interpolation::Bilinear, Some(&poly)).unwrap();
        let hole = hf.origin() + Vec2::new(10.0 * 2.0, 8.0 * 1.5);
        assert_eq!(d.clearance(hole), 0.0);
        assert_eq!(
            d.clearance(hole + Vec2::new(1.9, 1.4)),
            0.0,
            "invalid cells have e = 0"
        );
        assert_eq!(d.clearance(Vec2::new(0.0, 0.0)), 0.0);
        assert_eq!(
            d.clearance(Vec2::new(58.0, 20.0)),
            0.0,
            "outside the polygon"
        );
        assert!(d.clearance(Vec2::new(30.0, 0.0)) > 1.0);
        let l = d.lipschitz();
        let mut seed = 5u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32
        };
        for _ in 0..3000 {
            let a = Vec2::new(rnd() * 70.0, rnd() * 35.0 - 6.0);
            let b = a + Vec2::new(rnd() - 0.5, rnd() - 0.5) * 6.0;
            let (ea, eb) = (d.clearance(a), d.clearance(b));
            assert!((ea - eb).abs() <= l * a.distance(b) + 1e-4);
            let fp = Rect::new(a, b);
            let r = d.clearance_range(&fp);
            for t in [0.0, 0.3, 1.0] {
                let p = a.lerp(b, t);
                let e = d.clearance(p);
                assert!(r.lo - 1e-4 <= e && e <= r.hi + 1e-4, "{e} not in {r:?}");
            }
            let (e, g) = d.clearance_grad(a);
            assert!((e - ea).abs() < 1e-5);
            let h = 1e-2;
            let fd = (d.clearance(a + Vec2::X * h) - d.clearance(a - Vec2::X * h)) / (2.0 * h);
            // the min of distances has kinks; compare only where smooth
            let fd2 = (d.clearance(a + Vec2::X * 2.0 * h) - d.clearance(a - Vec2::X * 2.0 * h))
                / (4.0 * h);
            if ea > 0.05 && (fd - fd2).abs() < 1e-3 {
                assert!((fd - g.x).abs() < 2e-2, "{a}: {fd} vs {}", g.x);
            }
        }
    }
}

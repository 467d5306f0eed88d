//! Detail amplification of a DEM (Frasson et al. §5): fBm displacement of the elevation,
//! modulated by slope and altitude, evaluated in 3D.
//!
//! The leaf's elevation becomes `h(x, y) + d(p)` with
//!
//! ```text
//! d(p) = A · m(x, y) · t(p)
//! ```
//!
//! * `t` the project's seeded fBm turbulence in `[−1, 1]` (Musgrave's fBm, the paper's
//!   Algorithm 1), read at the **3D** point `p` — Frasson et al. §5 replace 2D noise by 3D
//!   noise because 2D noise is stretched on steep faces; with `p.z` in the noise a cliff
//!   gets as much relief per metre as a plain.
//! * `m ∈ [0, 1]` the roughness: Frasson et al. §5 assume that flat ground gathers
//!   sediment (smoother) and that high ground, less protected by vegetation, is rougher.
//!   So `m = (flat + (1 − flat)·smoothstep(0, steep, |∇h|)) · (1 − altitude + altitude·a)`
//!   with `a ∈ [0, 1]` the sample's elevation across the DEM's range. `m` is computed
//!   once per DEM sample (central differences) and interpolated bilinearly, so its range
//!   over a box and its Lipschitz constant come from the same min/max machinery as `h`.
//!
//! Bounds (what [`super::HeightfieldField`] needs): `|d| ≤ A·m_max` over a footprint, and
//! `|∇d| ≤ A·(|t|·|∇m| + m·|∇t|) ≤ A·(L_m + m_max·L_t)`, with `L_t` the fBm's proven
//! Lipschitz constant.

use glam::{Vec2, Vec3};

use super::DemError;
use super::grid::{Heightfield, Interpolation};
use super::pyramid::MinMaxPyramid;
use crate::field::{Fbm, Rect};

/// Parameters of the detail (validated by [`Detail::new`]).
#[derive(Clone, Debug, PartialEq)]
pub struct DetailParams {
    /// The fBm `t`: its seed, first-octave wavelength and octaves.
    pub noise: Fbm,
    /// `A`: the largest displacement, metres (`≥ 0`).
    pub amplitude: f32,
    /// Roughness of flat ground relative to steep ground, in `[0, 1]`.
    pub flat: f32,
    /// The slope `|∇h|` (rise over run) from which ground is fully rough (`> 0`).
    pub steep: f32,
    /// Weight of the altitude in the roughness, in `[0, 1]` (0: altitude does not matter;
    /// 1: the lowest ground is smooth).
    pub altitude: f32,
}

/// The detail `d(p) = A·m(x, y)·t(p)` over a placed heightfield.
#[derive(Clone, Debug)]
pub struct Detail {
    params: DetailParams,
    /// `m` per sample of the heightfield, interpolated bilinearly.
    rough: Heightfield,
    /// Range of `m` per cell.
    ranges: MinMaxPyramid,
    /// Global Lipschitz bound of `m`.
    lip_m: f32,
}

/// `0` below `a`, `1` above `b`, Hermite between.
fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl Detail {
    /// The detail over `hf` (placed and scaled: the leaf's own heightfield).
    pub fn new(hf: &Heightfield, params: &DetailParams) -> Result<Detail, DemError> {
        let p = params;
        let ok = p.amplitude >= 0.0
            && p.amplitude.is_finite()
            && (0.0..=1.0).contains(&p.flat)
            && p.steep > 0.0
            && p.steep.is_finite()
            && (0.0..=1.0).contains(&p.altitude);
        if !ok {
            return Err(DemError::Invalid {
                what: format!(
                    "detail: need amplitude >= 0, flat and altitude in [0, 1], steep > 0 \
                     (got amplitude {}, flat {}, steep {}, altitude {})",
                    p.amplitude, p.flat, p.steep, p.altitude
                ),
            });
        }
        let (nx, ny) = (hf.nx(), hf.ny());
        let (zlo, zhi) = hf.z_range().unwrap_or((0.0, 0.0));
        let span = (zhi - zlo).max(f32::MIN_POSITIVE);
        let cell = hf.cell();
        let at = |i: usize, j: usize| hf.at(i, j);
        let mut m = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let z = at(i, j);
                // Central differences (one-sided at the edges), NaN-tolerant: a missing
                // neighbour leaves that axis's slope at 0.
                let diff = |a: f32, b: f32, n: f32| {
                    let d = (b - a) / n;
                    if d.is_finite() { d } else { 0.0 }
                };
                let (i0, i1) = (i.saturating_sub(1), (i + 1).min(nx - 1));
                let (j0, j1) = (j.saturating_sub(1), (j + 1).min(ny - 1));
                let gx = diff(at(i0, j), at(i1, j), (i1 - i0).max(1) as f32 * cell.x);
                let gy = diff(at(i, j0), at(i, j1), (j1 - j0).max(1) as f32 * cell.y);
                let slope = Vec2::new(gx, gy).length();
                let by_slope = p.flat + (1.0 - p.flat) * smoothstep(0.0, p.steep, slope);
                let a = if z.is_nan() { 0.0 } else { (z - zlo) / span };
                let by_altitude = 1.0 - p.altitude + p.altitude * a;
                m.push((by_slope * by_altitude).clamp(0.0, 1.0));
            }
        }
        let rough = Heightfield::new(nx, ny, hf.origin(), cell, m)?;
        let (cx, cy) = rough.cells();
        let ranges = MinMaxPyramid::new(cx, cy, rough.cell_ranges(Interpolation::Bilinear));
        let lip_m = rough.lipschitz(Interpolation::Bilinear);
        Ok(Detail {
            params: p.clone(),
            rough,
            ranges,
            lip_m,
        })
    }

    /// The parameters it was built with.
    pub fn params(&self) -> &DetailParams {
        &self.params
    }

    /// The roughness raster `m` (one value per DEM sample).
    pub fn roughness(&self) -> &Heightfield {
        &self.rough
    }

    /// Global Lipschitz bound of `m`.
    pub fn lipschitz_m(&self) -> f32 {
        self.lip_m
    }

    /// `A`.
    #[inline]
    pub fn amplitude(&self) -> f32 {
        self.params.amplitude
    }

    /// `A·m(x, y)`: the largest displacement over the column at `xy`.
    #[inline]
    pub fn reach_at(&self, xy: Vec2) -> f32 {
        let m = self.rough.sample(xy, Interpolation::Bilinear);
        if m.is_nan() {
            0.0
        } else {
            self.params.amplitude * m
        }
    }

    /// `d(p)`.
    #[inline]
    pub fn value(&self, p: Vec3) -> f32 {
        let reach = self.reach_at(p.truncate());
        if reach == 0.0 {
            0.0
        } else {
            reach * self.params.noise.value(p)
        }
    }

    /// `(d(p), ∇d(p))`.
    pub fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let (m, gm) = self
            .rough
            .sample_grad(p.truncate(), Interpolation::Bilinear);
        if m.is_nan() {
            return (0.0, Vec3::ZERO);
        }
        let (t, gt) = self.params.noise.value_grad(p);
        let a = self.params.amplitude;
        (a * m * t, a * (t * gm.extend(0.0) + m * gt))
    }

    /// `A·max m` over the cells `i0..=i1 × j0..=j1`: `|d| ≤` this there.
    #[inline]
    pub fn reach(&self, i0: usize, i1: usize, j0: usize, j1: usize) -> f32 {
        self.params.amplitude * self.ranges.query(i0, i1, j0, j1)[1].max(0.0)
    }

    /// `A·max m` over cell `(i, j)` (0 where `m` is undefined): the per-cell values
    /// [`Detail::reach`] takes the maximum of.
    #[inline]
    pub fn cell_reach(&self, i: usize, j: usize) -> f32 {
        self.params.amplitude * self.ranges.cell(i, j)[1].max(0.0)
    }

    /// `A·max m` over the whole grid.
    pub fn reach_total(&self) -> f32 {
        self.params.amplitude * self.ranges.total()[1].max(0.0)
    }

    /// `reach` (`A·max m` over the cells under `fp`) sharpened around the footprint's
    /// centre `c`: `A·m(x) ≤ A·(m(c) + L_m·|x − c|)` on the convex `fp`, which must lie
    /// where `m` is defined (inside the heightfield's cells).
    #[inline]
    pub fn reach_near(&self, fp: &Rect, reach: f32) -> f32 {
        let c = (fp.min + fp.max) * 0.5;
        let m = self.rough.sample(c, Interpolation::Bilinear);
        let near = self.params.amplitude * (m + self.lip_m * (fp.max - c).length()) * (1.0 + 1e-5);
        // NaN (c outside the raster) keeps the cells' bound
        if near < reach { near } else { reach }
    }

    /// A bound of `|∇d|` where `A·m ≤ reach`: `A·L_m + reach·L_t`.
    #[inline]
    pub fn slope(&self, reach: f32) -> f32 {
        self.params.amplitude * self.lip_m + reach * self.params.noise.lipschitz()
    }

    /// A bound of `|∂d/∂z|` where `A·m ≤ reach`: `reach·L_t` (`m` does not vary with z).
    #[inline]
    pub fn slope_z(&self, reach: f32) -> f32 {
        reach * self.params.noise.lipschitz()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> Heightfield {
        // Flat and low on the west, a steep high slope on the east.
        let (nx, ny) = (12, 6);
        let z = (0..nx * ny)
            .map(|k| {
                let i = (k % nx) as f32;
                if i < 5.0 { 0.0 } else { (i - 5.0) * 20.0 }
            })
            .collect();
        Heightfield::new(nx, ny, Vec2::ZERO, Vec2::splat(10.0), z).unwrap()
    }

    fn params() -> DetailParams {
        DetailParams {
            noise: Fbm::with(7, 15.0, 4),
            amplitude: 3.0,
            flat: 0.2,
            steep: 1.0,
            altitude: 0.5,
        }
    }

    #[test]
    fn flat_low_ground_is_smoother_than_steep_high_ground() {
        let d = Detail::new(&ramp(), &params()).unwrap();
        let flat = d.reach_at(Vec2::new(15.0, 25.0));
        let steep = d.reach_at(Vec2::new(95.0, 25.0));
        // flat: 0.2 × (1 − 0.5) = 0.1 of A; steep and high: close to A
        assert!((flat - 0.3).abs() < 1e-4, "{flat}");
        assert!(steep > 2.5 && steep <= 3.0, "{steep}");
    }

    #[test]
    fn gradient_matches_differences_and_bounds_hold() {
        let d = Detail::new(&ramp(), &params()).unwrap();
        let lip = d.slope(d.reach_total());
        let h = 1e-2;
        for k in 0..400 {
            let p = Vec3::new(
                3.0 + (k * 37 % 101) as f32,
                2.0 + (k * 13 % 47) as f32,
                (k * 7 % 29) as f32 - 10.0,
            );
            let (v, g) = d.value_grad(p);
            assert!((v - d.value(p)).abs() < 1e-5);
            assert!(v.abs() <= d.reach_total() + 1e-5);
            for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
                let fd = (d.value(p + axis * h) - d.value(p - axis * h)) / (2.0 * h);
                assert!(
                    (fd - g.dot(axis)).abs() < 2e-2 * (1.0 + g.length()),
                    "{p} {fd} {g}"
                );
            }
            let q = p + Vec3::new(0.7, -0.4, 0.5) * ((k % 5) as f32 + 0.1);
            assert!((d.value(p) - d.value(q)).abs() <= lip * (p - q).length() + 1e-5);
        }
    }

    #[test]
    fn bad_parameters_are_refused() {
        let mut p = params();
        p.flat = 1.5;
        assert!(Detail::new(&ramp(), &p).is_err());
        let mut p = params();
        p.steep = 0.0;
        assert!(Detail::new(&ramp(), &p).is_err());
    }
}

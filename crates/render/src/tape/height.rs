//! Heightfields on the tape: the `HEIGHT` op, `σ(h(x, y) − z, R)` with `h` read from the
//! samples in [`super::Tape::heights`], and its CPU twin.
//!
//! Its parameters ([`height`]): `R`, the pyramid's level count `n`, the grid (origin,
//! cell, `nx`, `ny`), the samples' offset, then the offsets of the `n` levels of a max
//! pyramid of per-cell bounds of `|∇h|` (`slope_under`). The bound over a ball is σ's
//! slope over the range of `h − z` on the ball, times `√(1 + s²)` with `s` the slope
//! under the ball (Génevaux et al. 2015 §7.3.1).
//!
//! With [`flag::DETAIL`] the elevation is `h(x, y) + A·m(x, y)·t(p)`, the detail of
//! Frasson et al. §5 ([`crate::dem::detail`]): the roughness `m` follows the samples in
//! `heights` (bilinear, same grid), the fBm `t` is encoded in the parameters. Over a ball
//! the detail lies within `d(c) ± |∇d|·r`, clipped to `±A`, and adds its slope bound to
//! `√(1 + s²)`.

use glam::{Vec2, Vec3};

use super::TapeError;
use super::format::{fbm, flag, height, limit};
use super::noise::encode_fbm;
use crate::dem::{Detail, Heightfield, Interpolation, MinMaxPyramid};
use crate::field::falloff::{sigma, sigma_slope};
use crate::field::{Fbm, Interval};

/// A regular grid of elevations for [`super::TapeBuilder::heightfield`].
#[derive(Clone, Copy, Debug)]
pub struct HeightGrid<'a> {
    /// Position of sample `(0, 0)`, metres.
    pub origin: Vec2,
    /// Sample spacing, metres.
    pub cell: f32,
    /// Samples along x.
    pub nx: usize,
    /// Samples along y.
    pub ny: usize,
    /// Elevations, x fastest: `z[i + nx·j]` at `origin + cell·(i, j)`.
    pub z: &'a [f32],
    /// Between the samples: bilinear or Catmull-Rom bicubic, as
    /// [`crate::dem::Heightfield::sample`] interpolates.
    pub interpolation: Interpolation,
    /// Detail amplification over the same grid, if any.
    pub detail: Option<&'a Detail>,
}

/// Appends the samples of `grid` and its slope pyramid to `heights` (and a detail's
/// roughness, its fBm to `noises`); returns the `HEIGHT` flags and parameters with σ's
/// width `falloff`.
pub(super) fn encode(
    grid: &HeightGrid<'_>,
    falloff: f32,
    heights: &mut Vec<f32>,
    noises: &mut Vec<Fbm>,
) -> Result<(u32, Vec<f32>), TapeError> {
    let HeightGrid {
        origin,
        cell,
        nx,
        ny,
        z,
        interpolation,
        detail,
    } = *grid;
    if nx < 2
        || ny < 2
        || z.len() != nx * ny
        || cell.is_nan()
        || cell <= 0.0
        || z.iter().any(|v| !v.is_finite())
    {
        return Err(TapeError::Invalid(format!(
            "heightfield: need at least 2 × 2 finite samples ({nx} × {ny} given, {} values) and a positive cell",
            z.len()
        )));
    }
    // The CPU leaf's own bounds of |∇h| per cell (from its samples or stencil), as a
    // max pyramid, so a ball's slope is that of the cells under it (Génevaux et al. 2015 §7.3.1).
    let slopes = Heightfield::new(nx, ny, origin, Vec2::splat(cell), z.to_vec())
        .map_err(|e| TapeError::Invalid(format!("heightfield: {e}")))?
        .cell_slopes(interpolation);
    let pyramid = MinMaxPyramid::new(nx - 1, ny - 1, slopes);
    let levels = pyramid.levels().count();
    let mut q = vec![0.0; height::PYRAMID + levels];
    q[height::FALLOFF] = falloff;
    q[height::LEVELS] = levels as f32;
    q[height::ORIGIN] = origin.x;
    q[height::ORIGIN + 1] = origin.y;
    q[height::CELL] = cell;
    q[height::NX] = nx as f32;
    q[height::NY] = ny as f32;
    q[height::OFFSET] = heights.len() as f32;
    heights.extend_from_slice(z);
    for (k, (_, _, level)) in pyramid.levels().enumerate() {
        q[height::PYRAMID + k] = heights.len() as f32;
        heights.extend(level.iter().map(|s| s[1]));
    }
    let mut flags = 0;
    if let Some(d) = detail {
        let m = d.roughness();
        if m.nx() != nx || m.ny() != ny {
            return Err(TapeError::Invalid(
                "heightfield: the detail's roughness is not on the samples' grid".into(),
            ));
        }
        flags |= flag::DETAIL;
        q[height::DETAIL_AMPLITUDE] = d.amplitude();
        q[height::DETAIL_SLOPE] = d.slope(d.amplitude());
        q[height::DETAIL_ROUGH] = heights.len() as f32;
        heights.extend_from_slice(m.samples());
        let f = encode_fbm(noises.len(), &d.params().noise);
        q[height::DETAIL_FBM..height::DETAIL_FBM + fbm::LEN].copy_from_slice(&f);
        noises.push(d.params().noise);
    }
    if heights.len() >= limit::MAX_OFFSET {
        return Err(TapeError::Invalid(format!(
            "heightfield: {} samples and slopes in all exceed the 2^24 a tape indexes",
            heights.len()
        )));
    }
    if interpolation == Interpolation::Bicubic {
        flags |= flag::BICUBIC;
    }
    Ok((flags, q))
}

/// `(value at p, Lipschitz bound over B(c, r))` of the `HEIGHT` with flags `flags` and
/// parameters `q` over `heights` (a detail's fBm in `noises`); `BOUND`: compute the bound
/// (else the second component is 0).
#[inline]
pub(super) fn eval<const BOUND: bool>(
    (heights, noises): (&[f32], &[Fbm]),
    flags: u32,
    q: &[f32],
    p: Vec3,
    c: Vec3,
    r: f32,
) -> (f32, f32) {
    let fall = q[height::FALLOFF];
    let h = |x: f32, y: f32| {
        if flags & flag::BICUBIC != 0 {
            bicubic(heights, q, x, y)
        } else {
            bilinear(heights, q, q[height::OFFSET], x, y)
        }
    };
    let detail = |p: Vec3| {
        let m = bilinear(heights, q, q[height::DETAIL_ROUGH], p.x, p.y);
        let t = noises[q[height::DETAIL_FBM + fbm::INDEX] as usize].value(p);
        q[height::DETAIL_AMPLITUDE] * m * t
    };
    let has_detail = flags & flag::DETAIL != 0;
    let dp = if has_detail { detail(p) } else { 0.0 };
    let hp = h(p.x, p.y);
    let value = sigma(hp + dp - p.z, fall);
    if !BOUND {
        return (value, 0.0);
    }
    let hc = if p == c { hp } else { h(c.x, c.y) };
    let slope = slope_under(heights, q, c, r);
    let mut v = Interval::new(hc - slope * r - c.z - r, hc + slope * r - c.z + r);
    let mut l = (1.0 + slope * slope).sqrt();
    if has_detail {
        let (a, ld) = (q[height::DETAIL_AMPLITUDE], q[height::DETAIL_SLOPE]);
        let dc = if p == c { dp } else { detail(c) };
        v = Interval::new(v.lo + (dc - ld * r).max(-a), v.hi + (dc + ld * r).min(a));
        l += ld;
    }
    (value, sigma_slope(v, fall) * l)
}

/// The grid of `q`: origin x and y, cell, `nx`, `ny` (as the parameters hold them).
#[inline(always)]
fn grid(q: &[f32]) -> (f32, f32, f32, f32, f32) {
    (
        q[height::ORIGIN],
        q[height::ORIGIN + 1],
        q[height::CELL],
        q[height::NX],
        q[height::NY],
    )
}

/// A bound of `|∇h|` over the disc of radius `r` around `c` (and its clamp to the grid)
/// from the slope pyramid of the heightfield `q`: the cells under the disc's square are
/// `i0..=i1 × j0..=j1`, and at the level `k` of the highest bit where `i0` and `i1` (or
/// `j0` and `j1`) differ, they lie in at most 2 × 2 blocks, whose maximum is read.
fn slope_under(heights: &[f32], q: &[f32], c: Vec3, r: f32) -> f32 {
    let (ox, oy, cell, nx, ny) = grid(q);
    let index =
        |x: f32, o: f32, n: f32| (((x - o) / cell).clamp(0.0, n - 1.0).floor()).min(n - 2.0) as u32;
    let (i0, i1) = (index(c.x - r, ox, nx), index(c.x + r, ox, nx));
    let (j0, j1) = (index(c.y - r, oy, ny), index(c.y + r, oy, ny));
    let high = |a: u32, b: u32| 31u32.saturating_sub((a ^ b).leading_zeros());
    let levels = q[height::LEVELS] as u32;
    let k = high(i0, i1).max(high(j0, j1)).min(levels - 1);
    let w = (nx as u32 - 1 + (1 << k) - 1) >> k;
    let at = q[height::PYRAMID + k as usize] as usize;
    let s = |i: u32, j: u32| heights[at + (i + w * j) as usize];
    let (i0, i1, j0, j1) = (i0 >> k, i1 >> k, j0 >> k, j1 >> k);
    s(i0, j0).max(s(i1, j0)).max(s(i0, j1)).max(s(i1, j1))
}

/// Bilinear value at `(x, y)` of the samples at `off` in `heights` (the elevations, or a
/// detail's roughness), clamped to the grid of `q`.
fn bilinear(heights: &[f32], q: &[f32], off: f32, x: f32, y: f32) -> f32 {
    let (ox, oy, cell, nx, ny) = grid(q);
    let off = off as usize;
    let gx = ((x - ox) / cell).clamp(0.0, nx - 1.0);
    let gy = ((y - oy) / cell).clamp(0.0, ny - 1.0);
    let (i, j) = ((gx.floor()).min(nx - 2.0), (gy.floor()).min(ny - 2.0));
    let (fx, fy) = (gx - i, gy - j);
    let (i, j, w) = (i as usize, j as usize, nx as usize);
    let z = |a: usize, b: usize| heights[off + a + w * b];
    let bottom = z(i, j) + (z(i + 1, j) - z(i, j)) * fx;
    let top = z(i, j + 1) + (z(i + 1, j + 1) - z(i, j + 1)) * fx;
    bottom + (top - bottom) * fy
}

/// Bicubic (Catmull-Rom) elevation at `(x, y)` clamped to the grid, the stencil's indices
/// clamped at its edges: [`crate::dem::Heightfield::sample`]'s cell, weights and sum order.
fn bicubic(heights: &[f32], q: &[f32], x: f32, y: f32) -> f32 {
    let (ox, oy, cell, nx, ny) = grid(q);
    let off = q[height::OFFSET] as usize;
    let gx = ((x - ox) / cell).clamp(0.0, nx - 1.0);
    let gy = ((y - oy) / cell).clamp(0.0, ny - 1.0);
    let (i, j) = ((gx.floor()).min(nx - 2.0), (gy.floor()).min(ny - 2.0));
    let (wx, wy) = (
        crate::dem::interp::cr_weights(gx - i),
        crate::dem::interp::cr_weights(gy - j),
    );
    let (i, j, w, h) = (i as i64, j as i64, nx as i64, ny as i64);
    let mut v = 0.0;
    for (b, wyb) in wy.iter().enumerate() {
        let jj = (j + b as i64 - 1).clamp(0, h - 1);
        let mut row = 0.0;
        for (a, wxa) in wx.iter().enumerate() {
            let ii = (i + a as i64 - 1).clamp(0, w - 1);
            row += wxa * heights[off + (ii + w * jj) as usize];
        }
        v += wyb * row;
    }
    v
}

//! The two scalar profiles that turn distances into fields (Paris et al. 2019 §3.3, §5.1).
//!
//! * Wyvill's falloff `g(x) = (1 − x²)³` on `[0, 1]`, 0 beyond: skeletal primitives are
//!   `energy · g(d / R)`.
//! * The compactly supported sigmoid `σ_R` for signed, distance-like sources (heightfield
//!   vertical distance, the voxel S field, prism distance): `σ(0) = T`, `σ(x) = 2T` for
//!   `x ≥ R`, `σ(x) = 0` for `x ≤ −R`, odd about `(0, T)` and C¹.
//!
//! Paris et al. 2019 §5.1 also asks `σ'(0) = 1`. With distances in metres and `R` in metres that
//! cubic overshoots `2T` (it is monotone only for `R ≤ 3T`), so we keep the other three
//! constraints and take the monotone odd cubic `σ(x) = T(1 + 3u/2 − u³/2)`, `u = x / R`,
//! whose slope at 0 is `3T / (2R)`. The surface `σ = T` is still exactly `x = 0`.

use super::bounds::Interval;

/// The iso-value `T` of the field convention (Paris et al. 2019 §5.1): solid where
/// `f > T`, the surface at `f = T`. The papers' and the docs' formulas write it `T`.
pub const ISO: f32 = 0.5;

/// Where Wyvill's falloff crosses the iso-value, in units of `R`: `g(x) = T` at
/// `x = √(1 − T^⅓)`, 0.454 for `T = ½`. How far beyond its skeleton the surface of a
/// primitive of energy 1 stands, as a share of its falloff.
pub fn iso_reach() -> f32 {
    (1.0 - ISO.cbrt()).sqrt()
}

/// `max |g'(x)|` over `[0, 1]`, reached at `x = 1/√5`.
pub const WYVILL_MAX_SLOPE: f32 = 1.717_300_8;
/// Where `|g'|` peaks: `x = 1/√5`.
pub const WYVILL_PEAK_X: f32 = 0.447_213_6;

/// Wyvill's falloff `g(x) = (1 − x²)³` for `0 ≤ x < 1`, 0 beyond.
#[inline]
pub fn wyvill(x: f32) -> f32 {
    if x >= 1.0 {
        0.0
    } else {
        let s = 1.0 - x * x;
        s * s * s
    }
}

/// `(g(x), g'(x))`.
#[inline]
pub fn wyvill_d(x: f32) -> (f32, f32) {
    if x >= 1.0 {
        (0.0, 0.0)
    } else {
        let s = 1.0 - x * x;
        (s * s * s, -6.0 * x * s * s)
    }
}

/// Range of `g` over `x ∈ xs` (`x ≥ 0`); `g` decreases on `[0, ∞)`.
#[inline]
pub fn wyvill_interval(xs: Interval) -> Interval {
    Interval {
        lo: wyvill(xs.hi.max(0.0)),
        hi: wyvill(xs.lo.max(0.0)),
    }
}

/// `max |g'(x)|` over `x ∈ xs`.
#[inline]
pub fn wyvill_slope(xs: Interval) -> f32 {
    let (a, b) = (xs.lo.max(0.0), xs.hi.max(0.0));
    if a >= 1.0 {
        0.0
    } else if a <= WYVILL_PEAK_X && WYVILL_PEAK_X <= b {
        WYVILL_MAX_SLOPE
    } else {
        wyvill_d(a).1.abs().max(wyvill_d(b.min(1.0)).1.abs())
    }
}

/// The sigmoid `σ_R(x)`, from 0 (`x ≤ −R`) through `T` (`x = 0`) to `2T` (`x ≥ R`).
/// The cubic is clamped to `[0, 2T]`: in f32 it rounds a hair below 0 just inside `−R`,
/// which would make it non-monotone there (and intervals of it inverted).
#[inline]
pub fn sigma(x: f32, r: f32) -> f32 {
    let u = (x / r).clamp(-1.0, 1.0);
    (ISO * (1.0 + 1.5 * u - 0.5 * u * u * u)).clamp(0.0, 2.0 * ISO)
}

/// `(σ_R(x), σ_R'(x))`.
#[inline]
pub fn sigma_d(x: f32, r: f32) -> (f32, f32) {
    let u = (x / r).clamp(-1.0, 1.0);
    (sigma(x, r), 1.5 * ISO / r * (1.0 - u * u))
}

/// `max σ_R'` over all `x`: `3T / (2R)`.
#[inline]
pub fn sigma_max_slope(r: f32) -> f32 {
    1.5 * ISO / r
}

/// Range of `σ_R` over `xs` (σ is monotone).
#[inline]
pub fn sigma_interval(xs: Interval, r: f32) -> Interval {
    Interval {
        lo: sigma(xs.lo, r),
        hi: sigma(xs.hi, r),
    }
}

/// `max σ_R'(x)` over `xs`: the slope is largest where `|x|` is smallest.
#[inline]
pub fn sigma_slope(xs: Interval, r: f32) -> f32 {
    let nearest = if xs.contains(0.0) {
        0.0
    } else {
        xs.lo.abs().min(xs.hi.abs())
    };
    sigma_d(nearest, r).1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iso_reach_is_where_the_falloff_crosses_the_iso_value() {
        assert!((wyvill(iso_reach()) - ISO).abs() < 1e-6);
    }

    #[test]
    fn wyvill_shape() {
        assert_eq!(wyvill(0.0), 1.0);
        assert_eq!(wyvill(1.0), 0.0);
        let peak = (0..=10_000)
            .map(|i| wyvill_d(i as f32 / 10_000.0).1.abs())
            .fold(0.0, f32::max);
        assert!((peak - WYVILL_MAX_SLOPE).abs() < 1e-4 && peak <= WYVILL_MAX_SLOPE);
    }

    #[test]
    fn sigma_is_monotone_and_hits_its_constraints() {
        let r = 7.0;
        assert_eq!(sigma(0.0, r), ISO);
        assert_eq!(sigma(r, r), 2.0 * ISO);
        assert_eq!(sigma(-r, r), 0.0);
        assert_eq!(sigma_d(r, r).1, 0.0);
        let mut last = -1.0;
        for i in -1000..=1000 {
            let x = i as f32 * 0.01;
            let v = sigma(x, r);
            assert!(v >= last);
            assert!(
                (sigma(-x, r) - (2.0 * ISO - v)).abs() < 1e-6,
                "odd about (0, T)"
            );
            last = v;
        }
    }

    #[test]
    fn slopes_bound_finite_differences() {
        let r = 3.0;
        for i in 0..500 {
            let a = -4.0 + i as f32 * 0.016;
            let b = a + 0.3;
            let s = sigma_slope(Interval::new(a, b), r);
            let fd = (sigma(b, r) - sigma(a, r)) / 0.3;
            assert!(fd <= s + 1e-5);
            let (xa, xb) = (a.abs() / 3.0, a.abs() / 3.0 + 0.1);
            let ws = wyvill_slope(Interval::new(xa, xb));
            assert!((wyvill(xa) - wyvill(xb)).abs() / 0.1 <= ws + 1e-5);
        }
    }
}

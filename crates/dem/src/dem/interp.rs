//! Interpolation kernels on a grid cell: bilinear and Catmull-Rom bicubic, with the
//! constants that bound them (checked numerically in the tests below).

/// Catmull-Rom weights of samples `p[-1..=2]` at `t ∈ [0, 1]`.
#[inline]
pub fn cr_weights(t: f32) -> [f32; 4] {
    let t2 = t * t;
    let t3 = t2 * t;
    [
        0.5 * (-t3 + 2.0 * t2 - t),
        0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
        0.5 * (-3.0 * t3 + 4.0 * t2 + t),
        0.5 * (t3 - t2),
    ]
}

/// Derivatives of [`cr_weights`] with respect to `t`.
#[inline]
pub(crate) fn cr_weights_d(t: f32) -> [f32; 4] {
    let t2 = t * t;
    [
        0.5 * (-3.0 * t2 + 4.0 * t - 1.0),
        0.5 * (9.0 * t2 - 10.0 * t),
        0.5 * (-9.0 * t2 + 8.0 * t + 1.0),
        0.5 * (3.0 * t2 - 2.0 * t),
    ]
}

/// A bound on `|∂p/∂t|` of a 1D Catmull-Rom segment per unit of the largest neighbour
/// difference `max |p[k+1] − p[k]|`: `max_t` of the sum of the absolute coefficients of the
/// three differences, `1.5` at `t = ½`.
pub(crate) const CR_SLOPE: f32 = 1.5;

/// `max_t Σ|w_k(t)|` of the Catmull-Rom weights: `1.25` at `t = ½`.
pub(crate) const CR_ABS_SUM: f32 = 1.25;

/// Bicubic slope bound per axis: `|∂h/∂x| ≤ BICUBIC_SLOPE · max|Δx| / dx`.
pub(crate) const BICUBIC_SLOPE: f32 = CR_SLOPE * CR_ABS_SUM * 1.000_1;

/// Bicubic overshoot: over a cell, `h ∈ [m − c(M − m), M + c(M − m)]` with `m, M` the
/// min/max of its 4×4 stencil and `c` the largest sum of negative tensor weights,
/// `2 · 1.125 · 0.125` at `t = s = ½`.
pub(crate) const BICUBIC_OVERSHOOT: f32 = 0.281_25 * 1.000_1;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_partition_unity_and_derivatives_match() {
        for k in 0..=100 {
            let t = k as f32 / 100.0;
            let w = cr_weights(t);
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
            let d = cr_weights_d(t);
            let h = 1e-3;
            let (a, b) = (cr_weights(t - h), cr_weights(t + h));
            for i in 0..4 {
                assert!(((b[i] - a[i]) / (2.0 * h) - d[i]).abs() < 1e-3);
            }
        }
    }

    #[test]
    fn constants_bound_their_maxima() {
        let (mut slope, mut abs_sum, mut neg) = (0.0f32, 0.0f32, 0.0f32);
        for k in 0..=2000 {
            let t = k as f32 / 2000.0;
            let d = cr_weights_d(t);
            // p' = Σ d_k p_k = c0 δ0 + c1 δ1 + c2 δ2 with δk = p[k+1] − p[k]
            let c = [-d[0], -d[0] - d[1], d[3]];
            slope = slope.max(c.iter().map(|x| x.abs()).sum());
            let w = cr_weights(t);
            abs_sum = abs_sum.max(w.iter().map(|x| x.abs()).sum());
            for l in 0..=200 {
                let ws = cr_weights(l as f32 / 200.0);
                let mut n = 0.0;
                for a in w {
                    for b in ws {
                        n += (a * b).min(0.0).abs();
                    }
                }
                neg = neg.max(n);
            }
        }
        assert!(
            slope <= CR_SLOPE + 1e-5 && slope > CR_SLOPE - 1e-3,
            "{slope}"
        );
        assert!(
            abs_sum <= CR_ABS_SUM + 1e-5 && abs_sum > CR_ABS_SUM - 1e-3,
            "{abs_sum}"
        );
        assert!(
            neg <= BICUBIC_OVERSHOOT && neg > BICUBIC_OVERSHOOT - 1e-3,
            "{neg}"
        );
    }
}

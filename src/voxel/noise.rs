//! A small value-noise fBm with a proven Lipschitz bound, for the S-field displacement
//! `S − α·fbm(β·p)` (seed 000 §4.4, ch. 6).
//!
//! Value noise: pseudo-random lattice values in `[−1, 1]` blended with the C¹ smoothstep
//! `s(t) = t²(3 − 2t)`. Along x the derivative is `s'(t_x)` times a convex combination of
//! lattice differences, so `|∂n/∂x| ≤ max s' · 2 = 1.5 · 2 = 3`, likewise for y and z:
//! `‖∇n‖ ≤ 3√3`. The fBm sum of `octaves` terms `gainⁱ · n(lacunarityⁱ q)` is bounded by
//! `Σ gainⁱ` and its Lipschitz constant by `3√3 · Σ (gain · lacunarity)ⁱ`.
//!
//! (To be replaced by the shared `field::noise::Fbm` once it is merged.)

use glam::{IVec3, Vec3};

/// Fractional Brownian motion of value noise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fbm {
    /// Seed of the lattice values.
    pub seed: u32,
    /// Number of octaves.
    pub octaves: u32,
    /// Amplitude ratio between octaves.
    pub gain: f32,
    /// Frequency ratio between octaves.
    pub lacunarity: f32,
}

/// `‖∇n‖` bound of one octave of value noise.
const OCTAVE_LIPSCHITZ: f32 = 3.0 * 1.732_050_8;

#[inline]
fn lattice(g: IVec3, seed: u32) -> f32 {
    // A 32-bit integer hash (lowbias32-style mixing) mapped to [-1, 1].
    let mut h = (g.x as u32).wrapping_mul(0x8da6_b343)
        ^ (g.y as u32).wrapping_mul(0xd816_3841)
        ^ (g.z as u32).wrapping_mul(0xcb1a_b31f)
        ^ seed.wrapping_mul(0x9e37_79b9);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^= h >> 16;
    (h >> 8) as f32 * (2.0 / 16_777_215.0) - 1.0
}

/// One octave of value noise and its gradient.
fn value_noise(q: Vec3, seed: u32) -> (f32, Vec3) {
    let c = q.floor();
    let t = q - c;
    let c = c.as_ivec3();
    let s = t * t * (Vec3::splat(3.0) - 2.0 * t);
    let ds = 6.0 * t * (Vec3::ONE - t);
    let v = |dx, dy, dz| lattice(c + IVec3::new(dx, dy, dz), seed);
    let (v000, v100, v010, v110) = (v(0, 0, 0), v(1, 0, 0), v(0, 1, 0), v(1, 1, 0));
    let (v001, v101, v011, v111) = (v(0, 0, 1), v(1, 0, 1), v(0, 1, 1), v(1, 1, 1));
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let x00 = lerp(v000, v100, s.x);
    let x10 = lerp(v010, v110, s.x);
    let x01 = lerp(v001, v101, s.x);
    let x11 = lerp(v011, v111, s.x);
    let y0 = lerp(x00, x10, s.y);
    let y1 = lerp(x01, x11, s.y);
    let val = lerp(y0, y1, s.z);
    let gx = lerp(
        lerp(v100 - v000, v110 - v010, s.y),
        lerp(v101 - v001, v111 - v011, s.y),
        s.z,
    ) * ds.x;
    let gy = lerp(x10 - x00, x11 - x01, s.z) * ds.y;
    let gz = (y1 - y0) * ds.z;
    (val, Vec3::new(gx, gy, gz))
}

impl Fbm {
    /// `fbm(q)` and its gradient.
    pub fn value_grad(&self, q: Vec3) -> (f32, Vec3) {
        let (mut a, mut f) = (1.0, 1.0);
        let (mut v, mut g) = (0.0, Vec3::ZERO);
        for o in 0..self.octaves {
            // Offsets keep the octaves' lattices from lining up at the origin.
            let off = Vec3::new(17.31, -9.77, 5.13) * o as f32;
            let (n, dn) = value_noise(q * f + off, self.seed.wrapping_add(o.wrapping_mul(1013)));
            v += a * n;
            g += dn * (a * f);
            a *= self.gain;
            f *= self.lacunarity;
        }
        (v, g)
    }

    /// `fbm(q)`.
    pub fn value(&self, q: Vec3) -> f32 {
        self.value_grad(q).0
    }

    /// `max |fbm|`: `Σ gainⁱ`.
    pub fn amplitude(&self) -> f32 {
        (0..self.octaves).map(|o| self.gain.powi(o as i32)).sum()
    }

    /// `max ‖∇fbm‖`: `3√3 · Σ (gain · lacunarity)ⁱ`.
    pub fn lipschitz(&self) -> f32 {
        OCTAVE_LIPSCHITZ
            * (0..self.octaves)
                .map(|o| (self.gain * self.lacunarity).powi(o as i32))
                .sum::<f32>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const F: Fbm = Fbm {
        seed: 7,
        octaves: 4,
        gain: 0.5,
        lacunarity: 2.0,
    };

    #[test]
    fn bounds_hold_and_gradient_matches_differences() {
        let (amp, lip) = (F.amplitude(), F.lipschitz());
        let mut seen = 0.0f32;
        for i in 0..4000 {
            let p = Vec3::new(
                (i as f32 * 0.731).sin() * 40.0,
                (i as f32 * 1.37).cos() * 40.0,
                i as f32 * 0.0123,
            );
            let q = p + Vec3::new(0.013, -0.021, 0.017) * ((i % 7) as f32 + 1.0);
            let (v, g) = F.value_grad(p);
            assert!(v.abs() <= amp);
            assert!((v - F.value(q)).abs() <= lip * p.distance(q) + 1e-5);
            seen = seen.max((v - F.value(q)).abs() / p.distance(q));
            let e = 1e-3;
            let fd = Vec3::new(
                F.value(p + Vec3::X * e) - F.value(p - Vec3::X * e),
                F.value(p + Vec3::Y * e) - F.value(p - Vec3::Y * e),
                F.value(p + Vec3::Z * e) - F.value(p - Vec3::Z * e),
            ) / (2.0 * e);
            assert!((fd - g).length() < 0.02 * (1.0 + g.length()), "{fd} vs {g}");
        }
        assert!(
            seen > 0.1 * lip,
            "the bound is not absurdly loose ({seen} vs {lip})"
        );
        // Deterministic and seed-dependent.
        assert_eq!(F.value(Vec3::splat(0.3)), F.value(Vec3::splat(0.3)));
        assert_ne!(
            F.value(Vec3::splat(0.3)),
            Fbm { seed: 8, ..F }.value(Vec3::splat(0.3))
        );
    }
}

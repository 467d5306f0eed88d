//! The localized turbulence warp of Paris et al. 2019 §5.3: `f̃(p) = f(ω⁻¹(p))` with
//! `ω⁻¹(p) = p + δ(p)·f_D(p)`, where `δ` is a turbulence displacement (three fBm, one per
//! axis, of amplitude `A`) and `f_D ∈ [0, 1]` localizes it to a box with a Wyvill falloff.

use glam::{Mat3, Vec3};

use super::bounds::Aabb;
use super::falloff::{WYVILL_MAX_SLOPE, wyvill_d};
use super::noise::{Fbm, NoiseSpec};

/// A localized turbulence warp.
#[derive(Clone, Debug, PartialEq)]
pub struct Warp {
    turbulence: [Fbm; 3],
    amplitude: f32,
    /// `(box, falloff)`: `f_D = 1` in the box, `g(d / falloff)` around it. `None`: everywhere.
    region: Option<(Aabb, f32)>,
}

impl Warp {
    /// A warp of displacement amplitude `amplitude` (metres per axis) made of `noise`
    /// reseeded per axis, applied in `region` (a box and its falloff width) or everywhere.
    pub fn new(noise: Fbm, seed: u32, amplitude: f32, region: Option<(Aabb, f32)>) -> Self {
        let axis = |k: u32| {
            Fbm::with(
                seed.wrapping_add(0x632b_e5ab_u32.wrapping_mul(k + 1)),
                noise.wavelength(),
                noise.octaves(),
            )
        };
        Warp {
            turbulence: [axis(0), axis(1), axis(2)],
            amplitude,
            region,
        }
    }

    /// The warp of a tree-file turbulence spec (`amplitude` in metres) within `region`;
    /// `scene_seed` is the tree's global seed.
    pub fn from_spec(spec: &NoiseSpec, region: Option<(Aabb, f32)>, scene_seed: u32) -> Self {
        let noise = Fbm::new(spec, scene_seed);
        let seed = scene_seed ^ spec.seed_offset.rotate_left(16);
        Warp::new(noise, seed, spec.amplitude.get(), region)
    }

    /// The turbulence of each axis.
    pub fn turbulence(&self) -> &[Fbm; 3] {
        &self.turbulence
    }

    /// The displacement amplitude `A` (metres per axis).
    pub fn amplitude(&self) -> f32 {
        self.amplitude
    }

    /// The region `(box, falloff)` the warp is localized to, `None` for everywhere.
    pub fn region(&self) -> Option<(Aabb, f32)> {
        self.region
    }

    /// The farthest any point moves: `A·√3`.
    pub fn reach(&self) -> f32 {
        self.amplitude * 3f32.sqrt()
    }

    fn localize(&self, p: Vec3) -> (f32, Vec3) {
        match &self.region {
            None => (1.0, Vec3::ZERO),
            Some((b, r)) => {
                let q = b.clamp(p);
                let d = (p - q).length();
                if d == 0.0 {
                    return (1.0, Vec3::ZERO);
                }
                let (g, dg) = wyvill_d(d / r);
                (g, (p - q) / d * (dg / r))
            }
        }
    }

    /// `ω⁻¹(p)`: where the child is evaluated.
    #[inline]
    pub fn apply(&self, p: Vec3) -> Vec3 {
        let (fd, _) = self.localize(p);
        if fd == 0.0 {
            return p;
        }
        let d = Vec3::new(
            self.turbulence[0].value(p),
            self.turbulence[1].value(p),
            self.turbulence[2].value(p),
        );
        p + d * (self.amplitude * fd)
    }

    /// `ω⁻¹(p)` and its Jacobian `J` (`J[col j] = ∂ω⁻¹/∂p_j`).
    pub fn apply_jacobian(&self, p: Vec3) -> (Vec3, Mat3) {
        let (fd, gfd) = self.localize(p);
        if fd == 0.0 {
            return (p, Mat3::IDENTITY);
        }
        let (d0, g0) = self.turbulence[0].value_grad(p);
        let (d1, g1) = self.turbulence[1].value_grad(p);
        let (d2, g2) = self.turbulence[2].value_grad(p);
        let a = self.amplitude;
        let delta = Vec3::new(d0, d1, d2) * a;
        // Rows of J_δ are the gradients of the components; J = I + f_D J_δ + δ ⊗ ∇f_D.
        let j_delta_t = Mat3::from_cols(g0 * a, g1 * a, g2 * a);
        let outer_t = Mat3::from_cols(gfd * delta.x, gfd * delta.y, gfd * delta.z);
        let j = Mat3::IDENTITY + (j_delta_t * fd + outer_t).transpose();
        (p + delta * fd, j)
    }

    /// Lipschitz bound of `ω⁻¹`: `1 + A·√3·L_t + A·√3·max|∇f_D|`.
    pub fn lipschitz(&self) -> f32 {
        let lt = self
            .turbulence
            .iter()
            .map(Fbm::lipschitz)
            .fold(0.0, f32::max);
        let ld = self.region.map_or(0.0, |(_, r)| WYVILL_MAX_SLOPE / r);
        1.0 + self.reach() * (lt + ld)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn warp() -> Warp {
        let region = Aabb::new(Vec3::splat(-5.0), Vec3::splat(5.0));
        Warp::new(Fbm::with(3, 4.0, 3), 11, 1.5, Some((region, 3.0)))
    }

    #[test]
    fn jacobian_matches_finite_differences_and_lipschitz_holds() {
        let w = warp();
        let l = w.lipschitz();
        let mut s = 1u32;
        let mut rnd = || {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (s >> 8) as f32 / (1u32 << 24) as f32 * 20.0 - 10.0
        };
        for _ in 0..2000 {
            let p = Vec3::new(rnd(), rnd(), rnd());
            let (q, j) = w.apply_jacobian(p);
            assert!((q - w.apply(p)).length() < 1e-5);
            assert!((q - p).length() <= w.reach() + 1e-5);
            let h = 1e-3;
            for axis in 0..3 {
                let e = Vec3::AXES[axis] * h;
                let fd = (w.apply(p + e) - w.apply(p - e)) / (2.0 * h);
                assert!(
                    (fd - j.col(axis)).length() < 2e-2 * l,
                    "column {axis} at {p}: {fd} vs {}",
                    j.col(axis)
                );
            }
            let p2 = p + Vec3::new(rnd(), rnd(), rnd()) * 0.05;
            assert!((w.apply(p) - w.apply(p2)).length() <= l * (p - p2).length() + 1e-5);
        }
    }

    #[test]
    fn outside_the_region_nothing_moves() {
        let w = warp();
        let p = Vec3::new(9.0, 0.0, 0.0);
        assert_eq!(w.apply(p), p);
    }
}

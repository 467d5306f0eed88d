//! A deterministic random stream: the one source of random numbers of the generators, so
//! that a scene gives the same bytes on every machine and at every thread count.

use glam::Vec3;

/// A deterministic random stream (SplitMix64).
pub struct Rng(u64);

impl Rng {
    /// A stream from `seed`.
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ 0x6a09_e667_f3bc_c909)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A uniform number in `[0, 1)`.
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// A direction of the lower hemisphere (`z ≤ 0`), its `z = −u²` (`u` uniform): more
    /// often near the horizontal than a uniform draw, as water that reached a bed spreads
    /// along it.
    pub fn lower_hemisphere(&mut self) -> Vec3 {
        let u = self.unit();
        let z = -u * u;
        let phi = std::f32::consts::TAU * self.unit();
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

//! The tests' and benches' one random generator: SplitMix64 from a fixed seed, so every run
//! draws the same numbers and the tests need no RNG crate.

use glam::Vec3;
use karstic::field::Aabb;

/// SplitMix64 (Steele, Lea and Flood 2014): the state is the seed, advanced by a constant
/// and mixed on every draw.
pub struct Rng(pub u64);

impl Rng {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in `[a, b)`.
    pub fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.f32()
    }

    /// Uniform in the box `b`.
    pub fn in_box(&mut self, b: &Aabb) -> Vec3 {
        b.min + Vec3::new(self.f32(), self.f32(), self.f32()) * b.size()
    }

    /// Uniform in the ball of radius `r`.
    pub fn in_ball(&mut self, r: f32) -> Vec3 {
        loop {
            let p = Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            if p.length_squared() <= 1.0 {
                return p * r;
            }
        }
    }

    /// A uniform unit vector.
    pub fn dir(&mut self) -> Vec3 {
        loop {
            let v = self.in_ball(1.0);
            if v.length_squared() > 0.01 {
                return v.normalize();
            }
        }
    }
}

//! Sampled soundness of a field's segment Lipschitz bounds.

use glam::Vec3;
use karstic::field::{Aabb, Field};

use super::Rng;

/// Samples random pairs on random segments inside `region` and checks
/// `|f(a) − f(b)| ≤ λ_seg · |a − b|` (plus a float slack). Returns the pairs checked.
pub fn check_segment_lipschitz(f: &dyn Field, region: &Aabb, n: usize, seed: u64) -> usize {
    let mut rng = Rng(seed);
    let s = region.size();
    let pick =
        |rng: &mut Rng| region.min + Vec3::new(rng.f32() * s.x, rng.f32() * s.y, rng.f32() * s.z);
    for _ in 0..n {
        let a = pick(&mut rng);
        let b = a + (pick(&mut rng) - a) * rng.f32() * rng.f32();
        let lam = f.lipschitz_segment(a, b);
        let (u, v) = (rng.f32(), rng.f32());
        let (p, q) = (a.lerp(b, u), a.lerp(b, v));
        let df = (f.value(p) - f.value(q)).abs();
        assert!(
            df <= lam * p.distance(q) * 1.001 + 1e-5,
            "Lipschitz bound {lam} violated on [{a}, {b}]: |Δf| = {df} over {}",
            p.distance(q)
        );
        assert!(
            lam <= f.lipschitz() * 1.0001 + 1e-6,
            "local bound above the global one"
        );
    }
    n
}

//! A UV sphere mesh, an independent ground truth for traced depths.

use glam::Vec3;

/// A UV sphere of radius `r` with `n` segments around and `n / 2` rings: its chords lie
/// within `r(1 − cos(π/n))` of the sphere.
pub fn uv_sphere(c: Vec3, r: f32, n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let rings = n / 2;
    let mut pos = Vec::new();
    for i in 0..=rings {
        let th = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..n {
            let ph = std::f32::consts::TAU * j as f32 / n as f32;
            pos.push(c + r * Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()));
        }
    }
    let mut faces = Vec::new();
    for i in 0..rings {
        for j in 0..n {
            let (a, b) = (i * n + j, i * n + (j + 1) % n);
            faces.push([a, a + n, b]);
            faces.push([b, a + n, b + n]);
        }
    }
    (pos, faces)
}

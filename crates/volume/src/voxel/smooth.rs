//! Gaussian smoothing of the surface field (Becher 2016 §4.6.3): separable binomial passes
//! `[1 2 1] / 4` along x, y and z (a Gaussian of variance ½ voxel² per pass). A node on
//! the domain's face is left unchanged along that axis (linear extrapolation), so a
//! linear S — a plane's distance — is preserved exactly.

use super::diffuse::{Sweeps, jacobi};
use super::sparse::{Bricks, PAD};

/// Runs `passes` binomial passes on the non-`fixed` nodes of `s`.
pub fn smooth(bricks: &Bricks, active: &[bool], s: &mut Vec<f32>, fixed: &[bool], passes: u32) {
    let dims = bricks.geom.dims;
    for _ in 0..passes {
        for (axis, o) in [(0usize, 1usize), (1, PAD), (2, PAD * PAD)] {
            jacobi(
                bricks,
                active,
                s,
                fixed,
                Sweeps::Fixed(1),
                |p, i, g, _| {
                    if g[axis] == 0 || g[axis] == dims[axis] - 1 {
                        p[i]
                    } else {
                        0.25 * p[i - o] + 0.5 * p[i] + 0.25 * p[i + o]
                    }
                },
                |_, _| 0.0,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::voxel::sparse::{BRICK_NODES, LevelGeom};
    use glam::{IVec3, Vec3};

    #[test]
    fn keeps_linear_fields_and_damps_noise() {
        let geom = LevelGeom {
            origin: Vec3::ZERO,
            h: 1.0,
            dims: IVec3::new(13, 9, 17),
        };
        let b = Bricks::dense(geom);
        let fixed = b.rim().to_vec();
        let lin = |g: IVec3| 0.2 * g.x as f32 - 0.7 * g.y as f32 + 0.1 * g.z as f32;
        let mut s: Vec<f32> = (0..b.len() * BRICK_NODES)
            .map(|i| lin(b.node_coord(i)))
            .collect();
        smooth(&b, &[], &mut s, &fixed, 3);
        for (i, v) in s.iter().enumerate() {
            if geom.contains(b.node_coord(i)) {
                assert!((v - lin(b.node_coord(i))).abs() < 1e-4);
            }
        }
        let mut noisy: Vec<f32> = (0..b.len() * BRICK_NODES)
            .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        smooth(&b, &[], &mut noisy, &fixed, 1);
        let inner = b.node(IVec3::new(6, 4, 8)).unwrap();
        assert!(noisy[inner].abs() < 1e-6, "a checkerboard along x vanishes");
    }
}

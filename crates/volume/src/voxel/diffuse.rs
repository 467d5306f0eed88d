//! Guidance field diffusion (Becher 2016 §4.3) and noise field diffusion (§4.4) on one level
//! of the sparse grid, and the Jacobi driver every stencil of the pipeline runs on.
//!
//! * Normals: Perona–Malik anisotropic diffusion with `g(x) = 1 / (1 + (x/k)²)` of
//!   `x = ½ − ½ N·N'` (§4.3.1), homogeneous Neumann boundaries. Where a neighbour is
//!   still the zero vector the coefficient is 1 (plain Laplace), which the thesis intends
//!   ("g evaluates to 1") but its formula does not give (`g(½) ≈ 0` for `k = 0.01`).
//!   Vectors are renormalised after each step.
//! * Bitangents: the sign-invariant pairwise average of §4.3.2, axis by axis.
//! * Noise parameters: Laplace's equation (§4.4).
//!
//! The iterations are Jacobi sweeps (ping-pong buffers, parallel over bricks), so the
//! result does not depend on the thread count. The pipeline runs them coarse to fine: the
//! coarsest level to convergence, every finer level a fixed number of sweeps from the
//! prolonged coarse solution — the cascade that keeps fine iteration counts independent
//! of the resolution (the thesis's future work, ch. 8).

use glam::{IVec3, Vec2, Vec3};
use rayon::prelude::*;

use super::sparse::{BRICK, BRICK_NODES, Bricks, PAD, PAD_NODES, padded};
use super::voxelize::pair_bitangents;

/// How many sweeps to run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sweeps {
    /// Exactly this many.
    Fixed(u32),
    /// Until the largest change is below `tol`, at most `max`.
    Converge {
        /// Tolerance on the per-node change.
        tol: f32,
        /// Cap.
        max: u32,
    },
}

/// Offsets of the six face neighbours in a padded brick, with their axis and direction.
pub const FACES: [(isize, usize, i32); 6] = [
    (1, 0, 1),
    (-1, 0, -1),
    (PAD as isize, 1, 1),
    (-(PAD as isize), 1, -1),
    ((PAD * PAD) as isize, 2, 1),
    (-((PAD * PAD) as isize), 2, -1),
];

/// Runs Jacobi sweeps of `update` over the non-`fixed` nodes of `data`, in the bricks
/// marked in `active` (all bricks when `active` is empty; the others keep their values).
///
/// `update(pad, i, g, k)` gets a brick copy of `data` with a one-node halo, the padded
/// index `i` of the node, its global coordinates `g` and its data index `k`; it returns
/// the node's new value. `change` measures a node's update. Returns the number of sweeps
/// run.
pub fn jacobi<T>(
    bricks: &Bricks,
    active: &[bool],
    data: &mut Vec<T>,
    fixed: &[bool],
    sweeps: Sweeps,
    update: impl Fn(&[T], usize, IVec3, usize) -> T + Sync,
    change: impl Fn(T, T) -> f32 + Sync,
) -> u32
where
    T: Copy + Default + Send + Sync,
{
    let (max, tol) = match sweeps {
        Sweeps::Fixed(n) => (n, -1.0),
        Sweeps::Converge { tol, max } => (max, tol),
    };
    if max == 0 || bricks.is_empty() {
        return 0;
    }
    let measure = tol >= 0.0;
    let mut src = std::mem::take(data);
    let mut dst = src.clone();
    let mut done = 0;
    for _ in 0..max {
        let worst = dst
            .par_chunks_mut(BRICK_NODES)
            .enumerate()
            .map_init(
                || vec![T::default(); PAD_NODES],
                |pt, (b, out)| {
                    if !active.is_empty() && !active[b] {
                        return 0.0;
                    }
                    bricks.gather(&src, b, pt);
                    let base = bricks.coords()[b] * BRICK;
                    let mut worst = 0.0f32;
                    let mut l = 0;
                    for z in 0..BRICK {
                        for y in 0..BRICK {
                            for x in 0..BRICK {
                                let i = b * BRICK_NODES + l;
                                out[l] = if fixed[i] {
                                    src[i]
                                } else {
                                    let g = base + IVec3::new(x, y, z);
                                    let v = update(pt, padded(x, y, z), g, i);
                                    if measure {
                                        worst = worst.max(change(v, src[i]));
                                    }
                                    v
                                };
                                l += 1;
                            }
                        }
                    }
                    worst
                },
            )
            .reduce(|| 0.0, f32::max);
        std::mem::swap(&mut src, &mut dst);
        done += 1;
        if worst < tol {
            break;
        }
    }
    *data = src;
    done
}

/// Perona–Malik diffusion of the normal field (§4.3.1) with edge parameter `k`.
pub fn diffuse_normals(
    bricks: &Bricks,
    active: &[bool],
    n: &mut Vec<Vec3>,
    fixed: &[bool],
    k: f32,
    sweeps: Sweeps,
) -> u32 {
    let inv_k2 = 1.0 / (k * k);
    jacobi(
        bricks,
        active,
        n,
        fixed,
        sweeps,
        |p, i, _, _| {
            let c = p[i];
            let c_set = c != Vec3::ZERO;
            let mut acc = Vec3::ZERO;
            for (o, _, _) in FACES {
                let q = p[(i as isize + o) as usize];
                let g = if c_set && q != Vec3::ZERO {
                    let x = 0.5 - 0.5 * c.dot(q);
                    1.0 / (1.0 + x * x * inv_k2)
                } else {
                    1.0
                };
                acc += (q - c) * g;
            }
            (c + acc * (1.0 / 6.0)).normalize_or_zero()
        },
        |a, b| (a - b).length(),
    )
}

/// The sign-invariant average of two bitangents, zero-tolerant (§4.3.2).
fn avg(v: Vec3, w: Vec3) -> Vec3 {
    if v == Vec3::ZERO {
        w
    } else if w == Vec3::ZERO {
        v
    } else {
        pair_bitangents(v, w)
    }
}

/// Bitangent diffusion by sign-invariant averaging of the neighbours (§4.3.2):
/// `avg(avg(b_x, b_y), b_z)` of the per-axis pair averages.
pub fn diffuse_bitangents(
    bricks: &Bricks,
    active: &[bool],
    b: &mut Vec<Vec3>,
    fixed: &[bool],
    sweeps: Sweeps,
) -> u32 {
    jacobi(
        bricks,
        active,
        b,
        fixed,
        sweeps,
        |p, i, _, _| {
            let pair = |o: usize| avg(p[i + o], p[i - o]);
            let v = avg(avg(pair(1), pair(PAD * PAD)), pair(PAD));
            if v == Vec3::ZERO { p[i] } else { v }
        },
        |a, b| 1.0 - a.dot(b).abs(),
    )
}

/// Laplace diffusion of the noise parameters `(α, β)` (§4.4).
pub fn diffuse_noise(
    bricks: &Bricks,
    active: &[bool],
    r: &mut Vec<Vec2>,
    fixed: &[bool],
    sweeps: Sweeps,
) -> u32 {
    jacobi(
        bricks,
        active,
        r,
        fixed,
        sweeps,
        |p, i, _, _| {
            let mut acc = Vec2::ZERO;
            for (o, _, _) in FACES {
                acc += p[(i as isize + o) as usize];
            }
            acc * (1.0 / 6.0)
        },
        |a, b| (a - b).abs().max_element(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::voxel::sparse::LevelGeom;

    fn level(n: i32) -> Bricks {
        Bricks::dense(LevelGeom {
            origin: Vec3::ZERO,
            h: 1.0,
            dims: IVec3::splat(n),
        })
    }

    /// A field of `b` that is zero but on the planes `x = x0` and `x = x1`, where it is
    /// fixed to `v0` and `v1`.
    fn two_planes<T: Copy + Default>(
        b: &Bricks,
        (x0, v0): (i32, T),
        (x1, v1): (i32, T),
    ) -> (Vec<T>, Vec<bool>) {
        let mut v = vec![T::default(); b.len() * BRICK_NODES];
        let mut fixed = vec![false; v.len()];
        for i in 0..v.len() {
            let g = b.node_coord(i);
            if g.x == x0 {
                (v[i], fixed[i]) = (v0, true);
            } else if g.x == x1 {
                (v[i], fixed[i]) = (v1, true);
            }
        }
        (v, fixed)
    }

    #[test]
    fn laplace_converges_to_the_linear_solution() {
        // α fixed to 0 on the plane x = 0 and 1 on x = 15: the harmonic solution is linear.
        let b = level(16);
        let (mut r, fixed) = two_planes(&b, (0, Vec2::ZERO), (15, Vec2::ONE));
        let n = diffuse_noise(
            &b,
            &[],
            &mut r,
            &fixed,
            Sweeps::Converge {
                tol: 1e-6,
                max: 5000,
            },
        );
        assert!(n < 5000);
        for (i, v) in r.iter().enumerate() {
            let g = b.node_coord(i);
            if g.cmplt(IVec3::splat(16)).all() {
                assert!((v.x - g.x as f32 / 15.0).abs() < 2e-3, "{g}: {}", v.x);
            }
        }
    }

    #[test]
    fn perona_malik_fills_the_domain_and_keeps_an_edge() {
        // Two constraint planes with normals 90° apart: the filled field is unit
        // everywhere and the transition between the two halves stays sharp.
        let b = level(24);
        let (n, fixed) = two_planes(&b, (2, Vec3::Z), (21, Vec3::X));
        let (mut sharp, mut smooth) = (n.clone(), n.clone());
        diffuse_normals(&b, &[], &mut sharp, &fixed, 0.01, Sweeps::Fixed(200));
        diffuse_normals(&b, &[], &mut smooth, &fixed, 1e3, Sweeps::Fixed(200));
        let at = |v: &[Vec3], x: i32| v[b.node(IVec3::new(x, 10, 10)).unwrap()];
        for x in 0..24 {
            assert!((at(&sharp, x).length() - 1.0).abs() < 1e-4);
        }
        // Isotropic diffusion rotates gradually; anisotropic keeps plateaus near the
        // constraints (x = 6 and x = 17 stay within 10° of their side's normal).
        assert!(at(&sharp, 6).dot(Vec3::Z) > 0.985 && at(&sharp, 17).dot(Vec3::X) > 0.985);
        assert!(at(&smooth, 6).dot(Vec3::Z) < at(&sharp, 6).dot(Vec3::Z));
    }

    #[test]
    fn bitangents_ignore_sign() {
        let b = level(8);
        let (mut v, fixed) = two_planes(&b, (0, Vec3::Y), (7, -Vec3::Y));
        diffuse_bitangents(&b, &[], &mut v, &fixed, Sweeps::Fixed(20));
        for (i, x) in v.iter().enumerate() {
            if b.geom.contains(b.node_coord(i)) {
                assert!(x.y.abs() > 0.999, "{x}: opposite signs must not cancel");
            }
        }
    }
}

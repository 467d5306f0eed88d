//! Surface propagation (Becher 2016 §4.6): the surface field S from the seed nodes and the
//! normal field.
//!
//! * [`waves`]: signed distance propagation (§4.6.2). Wave after wave, every unset node
//!   next to set ones is set once, from its set face neighbours `x`:
//!   `S = S_x + (p − x)·N̄`, `N̄` the normalised mean of the two nodes' normals, keeping
//!   the candidate of smallest magnitude (the closest surface wins).
//! * [`relax`]: on levels below the base, Jacobi sweeps of the same local model averaged
//!   over the six neighbours — the least-squares fit of `∇S = N` (a Poisson equation)
//!   started from the prolonged coarse S — which carries the fine normals into S.
//! * [`streamlines`]: streamline propagation (§4.6.1): curves traced from the seed
//!   nodes along `B` and then along `B × N` add surface nodes.
//!
//! S is positive on the normals' side (the air) and negative behind them (the solid).

use glam::{IVec3, Vec2, Vec3};
use rayon::prelude::*;

use super::diffuse::{FACES, Sweeps, jacobi};
use super::sparse::{BRICK, BRICK_NODES, Bricks, PAD, PAD_NODES, padded};

/// Runs distance-propagation waves on `s`. `wave[i]` is 0 for unset nodes and the wave
/// that set the node plus one otherwise (seeds: 1); rim nodes are never set. Stops after
/// `max_waves` or when a wave sets nothing; returns the waves run.
pub fn waves(bricks: &Bricks, s: &mut [f32], wave: &mut [u16], n: &[Vec3], max_waves: u32) -> u32 {
    let h = bricks.geom.h;
    let nb = bricks.len();
    let rim = bricks.rim();
    let mut active: Vec<bool> = (0..nb)
        .map(|b| {
            wave[b * BRICK_NODES..(b + 1) * BRICK_NODES]
                .iter()
                .any(|&w| w > 0)
        })
        .collect();
    let mut done = 0;
    for w in 0..max_waves {
        let stamp = (w + 2).min(u16::MAX as u32) as u16;
        // Bricks next to an active one may change in this wave.
        let todo: Vec<bool> = (0..nb)
            .map(|b| {
                bricks
                    .neighbours(b)
                    .iter()
                    .any(|&k| k != super::sparse::NONE && active[k as usize])
            })
            .collect();
        let updates: Vec<Vec<(u32, f32)>> = (0..nb)
            .into_par_iter()
            .map_init(
                || {
                    (
                        vec![0f32; PAD_NODES],
                        vec![0u16; PAD_NODES],
                        vec![Vec3::ZERO; PAD_NODES],
                    )
                },
                |(ps, pw, pn), b| {
                    let mut out = Vec::new();
                    if !todo[b] {
                        return out;
                    }
                    bricks.gather(s, b, ps);
                    bricks.gather(wave, b, pw);
                    bricks.gather(n, b, pn);
                    let mut l = 0;
                    for z in 0..BRICK {
                        for y in 0..BRICK {
                            for x in 0..BRICK {
                                let i = b * BRICK_NODES + l;
                                l += 1;
                                if wave[i] != 0 || rim[i] {
                                    continue;
                                }
                                let pi = padded(x, y, z);
                                let mut best: Option<f32> = None;
                                for (o, axis, dir) in FACES {
                                    let q = (pi as isize + o) as usize;
                                    if pw[q] == 0 {
                                        continue;
                                    }
                                    let nbar = (pn[pi] + pn[q]).normalize_or(pn[q]);
                                    // p − x = −dir·h along the axis.
                                    let cand = ps[q] - dir as f32 * h * nbar[axis];
                                    if best.is_none_or(|b| cand.abs() < b.abs()) {
                                        best = Some(cand);
                                    }
                                }
                                if let Some(v) = best {
                                    out.push((i as u32, v));
                                }
                            }
                        }
                    }
                    out
                },
            )
            .collect();
        let mut any = false;
        active.iter_mut().for_each(|a| *a = false);
        for (b, u) in updates.iter().enumerate() {
            for &(i, v) in u {
                s[i as usize] = v;
                wave[i as usize] = stamp;
                active[b] = true;
                any = true;
            }
        }
        if !any {
            break;
        }
        done += 1;
    }
    done
}

/// Jacobi sweeps of the local distance model averaged over the in-domain face
/// neighbours, with relaxation factor 0.85, on the non-`fixed` nodes.
///
/// A node's update is `(1 − ω) S + ω · mean over its neighbours q of (S_q + (p − q)·N̄)`
/// with `N̄` the normal half-way between the nodes. N does not change during the sweeps, so
/// the normal terms and the neighbour counts are computed once per node.
pub fn relax(
    bricks: &Bricks,
    active: &[bool],
    s: &mut Vec<f32>,
    n: &[Vec3],
    fixed: &[bool],
    sweeps: Sweeps,
) -> u32 {
    let dims = bricks.geom.dims;
    let coef = relax_coefficients(bricks, active, n, fixed);
    jacobi(
        bricks,
        active,
        s,
        fixed,
        sweeps,
        |ps, i, g, k| {
            let c = coef[k];
            let sum = if g.cmpgt(IVec3::ZERO).all() && g.cmplt(dims - IVec3::ONE).all() {
                ps[i - 1]
                    + ps[i + 1]
                    + ps[i - PAD]
                    + ps[i + PAD]
                    + ps[i - PAD * PAD]
                    + ps[i + PAD * PAD]
            } else {
                let mut acc = 0.0;
                for (o, axis, dir) in FACES {
                    let ga = g[axis] + dir;
                    if ga >= 0 && ga < dims[axis] {
                        acc += ps[(i as isize + o) as usize];
                    }
                }
                acc
            };
            (1.0 - OMEGA) * ps[i] + c.y * sum + c.x
        },
        |a, b| (a - b).abs(),
    )
}

/// Relaxation factor of [`relax`].
const OMEGA: f32 = 0.85;

/// Per node of the swept bricks, `(ω · Σ (p − q)·N̄ / count, ω / count)` over its
/// in-domain face neighbours `q` (zero for fixed nodes and those without neighbours).
fn relax_coefficients(bricks: &Bricks, active: &[bool], n: &[Vec3], fixed: &[bool]) -> Vec<Vec2> {
    let h = bricks.geom.h;
    let dims = bricks.geom.dims;
    let mut coef = vec![Vec2::ZERO; n.len()];
    coef.par_chunks_mut(BRICK_NODES).enumerate().for_each_init(
        || vec![Vec3::ZERO; PAD_NODES],
        |pn, (b, out)| {
            if !active.is_empty() && !active[b] {
                return;
            }
            bricks.gather(n, b, pn);
            let base = bricks.coords()[b] * BRICK;
            let mut l = 0;
            for z in 0..BRICK {
                for y in 0..BRICK {
                    for x in 0..BRICK {
                        let (k, g) = (b * BRICK_NODES + l, base + IVec3::new(x, y, z));
                        l += 1;
                        if fixed[k] {
                            continue;
                        }
                        let i = padded(x, y, z);
                        let (mut acc, mut cnt) = (0.0, 0.0);
                        for (o, axis, dir) in FACES {
                            let ga = g[axis] + dir;
                            if ga < 0 || ga >= dims[axis] {
                                continue;
                            }
                            let q = (i as isize + o) as usize;
                            acc -= dir as f32 * h * 0.5 * (pn[i][axis] + pn[q][axis]);
                            cnt += 1.0;
                        }
                        if cnt > 0.0 {
                            out[l - 1] = Vec2::new(OMEGA * acc / cnt, OMEGA / cnt);
                        }
                    }
                }
            }
        },
    );
    coef
}

/// Streamline propagation (§4.6.1, Algorithm 4.2): from every seed node, a curve is
/// traced along `B` (first pass) and along `B × N` (second pass, from all surface nodes
/// found so far), in steps of `h/2`, up to `max_steps`, inside complete cells of the
/// level. Every node passed becomes a surface node whose S is its distance to the
/// traced point along N (stamped as set by the first wave: a source, not a fixed seed).
/// Marks are applied in seed order, so the result is deterministic.
pub fn streamlines(
    bricks: &Bricks,
    s: &mut [f32],
    wave: &mut [u16],
    n: &[Vec3],
    b: &[Vec3],
    max_steps: u32,
) -> usize {
    use super::sparse::trilinear;
    let g = bricks.geom;
    let step = 0.5 * g.h;
    let mut added = 0;
    for pass in 0..2 {
        let starts: Vec<usize> = (0..wave.len())
            .filter(|&i| wave[i] == 1 || wave[i] == 2)
            .collect();
        let marks: Vec<Vec<(usize, f32)>> = starts
            .par_iter()
            .map(|&i0| {
                let mut out = Vec::new();
                let mut x = g.pos(bricks.node_coord(i0));
                let dir_at = |x: Vec3| -> Option<(Vec3, Vec3)> {
                    let (idx, f) = bricks.cell(x)?;
                    let nn = trilinear(n, &idx, f).normalize_or_zero();
                    let bb = trilinear(b, &idx, f).normalize_or_zero();
                    let v = if pass == 0 {
                        bb
                    } else {
                        bb.cross(nn).normalize_or_zero()
                    };
                    (v != Vec3::ZERO).then_some((v, nn))
                };
                let Some((mut v, _)) = dir_at(x) else {
                    return out;
                };
                for _ in 0..max_steps {
                    x += v * step;
                    let Some((nv, nn)) = dir_at(x) else { break };
                    v = if nv.dot(v) < 0.0 { -nv } else { nv };
                    let gi = ((x - g.origin) / g.h).round().as_ivec3();
                    if !g.contains(gi) {
                        break;
                    }
                    if let Some(i) = bricks.node(gi) {
                        out.push((i, (g.pos(gi) - x).dot(nn)));
                    }
                }
                out
            })
            .collect();
        for (i, v) in marks.into_iter().flatten() {
            if wave[i] == 0 && !bricks.rim()[i] {
                // Set like a first wave: a source for the waves, but not a fixed seed,
                // so the relaxation can reconcile it with the seeds.
                wave[i] = 2;
                s[i] = v;
                added += 1;
            }
        }
    }
    added
}

/// Indices of the nodes with `wave == 1` (seeds) — used by tests and statistics.
pub fn seed_count(wave: &[u16]) -> usize {
    wave.iter().filter(|&&w| w == 1).count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::voxel::sparse::LevelGeom;

    #[test]
    fn waves_reproduce_the_distance_to_a_tilted_plane() {
        let geom = LevelGeom {
            origin: Vec3::ZERO,
            h: 0.5,
            dims: IVec3::new(20, 17, 23),
        };
        let b = Bricks::dense(geom);
        let nrm = Vec3::new(0.3, -0.4, 0.8).normalize();
        let c = Vec3::new(5.0, 4.0, 6.0);
        let total = b.len() * BRICK_NODES;
        let n = vec![nrm; total];
        let mut s = vec![0.0; total];
        let mut wave = vec![0u16; total];
        for i in 0..total {
            let p = geom.pos(b.node_coord(i));
            let d = (p - c).dot(nrm);
            if d.abs() < 0.5 * geom.h && geom.contains(b.node_coord(i)) {
                (s[i], wave[i]) = (d, 1);
            }
        }
        let w = waves(&b, &mut s, &mut wave, &n, 1000);
        assert!(w > 5 && w < 60);
        for i in 0..total {
            if geom.contains(b.node_coord(i)) {
                assert!(wave[i] > 0);
                assert!((s[i] - (geom.pos(b.node_coord(i)) - c).dot(nrm)).abs() < 1e-3);
            }
        }
        // Relaxation keeps the exact solution where it already holds.
        let fixed: Vec<bool> = wave
            .iter()
            .zip(b.rim())
            .map(|(&w, &r)| w == 1 || r)
            .collect();
        let before = s.clone();
        let mut s2 = s.clone();
        relax(&b, &[], &mut s2, &n, &fixed, Sweeps::Fixed(5));
        for i in 0..total {
            assert!((s2[i] - before[i]).abs() < 1e-3);
        }
    }
}

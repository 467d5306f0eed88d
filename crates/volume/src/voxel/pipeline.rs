//! The voxel pipeline (Becher 2016, ch. 4) on a stack of sparse levels, coarse to fine.
//!
//! Levels halve the voxel size from a coarsest level of at most 8 nodes per axis down to
//! the requested voxel. Every level is voxelized (§4.2). The normal, bitangent and noise
//! fields are diffused (§4.3, §4.4) to convergence on the coarsest level and for a fixed
//! number of sweeps on every finer one, starting from the prolonged coarser solution.
//! Levels up to the *base* (at most `base` nodes per axis) are dense; S is computed first
//! on the base by full distance propagation (§4.6.2, every node set once). Each finer
//! level allocates bricks only in a band around the coarser surface (`|S| < band·h`) and
//! around its seeds; there S starts from the prolonged coarse S, is re-propagated from
//! the level's own seeds for `band` waves, relaxed towards `∇S = N` and smoothed (§4.6.3).
//! Memory therefore follows the surface's area, not the domain's volume, and no level
//! runs more sweeps as the resolution grows.

use std::time::{Duration, Instant};

use glam::{IVec3, Vec2, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::diffuse::{Sweeps, diffuse_bitangents, diffuse_noise, diffuse_normals};
use super::propagate::{relax, streamlines, waves};
use super::smooth::smooth;
use super::sparse::{BRICK, BRICK_NODES, Bricks, LevelGeom, local, prolong};
use super::voxelize::{Constraint, voxelize};
use crate::curves::{CurveError, Features, Propagation};
use crate::field::Aabb;
use crate::io::check_budget;

/// Settings of one pipeline run.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Params {
    /// The domain.
    pub domain: Aabb,
    /// Finest voxel size (metres).
    pub voxel: f32,
    /// Perona–Malik `k`.
    pub k: f32,
    /// Sweeps per level below the coarsest (diffusion and S relaxation).
    pub iterations: u32,
    /// Half-width of the fine bands, in voxels of each level.
    pub band: f32,
    /// Largest node count per axis of the dense base level.
    pub base: u32,
    /// Smoothing passes on S.
    pub smoothing: u32,
    /// Surface propagation method.
    pub propagation: Propagation,
    /// Memory budget (bytes).
    pub max_memory: u64,
    /// Ribbon width of curves that set none (metres).
    pub ribbon: f32,
    /// Keep the diffused guidance normals N in the result ([`Volume::normals`]), e.g.
    /// for Feature Curve expansion.
    pub keep_normals: bool,
    /// Width of the sigmoid the field puts on S ([`super::FieldParams::transition`]). The
    /// result's S is clamped to `±(transition + α_max + 2 voxels)`: beyond
    /// `transition + α_max` the field is constant, and far from the seeds S holds
    /// whatever the coarse levels left (on a terrain, distances of a hundred metres),
    /// which meets the fine band's values in steep ramps that would only inflate the
    /// Lipschitz bounds.
    pub transition: f32,
}

/// Guidance ribbons reach at least this many voxels of each level (see
/// [`crate::curves::curve_ribbon`]).
const GUIDE_VOXELS: f32 = 1.5;

/// A level voxelizes a tunnel (an arch beam) only if its section (thickness) spans this
/// many voxels.
const TUNNEL_VOXELS: f32 = 3.0;

/// What happened on one level.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LevelStats {
    /// Level number (0 = finest).
    pub level: u32,
    /// Voxel size.
    pub h: f32,
    /// Node counts of the full level.
    pub dims: IVec3,
    /// Dense (every brick) or banded.
    pub dense: bool,
    /// Allocated bricks.
    pub bricks: usize,
    /// Bricks the sweeps ran on (near constraints).
    pub active_bricks: usize,
    /// Voxelized nodes.
    pub constraints: usize,
    /// Seed nodes.
    pub seeds: usize,
    /// Normal diffusion sweeps.
    pub normal_sweeps: u32,
    /// Bitangent diffusion sweeps.
    pub bitangent_sweeps: u32,
    /// Noise diffusion sweeps.
    pub noise_sweeps: u32,
    /// Distance propagation waves.
    pub waves: u32,
    /// S relaxation sweeps.
    pub relax_sweeps: u32,
    /// Surface nodes added by streamlines.
    pub streamline_nodes: usize,
}

/// Wall-clock time per stage, summed over levels (the thesis's Table 7.2 rows).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StageTimes {
    /// Proxy meshes of the primitives.
    pub proxy: Duration,
    /// Allocation and initial values (the thesis's "reset").
    pub reset: Duration,
    /// Voxelization.
    pub voxelize: Duration,
    /// Normal and bitangent diffusion.
    pub guidance: Duration,
    /// Noise diffusion.
    pub noise: Duration,
    /// Surface propagation (waves, streamlines, relaxation).
    pub propagate: Duration,
    /// Smoothing.
    pub smooth: Duration,
    /// Bounds for the field.
    pub finish: Duration,
}

impl StageTimes {
    /// Sum of all stages.
    pub fn total(&self) -> Duration {
        self.proxy
            + self.reset
            + self.voxelize
            + self.guidance
            + self.noise
            + self.propagate
            + self.smooth
            + self.finish
    }
}

/// Statistics of a run.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    /// Per level, coarsest first.
    pub levels: Vec<LevelStats>,
    /// Per stage.
    pub times: StageTimes,
    /// Proxy triangles of the finest level.
    pub triangles: usize,
    /// Largest memory held by the grids at once (bytes, counted: bricks × bytes per node
    /// plus tables).
    pub peak_bytes: u64,
    /// Memory of the result kept by the field.
    pub field_bytes: u64,
    /// True when no seed exists: the field is empty.
    pub empty: bool,
}

/// Per-brick bounds of the stored channels, for intervals and Lipschitz bounds.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct BrickBounds {
    /// `[min, max]` of S.
    pub s: [f32; 2],
    /// `[min, max]` of α.
    pub alpha: [f32; 2],
    /// `[min, max]` of β.
    pub beta: [f32; 2],
    /// Per axis, the largest |S difference| / h along an edge starting in the brick.
    pub grad_s: Vec3,
    /// Largest ‖∇α‖ bound (per-axis edge maxima combined).
    pub grad_alpha: f32,
    /// Largest ‖∇β‖ bound.
    pub grad_beta: f32,
}

/// The result: S and `(α, β)` on a stack of levels (base first, finest last).
#[derive(Debug, Default)]
pub struct Volume {
    /// Levels, coarsest (dense base) first.
    pub levels: Vec<Bricks>,
    /// S per level.
    pub s: Vec<Vec<f32>>,
    /// α per level.
    pub alpha: Vec<Vec<f32>>,
    /// β per level.
    pub beta: Vec<Vec<f32>>,
    /// Bounds per level and brick.
    pub bounds: Vec<Vec<BrickBounds>>,
    /// The diffused guidance normals N per level, with [`Params::keep_normals`] (empty
    /// otherwise).
    pub normals: Vec<Vec<Vec3>>,
    /// Statistics.
    pub stats: Stats,
}

/// Bytes per node held while a level is processed (N, R, S, wave stamps, masks, plus a
/// ping-pong copy of the largest channel) and, with streamlines, B.
fn work_bytes(streamline: bool) -> u64 {
    let b = 12 + 8 + 4 + 2 + 2 + 12 + 4;
    if streamline { b + 24 } else { b }
}

/// Bytes per node kept by a finished level until the end (N for prolongation, R, S).
fn kept_bytes(streamline: bool) -> u64 {
    if streamline {
        12 + 12 + 8 + 4
    } else {
        12 + 8 + 4
    }
}

/// The levels' lattices, finest first.
pub fn level_geoms(domain: &Aabb, voxel: f32) -> Result<Vec<LevelGeom>, CurveError> {
    let size = domain.size();
    if domain.is_empty() || !size.is_finite() || size.min_element() <= 0.0 {
        return Err(CurveError::invalid(
            "domain",
            "must be a box with min < max on every axis",
        ));
    }
    let n = (size / voxel).ceil() + Vec3::ONE;
    if n.max_element() > (1 << 20) as f32 {
        return Err(CurveError::invalid(
            "voxel",
            format!("{voxel} m gives {} nodes along an axis", n.max_element()),
        ));
    }
    let mut g = LevelGeom {
        origin: domain.min,
        h: voxel,
        dims: n.as_ivec3().max(IVec3::splat(2)),
    };
    let mut out = vec![g];
    while g.dims.max_element() > 8 {
        g = g.coarser();
        out.push(g);
    }
    Ok(out)
}

/// Runs the pipeline on the primitives of `features`: each level voxelizes their proxy
/// meshes, with segments of half its voxel and guidance ribbons of [`GUIDE_VOXELS`].
pub fn run(features: &Features, p: &Params) -> Result<Volume, CurveError> {
    let geoms = level_geoms(&p.domain, p.voxel)?;
    let top = geoms.len() - 1;
    let base = (0..=top)
        .find(|&l| geoms[l].dims.max_element() <= p.base.max(8) as i32)
        .unwrap_or(top);
    let streamline = p.propagation == Propagation::Streamline;
    let mut stats = Stats::default();
    let tables: u64 = geoms.iter().map(Bricks::table_bytes).sum();
    let dense_nodes: u64 = geoms[base..]
        .iter()
        .map(|g| g.bdims().as_u64vec3().element_product() * BRICK_NODES as u64)
        .sum();
    check_budget(
        "the dense levels of the voxel pipeline",
        tables + dense_nodes * kept_bytes(streamline),
        p.max_memory,
    )?;

    // Levels before the first one with seeds (thin tunnels and arch beams only appear on
    // fine levels) hold a constant S just outside the first seeded level's band: in the
    // rock around thin tunnels, in the air around thin arches.
    let Some(first_seeded) = (0..=top)
        .rev()
        .find(|&l| features.has_seed(TUNNEL_VOXELS * geoms[l].h))
    else {
        stats.empty = true;
        return Ok(Volume {
            stats,
            ..Default::default()
        });
    };
    let behind = (p.band + 2.0)
        * geoms[first_seeded].h
        * features.outside_of_thin(TUNNEL_VOXELS * geoms[top].h);
    let finest = features.proxy(p.ribbon, p.ribbon, 0.5 * p.voxel, 0.0);
    let uniform_noise = finest.vertices.windows(2).all(|w| w[0].noise == w[1].noise);
    let max_alpha = finest
        .vertices
        .iter()
        .map(|v| v.noise.x)
        .fold(0.0, f32::max);
    drop(finest);
    let mut seen_seeds = false;
    let mut levels: Vec<Bricks> = Vec::new();
    let (mut n_ch, mut b_ch, mut r_ch, mut s_ch) = (
        Vec::<Vec<Vec3>>::new(),
        Vec::<Vec<Vec3>>::new(),
        Vec::<Vec<Vec2>>::new(),
        Vec::<Vec<f32>>::new(),
    );
    let mut kept = 0u64;
    let mut times = StageTimes::default();
    let t = &mut times;
    for l in (0..=top).rev() {
        let geom = geoms[l];
        let first = l == top;
        let mut ls = LevelStats {
            level: l as u32,
            h: geom.h,
            dims: geom.dims,
            dense: l >= base,
            ..Default::default()
        };
        let clock = Instant::now();
        let mesh = features.proxy(
            p.ribbon,
            GUIDE_VOXELS * geom.h,
            0.5 * geom.h,
            TUNNEL_VOXELS * geom.h,
        );
        t.proxy += clock.elapsed();
        let clock = Instant::now();
        let cons = voxelize(&mesh, &geom);
        t.voxelize += clock.elapsed();
        stats.triangles = mesh.triangles.len();
        drop(mesh);
        ls.constraints = cons.len();

        let clock = Instant::now();
        let bricks = if l >= base {
            Bricks::dense(geom)
        } else {
            let coords = band_bricks(&levels, &s_ch, geom, p.band * geom.h, &cons);
            let need = kept + coords.len() as u64 * BRICK_NODES as u64 * work_bytes(streamline);
            check_budget(
                format!("level {l} of the voxel pipeline ({} bricks)", coords.len()),
                need,
                p.max_memory,
            )?;
            Bricks::new(geom, coords)
        };
        ls.bricks = bricks.len();
        let total = bricks.len() * BRICK_NODES;
        stats.peak_bytes = stats
            .peak_bytes
            .max(kept + total as u64 * work_bytes(streamline) + bricks.overhead_bytes());
        let rim = bricks.rim();
        // Constraint data indices (constraints in missing bricks are dropped).
        let at: Vec<(usize, &Constraint)> = cons
            .iter()
            .filter_map(|c| bricks.node(c.node).map(|i| (i, c)))
            .filter(|(i, _)| !rim[*i])
            .collect();
        // Below the coarsest level, sweeps only run near this level's constraints (one
        // brick around them): elsewhere the prolonged coarse solution already is the
        // smooth solution, and a sweep would not change it.
        let active = if first {
            Vec::new()
        } else {
            active_bricks(&bricks, &at)
        };
        ls.active_bricks = if first {
            bricks.len()
        } else {
            active.iter().filter(|&&a| a).count()
        };
        let sweeps = if first {
            Sweeps::Converge {
                tol: 1e-4,
                max: 64 * geom.dims.max_element() as u32,
            }
        } else {
            Sweeps::Fixed(p.iterations)
        };
        let init = |ch: &[Vec<Vec3>]| {
            if first {
                vec![Vec3::ZERO; total]
            } else {
                prolong(&levels, ch, &bricks)
            }
        };
        let mut n = init(&n_ch);
        // Around tubes too thin for the coarser level the prolonged guidance is that of
        // their surroundings (on a terrain, the ground's upward normals): cleared, it
        // fills from the tubes' own constraints (a zero neighbour weighs fully, §4.3).
        let fresh = features.fresh_room(TUNNEL_VOXELS * geom.h, 2.0 * geom.h);
        if !first && !fresh.is_empty() {
            n.par_iter_mut().enumerate().for_each(|(i, n)| {
                let g = bricks.node_coord(i);
                if fresh.contains(geom.origin + g.as_vec3() * geom.h) {
                    *n = Vec3::ZERO;
                }
            });
        }
        let mut b = if streamline { init(&b_ch) } else { Vec::new() };
        let mut r = if first {
            let mean = cons.iter().map(|c| c.noise).sum::<Vec2>() / cons.len().max(1) as f32;
            vec![mean; total]
        } else {
            prolong(&levels, &r_ch, &bricks)
        };
        let mut fixed_n = rim.to_vec();
        let mut fixed_r = rim.to_vec();
        let mut fixed_b = rim.to_vec();
        for &(i, c) in &at {
            if c.normal != Vec3::ZERO {
                (n[i], fixed_n[i]) = (c.normal, true);
            }
            (r[i], fixed_r[i]) = (c.noise, true);
            if streamline && c.bitangent != Vec3::ZERO {
                (b[i], fixed_b[i]) = (c.bitangent, true);
            }
        }
        t.reset += clock.elapsed();

        let clock = Instant::now();
        ls.normal_sweeps = diffuse_normals(&bricks, &active, &mut n, &fixed_n, p.k, sweeps);
        if streamline {
            ls.bitangent_sweeps = diffuse_bitangents(&bricks, &active, &mut b, &fixed_b, sweeps);
        }
        drop((fixed_n, fixed_b));
        t.guidance += clock.elapsed();
        let clock = Instant::now();
        // Uniform noise parameters are already the solution of Laplace's equation.
        if !uniform_noise {
            ls.noise_sweeps = diffuse_noise(&bricks, &active, &mut r, &fixed_r, sweeps);
        }
        drop(fixed_r);
        t.noise += clock.elapsed();

        // S: on the coarsest level, distance propagation through the whole level then
        // relaxation to convergence; below, the prolonged S re-propagated from the level's
        // own seeds for `band` waves, blended in, and relaxed for a fixed number of sweeps.
        let clock = Instant::now();
        let sp = if !seen_seeds {
            vec![behind; total]
        } else {
            prolong(&levels, &s_ch, &bricks)
        };
        let mut s = sp.clone();
        let mut wave = vec![0u16; total];
        for &(i, c) in &at {
            if let Some(d) = c.seed {
                (s[i], wave[i]) = (d, 1);
                ls.seeds += 1;
            }
        }
        let full = !seen_seeds;
        let waiting = ls.seeds == 0 && (l == 0 || !seen_seeds);
        if waiting && l == 0 {
            stats.empty = true;
            stats.times = times;
            stats.levels.push(ls);
            return Ok(Volume {
                stats,
                ..Default::default()
            });
        }
        if waiting {
            // Nothing here yet: keep the constant.
            t.propagate += clock.elapsed();
        } else {
            seen_seeds = true;
            let reach = if full && first {
                (geom.dims.element_sum() * 2) as u32
            } else {
                p.band.ceil() as u32
            };
            if streamline {
                ls.streamline_nodes = streamlines(&bricks, &mut s, &mut wave, &n, &b, 2 * reach);
            }
            ls.waves = waves(&bricks, &mut s, &mut wave, &n, reach);
            let fixed_s: Vec<bool> = wave.iter().zip(rim).map(|(&w, &r)| w == 1 || r).collect();
            if !(full && first) {
                // Blend the re-propagated values into the prolonged ones over the outer half
                // of the waves.
                let k = reach.max(1) as f32;
                s.par_iter_mut()
                    .zip(&sp)
                    .zip(&wave)
                    .for_each(|((s, &sp), &w)| {
                        if w > 1 {
                            let a = ((w as f32 - 1.0 - 0.5 * k) / (0.5 * k)).clamp(0.0, 1.0);
                            *s += (sp - *s) * a;
                        }
                    });
            }
            drop((sp, wave));
            let relax_sweeps = if full && first {
                Sweeps::Converge {
                    tol: 1e-3 * geom.h,
                    max: 4096,
                }
            } else {
                Sweeps::Fixed(p.iterations)
            };
            ls.relax_sweeps = relax(&bricks, &active, &mut s, &n, &fixed_s, relax_sweeps);
            t.propagate += clock.elapsed();
            let clock = Instant::now();
            smooth(&bricks, &active, &mut s, &fixed_s, p.smoothing);
            t.smooth += clock.elapsed();
        }
        kept += total as u64 * kept_bytes(streamline) + bricks.overhead_bytes();
        levels.push(bricks);
        n_ch.push(n);
        b_ch.push(b);
        r_ch.push(r);
        s_ch.push(s);
        stats.levels.push(ls);
    }

    stats.times = times;
    let clock = Instant::now();
    let first = top - base;
    let levels: Vec<Bricks> = levels.drain(first..).collect();
    let cap = p.transition + max_alpha + 2.0 * p.voxel;
    let mut s: Vec<Vec<f32>> = s_ch.drain(first..).collect();
    s.par_iter_mut()
        .flat_map(|s| s.par_iter_mut())
        .for_each(|v| *v = v.clamp(-cap, cap));
    let alpha: Vec<Vec<f32>> = r_ch[first..]
        .iter()
        .map(|r| r.iter().map(|v| v.x).collect())
        .collect();
    let beta: Vec<Vec<f32>> = r_ch[first..]
        .iter()
        .map(|r| r.iter().map(|v| v.y).collect())
        .collect();
    let normals: Vec<Vec<Vec3>> = if p.keep_normals {
        n_ch.drain(first..).collect()
    } else {
        Vec::new()
    };
    drop((n_ch, b_ch, r_ch));
    let bounds = (0..levels.len())
        .map(|l| brick_bounds(&levels[l], &s[l], &alpha[l], &beta[l]))
        .collect();
    stats.field_bytes = levels
        .iter()
        .map(|b| {
            let per_node = if p.keep_normals { 24 } else { 12 };
            b.len() as u64 * BRICK_NODES as u64 * per_node + b.overhead_bytes()
        })
        .sum();
    stats.times.finish += clock.elapsed();
    Ok(Volume {
        levels,
        s,
        alpha,
        beta,
        bounds,
        normals,
        stats,
    })
}

/// Bricks of a level below the base: those covering the coarser surface band
/// (`|S| < width` on the finest level built so far) and the level's seed nodes.
fn band_bricks(
    levels: &[Bricks],
    s_ch: &[Vec<f32>],
    geom: LevelGeom,
    width: f32,
    cons: &[Constraint],
) -> Vec<IVec3> {
    let parent = levels.last().expect("a coarser level");
    let s = s_ch.last().expect("S on the coarser level");
    let mut coords: Vec<IVec3> = (0..parent.len())
        .into_par_iter()
        .flat_map_iter(|b| {
            let mut out = Vec::new();
            for k in 0..BRICK_NODES {
                let i = b * BRICK_NODES + k;
                let g = parent.node_coord(i);
                if !parent.geom.contains(g) || s[i].abs() >= width {
                    continue;
                }
                // The fine nodes of the coarse cells around g.
                let lo = ((g * 2 - IVec3::splat(2)).max(IVec3::ZERO)) / BRICK;
                let hi = ((g * 2 + IVec3::splat(2)).min(geom.dims - IVec3::ONE)) / BRICK;
                for z in lo.z..=hi.z {
                    for y in lo.y..=hi.y {
                        for x in lo.x..=hi.x {
                            out.push(IVec3::new(x, y, z));
                        }
                    }
                }
            }
            out.sort_unstable_by_key(|c| (c.z, c.y, c.x));
            out.dedup();
            out.into_iter()
        })
        .collect();
    // Seed bricks and their neighbours, so that seeds stay off the rim.
    let mut seeds: Vec<IVec3> = cons
        .iter()
        .filter(|c| c.seed.is_some())
        .map(|c| c.node / BRICK)
        .collect();
    seeds.dedup();
    for c in seeds {
        for k in 0..27 {
            coords.push(c + IVec3::new(k % 3, (k / 3) % 3, k / 9) - IVec3::ONE);
        }
    }
    // Each brick once, so the budget check counts what is allocated.
    coords.par_sort_unstable_by_key(|c| (c.z, c.y, c.x));
    coords.dedup();
    coords
}

/// Bricks holding a constraint node and their 26 neighbours.
fn active_bricks(bricks: &Bricks, at: &[(usize, &Constraint)]) -> Vec<bool> {
    let mut near = vec![false; bricks.len()];
    for &(i, _) in at {
        near[i / BRICK_NODES] = true;
    }
    let mut active = near.clone();
    {
        let prev = active.clone();
        for (b, a) in active.iter_mut().enumerate() {
            *a = *a
                || bricks
                    .neighbours(b)
                    .iter()
                    .any(|&k| k != super::sparse::NONE && prev[k as usize]);
        }
    }
    active
}

/// Ranges and slopes of the channels per brick.
fn brick_bounds(bricks: &Bricks, s: &[f32], alpha: &[f32], beta: &[f32]) -> Vec<BrickBounds> {
    let g = bricks.geom;
    const STRIDE: [usize; 3] = [1, BRICK as usize, (BRICK * BRICK) as usize];
    (0..bricks.len())
        .into_par_iter()
        .map(|b| {
            let mut out = BrickBounds {
                s: [f32::INFINITY, f32::NEG_INFINITY],
                alpha: [f32::INFINITY, f32::NEG_INFINITY],
                beta: [f32::INFINITY, f32::NEG_INFINITY],
                ..Default::default()
            };
            let base = bricks.coords()[b] * BRICK;
            // The brick's nodes inside the domain.
            let lim = (g.dims - base).min(IVec3::splat(BRICK));
            let (mut gs, mut ga, mut gb) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
            let grow = |r: &mut [f32; 2], v: f32| *r = [r[0].min(v), r[1].max(v)];
            for z in 0..lim.z {
                for y in 0..lim.y {
                    for x in 0..lim.x {
                        let l = IVec3::new(x, y, z);
                        let i = b * BRICK_NODES + local(l);
                        grow(&mut out.s, s[i]);
                        grow(&mut out.alpha, alpha[i]);
                        grow(&mut out.beta, beta[i]);
                        for a in 0..3 {
                            // The edge to the next node along the axis, inside the domain.
                            let next = if l[a] < lim[a] - 1 {
                                Some(i + STRIDE[a])
                            } else if base[a] + l[a] + 1 < g.dims[a] {
                                let mut e = IVec3::ZERO;
                                e[a] = 1;
                                bricks.node(base + l + e)
                            } else {
                                None
                            };
                            if let Some(j) = next {
                                gs[a] = gs[a].max((s[j] - s[i]).abs());
                                ga[a] = ga[a].max((alpha[j] - alpha[i]).abs());
                                gb[a] = gb[a].max((beta[j] - beta[i]).abs());
                            }
                        }
                    }
                }
            }
            out.grad_s = gs / g.h;
            out.grad_alpha = ga.length() / g.h;
            out.grad_beta = gb.length() / g.h;
            out
        })
        .collect()
}

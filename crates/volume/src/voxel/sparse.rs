//! The sparse grid: one level of small dense bricks of 8³ nodes, allocated only where
//! needed, and the multi-level sampler that makes a stack of levels one continuous field.
//!
//! Grids are *vertex-centred*: node `g` of a level sits at `origin + g·h`, and node `g` of
//! a coarse level coincides with node `2g` of the next finer one, so a fine cell always
//! lies inside one coarse cell. A point is evaluated on the finest level whose cell around
//! it has all eight corners allocated; a fine level's *rim* nodes (those next to a missing
//! brick) hold the coarser levels' value, which makes the stack continuous (see
//! `docs/feature-curves.md`).
//!
//! Bricks are stored in sorted `(z, y, x)` order and found through a dense table of brick
//! coordinates, so iteration order never depends on hashing.

use std::ops::{Add, Mul};

use glam::{IVec3, Vec2, Vec3};
use rayon::prelude::*;

/// Nodes per brick edge.
pub const BRICK: i32 = 8;
/// Nodes per brick.
pub const BRICK_NODES: usize = 512;
/// Edge of a brick padded with a one-node halo.
pub const PAD: usize = 10;
/// Nodes of a padded brick.
pub const PAD_NODES: usize = PAD * PAD * PAD;
/// A missing brick.
pub const NONE: u32 = u32::MAX;

/// Values the grids hold: interpolable by weights.
pub trait Lerp:
    Copy + Default + Add<Output = Self> + Mul<f32, Output = Self> + Send + Sync
{
}
impl Lerp for f32 {}
impl Lerp for Vec2 {}
impl Lerp for Vec3 {}

/// The lattice of one level.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelGeom {
    /// Position of node `(0, 0, 0)`.
    pub origin: Vec3,
    /// Node spacing (metres).
    pub h: f32,
    /// Node count per axis (at least 2).
    pub dims: IVec3,
}

impl LevelGeom {
    /// Brick count per axis.
    pub fn bdims(&self) -> IVec3 {
        (self.dims + IVec3::splat(BRICK - 1)) / BRICK
    }

    /// World position of node `g`.
    pub fn pos(&self, g: IVec3) -> Vec3 {
        self.origin + g.as_vec3() * self.h
    }

    /// True when `g` is a node of the domain.
    pub fn contains(&self, g: IVec3) -> bool {
        g.cmpge(IVec3::ZERO).all() && g.cmplt(self.dims).all()
    }

    /// The next coarser level (spacing doubled, node `g` at fine node `2g`).
    pub fn coarser(&self) -> LevelGeom {
        LevelGeom {
            origin: self.origin,
            h: 2.0 * self.h,
            dims: (self.dims - IVec3::ONE + IVec3::ONE) / 2 + IVec3::ONE,
        }
    }

    /// Total node count.
    pub fn node_count(&self) -> u64 {
        self.dims.as_u64vec3().element_product()
    }
}

/// Local index of node `l` (each coordinate in `0..8`) inside a brick.
#[inline]
pub fn local(l: IVec3) -> usize {
    (l.x + BRICK * (l.y + BRICK * l.z)) as usize
}

/// Index into a padded brick of local coordinates `l` (each in `-1..=8`).
#[inline]
pub fn padded(x: i32, y: i32, z: i32) -> usize {
    ((x + 1) + PAD as i32 * ((y + 1) + PAD as i32 * (z + 1))) as usize
}

/// One level's allocation: which bricks exist, their neighbours and rim nodes.
#[derive(Clone, Debug)]
pub struct Bricks {
    /// The lattice.
    pub geom: LevelGeom,
    table: Vec<u32>,
    coords: Vec<IVec3>,
    neighbours: Vec<[u32; 27]>,
    rim: Vec<bool>,
}

impl Bricks {
    /// Bytes of the brick table of `geom` (checked against the budget before building).
    pub fn table_bytes(geom: &LevelGeom) -> u64 {
        geom.bdims().as_u64vec3().element_product() * 4
    }

    /// The level with the given bricks (duplicates and out-of-range ones are dropped).
    pub fn new(geom: LevelGeom, mut coords: Vec<IVec3>) -> Self {
        let bd = geom.bdims();
        coords.retain(|c| c.cmpge(IVec3::ZERO).all() && c.cmplt(bd).all());
        coords.sort_unstable_by_key(|c| (c.z, c.y, c.x));
        coords.dedup();
        let mut table = vec![NONE; bd.as_u64vec3().element_product() as usize];
        for (i, c) in coords.iter().enumerate() {
            table[(c.x + bd.x * (c.y + bd.y * c.z)) as usize] = i as u32;
        }
        let mut b = Bricks {
            geom,
            table,
            coords,
            neighbours: Vec::new(),
            rim: Vec::new(),
        };
        b.neighbours = b
            .coords
            .iter()
            .map(|&c| {
                let mut n = [NONE; 27];
                for (k, nk) in n.iter_mut().enumerate() {
                    let d = IVec3::new(k as i32 % 3, (k as i32 / 3) % 3, k as i32 / 9) - IVec3::ONE;
                    *nk = b.brick(c + d);
                }
                n
            })
            .collect();
        b.rim = b.compute_rim();
        b
    }

    /// Every brick of the level.
    pub fn dense(geom: LevelGeom) -> Self {
        let bd = geom.bdims();
        let mut coords = Vec::with_capacity(bd.as_u64vec3().element_product() as usize);
        for z in 0..bd.z {
            for y in 0..bd.y {
                for x in 0..bd.x {
                    coords.push(IVec3::new(x, y, z));
                }
            }
        }
        Bricks::new(geom, coords)
    }

    /// Nodes that are fixed to the coarser levels' values: those with one of their 26
    /// neighbours (inside the domain) in a missing brick, and those outside the domain.
    fn compute_rim(&self) -> Vec<bool> {
        let mut rim = vec![false; self.coords.len() * BRICK_NODES];
        rim.par_chunks_mut(BRICK_NODES)
            .enumerate()
            .for_each(|(b, out)| {
                let base = self.coords[b] * BRICK;
                let nb = &self.neighbours[b];
                let full = nb.iter().all(|&n| n != NONE);
                // Offsets a node at local coordinate l reaches: 0, and ±1 on the brick's faces.
                let reach = |l: i32| -> (i32, i32) {
                    (
                        if l == 0 { -1 } else { 0 },
                        if l == BRICK - 1 { 1 } else { 0 },
                    )
                };
                for z in 0..BRICK {
                    for y in 0..BRICK {
                        for x in 0..BRICK {
                            let g = base + IVec3::new(x, y, z);
                            let r = if !self.geom.contains(g) {
                                true
                            } else if full {
                                false
                            } else {
                                let (rx, ry, rz) = (reach(x), reach(y), reach(z));
                                let mut missing = false;
                                for dz in rz.0..=rz.1 {
                                    for dy in ry.0..=ry.1 {
                                        for dx in rx.0..=rx.1 {
                                            let d = IVec3::new(dx, dy, dz);
                                            // Only neighbours inside the domain count.
                                            let inside = self.geom.contains(g + d);
                                            missing |= inside
                                                && nb[((dx + 1) + 3 * (dy + 1) + 9 * (dz + 1))
                                                    as usize]
                                                    == NONE;
                                        }
                                    }
                                }
                                missing
                            };
                            out[local(IVec3::new(x, y, z))] = r;
                        }
                    }
                }
            });
        rim
    }

    /// Number of allocated bricks.
    pub fn len(&self) -> usize {
        self.coords.len()
    }

    /// True when no brick is allocated.
    pub fn is_empty(&self) -> bool {
        self.coords.is_empty()
    }

    /// Brick coordinates, sorted.
    pub fn coords(&self) -> &[IVec3] {
        &self.coords
    }

    /// Index of brick `c`, or [`NONE`].
    #[inline]
    pub fn brick(&self, c: IVec3) -> u32 {
        let bd = self.geom.bdims();
        if c.cmplt(IVec3::ZERO).any() || c.cmpge(bd).any() {
            return NONE;
        }
        self.table[(c.x + bd.x * (c.y + bd.y * c.z)) as usize]
    }

    /// Data index of node `g`, or `None` when its brick is missing.
    #[inline]
    pub fn node(&self, g: IVec3) -> Option<usize> {
        let b = self.brick(g >> 3);
        (b != NONE).then(|| b as usize * BRICK_NODES + local(g & 7))
    }

    /// Indices of the 26 neighbours of brick `b` and itself (`(dx+1) + 3(dy+1) + 9(dz+1)`).
    pub fn neighbours(&self, b: usize) -> &[u32; 27] {
        &self.neighbours[b]
    }

    /// True for rim (and out-of-domain) nodes, by data index.
    pub fn rim(&self) -> &[bool] {
        &self.rim
    }

    /// Global node coordinates of data index `i`.
    pub fn node_coord(&self, i: usize) -> IVec3 {
        let l = (i % BRICK_NODES) as i32;
        self.coords[i / BRICK_NODES] * BRICK + IVec3::new(l & 7, (l >> 3) & 7, l >> 6)
    }

    /// Bytes taken by the allocation itself (table, neighbours, rim mask).
    pub fn overhead_bytes(&self) -> u64 {
        (self.table.len() * 4
            + self.neighbours.len() * 27 * 4
            + self.coords.len() * 12
            + self.rim.len()) as u64
    }

    /// Copies brick `b` of `data` with a one-node halo into `pad`. Halo nodes outside the
    /// domain repeat the boundary node (homogeneous Neumann); halo nodes in a missing
    /// brick repeat the nearest node of `b` (only rim nodes read them, and rim nodes are
    /// never updated).
    pub fn gather<T: Copy>(&self, data: &[T], b: usize, pad: &mut [T]) {
        let c = self.coords[b];
        let base = c * BRICK;
        let dims = self.geom.dims;
        // Per axis and padded coordinate: neighbour offset (-1, 0, 1) and local index.
        let mut ax = [[(0i32, 0i32); PAD]; 3];
        for (a, axis) in ax.iter_mut().enumerate() {
            for (p, e) in axis.iter_mut().enumerate() {
                let g = (base[a] + p as i32 - 1).clamp(0, dims[a] - 1);
                *e = ((g >> 3) - c[a], g & 7);
            }
        }
        let nb = &self.neighbours[b];
        let own = &data[b * BRICK_NODES..(b + 1) * BRICK_NODES];
        // A node of the brick at offset (dx, dy, dz), local (lx, ly, lz); the nearest own
        // node when that brick is missing.
        let at = |dx: i32, dy: i32, dz: i32, lx: i32, ly: i32, lz: i32| -> T {
            let n = nb[((dx + 1) + 3 * (dy + 1) + 9 * (dz + 1)) as usize];
            if n == NONE {
                let f = |d: i32, l: i32| {
                    if d < 0 {
                        0
                    } else if d > 0 {
                        7
                    } else {
                        l
                    }
                };
                own[local(IVec3::new(f(dx, lx), f(dy, ly), f(dz, lz)))]
            } else {
                data[n as usize * BRICK_NODES + local(IVec3::new(lx, ly, lz))]
            }
        };
        let (x0, x9) = (ax[0][0], ax[0][PAD - 1]);
        let inner_x = (1..PAD - 1).all(|p| ax[0][p] == (0, p as i32 - 1));
        let mut k = 0;
        for &(dz, lz) in &ax[2] {
            for &(dy, ly) in &ax[1] {
                pad[k] = at(x0.0, dy, dz, x0.1, ly, lz);
                // The eight middle nodes of a row come from one brick.
                let n = nb[(1 + 3 * (dy + 1) + 9 * (dz + 1)) as usize];
                if inner_x && n != NONE {
                    let start = n as usize * BRICK_NODES + local(IVec3::new(0, ly, lz));
                    pad[k + 1..k + 9].copy_from_slice(&data[start..start + 8]);
                } else {
                    for p in 1..PAD - 1 {
                        let (dx, lx) = ax[0][p];
                        pad[k + p] = at(dx, dy, dz, lx, ly, lz);
                    }
                }
                pad[k + PAD - 1] = at(x9.0, dy, dz, x9.1, ly, lz);
                k += PAD;
            }
        }
    }

    /// The cell of this level around `p` when all its corners are allocated: data indices
    /// of the corners (corner `k` at offset `(k & 1, k >> 1 & 1, k >> 2)`) and the
    /// fractional position inside the cell. `p` is clamped to the domain.
    #[inline]
    pub fn cell(&self, p: Vec3) -> Option<([u32; 8], Vec3)> {
        let g = &self.geom;
        let q = ((p - g.origin) / g.h).clamp(Vec3::ZERO, (g.dims - IVec3::ONE).as_vec3());
        let c = q.floor().as_ivec3().min(g.dims - IVec3::splat(2));
        let f = q - c.as_vec3();
        let l = c & 7;
        if l.cmplt(IVec3::splat(7)).all() {
            let b = self.brick(c >> 3);
            if b == NONE {
                return None;
            }
            let i = b * BRICK_NODES as u32 + local(l) as u32;
            return Some(([i, i + 1, i + 8, i + 9, i + 64, i + 65, i + 72, i + 73], f));
        }
        let mut idx = [0u32; 8];
        for (k, e) in idx.iter_mut().enumerate() {
            let d = IVec3::new(k as i32 & 1, (k as i32 >> 1) & 1, k as i32 >> 2);
            *e = self.node(c + d)? as u32;
        }
        Some((idx, f))
    }
}

/// Trilinear weights of the 8 corners at fractional position `f`.
#[inline]
pub fn weights(f: Vec3) -> [f32; 8] {
    let (x1, y1, z1) = (f.x, f.y, f.z);
    let (x0, y0, z0) = (1.0 - x1, 1.0 - y1, 1.0 - z1);
    [
        x0 * y0 * z0,
        x1 * y0 * z0,
        x0 * y1 * z0,
        x1 * y1 * z0,
        x0 * y0 * z1,
        x1 * y0 * z1,
        x0 * y1 * z1,
        x1 * y1 * z1,
    ]
}

/// Interpolates `data` at the corners `idx` with fractional position `f`.
#[inline]
pub fn trilinear<T: Lerp>(data: &[T], idx: &[u32; 8], f: Vec3) -> T {
    let w = weights(f);
    let mut acc = T::default();
    for k in 0..8 {
        acc = acc + data[idx[k] as usize] * w[k];
    }
    acc
}

/// Value and gradient (per metre, cell size `h`) of the trilinear interpolant of scalars.
#[inline]
pub fn trilinear_grad(data: &[f32], idx: &[u32; 8], f: Vec3, h: f32) -> (f32, Vec3) {
    let v = idx.map(|i| data[i as usize]);
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let (x, y, z) = (f.x, f.y, f.z);
    let c00 = lerp(v[0], v[1], x);
    let c10 = lerp(v[2], v[3], x);
    let c01 = lerp(v[4], v[5], x);
    let c11 = lerp(v[6], v[7], x);
    let c0 = lerp(c00, c10, y);
    let c1 = lerp(c01, c11, y);
    let val = lerp(c0, c1, z);
    let dz = c1 - c0;
    let dy = lerp(c10 - c00, c11 - c01, z);
    let dx = lerp(
        lerp(v[1] - v[0], v[3] - v[2], y),
        lerp(v[5] - v[4], v[7] - v[6], y),
        z,
    );
    (val, Vec3::new(dx, dy, dz) / h)
}

/// The finest level of `levels` (coarsest first) whose cell around `p` is complete, with
/// its corners and fraction. `None` only when the coarsest level is incomplete there.
#[inline]
pub fn locate(levels: &[Bricks], p: Vec3) -> Option<(usize, [u32; 8], Vec3)> {
    levels
        .iter()
        .enumerate()
        .rev()
        .find_map(|(l, b)| b.cell(p).map(|(i, f)| (l, i, f)))
}

/// The value of `channel` (one data vector per level of `levels`) at `p`.
pub fn sample<T: Lerp>(levels: &[Bricks], channel: &[Vec<T>], p: Vec3) -> T {
    match locate(levels, p) {
        Some((l, idx, f)) => trilinear(&channel[l], &idx, f),
        None => T::default(),
    }
}

/// Values of the stack `levels` at every node of `fine` (one step finer than the stack's
/// finest level): exact factor-two prolongation, parallel over bricks.
pub fn prolong<T: Lerp>(levels: &[Bricks], channel: &[Vec<T>], fine: &Bricks) -> Vec<T> {
    let top = levels.len() - 1;
    let parent = &levels[top];
    let mut out = vec![T::default(); fine.len() * BRICK_NODES];
    out.par_chunks_mut(BRICK_NODES)
        .enumerate()
        .for_each(|(b, out)| {
            // Parent nodes 4c .. 4c + 4 per axis.
            let pbase = fine.coords[b] * (BRICK / 2);
            let mut block = [T::default(); 125];
            for z in 0..5 {
                for y in 0..5 {
                    for x in 0..5 {
                        let g = (pbase + IVec3::new(x, y, z)).min(parent.geom.dims - IVec3::ONE);
                        block[(x + 5 * (y + 5 * z)) as usize] = match parent.node(g) {
                            Some(i) => channel[top][i],
                            None => sample(levels, channel, parent.geom.pos(g)),
                        };
                    }
                }
            }
            for z in 0..BRICK {
                for y in 0..BRICK {
                    for x in 0..BRICK {
                        let (px, py, pz) = (x / 2, y / 2, z / 2);
                        let (ox, oy, oz) = (x & 1, y & 1, z & 1);
                        let mut acc = T::default();
                        let mut n = 0;
                        for dz in 0..=oz {
                            for dy in 0..=oy {
                                for dx in 0..=ox {
                                    acc = acc
                                        + block[(px + dx + 5 * (py + dy + 5 * (pz + dz))) as usize];
                                    n += 1;
                                }
                            }
                        }
                        out[local(IVec3::new(x, y, z))] = acc * (1.0 / n as f32);
                    }
                }
            }
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geom(n: i32) -> LevelGeom {
        LevelGeom {
            origin: Vec3::new(-1.0, 2.0, 0.5),
            h: 0.5,
            dims: IVec3::new(n, n - 3, n + 5),
        }
    }

    #[test]
    fn gather_clamps_at_the_domain_and_reads_neighbours() {
        let g = geom(20);
        let b = Bricks::dense(g);
        let data: Vec<f32> = (0..b.len() * BRICK_NODES)
            .map(|i| {
                let c = b.node_coord(i);
                (c.x + 100 * c.y + 10_000 * c.z) as f32
            })
            .collect();
        let mut pad = vec![0.0; PAD_NODES];
        for bi in 0..b.len() {
            b.gather(&data, bi, &mut pad);
            let base = b.coords()[bi] * BRICK;
            for z in -1..=8 {
                for y in -1..=8 {
                    for x in -1..=8 {
                        let gc =
                            (base + IVec3::new(x, y, z)).clamp(IVec3::ZERO, g.dims - IVec3::ONE);
                        assert_eq!(
                            pad[padded(x, y, z)],
                            (gc.x + 100 * gc.y + 10_000 * gc.z) as f32
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn rim_marks_nodes_next_to_missing_bricks() {
        let g = geom(40);
        let b = Bricks::new(g, vec![IVec3::new(1, 1, 1), IVec3::new(2, 1, 1)]);
        let rim = b.rim();
        let at = |g: IVec3| rim[b.node(g).unwrap()];
        assert!(at(IVec3::new(8, 8, 8)));
        assert!(!at(IVec3::new(12, 12, 12)));
        assert!(!at(IVec3::new(15, 12, 12)), "the +x neighbour exists");
        assert!(at(IVec3::new(23, 12, 12)));
        assert!(
            b.cell(g.pos(IVec3::new(9, 9, 9)) + Vec3::splat(0.1))
                .is_some()
        );
        assert!(
            b.cell(g.pos(IVec3::new(23, 9, 9)) + Vec3::splat(0.1))
                .is_none()
        );
    }

    #[test]
    fn prolongation_of_a_linear_field_is_exact_and_the_stack_is_continuous() {
        let coarse_g = geom(24).coarser();
        let coarse = Bricks::dense(coarse_g);
        let lin = |p: Vec3| 0.3 * p.x - 1.2 * p.y + 0.7 * p.z + 2.0;
        let cdata: Vec<f32> = (0..coarse.len() * BRICK_NODES)
            .map(|i| lin(coarse_g.pos(coarse.node_coord(i))))
            .collect();
        let fine_g = geom(24);
        let fine = Bricks::new(fine_g, vec![IVec3::new(1, 1, 1), IVec3::new(1, 2, 1)]);
        let fdata = prolong(
            std::slice::from_ref(&coarse),
            std::slice::from_ref(&cdata),
            &fine,
        );
        for (i, v) in fdata.iter().enumerate() {
            let c = fine.node_coord(i);
            if fine_g.contains(c) {
                assert!((v - lin(fine_g.pos(c))).abs() < 1e-4);
            }
        }
        let levels = vec![coarse, fine];
        let ch = vec![cdata, fdata];
        for k in 0..200 {
            let p = fine_g.origin
                + Vec3::new(
                    k as f32 * 0.055,
                    2.0 + k as f32 * 0.037,
                    13.0 - k as f32 * 0.061,
                );
            assert!((sample(&levels, &ch, p) - lin(p)).abs() < 1e-4);
        }
    }
}

//! Tricubic (Catmull–Rom) interpolation of S on the finest level, blended into the
//! trilinear field where the stencil runs out, and the bounds that keep the S-field's
//! interval and Lipschitz answers sound with it.
//!
//! The tricubic interpolant `C` of a cell reads the 4³ nodes from one before to two after
//! the cell on each axis (clamped to the domain: homogeneous Neumann). It passes through
//! the nodes and is C¹. It is used only on the finest level, blended with the trilinear
//! interpolant `L` by a weight `w` that is itself the trilinear interpolant of node flags:
//!
//! ```text
//!   S = L + w·(C − L),     w(node) = 1 when every node within 2 of it is allocated
//! ```
//!
//! A cell with a flagged corner has its whole stencil, and `w` vanishes on the faces of the
//! finest level's complete region (their nodes lie next to a missing brick), where the
//! coarser levels take over with their trilinear values: the stacked field stays
//! continuous, so one Lipschitz bound still holds across levels.
//!
//! **Bounds.** With `Δ²ₐ` the largest second difference of S along axis `a` over the
//! stencil and `gₐ` the largest edge slope (`|ΔS|/h`), `cₐ = Δ²ₐ/h`:
//!
//! * 1D, `C − L = t(1−t)/2 · [−(1−t)Δ²(0) − tΔ²(1)]`, so `|C − L| ≤ Δ²/8`; in 3D, writing
//!   `CₓC_yC_z − LₓL_yL_z = (Cₓ−Lₓ)C_yC_z + Lₓ(C_y−L_y)C_z + LₓL_y(C_z−L_z)` and
//!   `Σ|wᵢ| ≤ 5/4` for the Catmull–Rom weights:
//!   `|C − L| ≤ E = h·(25/16·cₓ + 5/4·c_y + c_z)/8`. The value range grows by `E`.
//! * 1D derivative: `C' = d₀ + a(t)(d₋₁ − d₀) + c(t)(d₁ − d₀)` with `|a| + |c| ≤ ½`, so
//!   `|C'| ≤ g + c/2`; across rows, `C_yC_z = L_yL_z + (C_y−L_y)C_z + L_y(C_z−L_z)`, and
//!   the second differences of a row's derivative are at most `Σ|w'ᵢ| ≤ 3` times those of
//!   S: `|∂ₓC| ≤ gₓ + cₓ/2 + (15/32)·c_y + (3/8)·c_z` (and the same by symmetry).
//! * `∂S = (1−w)∂L + w∂C + (C − L)∂w` with `|∂ₐw| ≤ 1/h` where `w` varies:
//!   `|∂ₐS| ≤ Gₐ + E/h`.
//!
//! All three are sampled in `tests/curves_field.rs`.

use glam::{IVec3, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::pipeline::BrickBounds;
use super::sparse::{BRICK, BRICK_NODES, Bricks, NONE, PAD_NODES, local, padded, trilinear_grad};

/// How S is interpolated between the voxel nodes (a `FeatureVolume`'s `interpolation`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Interpolation {
    /// Trilinear: C⁰, the tightest bounds, the cheapest.
    #[default]
    Trilinear,
    /// Catmull–Rom tricubic on the finest level: C¹, smooth normals; 64 nodes read per
    /// evaluation instead of 8, and wider Lipschitz bounds where S bends.
    Tricubic,
}

/// Per-brick bounds of the tricubic blend.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CubicBounds {
    /// Per axis, the largest |second difference of S| / h at a node of the brick.
    pub curv: Vec3,
    /// `[min, max]` of the blend weight at the brick's nodes.
    pub w: [f32; 2],
}

impl CubicBounds {
    /// Bounds of nothing (the identity of [`CubicBounds::hull`]).
    pub const EMPTY: CubicBounds = CubicBounds {
        curv: Vec3::ZERO,
        w: [f32::INFINITY, f32::NEG_INFINITY],
    };

    /// Bounds of both.
    pub fn hull(&self, o: &CubicBounds) -> CubicBounds {
        CubicBounds {
            curv: self.curv.max(o.curv),
            w: [self.w[0].min(o.w[0]), self.w[1].max(o.w[1])],
        }
    }

    /// `E`: a bound of `|S − L|`, the blend's departure from the trilinear interpolant, at
    /// points whose stencils these bounds cover (0 where the blend weight is 0 throughout).
    /// `h`: the finest level's voxel.
    pub fn value_error(&self, h: f32) -> f32 {
        if !(self.w[1] > 0.0) {
            return 0.0;
        }
        let c = self.curv;
        h * (25.0 / 16.0 * c.x + 1.25 * c.y + c.z) / 8.0
    }

    /// `b` (trilinear bounds of S over the same nodes) widened to bound the blended field:
    /// the value range by `E`, the slopes by the tricubic's and the blend's terms (see the
    /// module's documentation). `h`: the finest level's voxel.
    pub fn widen(&self, b: &BrickBounds, h: f32) -> BrickBounds {
        if !(self.w[1] > 0.0) {
            return *b;
        }
        let c = self.curv;
        let e = self.value_error(h);
        let cross = |a: f32, o1: f32, o2: f32| a / 2.0 + 15.0 / 32.0 * o1 + 3.0 / 8.0 * o2;
        let mut grad = b.grad_s
            + Vec3::new(
                cross(c.x, c.y, c.z),
                cross(c.y, c.x, c.z),
                cross(c.z, c.x, c.y),
            );
        if self.w[0] < self.w[1] {
            grad += Vec3::splat(e / h);
        }
        BrickBounds {
            s: [b.s[0] - e, b.s[1] + e],
            grad_s: grad,
            ..*b
        }
    }
}

/// The tricubic data of the finest level: the blend weight per node and the per-brick
/// bounds.
#[derive(Clone, Debug)]
pub struct Cubic {
    /// Blend weight (0 or 1) per node of the finest level, by data index.
    w: Vec<f32>,
    /// Per brick of the finest level.
    bounds: Vec<CubicBounds>,
    /// Hull of `bounds`.
    all: CubicBounds,
    /// Per brick, `E` over the bounds of its 26 neighbours and itself: a bound of
    /// `|S − L|` in every cell whose first corner lies in the brick (its stencil stays in
    /// those bricks).
    near: Vec<f32>,
}

impl Cubic {
    /// The blend weights and bounds of the finest level `bricks` holding `s`.
    pub fn new(bricks: &Bricks, s: &[f32]) -> Cubic {
        let g = bricks.geom;
        let rim = bricks.rim();
        let mut w = vec![0.0f32; bricks.len() * BRICK_NODES];
        let bounds: Vec<CubicBounds> = w
            .par_chunks_mut(BRICK_NODES)
            .enumerate()
            .map(|(b, w)| {
                let mut pr = vec![true; PAD_NODES];
                let mut ps = vec![0.0f32; PAD_NODES];
                bricks.gather(rim, b, &mut pr);
                bricks.gather(s, b, &mut ps);
                let base = bricks.coords()[b] * BRICK;
                let mut out = CubicBounds::EMPTY;
                for z in 0..BRICK {
                    for y in 0..BRICK {
                        for x in 0..BRICK {
                            if !g.contains(base + IVec3::new(x, y, z)) {
                                continue;
                            }
                            // Every node within 1 (clamped to the domain) has all of its
                            // neighbours: every node within 2 is allocated.
                            let mut deep = true;
                            for d in 0..27 {
                                let (dx, dy, dz) = (d % 3 - 1, d / 3 % 3 - 1, d / 9 - 1);
                                deep &= !pr[padded(x + dx, y + dy, z + dz)];
                            }
                            let v = if deep { 1.0 } else { 0.0 };
                            w[local(IVec3::new(x, y, z))] = v;
                            out.w = [out.w[0].min(v), out.w[1].max(v)];
                            let at = |dx: i32, dy: i32, dz: i32| ps[padded(x + dx, y + dy, z + dz)];
                            let c = at(0, 0, 0);
                            let d2 = Vec3::new(
                                at(-1, 0, 0) - 2.0 * c + at(1, 0, 0),
                                at(0, -1, 0) - 2.0 * c + at(0, 1, 0),
                                at(0, 0, -1) - 2.0 * c + at(0, 0, 1),
                            );
                            out.curv = out.curv.max(d2.abs() / g.h);
                        }
                    }
                }
                out
            })
            .collect();
        let all = bounds.iter().fold(CubicBounds::EMPTY, |a, x| a.hull(x));
        let near = (0..bricks.len())
            .into_par_iter()
            .map(|b| {
                bricks
                    .neighbours(b)
                    .iter()
                    .filter(|&&k| k != NONE)
                    .fold(CubicBounds::EMPTY, |a, &k| a.hull(&bounds[k as usize]))
                    .value_error(g.h)
            })
            .collect();
        Cubic {
            w,
            bounds,
            all,
            near,
        }
    }

    /// A bound of `|S − L|` (the blend's departure from the trilinear interpolant) in the
    /// cell whose first corner has data index `i0` ([`CubicBounds::value_error`] over the
    /// bricks its stencil reads).
    #[inline]
    pub fn cell_error(&self, i0: u32) -> f32 {
        self.near[i0 as usize / BRICK_NODES]
    }

    /// Bounds of brick `b`.
    pub fn brick(&self, b: usize) -> &CubicBounds {
        &self.bounds[b]
    }

    /// The blend weight (0 or 1) per node of the finest level, by data index.
    pub fn weights(&self) -> &[f32] {
        &self.w
    }

    /// Bounds over every brick.
    pub fn all(&self) -> &CubicBounds {
        &self.all
    }

    /// Bytes held.
    pub fn bytes(&self) -> u64 {
        (self.w.len() * 4
            + self.bounds.len() * std::mem::size_of::<CubicBounds>()
            + self.near.len() * 4) as u64
    }

    /// S and its gradient in the finest level's cell `idx` at fraction `f`, given the
    /// trilinear `(value, gradient)` there: the blend `L + w·(C − L)`. Without `GRAD` the
    /// gradient is not computed (the value is the same).
    pub fn eval<const GRAD: bool>(
        &self,
        bricks: &Bricks,
        s: &[f32],
        idx: &[u32; 8],
        f: Vec3,
        lin: (f32, Vec3),
    ) -> (f32, Vec3) {
        if idx.iter().all(|&i| self.w[i as usize] == 0.0) {
            return lin;
        }
        let h = bricks.geom.h;
        let Some(v) = stencil(bricks, s, idx[0]) else {
            return lin;
        };
        let (wv, wg) = trilinear_grad(&self.w, idx, f, h);
        let (c, cg) = catmull_rom::<GRAD>(&v, f, h);
        let d = c - lin.0;
        (lin.0 + wv * d, lin.1 + (cg - lin.1) * wv + wg * d)
    }
}

/// The 4³ nodes around the cell whose first corner has data index `i0` (x fastest),
/// clamped to the domain; `None` when one is missing.
fn stencil(bricks: &Bricks, s: &[f32], i0: u32) -> Option<[f32; 64]> {
    let g = bricks.geom;
    let c = bricks.node_coord(i0 as usize);
    let l = c & 7;
    let mut v = [0.0f32; 64];
    let inside = c.cmpge(IVec3::ONE).all() && (c + 2).cmplt(g.dims).all();
    if inside && l.cmpge(IVec3::ONE).all() && l.cmple(IVec3::splat(BRICK - 3)).all() {
        // One brick holds the whole stencil.
        let base = i0 as usize - (1 + 8 + 64);
        for (k, e) in v.iter_mut().enumerate() {
            *e = s[base + (k & 3) + 8 * ((k >> 2) & 3) + 64 * (k >> 4)];
        }
        return Some(v);
    }
    // Across bricks: on each axis the four (clamped) nodes lie in the first one's brick or
    // the next, so at most eight bricks are looked up, each once, where 64 nodes were.
    let top = g.dims - IVec3::ONE;
    let first: IVec3 = (c - IVec3::ONE).clamp(IVec3::ZERO, top) >> 3;
    let mut side = [[0usize; 4]; 3];
    let mut offset = [[0usize; 4]; 3];
    for a in 0..3 {
        for k in 0..4 {
            let n = (c[a] + k as i32 - 1).clamp(0, top[a]);
            side[a][k] = ((n >> 3) - first[a]) as usize;
            offset[a][k] = ((n & 7) << (3 * a)) as usize;
        }
    }
    // The stencil is a product of its axes' nodes: it needs every brick of the product of
    // their sides.
    let mut base = [0usize; 8];
    for sz in 0..=side[2][3] {
        for sy in 0..=side[1][3] {
            for sx in 0..=side[0][3] {
                let b = bricks.brick(first + IVec3::new(sx as i32, sy as i32, sz as i32));
                if b == NONE {
                    return None;
                }
                base[sx + 2 * sy + 4 * sz] = b as usize * BRICK_NODES;
            }
        }
    }
    for (z, plane) in v.chunks_exact_mut(16).enumerate() {
        for (y, row) in plane.chunks_exact_mut(4).enumerate() {
            let at = 2 * side[1][y] + 4 * side[2][z];
            let start = offset[1][y] + offset[2][z];
            let ends = [base[at] + start, base[at + 1] + start];
            for (x, e) in row.iter_mut().enumerate() {
                *e = s[ends[side[0][x]] + offset[0][x]];
            }
        }
    }
    Some(v)
}

/// [`stencil`] node by node: the reference its brick-wise gathering is checked against.
#[cfg(test)]
fn stencil_by_node(bricks: &Bricks, s: &[f32], i0: u32) -> Option<[f32; 64]> {
    let g = bricks.geom;
    let c = bricks.node_coord(i0 as usize);
    let mut v = [0.0f32; 64];
    for (k, e) in v.iter_mut().enumerate() {
        let d = IVec3::new(k as i32 & 3, (k as i32 >> 2) & 3, k as i32 >> 4) - IVec3::ONE;
        let n = (c + d).clamp(IVec3::ZERO, g.dims - IVec3::ONE);
        *e = s[bricks.node(n)?];
    }
    Some(v)
}

/// Catmull–Rom weights and their derivatives at `t ∈ [0, 1]` for the nodes −1, 0, 1, 2.
#[inline]
fn weights(t: f32) -> ([f32; 4], [f32; 4]) {
    let (t2, t3) = (t * t, t * t * t);
    (
        [
            0.5 * (-t3 + 2.0 * t2 - t),
            0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
            0.5 * (-3.0 * t3 + 4.0 * t2 + t),
            0.5 * (t3 - t2),
        ],
        [
            0.5 * (-3.0 * t2 + 4.0 * t - 1.0),
            0.5 * (9.0 * t2 - 10.0 * t),
            0.5 * (-9.0 * t2 + 8.0 * t + 1.0),
            0.5 * (3.0 * t2 - 2.0 * t),
        ],
    )
}

/// Value and gradient (per metre; zero without `GRAD`) of the tricubic interpolant of the
/// 4³ nodes `v` at fraction `f` of the middle cell.
fn catmull_rom<const GRAD: bool>(v: &[f32; 64], f: Vec3, h: f32) -> (f32, Vec3) {
    let (wx, dx) = weights(f.x);
    let (wy, dy) = weights(f.y);
    let (wz, dz) = weights(f.z);
    let (mut val, mut g) = (0.0, Vec3::ZERO);
    for k in 0..4 {
        let (mut a, mut ax, mut ay) = (0.0, 0.0, 0.0);
        for j in 0..4 {
            let row = &v[16 * k + 4 * j..16 * k + 4 * j + 4];
            let (mut r, mut rx) = (0.0, 0.0);
            for i in 0..4 {
                r += wx[i] * row[i];
                if GRAD {
                    rx += dx[i] * row[i];
                }
            }
            a += wy[j] * r;
            if GRAD {
                ax += wy[j] * rx;
                ay += dy[j] * r;
            }
        }
        val += wz[k] * a;
        if GRAD {
            g += Vec3::new(wz[k] * ax, wz[k] * ay, dz[k] * a);
        }
    }
    (val, g / h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::voxel::sparse::LevelGeom;

    /// The brick-wise gathering of a stencil reads the nodes (or finds a brick missing)
    /// as node-by-node lookups do, at every cell of a level with holes whose size is not
    /// a whole number of bricks: inside bricks, across their faces, edges and corners, and
    /// clamped at the domain's faces.
    #[test]
    fn stencils_gather_the_nodes_around_the_cell() {
        let geom = LevelGeom {
            origin: Vec3::ZERO,
            h: 1.0,
            dims: IVec3::new(21, 18, 13),
        };
        let coords: Vec<IVec3> = (0..2)
            .flat_map(|z| (0..3).flat_map(move |y| (0..3).map(move |x| IVec3::new(x, y, z))))
            .filter(|&c| c != IVec3::new(1, 1, 0))
            .collect();
        let bricks = Bricks::new(geom, coords);
        let s: Vec<f32> = (0..bricks.len() * BRICK_NODES).map(|i| i as f32).collect();
        let (mut found, mut missing) = (0, 0);
        for i in 0..bricks.len() * BRICK_NODES {
            let c = bricks.node_coord(i);
            if !(c.cmplt(geom.dims - 1).all()) {
                continue;
            }
            let got = stencil(&bricks, &s, i as u32);
            assert_eq!(got, stencil_by_node(&bricks, &s, i as u32), "cell {c}");
            found += usize::from(got.is_some());
            missing += usize::from(got.is_none());
        }
        assert!(
            found > 2000 && missing > 200,
            "{found} stencils, {missing} missing"
        );
    }

    /// Rough data (zigzags and bumps that make Catmull–Rom overshoot) on a sparse level
    /// with holes: the blended field stays inside the widened value range, its gradient
    /// inside the widened slopes, it is continuous (pairs across cells and across the
    /// blend's edge obey the bound), and the widening is needed.
    #[test]
    fn blend_obeys_the_widened_bounds() {
        let geom = LevelGeom {
            origin: Vec3::new(1.0, -2.0, 0.5),
            h: 0.5,
            dims: IVec3::new(30, 26, 22),
        };
        let mut coords = Vec::new();
        for z in 0..3 {
            for y in 0..4 {
                for x in 0..4 {
                    if (x, y, z) != (1, 1, 1) && (x, y, z) != (3, 0, 2) {
                        coords.push(IVec3::new(x, y, z));
                    }
                }
            }
        }
        let bricks = Bricks::new(geom, coords);
        let mut seed = 7u64;
        let mut rnd = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32
        };
        let s: Vec<f32> = (0..bricks.len() * BRICK_NODES)
            .map(|i| {
                let c = bricks.node_coord(i);
                // A zigzag along x (Catmull–Rom's slope overshoots the edges' by half), bumps
                // along z (its value overshoots the nodes'), a tilt along y, a little noise.
                let zig = if c.x % 2 == 0 { 0.5 } else { -0.5 };
                let bump = if matches!(c.z % 4, 1 | 2) { 0.8 } else { 0.0 };
                zig + bump + 0.1 * c.y as f32 + 0.01 * rnd()
            })
            .collect();
        // Trilinear bounds over the level (what the pipeline's brick bounds hold).
        let mut lin = BrickBounds {
            s: [f32::INFINITY, f32::NEG_INFINITY],
            ..Default::default()
        };
        for (i, &v) in s.iter().enumerate() {
            let c = bricks.node_coord(i);
            if !geom.contains(c) {
                continue;
            }
            lin.s = [lin.s[0].min(v), lin.s[1].max(v)];
            for a in 0..3 {
                let mut e = IVec3::ZERO;
                e[a] = 1;
                if let Some(j) = bricks.node(c + e).filter(|_| geom.contains(c + e)) {
                    lin.grad_s[a] = lin.grad_s[a].max((s[j] - v).abs() / geom.h);
                }
            }
        }
        let cubic = Cubic::new(&bricks, &s);
        assert!(cubic.all().w == [0.0, 1.0], "the blend has an edge");
        let wide = cubic.all().widen(&lin, geom.h);
        let eval = |p: Vec3| {
            let (idx, f) = bricks.cell(p)?;
            let t = trilinear_grad(&s, &idx, f, geom.h);
            Some(cubic.eval::<true>(&bricks, &s, &idx, f, t))
        };
        let (mut over_value, mut over_slope) = (false, false);
        let lip = wide.grad_s.length();
        let size = (geom.dims - 1).as_vec3() * geom.h;
        for _ in 0..40_000 {
            let p = geom.origin + Vec3::new(rnd(), rnd(), rnd()) * size;
            let Some((v, g)) = eval(p) else { continue };
            assert!(
                v >= wide.s[0] - 1e-4 && v <= wide.s[1] + 1e-4,
                "{v} outside {:?}",
                wide.s
            );
            assert!(
                g.abs().cmple(wide.grad_s * (1.0 + 1e-4) + 1e-4).all(),
                "gradient {g} above {}",
                wide.grad_s
            );
            over_value |= v < lin.s[0] || v > lin.s[1];
            over_slope |= g.abs().cmpgt(lin.grad_s).any();
            let q = p + (Vec3::new(rnd(), rnd(), rnd()) - 0.5) * geom.h * 1.5;
            if let Some((w, _)) = eval(q) {
                assert!((v - w).abs() <= lip * p.distance(q) * (1.0 + 1e-4) + 1e-4);
            }
        }
        assert!(over_value && over_slope, "the data exercises the overshoot");
    }

    #[test]
    fn catmull_rom_passes_through_nodes_and_reproduces_quadratics() {
        let q = |p: Vec3| 0.3 * p.x * p.x - 0.7 * p.y * p.z + 1.1 * p.z - 0.2 * p.x * p.y;
        let mut v = [0.0; 64];
        for (k, e) in v.iter_mut().enumerate() {
            let d = IVec3::new(k as i32 & 3, (k as i32 >> 2) & 3, k as i32 >> 4) - IVec3::ONE;
            *e = q(d.as_vec3());
        }
        for f in [
            Vec3::ZERO,
            Vec3::ONE,
            Vec3::new(0.3, 0.8, 0.55),
            Vec3::splat(0.5),
        ] {
            let (c, g) = catmull_rom::<true>(&v, f, 1.0);
            assert!((c - q(f)).abs() < 1e-4, "{c} vs {}", q(f));
            let e = 1e-2;
            let fd = Vec3::new(
                q(f + Vec3::X * e) - q(f - Vec3::X * e),
                q(f + Vec3::Y * e) - q(f - Vec3::Y * e),
                q(f + Vec3::Z * e) - q(f - Vec3::Z * e),
            ) / (2.0 * e);
            assert!((g - fd).length() < 1e-3, "{g} vs {fd}");
        }
    }

    #[test]
    fn weight_constants_of_the_bounds_hold() {
        for i in 0..=1000 {
            let t = i as f32 / 1000.0;
            let (w, d) = weights(t);
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
            assert!(w.iter().map(|x| x.abs()).sum::<f32>() <= 1.25 + 1e-6);
            assert!(d.iter().map(|x| x.abs()).sum::<f32>() <= 3.0 + 1e-5);
            // C' = Σ w'ᵢ vᵢ = d₀ + a (d₋₁ − d₀) + c (d₁ − d₀) with a = −w'₋₁, c = w'₂.
            let (a, c) = (-d[0], d[3]);
            let (dm, d0, d1) = (0.7f32, -1.3f32, 2.9f32);
            let v = [0.0, dm, dm + d0, dm + d0 + d1];
            let direct: f32 = (0..4).map(|i| d[i] * v[i]).sum();
            assert!((direct - (d0 + a * (dm - d0) + c * (d1 - d0))).abs() < 1e-4);
            assert!(a.abs() + c.abs() <= 0.5 + 1e-6);
        }
    }
}

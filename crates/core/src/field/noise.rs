//! Seeded 3D simplex noise and fBm turbulence (Paris et al. 2019 §3.3) with proven bounds.
//!
//! * [`simplex`] / [`simplex_grad`]: gradient noise `n: R³ → [−1, 1]` on the skewed
//!   simplex lattice (Perlin 2001, Gustavson's formulation) with value and analytic
//!   gradient. The gradient of each lattice vertex comes from an integer hash of the
//!   vertex and the seed: no permutation table and no global state, so a noise source is
//!   a few bytes (cheap to store in 100,000 primitives, and the same hash ports to WGSL).
//! * [`Fbm`]: the turbulence `t(p) = Σ_{k<o} ½^k n(2^k p / λ) / Σ_{k<o} ½^k`, in
//!   `[−1, 1]`, with value, gradient, a global Lipschitz bound and an interval over a box.
//! * [`NoiseSpec`]: the tree-file form, `(amplitude: 0.5, wavelength: 4, octaves: 4)`.
//!
//! The kernel radius is `r² = ½`, not the `0.6` of the original code: with `r² = ½` a
//! lattice vertex never reaches a point outside the simplices around it (the nearest
//! other vertex is at squared distance `¾`), so the 4-corner sum equals the sum over the
//! whole lattice and `n` is C¹. With `0.6` it jumps on simplex faces and has no Lipschitz
//! constant at all. The test `four_corners_equal_the_whole_lattice` checks this.

use glam::{BVec4A, Vec3, Vec4};
use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize};

use super::bounds::{Aabb, Interval};
use super::lanes::Lanes;
#[cfg(target_arch = "x86_64")]
use super::lanes::{F8, M8};
use crate::value::{NonNegative, Positive};

/// Skew factor to the simplex lattice in 3D: `(√4 − 1) / 3`.
pub const F3: f32 = 1.0 / 3.0;
/// Unskew factor: `(1 − 1/√4) / 3`.
pub const G3: f32 = 1.0 / 6.0;
/// Squared kernel radius `r²`.
pub const R2: f32 = 0.5;

/// Value scale `S`: `n = S · Σ_v (r² − |p − v|²)⁴₊ (g_v · (p − v))`.
///
/// **Range proof.** Each term is at most `|g| a⁴ ρ` in absolute value, where `ρ = |p − v|`,
/// `a = r² − ρ²` and `|g| = √2` for every gradient of the set. So
/// `|n(p)| ≤ S · Ψ(p)` with `Ψ(p) = Σ_v √2 a_v⁴ ρ_v`, a lattice-periodic function of the
/// position only. A branch-and-bound over one lattice cell (test
/// `proof_of_range_and_lipschitz_bounds`, exact per-box maxima of each monotone piece,
/// f64) gives `sup Ψ ≤ 0.013150`, so `S = 76 ≤ 1 / sup Ψ` proves `|n| ≤ 1`.
pub const SIMPLEX_SCALE: f32 = 76.0;

/// A proven global Lipschitz bound of [`simplex`]: `|n(p) − n(q)| ≤ 7.8 |p − q|`.
///
/// **Derivation.** For one vertex term `h(d) = a⁴ (g · d)` with `a = r² − |d|²`,
/// `∇h = a⁴ g − 8 a³ (g · d) d`. Split `g = γ d̂ + g⊥` along `d̂ = d / ρ`:
/// `∇h = γ (a⁴ − 8 a³ ρ²) d̂ + a⁴ g⊥`, hence
/// `|∇h| ≤ |g| a³ max(a, |a − 8ρ²|) = √2 a³ max(a, |r² − 9ρ²|) =: φ(ρ)`
/// (equality when `g ∥ d` or `g ⊥ d`). The terms vanish with their first derivatives at
/// `ρ = r`, so `n` is C¹ and `|∇n(p)| ≤ S · Φ(p)`, `Φ(p) = Σ_v φ(|p − v|)`. `Φ` depends on
/// the position only (not on the seed); it is lattice periodic, and the same
/// branch-and-bound over one cell proves `sup Φ ≤ 0.102604`, so
/// `|∇n| ≤ 76 · 0.102604 ≤ 7.8`. Alone, a vertex gives `S √2 r⁸ ≈ 6.72` (reached at every
/// lattice vertex), so the bound is within 16% of the true supremum (sampling sees 6.88).
pub const SIMPLEX_LIPSCHITZ: f32 = 7.8;

/// Frequency ratio between successive octaves of [`Fbm`] (Paris et al. 2019 §3.3: `2^k`).
pub const LACUNARITY: f32 = 2.0;
/// Amplitude ratio between successive octaves of [`Fbm`] (Paris et al. 2019 §3.3: `1 / 2^k`).
pub const GAIN: f32 = 0.5;
/// Most octaves a [`NoiseSpec`] accepts.
pub const MAX_OCTAVES: u32 = 12;

/// Gradient directions: the 12 cube-edge midpoints (`|g| = √2`), 4 of them repeated so a
/// 4-bit index picks one without a modulo.
const GRADIENTS: [[f32; 3]; 16] = [
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [1.0, -1.0, 0.0],
    [-1.0, -1.0, 0.0],
    [1.0, 0.0, 1.0],
    [-1.0, 0.0, 1.0],
    [1.0, 0.0, -1.0],
    [-1.0, 0.0, -1.0],
    [0.0, 1.0, 1.0],
    [0.0, -1.0, 1.0],
    [0.0, 1.0, -1.0],
    [0.0, -1.0, -1.0],
    [1.0, 1.0, 0.0],
    [0.0, -1.0, 1.0],
    [-1.0, 1.0, 0.0],
    [0.0, -1.0, -1.0],
];

/// A 32-bit integer finaliser (the "lowbias32" mix): every input bit affects every
/// output bit. Used to derive seeds and lattice gradients.
#[inline]
pub fn mix32(mut h: u32) -> u32 {
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^ (h >> 16)
}

/// The lattice hash's multipliers of `i`, `j`, `k`.
const HASH_X: u32 = 0x8da6_b343;
const HASH_Y: u32 = 0xd816_3841;
const HASH_Z: u32 = 0xcb1a_b31f;

/// The gradient of lattice vertex `(i, j, k)` for `seed`.
#[inline]
fn gradient(seed: u32, i: i32, j: i32, k: i32) -> Vec3 {
    let h = mix32(
        seed ^ (i as u32).wrapping_mul(HASH_X)
            ^ (j as u32).wrapping_mul(HASH_Y)
            ^ (k as u32).wrapping_mul(HASH_Z),
    );
    Vec3::from_array(GRADIENTS[(h >> 28) as usize])
}

/// Seeded 2D cellular noise at `q` (Worley 1996; one jittered feature point a unit
/// cell): the hash of the nearest feature point (which cell `q` belongs to) and how far
/// `q` lies from the border with the next (`F2 − F1`, 0 on the border), and `q`'s offset
/// from its own point.
pub fn cellular(seed: u32, q: glam::Vec2) -> (u32, f32, glam::Vec2) {
    let c = q.floor();
    let (mut f1, mut f2, mut id) = (f32::INFINITY, f32::INFINITY, 0u32);
    let mut offset = glam::Vec2::ZERO;
    for dj in -1..=1 {
        for di in -1..=1 {
            let cell = c + glam::Vec2::new(di as f32, dj as f32);
            let h = mix32(
                (cell.x as i32 as u32).wrapping_mul(HASH_X)
                    ^ (cell.y as i32 as u32).wrapping_mul(HASH_Y)
                    ^ mix32(seed),
            );
            let u = |s: u32| (mix32(h ^ s) & 0xffff) as f32 / 65536.0;
            let v = q - (cell + glam::Vec2::new(u(1), u(2)));
            let d = v.length();
            if d < f1 {
                (f2, f1, id, offset) = (f1, d, h, v);
            } else if d < f2 {
                f2 = d;
            }
        }
    }
    (id, f2 - f1, offset)
}

/// A hash `h`'s share `s` as a number in `[0, 1)`.
#[inline]
pub fn unit(h: u32, s: u32) -> f32 {
    (mix32(h ^ s) & 0xffff) as f32 / 65536.0
}

/// Seeded 3D simplex noise `n(p) ∈ [−1, 1]`, lattice spacing ≈ 1 (input in lattice units).
#[inline]
pub fn simplex(seed: u32, p: Vec3) -> f32 {
    simplex_impl::<false>(seed, p).0
}

/// `(n(p), ∇n(p))`, the gradient exact (the kernel is C¹).
#[inline]
pub fn simplex_grad(seed: u32, p: Vec3) -> (f32, Vec3) {
    simplex_impl::<true>(seed, p)
}

/// `⌊x⌋` without a call into libm (the baseline x86-64 has no rounding instruction):
/// truncation, one step down for negative non-integers. Exact for every `x` (from `2²³`
/// on, every float is an integer), except that `−0` gives `+0`.
#[inline(always)]
fn floor(x: f32) -> f32 {
    if x.abs() < 8_388_608.0 {
        let t = x as i32 as f32;
        if t > x { t - 1.0 } else { t }
    } else {
        x
    }
}

#[inline(always)]
fn simplex_impl<const GRAD: bool>(seed: u32, p: Vec3) -> (f32, Vec3) {
    // Skew to find the lattice cell, then unskew the cell origin back.
    let s = (p.x + p.y + p.z) * F3;
    let (i, j, k) = (floor(p.x + s), floor(p.y + s), floor(p.z + s));
    let t = (i + j + k) * G3;
    let d0 = p - Vec3::new(i - t, j - t, k - t);
    // The simplex of the cell holding p: walk the axes in decreasing order of d0. The
    // first step is along the largest component, the second adds the middle one; written
    // with comparisons instead of branches, which the CPU cannot predict here.
    let (xy, yz, xz) = (d0.x >= d0.y, d0.y >= d0.z, d0.x >= d0.z);
    let o1 = [xy & xz, !xy & yz, !xz & !yz].map(i32::from);
    let o2 = [xy | xz, !xy | yz, !yz | !xz].map(i32::from);
    let (ii, jj, kk) = (i as i32, j as i32, k as i32);
    let corners = [[0, 0, 0], o1, o2, [1, 1, 1]];
    let mut value = 0.0;
    let mut grad = Vec3::ZERO;
    for (c, o) in corners.iter().enumerate() {
        let off = Vec3::new(o[0] as f32, o[1] as f32, o[2] as f32);
        let d = d0 - off + Vec3::splat(c as f32 * G3);
        // A corner out of reach adds `0 · (g · d)`, which leaves the sums as they are.
        let a = (R2 - d.length_squared()).max(0.0);
        let g = gradient(seed, ii + o[0], jj + o[1], kk + o[2]);
        let gd = g.dot(d);
        let a2 = a * a;
        value += a2 * a2 * gd;
        if GRAD {
            grad += a2 * a * (a * g - 8.0 * gd * d);
        }
    }
    (SIMPLEX_SCALE * value, SIMPLEX_SCALE * grad)
}

/// Lanes the simplex kernel runs on, with their lattice hash.
pub trait NoiseLanes: Lanes {
    /// The lattice hash of [`gradient`] on these lanes.
    type Lattice: LatticeLanes<Self>;
}

/// The lattice hash of [`gradient`] on the lanes of `L`.
pub trait LatticeLanes<L: Lanes> {
    /// The lanes' seeds (`seeds[..N]`) and cells (`ijk`, integer floats).
    fn new(seeds: &[u32], ijk: [L; 3]) -> Self;
    /// The gradients the hash picks for the corner `o` (per axis, the lanes that step to
    /// the upper plane), per axis.
    fn gradients(&self, o: [L::Mask; 3]) -> [L; 3];
}

impl NoiseLanes for Vec4 {
    type Lattice = Lattice4;
}

#[cfg(target_arch = "x86_64")]
impl NoiseLanes for F8 {
    type Lattice = Lattice8;
}

/// Noises on the lanes, one per lane: lane `l` is `simplex(seeds[l], (x, y, z)[l])` bit for
/// bit — the same operations in the same order on the lanes of SIMD registers (no fused
/// multiply-add), the simplex's corners chosen by masks. The octaves of a multifractal are
/// independent noises, evaluated this way, or one octave at many points. The lattice hash
/// and the gradients' dot products run on the lanes too ([`LatticeLanes`]). With `GRAD`,
/// the gradients too, per axis, as [`simplex_grad`] gives them bit for bit (zeros
/// otherwise).
#[inline(always)]
fn simplex_lanes<L: NoiseLanes, const GRAD: bool>(seeds: &[u32], x: L, y: L, z: L) -> (L, [L; 3]) {
    let s = (x + y + z) * L::splat(F3);
    let (i, j, k) = ((x + s).floor(), (y + s).floor(), (z + s).floor());
    let t = (i + j + k) * L::splat(G3);
    let d0 = [x - (i - t), y - (j - t), z - (k - t)];
    let (xy, yz, xz) = (d0[0].cmpge(d0[1]), d0[1].cmpge(d0[2]), d0[0].cmpge(d0[2]));
    let (no, yes) = (L::mask_splat(false), L::mask_splat(true));
    let corners = [
        [no; 3],
        [xy & xz, !xy & yz, !xz & !yz],
        [xy | xz, !xy | yz, !yz | !xz],
        [yes; 3],
    ];
    let lattice = L::Lattice::new(seeds, [i, j, k]);
    let mut value = L::ZERO;
    let mut grad = [L::ZERO; 3];
    for (c, o) in corners.into_iter().enumerate() {
        let g = L::splat(c as f32 * G3);
        let mut d = d0;
        for a in 0..3 {
            d[a] = d0[a] - L::select(o[a], L::ONE, L::ZERO) + g;
        }
        let a = (L::splat(R2) - (d[0] * d[0] + d[1] * d[1] + d[2] * d[2])).max(L::ZERO);
        let gv = lattice.gradients(o);
        let gd = gv[0] * d[0] + gv[1] * d[1] + gv[2] * d[2];
        let a2 = a * a;
        value += a2 * a2 * gd;
        if GRAD {
            // a²·a·(a·g − (8·(g · d))·d), in the scalar kernel's order
            let (a3, gd8) = (a2 * a, L::splat(8.0) * gd);
            for axis in 0..3 {
                grad[axis] += a3 * (a * gv[axis] - gd8 * d[axis]);
            }
        }
    }
    let scale = L::splat(SIMPLEX_SCALE);
    for g in &mut grad {
        *g = scale * *g;
    }
    (scale * value, grad)
}

/// The lattice hash of [`gradient`] for four lanes: per axis and lane, the hash's product
/// of the cell's lower lattice plane (`(i + 1)·m = i·m + m` gives the upper one).
#[cfg(target_arch = "x86_64")]
pub struct Lattice4 {
    seeds: std::arch::x86_64::__m128i,
    products: [std::arch::x86_64::__m128i; 3],
}

/// The multipliers of the axes of the lattice hash.
#[cfg(target_arch = "x86_64")]
const MULTIPLIERS: [u32; 3] = [HASH_X, HASH_Y, HASH_Z];

#[cfg(target_arch = "x86_64")]
impl LatticeLanes<Vec4> for Lattice4 {
    #[inline(always)]
    fn new(seeds: &[u32], ijk: [Vec4; 3]) -> Lattice4 {
        use std::arch::x86_64::*;
        // SAFETY: SSE2 is part of the x86-64 baseline; no memory is accessed.
        unsafe {
            let mut products = [_mm_setzero_si128(); 3];
            for (a, v) in ijk.into_iter().enumerate() {
                // `v as i32` as Rust converts: saturating, NaN to 0 (the instruction gives
                // i32::MIN for every float out of range and for NaN).
                let f = __m128::from(v);
                let t = _mm_cvttps_epi32(f);
                let over = _mm_castps_si128(_mm_cmpge_ps(f, _mm_set1_ps(2_147_483_648.0)));
                let t = _mm_or_si128(
                    _mm_andnot_si128(over, t),
                    _mm_and_si128(over, _mm_set1_epi32(i32::MAX)),
                );
                let t = _mm_and_si128(t, _mm_castps_si128(_mm_cmpord_ps(f, f)));
                products[a] = mul32(t, MULTIPLIERS[a]);
            }
            Lattice4 {
                seeds: _mm_set_epi32(
                    seeds[3] as i32,
                    seeds[2] as i32,
                    seeds[1] as i32,
                    seeds[0] as i32,
                ),
                products,
            }
        }
    }

    /// The rows of [`GRADIENTS`] decoded on the lanes. Rows 0–7 start with x, 8–15 with
    /// y; the second term is y for rows 0–3, x for rows 12 and 14, z otherwise; bit 0 of
    /// the row flips the first, bit 1 the second.
    #[inline(always)]
    fn gradients(&self, o: [BVec4A; 3]) -> [Vec4; 3] {
        use std::arch::x86_64::*;
        let row = self.row(o);
        // SAFETY: SSE2 is part of the x86-64 baseline; no memory is accessed.
        unsafe {
            let bit = |b: i32| _mm_and_si128(row, _mm_set1_epi32(b));
            let one = _mm_set1_ps(1.0);
            let s1 = _mm_xor_ps(one, _mm_castsi128_ps(_mm_slli_epi32::<31>(bit(1))));
            let s2 = _mm_xor_ps(one, _mm_castsi128_ps(_mm_slli_epi32::<30>(bit(2))));
            let first_x = _mm_castsi128_ps(_mm_cmplt_epi32(row, _mm_set1_epi32(8)));
            let second_y = _mm_castsi128_ps(_mm_cmplt_epi32(row, _mm_set1_epi32(4)));
            let second_x = _mm_castsi128_ps(_mm_cmpeq_epi32(
                _mm_or_si128(row, _mm_set1_epi32(2)),
                _mm_set1_epi32(14),
            ));
            let second_z = _mm_andnot_ps(
                _mm_or_ps(second_y, second_x),
                _mm_castsi128_ps(_mm_set1_epi32(-1)),
            );
            let gx = _mm_add_ps(_mm_and_ps(first_x, s1), _mm_and_ps(second_x, s2));
            let gy = _mm_add_ps(_mm_andnot_ps(first_x, s1), _mm_and_ps(second_y, s2));
            let gz = _mm_and_ps(second_z, s2);
            [gx, gy, gz].map(Vec4::from)
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl Lattice4 {
    /// The gradient rows (`0..16`) the hash picks for the corner `o`, per lane.
    #[inline(always)]
    fn row(&self, o: [BVec4A; 3]) -> std::arch::x86_64::__m128i {
        use std::arch::x86_64::*;
        // SAFETY: SSE2 is part of the x86-64 baseline; no memory is accessed.
        unsafe {
            let mut h = self.seeds;
            for ((up, p), m) in o.into_iter().zip(self.products).zip(MULTIPLIERS) {
                let up = _mm_castps_si128(__m128::from(up));
                let m = _mm_set1_epi32(m as i32);
                h = _mm_xor_si128(h, _mm_add_epi32(p, _mm_and_si128(up, m)));
            }
            // mix32, on the lanes.
            h = _mm_xor_si128(h, _mm_srli_epi32::<16>(h));
            h = mul32(h, 0x7feb_352d);
            h = _mm_xor_si128(h, _mm_srli_epi32::<15>(h));
            h = mul32(h, 0x846c_a68b);
            h = _mm_xor_si128(h, _mm_srli_epi32::<16>(h));
            _mm_srli_epi32::<28>(h)
        }
    }
}

/// The low 32 bits of the lanes' products by `m` (SSE2 multiplies only lanes 0 and 2 to
/// 64 bits at a time).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn mul32(a: std::arch::x86_64::__m128i, m: u32) -> std::arch::x86_64::__m128i {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is part of the x86-64 baseline; no memory is accessed.
    unsafe {
        let m = _mm_set1_epi32(m as i32);
        let even = _mm_mul_epu32(a, m);
        let odd = _mm_mul_epu32(_mm_srli_epi64::<32>(a), m);
        _mm_unpacklo_epi32(
            _mm_shuffle_epi32::<0b00_00_10_00>(even),
            _mm_shuffle_epi32::<0b00_00_10_00>(odd),
        )
    }
}

/// [`Lattice4`] on the eight lanes of [`F8`], with AVX2's 32-bit products: the same
/// integers, so the same gradients, lane for lane.
#[cfg(target_arch = "x86_64")]
pub struct Lattice8 {
    seeds: std::arch::x86_64::__m256i,
    products: [std::arch::x86_64::__m256i; 3],
}

// SAFETY (every `unsafe` block of this impl): no memory is accessed but the
// bounds-checked `seeds[..8]`, and `F8` lanes exist only where AVX2 runs
// (`field::lanes`).
#[cfg(target_arch = "x86_64")]
impl LatticeLanes<F8> for Lattice8 {
    #[inline(always)]
    fn new(seeds: &[u32], ijk: [F8; 3]) -> Lattice8 {
        use std::arch::x86_64::*;
        let seeds = &seeds[..8];
        unsafe {
            let mut products = [_mm256_setzero_si256(); 3];
            for a in 0..3 {
                // `v as i32` as Rust converts, as in `Lattice4::new`.
                let f = ijk[a].0;
                let t = _mm256_cvttps_epi32(f);
                let big = _mm256_set1_ps(2_147_483_648.0);
                let over = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_GE_OS>(f, big));
                let t = _mm256_or_si256(
                    _mm256_andnot_si256(over, t),
                    _mm256_and_si256(over, _mm256_set1_epi32(i32::MAX)),
                );
                let t = _mm256_and_si256(t, _mm256_castps_si256(_mm256_cmp_ps::<_CMP_ORD_Q>(f, f)));
                products[a] = _mm256_mullo_epi32(t, _mm256_set1_epi32(MULTIPLIERS[a] as i32));
            }
            Lattice8 {
                seeds: _mm256_loadu_si256(seeds.as_ptr().cast()),
                products,
            }
        }
    }

    #[inline(always)]
    fn gradients(&self, o: [M8; 3]) -> [F8; 3] {
        use std::arch::x86_64::*;
        unsafe {
            let mut h = self.seeds;
            for a in 0..3 {
                let up = _mm256_castps_si256(o[a].0);
                let m = _mm256_set1_epi32(MULTIPLIERS[a] as i32);
                h = _mm256_xor_si256(
                    h,
                    _mm256_add_epi32(self.products[a], _mm256_and_si256(up, m)),
                );
            }
            // mix32, on the lanes.
            h = _mm256_xor_si256(h, _mm256_srli_epi32::<16>(h));
            h = _mm256_mullo_epi32(h, _mm256_set1_epi32(0x7feb_352d));
            h = _mm256_xor_si256(h, _mm256_srli_epi32::<15>(h));
            h = _mm256_mullo_epi32(h, _mm256_set1_epi32(0x846c_a68b_u32 as i32));
            h = _mm256_xor_si256(h, _mm256_srli_epi32::<16>(h));
            let row = _mm256_srli_epi32::<28>(h);
            // The rows decoded as in `Lattice4::gradients`.
            let int = _mm256_set1_epi32;
            let one = _mm256_set1_ps(1.0);
            let b1 = _mm256_slli_epi32::<31>(_mm256_and_si256(row, int(1)));
            let b2 = _mm256_slli_epi32::<30>(_mm256_and_si256(row, int(2)));
            let s1 = _mm256_xor_ps(one, _mm256_castsi256_ps(b1));
            let s2 = _mm256_xor_ps(one, _mm256_castsi256_ps(b2));
            let first_x = _mm256_castsi256_ps(_mm256_cmpgt_epi32(int(8), row));
            let second_y = _mm256_castsi256_ps(_mm256_cmpgt_epi32(int(4), row));
            let second_x =
                _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_or_si256(row, int(2)), int(14)));
            let second_z = _mm256_andnot_ps(
                _mm256_or_ps(second_y, second_x),
                _mm256_castsi256_ps(int(-1)),
            );
            let gx = _mm256_add_ps(_mm256_and_ps(first_x, s1), _mm256_and_ps(second_x, s2));
            let gy = _mm256_add_ps(_mm256_andnot_ps(first_x, s1), _mm256_and_ps(second_y, s2));
            let gz = _mm256_and_ps(second_z, s2);
            [F8(gx), F8(gy), F8(gz)]
        }
    }
}

/// The lattice hash for four lanes, lane by lane with [`gradient`] (no 32-bit vector
/// multiply on this target).
#[cfg(not(target_arch = "x86_64"))]
pub struct Lattice4 {
    seeds: [u32; 4],
    /// Per axis and lane, the cell's lower lattice plane.
    cells: [[i32; 4]; 3],
}

#[cfg(not(target_arch = "x86_64"))]
impl LatticeLanes<Vec4> for Lattice4 {
    #[inline(always)]
    fn new(seeds: &[u32], ijk: [Vec4; 3]) -> Lattice4 {
        let seeds = [seeds[0], seeds[1], seeds[2], seeds[3]];
        let cells = ijk.map(|v| v.to_array().map(|f| f as i32));
        Lattice4 { seeds, cells }
    }

    #[inline(always)]
    fn gradients(&self, o: [BVec4A; 3]) -> [Vec4; 3] {
        let bits = o.map(|m| m.bitmask());
        let rows: [Vec4; 4] = std::array::from_fn(|l| {
            let c = |a: usize| self.cells[a][l] + ((bits[a] >> l) & 1) as i32;
            gradient(self.seeds[l], c(0), c(1), c(2)).extend(0.0)
        });
        let gt = glam::Mat4::from_cols(rows[0], rows[1], rows[2], rows[3]).transpose();
        [gt.x_axis, gt.y_axis, gt.z_axis]
    }
}

/// How many octaves an fBm sums: `1..=12`, 4 when omitted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(transparent)]
pub struct Octaves(u32);

impl Octaves {
    /// `n` octaves; `None` outside `1..=12`.
    pub fn new(n: u32) -> Option<Self> {
        (1..=MAX_OCTAVES).contains(&n).then_some(Octaves(n))
    }

    /// The count.
    pub fn get(self) -> u32 {
        self.0
    }
}

impl Default for Octaves {
    fn default() -> Self {
        Octaves(4)
    }
}

impl<'de> Deserialize<'de> for Octaves {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let n = u32::deserialize(d)?;
        Octaves::new(n).ok_or_else(|| {
            D::Error::custom(format!("expected 1 to {MAX_OCTAVES} octaves, found {n}"))
        })
    }
}

/// Noise of a tree file: `(amplitude: 0.5, wavelength: 4.0, octaves: 4, seed_offset: 0)`.
///
/// `amplitude` is in metres (how far the surface moves), `wavelength` in metres (the
/// period of the first octave), `octaves` in `1..=12` (default 4), and `seed_offset`
/// (default 0) is combined with the scene's global seed, so two nodes with the same
/// spec share their noise unless their offsets differ.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoiseSpec {
    /// Displacement amplitude `A` in metres.
    pub amplitude: NonNegative,
    /// Wavelength `λ` of the first octave, in metres.
    pub wavelength: Positive,
    /// Octave count.
    #[serde(default)]
    pub octaves: Octaves,
    /// Added to the scene seed.
    #[serde(default)]
    pub seed_offset: u32,
}

/// fBm turbulence `t(p) = Σ_{k<o} ½^k n_k(2^k p / λ + k·c) / Σ_{k<o} ½^k ∈ [−1, 1]`
/// (Paris et al. 2019 §3.3), each octave with its own seed and a fixed shift `k·c` so the octaves
/// do not share their zeros at the lattice vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fbm {
    seed: u32,
    inv_wavelength: f32,
    octaves: u32,
    /// `1 / Σ ½^k`.
    norm: f32,
    lipschitz: f32,
}

/// The scales of the four octaves `k0 .. k0 + 4` from octave `k0`'s lattice units.
const OCTAVE_SCALES: [f32; 4] = [
    1.0,
    LACUNARITY,
    LACUNARITY * LACUNARITY,
    LACUNARITY * LACUNARITY * LACUNARITY,
];

/// Shift of octave `k` in lattice units: `k · OCTAVE_SHIFT`.
pub const OCTAVE_SHIFT: Vec3 = Vec3::new(0.547_7, 0.312_7, 0.753_1);

impl Fbm {
    /// The turbulence of a tree-file spec; `scene_seed` is the tree's global seed.
    pub fn new(spec: &NoiseSpec, scene_seed: u32) -> Self {
        let seed = mix32(scene_seed ^ mix32(spec.seed_offset.wrapping_add(0x9e37_79b9)));
        Fbm::with(seed, spec.wavelength.get(), spec.octaves.get())
    }

    /// The turbulence with an explicit seed, first-octave wavelength (metres, `> 0`) and
    /// octave count (clamped to `1..=12`).
    pub fn with(seed: u32, wavelength: f32, octaves: u32) -> Self {
        let octaves = octaves.clamp(1, MAX_OCTAVES);
        let (mut amp, mut freq, mut sum_amp, mut sum_slope) = (1.0f32, 1.0f32, 0.0f32, 0.0f32);
        for _ in 0..octaves {
            sum_amp += amp;
            sum_slope += amp * freq;
            amp *= GAIN;
            freq *= LACUNARITY;
        }
        let inv_wavelength = 1.0 / wavelength;
        Fbm {
            seed,
            inv_wavelength,
            octaves,
            norm: 1.0 / sum_amp,
            // |∇t| ≤ Σ ½^k 2^k |∇n| / (λ Σ ½^k); rounded up by one part in 10⁵ so the
            // f32 sums above can never make it optimistic.
            lipschitz: SIMPLEX_LIPSCHITZ * sum_slope * inv_wavelength / sum_amp * 1.000_01,
        }
    }

    /// The seed of the first octave (octave `k` uses `seed + k·0x9e3779b9`).
    pub fn seed(&self) -> u32 {
        self.seed
    }

    /// `1 / λ`: the first octave's frequency, as the evaluation uses it.
    pub fn inv_wavelength(&self) -> f32 {
        self.inv_wavelength
    }

    /// `1 / Σ_{k<o} ½^k`: the normalisation of the octave sum.
    pub fn norm(&self) -> f32 {
        self.norm
    }

    /// Wavelength of the first octave, in metres.
    pub fn wavelength(&self) -> f32 {
        1.0 / self.inv_wavelength
    }

    /// Number of octaves.
    pub fn octaves(&self) -> u32 {
        self.octaves
    }

    /// `t(p)`: the octaves four at a time ([`Fbm::octaves4`]), summed in the order
    /// [`Fbm::value_grad`] sums them, so both give the same value bit for bit.
    #[inline]
    pub fn value(&self, p: Vec3) -> f32 {
        let mut q = p * self.inv_wavelength;
        let mut amp = 1.0f32;
        let mut value = 0.0f32;
        let mut k0 = 0;
        while k0 < self.octaves {
            let four = self.octaves4(k0, q).to_array();
            for n in &four[..(self.octaves - k0).min(4) as usize] {
                value += amp * n;
                amp *= GAIN;
            }
            // LACUNARITY⁴ = 16: exact, as four products by 2 are.
            q *= LACUNARITY * LACUNARITY * LACUNARITY * LACUNARITY;
            k0 += 4;
        }
        value * self.norm
    }

    /// `(t(p), ∇t(p))`: the octaves four at a time with their gradients
    /// ([`Fbm::octaves4_grad`]), summed octave by octave as `Σ ½^k n_k` and
    /// `Σ (½^k·2^k/λ) ∇n_k` — the same value as [`Fbm::value`], bit for bit.
    #[inline]
    pub fn value_grad(&self, p: Vec3) -> (f32, Vec3) {
        let mut q = p * self.inv_wavelength;
        let (mut amp, mut freq) = (1.0f32, self.inv_wavelength);
        let (mut value, mut grad) = (0.0f32, Vec3::ZERO);
        let mut k0 = 0;
        while k0 < self.octaves {
            let (n, [gx, gy, gz]) = self.octaves4_grad(k0, q);
            let (n, gx, gy, gz) = (n.to_array(), gx.to_array(), gy.to_array(), gz.to_array());
            for l in 0..(self.octaves - k0).min(4) as usize {
                value += amp * n[l];
                grad += (amp * freq) * Vec3::new(gx[l], gy[l], gz[l]);
                amp *= GAIN;
                freq *= LACUNARITY;
            }
            q *= LACUNARITY * LACUNARITY * LACUNARITY * LACUNARITY;
            k0 += 4;
        }
        (value * self.norm, grad * self.norm)
    }

    /// Octave `k` alone, unweighted: `n_k(q + k·c)` (and its gradient in lattice units),
    /// where `q = 2^k p / λ` is the point in the octave's lattice units: the reference the
    /// four-lane evaluations are checked against.
    #[cfg(test)]
    fn octave<const GRAD: bool>(&self, k: u32, q: Vec3) -> (f32, Vec3) {
        let seed = self.seed.wrapping_add(k.wrapping_mul(0x9e37_79b9));
        simplex_impl::<GRAD>(seed, q + k as f32 * OCTAVE_SHIFT)
    }

    /// Octaves `k0 .. k0 + 4` alone, unweighted: lane `l` is octave `k0 + l`,
    /// `n_k(2^l q + k·c)` (bit for bit the scalar noise; lanes past the last octave hold
    /// noise too), `q` the point in octave `k0`'s lattice units. The elevation trees'
    /// multifractals weight the octaves their own way (the elevation trees).
    #[inline]
    pub fn octaves4(&self, k0: u32, q: Vec3) -> Vec4 {
        self.octaves4_impl::<false>(k0, q).0
    }

    /// Octave `k` alone at `L::N` points, unweighted: lane `l` is lane `k mod 4` of
    /// [`Fbm::octaves4`]`(k − k mod 4, q_l)` bit for bit, where `q_l = (q[0], q[1], q[2])[l]`
    /// is a point in the lattice units of octave `k − k mod 4` — the same operations, with
    /// one seed on every lane. The elevation trees' multifractals evaluate the octaves of
    /// many points this way (the elevation trees).
    #[inline(always)]
    pub fn octave_lanes<L: NoiseLanes>(&self, k: u32, q: [L; 3]) -> L {
        let seeds = [self.seed.wrapping_add(k.wrapping_mul(0x9e37_79b9)); 8];
        let scale = L::splat(OCTAVE_SCALES[(k % 4) as usize]);
        let kf = L::splat(k as f32);
        simplex_lanes::<L, false>(
            &seeds[..L::N],
            q[0] * scale + kf * L::splat(OCTAVE_SHIFT.x),
            q[1] * scale + kf * L::splat(OCTAVE_SHIFT.y),
            q[2] * scale + kf * L::splat(OCTAVE_SHIFT.z),
        )
        .0
    }

    /// [`Fbm::octaves4`] with each octave's gradient in its lattice units, per axis.
    #[inline]
    fn octaves4_grad(&self, k0: u32, q: Vec3) -> (Vec4, [Vec4; 3]) {
        self.octaves4_impl::<true>(k0, q)
    }

    #[inline(always)]
    fn octaves4_impl<const GRAD: bool>(&self, k0: u32, q: Vec3) -> (Vec4, [Vec4; 3]) {
        let ks: [u32; 4] = std::array::from_fn(|l| k0 + l as u32);
        let seeds = ks.map(|k| self.seed.wrapping_add(k.wrapping_mul(0x9e37_79b9)));
        let kf = Vec4::from_array(ks.map(|k| k as f32));
        let scale = Vec4::from_array(OCTAVE_SCALES);
        let lane = |q: f32, c: f32| Vec4::splat(q) * scale + kf * c;
        simplex_lanes::<Vec4, GRAD>(
            &seeds,
            lane(q.x, OCTAVE_SHIFT.x),
            lane(q.y, OCTAVE_SHIFT.y),
            lane(q.z, OCTAVE_SHIFT.z),
        )
    }

    /// A proven Lipschitz bound: `SIMPLEX_LIPSCHITZ · Σ (½·2)^k / (λ Σ ½^k)`
    /// `= SIMPLEX_LIPSCHITZ · o / (λ (2 − 2^{1−o}))` for `o` octaves.
    #[inline]
    pub fn lipschitz(&self) -> f32 {
        self.lipschitz
    }

    /// A range holding `t(p)` for every `p` in `b`: `[−1, 1]` clipped by
    /// `t(centre) ± λ_t · half-diagonal`.
    pub fn interval(&self, b: &Aabb) -> Interval {
        let r = self.lipschitz * b.radius();
        let t = self.value(b.center());
        Interval::new((t - r).max(-1.0), (t + r).min(1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator for the tests (splitmix-like over `mix32`).
    struct Rng(u32);
    impl Rng {
        fn f(&mut self) -> f32 {
            self.0 = self.0.wrapping_add(0x9e37_79b9);
            (mix32(self.0) >> 8) as f32 / (1u32 << 24) as f32
        }
        fn v(&mut self, s: f32) -> Vec3 {
            Vec3::new(self.f() - 0.5, self.f() - 0.5, self.f() - 0.5) * s
        }
    }

    /// The same noise, summed over every lattice vertex within reach instead of the 4
    /// corners of the simplex: equal iff the kernel never leaks past the simplex.
    fn brute(seed: u32, p: Vec3) -> f32 {
        let s = (p.x + p.y + p.z) * F3;
        let base = [
            (p.x + s).floor() as i32,
            (p.y + s).floor() as i32,
            (p.z + s).floor() as i32,
        ];
        let mut sum = 0.0;
        for di in -2..=3 {
            for dj in -2..=3 {
                for dk in -2..=3 {
                    let (i, j, k) = (base[0] + di, base[1] + dj, base[2] + dk);
                    let t = (i + j + k) as f32 * G3;
                    let d = p - Vec3::new(i as f32 - t, j as f32 - t, k as f32 - t);
                    let a = R2 - d.length_squared();
                    if a > 0.0 {
                        sum += a.powi(4) * gradient(seed, i, j, k).dot(d);
                    }
                }
            }
        }
        SIMPLEX_SCALE * sum
    }

    #[test]
    fn four_corners_equal_the_whole_lattice() {
        let mut rng = Rng(1);
        for _ in 0..20_000 {
            let p = rng.v(40.0);
            assert!(
                (simplex(7, p) - brute(7, p)).abs() < 1e-4,
                "at {p}: {} vs {}",
                simplex(7, p),
                brute(7, p)
            );
        }
    }

    #[test]
    fn the_fbm_value_is_the_octave_by_octave_sum_bit_for_bit() {
        let mut rng = Rng(5);
        for n in 0..20_000 {
            let p = rng.v([0.5, 300.0, 2e4][n % 3]);
            let f = Fbm::with(rng.0, [3.0, 40.0][n % 2], 1 + n as u32 % 12);
            let (a, (b, g)) = (f.value(p), f.value_grad(p));
            assert_eq!(
                a.to_bits(),
                b.to_bits(),
                "{} octaves at {p}: {a} vs {b}",
                f.octaves()
            );
            // the gradient, four octaves at a time, is the scalar kernels' sum
            let mut q = p * f.inv_wavelength();
            let (mut amp, mut freq, mut want) = (1.0f32, f.inv_wavelength(), Vec3::ZERO);
            for k in 0..f.octaves() {
                want += (amp * freq) * f.octave::<true>(k, q).1;
                amp *= GAIN;
                freq *= LACUNARITY;
                q *= LACUNARITY;
            }
            want *= f.norm();
            assert_eq!(
                g.to_array().map(f32::to_bits),
                want.to_array().map(f32::to_bits),
                "{} octaves at {p}: {g} vs {want}",
                f.octaves()
            );
        }
    }

    #[test]
    fn four_octaves_at_once_are_the_octaves_bit_for_bit() {
        let mut rng = Rng(3);
        for n in 0..20_000 {
            // Points of every scale, lattice vertices and faces among them.
            let q = if n % 10 == 0 {
                rng.v(8.0).round()
            } else {
                rng.v([0.01, 40.0, 3e4][n % 3])
            };
            let f = Fbm::with(rng.0, 1.0, 12);
            let k0 = 4 * (n as u32 % 3);
            let four = f.octaves4(k0, q).to_array();
            for (l, v) in four.iter().enumerate() {
                let k = k0 + l as u32;
                let one = f.octave::<false>(k, q * 2f32.powi(l as i32)).0;
                assert_eq!(
                    v.to_bits(),
                    one.to_bits(),
                    "octave {k} at {q}: {v} vs {one}"
                );
            }
        }
    }

    #[test]
    fn one_octave_at_four_points_is_the_octave_bit_for_bit() {
        let mut rng = Rng(4);
        for n in 0..5_000 {
            let q: [Vec3; 4] = std::array::from_fn(|l| {
                if (n + l) % 10 == 0 {
                    rng.v(8.0).round()
                } else {
                    rng.v([0.01, 40.0, 3e4][(n + l) % 3])
                }
            });
            let f = Fbm::with(rng.0, 1.0, 12);
            let k = n as u32 % 12;
            let lanes = [0, 1, 2].map(|a| Vec4::from_array(q.map(|q| q[a])));
            let four = f.octave_lanes(k, lanes).to_array();
            for (v, q) in four.iter().zip(q) {
                let one = f.octaves4(k - k % 4, q).to_array()[(k % 4) as usize];
                assert_eq!(
                    v.to_bits(),
                    one.to_bits(),
                    "octave {k} at {q}: {v} vs {one}"
                );
            }
        }
    }

    /// The AVX2 kernel at eight points, where the CPU has AVX2: each lane is the
    /// four-lane kernel's bit for bit, at points of every scale, lattice vertices and
    /// faces, and not finite.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn eight_lanes_are_four_lanes_bit_for_bit() {
        #[target_feature(enable = "avx2")]
        fn eight(f: &Fbm, k: u32, q: [[f32; 8]; 3]) -> [f32; 8] {
            let mut out = [0.0; 8];
            f.octave_lanes(k, q.map(|v| F8::load(&v))).store(&mut out);
            out
        }
        if !super::super::lanes::has_avx2() {
            return;
        }
        let mut rng = Rng(6);
        let specials = [f32::NAN, f32::INFINITY, -3e9, 1e8, -0.0];
        for n in 0..5_000 {
            let q: [Vec3; 8] = std::array::from_fn(|l| match (n + l) % 13 {
                0 => rng.v(8.0).round(),
                1 => Vec3::new(specials[(n / 13) % 5], rng.f(), rng.f()),
                m => rng.v([0.01, 40.0, 3e4][m % 3]),
            });
            let f = Fbm::with(rng.0, 1.0, 12);
            let k = n as u32 % 12;
            let axes = [0, 1, 2].map(|a| q.map(|q| q[a]));
            // SAFETY: the CPU has AVX2 (checked above).
            let got = unsafe { eight(&f, k, axes) };
            for half in 0..2 {
                let four = axes.map(|v| Vec4::from_slice(&v[4 * half..]));
                let want = f.octave_lanes(k, four).to_array();
                for l in 0..4 {
                    assert_eq!(
                        got[4 * half + l].to_bits(),
                        want[l].to_bits(),
                        "octave {k} at {}",
                        q[4 * half + l]
                    );
                }
            }
        }
    }

    #[test]
    fn deterministic_and_seeded() {
        let p = Vec3::new(1.3, -2.7, 0.4);
        assert_eq!(simplex(3, p), simplex(3, p));
        assert_ne!(simplex(3, p), simplex(4, p));
        let spec: NoiseSpec = ron::from_str("(amplitude: 1, wavelength: 3)").unwrap();
        assert_eq!(Fbm::new(&spec, 9).value(p), Fbm::new(&spec, 9).value(p));
        assert_ne!(Fbm::new(&spec, 9).value(p), Fbm::new(&spec, 10).value(p));
        let shifted = NoiseSpec {
            seed_offset: 1,
            ..spec
        };
        assert_ne!(Fbm::new(&spec, 9).value(p), Fbm::new(&shifted, 9).value(p));
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let mut rng = Rng(2);
        let fbm = Fbm::with(5, 3.0, 5);
        for _ in 0..5_000 {
            let p = rng.v(30.0);
            let (_, g) = simplex_grad(11, p);
            let (_, gt) = fbm.value_grad(p);
            let h = 1e-3;
            for axis in 0..3 {
                let e = Vec3::AXES[axis] * h;
                let fd = (simplex(11, p + e) - simplex(11, p - e)) / (2.0 * h);
                assert!(
                    (fd - g[axis]).abs() < 2e-2,
                    "simplex {p} axis {axis}: {fd} vs {}",
                    g[axis]
                );
                let fdt = (fbm.value(p + e) - fbm.value(p - e)) / (2.0 * h);
                assert!(
                    (fdt - gt[axis]).abs() < 2e-2,
                    "fbm {p} axis {axis}: {fdt} vs {}",
                    gt[axis]
                );
            }
        }
    }

    /// Millions of samples: neither the gradient nor a difference quotient exceeds the
    /// proven constant, and the constant is within 3× of what is observed.
    #[test]
    fn lipschitz_bound_holds_and_is_tight() {
        let mut rng = Rng(3);
        let (mut max_grad, mut max_fd, mut max_val) = (0.0f32, 0.0f32, 0.0f32);
        for n in 0..2_000_000u32 {
            let p = rng.v(200.0);
            let (v, g) = simplex_grad(n % 7, p);
            max_grad = max_grad.max(g.length());
            max_val = max_val.max(v.abs());
            if n % 4 == 0 {
                let q = p + rng.v(0.02);
                let d = (p - q).length();
                if d > 1e-3 {
                    max_fd = max_fd.max((simplex(n % 7, p) - simplex(n % 7, q)).abs() / d);
                }
            }
        }
        println!(
            "simplex: max |∇n| = {max_grad}, max FD quotient = {max_fd}, \
             SIMPLEX_LIPSCHITZ = {SIMPLEX_LIPSCHITZ}, max |n| = {max_val}"
        );
        assert!(max_grad <= SIMPLEX_LIPSCHITZ && max_fd <= SIMPLEX_LIPSCHITZ);
        assert!(SIMPLEX_LIPSCHITZ < 3.0 * max_grad);
        assert!(max_val <= 1.0 && max_val > 0.5);

        let fbm = Fbm::with(1, 2.5, 6);
        let (mut fmax_g, mut fmax_v) = (0.0f32, 0.0f32);
        for _ in 0..300_000 {
            let p = rng.v(300.0);
            let (v, g) = fbm.value_grad(p);
            fmax_g = fmax_g.max(g.length());
            fmax_v = fmax_v.max(v.abs());
            let q = p + rng.v(0.05);
            let d = (p - q).length();
            if d > 1e-3 {
                assert!((fbm.value(p) - fbm.value(q)).abs() <= fbm.lipschitz() * d + 1e-5);
            }
        }
        println!(
            "fbm: max |∇t| = {fmax_g}, lipschitz() = {}",
            fbm.lipschitz()
        );
        assert!(fmax_g <= fbm.lipschitz() && fmax_v <= 1.0);
    }

    #[test]
    fn interval_contains_samples() {
        let mut rng = Rng(4);
        let fbm = Fbm::with(8, 5.0, 4);
        for _ in 0..2_000 {
            let c = rng.v(100.0);
            let b = Aabb::new(c, c + rng.v(8.0));
            let iv = fbm.interval(&b);
            for _ in 0..64 {
                let s = rng.v(1.0) + Vec3::splat(0.5);
                let p = b.min + s * b.size();
                assert!(iv.contains(fbm.value(p)), "{p} not in {iv:?}");
            }
            for p in b.corners() {
                assert!(iv.contains(fbm.value(p)));
            }
        }
    }

    #[test]
    fn spec_parses_validates_and_round_trips() {
        let s: NoiseSpec =
            ron::from_str("(amplitude: 0.5, wavelength: 4.0, octaves: 6, seed_offset: 3)").unwrap();
        assert_eq!(s.octaves.get(), 6);
        assert_eq!(
            ron::from_str::<NoiseSpec>(&ron::to_string(&s).unwrap()).unwrap(),
            s
        );
        let d: NoiseSpec = ron::from_str("(amplitude: 0, wavelength: 1)").unwrap();
        assert_eq!((d.octaves.get(), d.seed_offset), (4, 0));
        let e = ron::from_str::<NoiseSpec>("(amplitude: 1,\n wavelength: 2,\n octaves: 13)")
            .unwrap_err();
        assert_eq!(e.span.start.line, 3);
        assert!(e.to_string().contains("1 to 12 octaves"), "{e}");
        assert!(ron::from_str::<NoiseSpec>("(amplitude: 1, wavelength: 2, octaves: 0)").is_err());
        assert!(ron::from_str::<NoiseSpec>("(amplitude: -1, wavelength: 2)").is_err());
        assert!(ron::from_str::<NoiseSpec>("(amplitude: 1, wavelength: 0)").is_err());
        let e =
            ron::from_str::<NoiseSpec>("(amplitude: 1, wavelength: 2, lacunarity: 2)").unwrap_err();
        assert!(e.to_string().contains("lacunarity"), "{e}");
    }

    /// The computer-assisted part of the proofs of [`SIMPLEX_SCALE`] and
    /// [`SIMPLEX_LIPSCHITZ`]: a branch-and-bound over one lattice cell of
    /// `Ψ(p) = Σ √2 a⁴ ρ` and `Φ(p) = Σ √2 a³ max(a, |r² − 9ρ²|)`, in f64.
    ///
    /// Boxes are boxes of skewed coordinates inside the unit cell (which tiles space); a
    /// box's unskewed bounding box gives each vertex a distance range `[ρ₀, ρ₁]`, and each
    /// term's maximum over that range is exact (each is a max of functions that are
    /// monotone between known critical points). The sum of those maxima bounds the sum.
    #[test]
    fn proof_of_range_and_lipschitz_bounds() {
        let r2 = 0.5f64;
        let r = r2.sqrt();
        let s2 = 2f64.sqrt();
        let a = |rho: f64| (r2 - rho * rho).max(0.0);
        let psi = |rho: f64| s2 * a(rho).powi(4) * rho;
        let phi = |rho: f64| s2 * a(rho).powi(3) * a(rho).max((r2 - 9.0 * rho * rho).abs());
        // Exact maxima over [lo, hi]: ψ peaks at ρ = r/3; the second factor of φ at
        // ρ = r/√3 (and a⁴ is decreasing).
        let psi_max = |lo: f64, hi: f64| {
            let m = psi(lo).max(psi(hi));
            if lo <= r / 3.0 && r / 3.0 <= hi {
                m.max(psi(r / 3.0))
            } else {
                m
            }
        };
        let phi_max = |lo: f64, hi: f64| {
            let b = |x: f64| s2 * a(x).powi(3) * (r2 - 9.0 * x * x).abs();
            let mut m = (s2 * a(lo).powi(4)).max(b(lo)).max(b(hi));
            let c = r / 3f64.sqrt();
            if lo <= c && c <= hi {
                m = m.max(b(c));
            }
            m
        };
        let g3 = 1.0 / 6.0;
        let unskew = |s: [f64; 3]| {
            let t = (s[0] + s[1] + s[2]) * g3;
            [s[0] - t, s[1] - t, s[2] - t]
        };
        let mut verts = Vec::new();
        for i in -2..=3 {
            for j in -2..=3 {
                for k in -2..=3 {
                    verts.push(unskew([i as f64, j as f64, k as f64]));
                }
            }
        }
        // (upper bound over the box, value at its centre) for both functions.
        let bound = |lo: [f64; 3], hi: [f64; 3]| {
            let mut bmin = [f64::INFINITY; 3];
            let mut bmax = [f64::NEG_INFINITY; 3];
            for c in 0..8 {
                let s = [
                    if c & 1 == 0 { lo[0] } else { hi[0] },
                    if c & 2 == 0 { lo[1] } else { hi[1] },
                    if c & 4 == 0 { lo[2] } else { hi[2] },
                ];
                let u = unskew(s);
                for ax in 0..3 {
                    bmin[ax] = bmin[ax].min(u[ax]);
                    bmax[ax] = bmax[ax].max(u[ax]);
                }
            }
            let mid = unskew([
                (lo[0] + hi[0]) / 2.0,
                (lo[1] + hi[1]) / 2.0,
                (lo[2] + hi[2]) / 2.0,
            ]);
            let (mut up_psi, mut up_phi, mut at_psi, mut at_phi) = (0.0, 0.0, 0.0, 0.0);
            for v in &verts {
                let (mut near, mut far, mut dm) = (0.0, 0.0, 0.0);
                for ax in 0..3 {
                    let n = (bmin[ax] - v[ax]).max(v[ax] - bmax[ax]).max(0.0);
                    let f = (v[ax] - bmin[ax]).abs().max((v[ax] - bmax[ax]).abs());
                    near += n * n;
                    far += f * f;
                    dm += (mid[ax] - v[ax]) * (mid[ax] - v[ax]);
                }
                let (near, far, dm) = (f64::sqrt(near), f64::sqrt(far).min(r), f64::sqrt(dm));
                if near < r {
                    up_psi += psi_max(near, far);
                    up_phi += phi_max(near, far);
                }
                at_psi += psi(dm.min(r));
                at_phi += phi(dm.min(r));
            }
            (up_psi, up_phi, at_psi, at_phi)
        };
        let run = |which: usize| {
            let mut best = 0.0f64;
            let mut proven = 0.0f64;
            let mut stack = vec![([0.0f64; 3], [1.0f64; 3])];
            while let Some((lo, hi)) = stack.pop() {
                let (up_psi, up_phi, at_psi, at_phi) = bound(lo, hi);
                let (up, at) = if which == 0 {
                    (up_psi, at_psi)
                } else {
                    (up_phi, at_phi)
                };
                best = best.max(at);
                if up <= best * (1.0 + 1e-3) || hi[0] - lo[0] < 1e-4 {
                    proven = proven.max(up);
                    continue;
                }
                let ax = (0..3)
                    .max_by(|&x, &y| (hi[x] - lo[x]).total_cmp(&(hi[y] - lo[y])))
                    .unwrap();
                let m = (lo[ax] + hi[ax]) / 2.0;
                let (mut h1, mut l2) = (hi, lo);
                h1[ax] = m;
                l2[ax] = m;
                stack.push((lo, h1));
                stack.push((l2, hi));
            }
            (best, proven.max(best))
        };
        let (psi_seen, psi_sup) = run(0);
        let (phi_seen, phi_sup) = run(1);
        println!("sup Ψ ∈ [{psi_seen}, {psi_sup}], sup Φ ∈ [{phi_seen}, {phi_sup}]");
        assert!(
            SIMPLEX_SCALE as f64 * psi_sup <= 1.0,
            "range bound not proven"
        );
        assert!(
            SIMPLEX_SCALE as f64 * phi_sup <= SIMPLEX_LIPSCHITZ as f64,
            "Lipschitz bound not proven: {}",
            SIMPLEX_SCALE as f64 * phi_sup
        );
    }
}

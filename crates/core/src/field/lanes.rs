//! Float vectors of 4 or 8 lanes behind one trait, so a kernel is written once and run at
//! the width the CPU has: glam's `Vec4` (SSE2, the x86-64 baseline, or any target) and
//! [`F8`] (AVX2, x86-64 only, chosen at run time where the CPU has it).
//!
//! Every operation is the same IEEE operation on each lane at both widths (no fused
//! multiply-add, `floor` and `max` with glam's SSE2 semantics), so a kernel gives the same
//! bits whichever width runs it. The [`F8`] operations are compiled into AVX2 code only
//! inside a function with `#[target_feature(enable = "avx2")]`: a kernel instantiated with
//! `F8` must be `#[inline(always)]` all the way up to such a function.

use std::ops::{Add, AddAssign, BitAnd, BitOr, Div, Mul, Not, Sub};

use glam::{BVec4A, Vec4};

/// A vector of [`Lanes::N`] `f32` lanes.
pub trait Lanes:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> + AddAssign
{
    /// The lane count.
    const N: usize;
    /// A per-lane mask (all bits set or clear).
    type Mask: Copy
        + BitAnd<Output = Self::Mask>
        + BitOr<Output = Self::Mask>
        + Not<Output = Self::Mask>;
    /// The lanes' `0.0`.
    const ZERO: Self;
    /// The lanes' `1.0`.
    const ONE: Self;
    /// `v` on every lane.
    fn splat(v: f32) -> Self;
    /// The first `N` values of `v` (`v.len() ≥ N`).
    fn load(v: &[f32]) -> Self;
    /// The lanes into `out[..N]` (`out.len() ≥ N`).
    fn store(self, out: &mut [f32]);
    /// `_mm_max_ps`: `rhs` where either is NaN.
    fn max(self, rhs: Self) -> Self;
    /// `⌊v⌋` as glam's SSE2 `Vec4::floor` gives it (`−0` to `+0`; NaN, infinities and
    /// floats from `2²³` on unchanged).
    fn floor(self) -> Self;
    /// `|v|` (the sign bit cleared).
    fn abs(self) -> Self;
    /// `self ≥ rhs` (false on NaN).
    fn cmpge(self, rhs: Self) -> Self::Mask;
    /// `self < rhs` (false on NaN).
    fn cmplt(self, rhs: Self) -> Self::Mask;
    /// `self > rhs` (false on NaN).
    fn cmpgt(self, rhs: Self) -> Self::Mask;
    /// `mask ? a : b` per lane.
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self;
    /// `v` on every lane of a mask.
    fn mask_splat(v: bool) -> Self::Mask;
}

impl Lanes for Vec4 {
    const N: usize = 4;
    type Mask = BVec4A;
    const ZERO: Self = Vec4::ZERO;
    const ONE: Self = Vec4::ONE;

    #[inline(always)]
    fn splat(v: f32) -> Self {
        Vec4::splat(v)
    }

    #[inline(always)]
    fn load(v: &[f32]) -> Self {
        Vec4::from_slice(v)
    }

    #[inline(always)]
    fn store(self, out: &mut [f32]) {
        self.write_to_slice(out)
    }

    #[inline(always)]
    fn max(self, rhs: Self) -> Self {
        Vec4::max(self, rhs)
    }

    #[inline(always)]
    fn floor(self) -> Self {
        Vec4::floor(self)
    }

    #[inline(always)]
    fn abs(self) -> Self {
        Vec4::abs(self)
    }

    #[inline(always)]
    fn cmpge(self, rhs: Self) -> BVec4A {
        Vec4::cmpge(self, rhs)
    }

    #[inline(always)]
    fn cmplt(self, rhs: Self) -> BVec4A {
        Vec4::cmplt(self, rhs)
    }

    #[inline(always)]
    fn cmpgt(self, rhs: Self) -> BVec4A {
        Vec4::cmpgt(self, rhs)
    }

    #[inline(always)]
    fn select(mask: BVec4A, a: Self, b: Self) -> Self {
        Vec4::select(mask, a, b)
    }

    #[inline(always)]
    fn mask_splat(v: bool) -> BVec4A {
        BVec4A::splat(v)
    }
}

#[cfg(target_arch = "x86_64")]
pub use avx2::{F8, M8, has_avx2};

#[cfg(target_arch = "x86_64")]
mod avx2 {
    //! Eight lanes in an AVX register. Each operation is an `unsafe` intrinsic call: it is
    //! only executed inside functions compiled with AVX2, which callers reach only after
    //! [`has_avx2`].
    use std::arch::x86_64::*;
    use std::ops::{Add, AddAssign, BitAnd, BitOr, Div, Mul, Not, Sub};

    use super::Lanes;

    /// Whether this CPU runs AVX2 (cached by the standard library after the first call).
    #[inline]
    pub fn has_avx2() -> bool {
        std::arch::is_x86_feature_detected!("avx2")
    }

    /// Eight `f32` lanes.
    #[derive(Clone, Copy, Debug)]
    #[repr(transparent)]
    pub struct F8(pub __m256);

    /// Eight lane masks.
    #[derive(Clone, Copy, Debug)]
    #[repr(transparent)]
    pub struct M8(pub __m256);

    // SAFETY (every `unsafe` block of this module): the intrinsics touch no memory except
    // through the bounds-checked slices of `load` and `store`, and run only where AVX2 is
    // present (the module's contract above).
    macro_rules! binary {
        ($trait:ident, $f:ident, $ty:ident, $op:ident) => {
            impl $trait for $ty {
                type Output = $ty;
                #[inline(always)]
                fn $f(self, rhs: $ty) -> $ty {
                    $ty(unsafe { $op(self.0, rhs.0) })
                }
            }
        };
    }
    binary!(Add, add, F8, _mm256_add_ps);
    binary!(Sub, sub, F8, _mm256_sub_ps);
    binary!(Mul, mul, F8, _mm256_mul_ps);
    binary!(Div, div, F8, _mm256_div_ps);
    binary!(BitAnd, bitand, M8, _mm256_and_ps);
    binary!(BitOr, bitor, M8, _mm256_or_ps);

    impl AddAssign for F8 {
        #[inline(always)]
        fn add_assign(&mut self, rhs: F8) {
            *self = *self + rhs;
        }
    }

    impl Not for M8 {
        type Output = M8;
        #[inline(always)]
        fn not(self) -> M8 {
            M8(unsafe { _mm256_xor_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(-1))) })
        }
    }

    impl Lanes for F8 {
        const N: usize = 8;
        type Mask = M8;
        // SAFETY: plain data of the same size.
        const ZERO: Self = F8(unsafe { std::mem::transmute::<[f32; 8], __m256>([0.0; 8]) });
        const ONE: Self = F8(unsafe { std::mem::transmute::<[f32; 8], __m256>([1.0; 8]) });

        #[inline(always)]
        fn splat(v: f32) -> Self {
            F8(unsafe { _mm256_set1_ps(v) })
        }

        #[inline(always)]
        fn load(v: &[f32]) -> Self {
            let v = &v[..8];
            F8(unsafe { _mm256_loadu_ps(v.as_ptr()) })
        }

        #[inline(always)]
        fn store(self, out: &mut [f32]) {
            let out = &mut out[..8];
            unsafe { _mm256_storeu_ps(out.as_mut_ptr(), self.0) }
        }

        #[inline(always)]
        fn max(self, rhs: Self) -> Self {
            F8(unsafe { _mm256_max_ps(self.0, rhs.0) })
        }

        /// glam's SSE2 `floor` (`m128_floor`, after DirectXMath's `XMVectorFloor`) on
        /// eight lanes: truncate, step down where the truncation is above `v`, and keep
        /// `v` where `|v| ≥ 2²³` or `v` is NaN.
        #[inline(always)]
        fn floor(self) -> Self {
            unsafe {
                let v = self.0;
                let bits = _mm256_and_si256(_mm256_castps_si256(v), _mm256_set1_epi32(i32::MAX));
                let small = _mm256_cmpgt_epi32(_mm256_set1_epi32(0x4b00_0000), bits);
                let t = _mm256_cvtepi32_ps(_mm256_cvttps_epi32(v));
                let larger = _mm256_cmp_ps::<_CMP_GT_OS>(t, v);
                let t = _mm256_add_ps(t, _mm256_cvtepi32_ps(_mm256_castps_si256(larger)));
                let t = _mm256_and_ps(t, _mm256_castsi256_ps(small));
                let keep = _mm256_andnot_si256(small, _mm256_castps_si256(v));
                F8(_mm256_or_ps(t, _mm256_castsi256_ps(keep)))
            }
        }

        #[inline(always)]
        fn abs(self) -> Self {
            F8(unsafe { _mm256_and_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(i32::MAX))) })
        }

        #[inline(always)]
        fn cmpge(self, rhs: Self) -> M8 {
            M8(unsafe { _mm256_cmp_ps::<_CMP_GE_OS>(self.0, rhs.0) })
        }

        #[inline(always)]
        fn cmplt(self, rhs: Self) -> M8 {
            M8(unsafe { _mm256_cmp_ps::<_CMP_LT_OS>(self.0, rhs.0) })
        }

        #[inline(always)]
        fn cmpgt(self, rhs: Self) -> M8 {
            M8(unsafe { _mm256_cmp_ps::<_CMP_GT_OS>(self.0, rhs.0) })
        }

        #[inline(always)]
        fn select(mask: M8, a: Self, b: Self) -> Self {
            F8(unsafe { _mm256_or_ps(_mm256_andnot_ps(mask.0, b.0), _mm256_and_ps(a.0, mask.0)) })
        }

        #[inline(always)]
        fn mask_splat(v: bool) -> M8 {
            M8(unsafe { _mm256_castsi256_ps(_mm256_set1_epi32(-i32::from(v))) })
        }
    }
}

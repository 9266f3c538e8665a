//! The kernels' SIMD registers as [`lanes`](crate::lanes): eight `f32` lanes of AVX2
//! ([`Avx2F32`]) and sixteen of AVX-512 ([`Avx512F32`]), with their masks, implementing
//! [`Real`] and [`Mask`] one instruction an operation. So the ray–triangle arithmetic
//! ([`crate::intersect::intersect_lanes`]) is one source for one ray and one triangle (`f32`),
//! for one ray against a packet of triangles ([`super::kernels`]) and for a packet of rays
//! against one triangle ([`super::packet`]).
//!
//! Every operation is the `f32` one in each lane, exactly rounded, never fused: the same bits
//! as the scalar code.
//!
//! **Where they may be used.** Their operations are the instruction set's intrinsics, which only
//! a CPU with it runs. So these types are private to [`super`] and used only in code reached
//! through a kernel proof ([`Avx2`](super::simd::Avx2), [`Avx512`](super::simd::Avx512),
//! whose values exist only on a CPU that runs them): the `#[target_feature]` entry points and
//! what inlines into them. (`ZERO` and `load` are plain memory; everything else, `splat`
//! included, is an instruction of the set.)

use std::arch::x86_64::*;
use std::mem::transmute;
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

use crate::lanes::{Mask, Real};

/// Eight `f32` lanes in an AVX register.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub(in crate::accel) struct Avx2F32(pub(in crate::accel) __m256);

/// Eight comparison answers in an AVX register: all ones in a lane that is true.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub(in crate::accel) struct Avx2Mask(pub(in crate::accel) __m256);

/// Sixteen `f32` lanes in an AVX-512 register.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub(in crate::accel) struct Avx512F32(pub(in crate::accel) __m512);

/// Sixteen comparison answers in an AVX-512 mask register: bit `i` for lane `i`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub(in crate::accel) struct Avx512Mask(pub(in crate::accel) __mmask16);

impl Avx2F32 {
    /// The eight floats of `a`.
    #[inline(always)]
    pub(in crate::accel) fn load(a: &[f32; 8]) -> Self {
        // SAFETY: `a` is eight readable f32; an unaligned read of plain memory.
        Self(unsafe { std::ptr::read_unaligned(a.as_ptr().cast::<__m256>()) })
    }

    #[inline(always)]
    fn lanes(self) -> [f32; 8] {
        // SAFETY: a register of eight f32 is eight f32.
        unsafe { transmute(self.0) }
    }
}

impl Avx512F32 {
    /// The sixteen floats of `a`.
    #[inline(always)]
    pub(in crate::accel) fn load(a: &[f32; 16]) -> Self {
        // SAFETY: `a` is sixteen readable f32; an unaligned read of plain memory.
        Self(unsafe { std::ptr::read_unaligned(a.as_ptr().cast::<__m512>()) })
    }

    #[inline(always)]
    fn lanes(self) -> [f32; 16] {
        // SAFETY: a register of sixteen f32 is sixteen f32.
        unsafe { transmute(self.0) }
    }
}

impl PartialEq for Avx2F32 {
    fn eq(&self, o: &Self) -> bool {
        self.lanes() == o.lanes()
    }
}

impl PartialEq for Avx512F32 {
    fn eq(&self, o: &Self) -> bool {
        self.lanes() == o.lanes()
    }
}

impl PartialEq for Avx2Mask {
    fn eq(&self, o: &Self) -> bool {
        // SAFETY: a register of eight f32 is eight u32.
        let bits = |m: &Self| unsafe { transmute::<__m256, [u32; 8]>(m.0) };
        bits(self) == bits(o)
    }
}

// The operations below are the instructions of AVX (and AVX2, FMA) or AVX-512 F and DQ: see
// the module docs for why their values only exist where the CPU runs them. Hence `unsafe`.

macro_rules! arithmetic {
    ($t:ident, $($trait:ident $method:ident $intrinsic:ident),*) => {$(
        impl $trait for $t {
            type Output = Self;

            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                // SAFETY: a value of this type only exists where its instruction set runs.
                Self(unsafe { $intrinsic(self.0, o.0) })
            }
        }
    )*};
}

arithmetic!(Avx2F32, Add add _mm256_add_ps, Sub sub _mm256_sub_ps, Mul mul _mm256_mul_ps,
    Div div _mm256_div_ps);
arithmetic!(Avx2Mask, BitAnd bitand _mm256_and_ps, BitOr bitor _mm256_or_ps);
arithmetic!(Avx512F32, Add add _mm512_add_ps, Sub sub _mm512_sub_ps, Mul mul _mm512_mul_ps,
    Div div _mm512_div_ps);

impl Neg for Avx2F32 {
    type Output = Self;

    /// The sign bit flipped, as `-x` on an `f32`.
    #[inline(always)]
    fn neg(self) -> Self {
        // SAFETY: as above.
        Self(unsafe { _mm256_xor_ps(self.0, _mm256_set1_ps(-0.0)) })
    }
}

impl Neg for Avx512F32 {
    type Output = Self;

    /// The sign bit flipped, as `-x` on an `f32`.
    #[inline(always)]
    fn neg(self) -> Self {
        // SAFETY: as above.
        Self(unsafe { _mm512_xor_ps(self.0, _mm512_set1_ps(-0.0)) })
    }
}

impl Not for Avx2Mask {
    type Output = Self;

    #[inline(always)]
    fn not(self) -> Self {
        // SAFETY: as above.
        Self(unsafe { _mm256_xor_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(-1))) })
    }
}

impl BitAnd for Avx512Mask {
    type Output = Self;

    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        Self(self.0 & o.0)
    }
}

impl BitOr for Avx512Mask {
    type Output = Self;

    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        Self(self.0 | o.0)
    }
}

impl Not for Avx512Mask {
    type Output = Self;

    #[inline(always)]
    fn not(self) -> Self {
        Self(!self.0)
    }
}

impl Mask for Avx2Mask {
    // SAFETY: eight u32 are a register of eight lanes.
    const NONE: Self = Self(unsafe { transmute::<[u32; 8], __m256>([0; 8]) });

    #[inline(always)]
    fn splat(b: bool) -> Self {
        // SAFETY: as above.
        Self(unsafe { transmute::<[u32; 8], __m256>([if b { u32::MAX } else { 0 }; 8]) })
    }

    #[inline(always)]
    fn any(self) -> bool {
        // SAFETY: a value of this type only exists where its instruction set runs.
        unsafe { _mm256_movemask_ps(self.0) != 0 }
    }
}

impl Mask for Avx512Mask {
    const NONE: Self = Self(0);

    #[inline(always)]
    fn splat(b: bool) -> Self {
        Self(if b { u16::MAX } else { 0 })
    }

    #[inline(always)]
    fn any(self) -> bool {
        self.0 != 0
    }
}

impl Real for Avx2F32 {
    type Mask = Avx2Mask;
    // SAFETY: eight f32 are a register of eight lanes.
    const ZERO: Self = Self(unsafe { transmute::<[f32; 8], __m256>([0.0; 8]) });
    const ONE: bool = false;

    // SAFETY (the methods below): a value of this type only exists where its instruction set
    // runs. (`splat` too: the broadcast instruction, which the compiler schedules better than a
    // repeated array.)

    #[inline(always)]
    fn splat(x: f32) -> Self {
        Self(unsafe { _mm256_set1_ps(x) })
    }

    #[inline(always)]
    fn sqrt(self) -> Self {
        Self(unsafe { _mm256_sqrt_ps(self.0) })
    }

    #[inline(always)]
    fn simd_max(self, o: Self) -> Self {
        // `maxps` gives its second operand if either is NaN; `f32::max` the other value.
        unsafe {
            let max = _mm256_max_ps(o.0, self.0);
            Self(_mm256_blendv_ps(
                max,
                o.0,
                _mm256_cmp_ps::<_CMP_UNORD_Q>(self.0, self.0),
            ))
        }
    }

    #[inline(always)]
    fn simd_min(self, o: Self) -> Self {
        unsafe {
            let min = _mm256_min_ps(o.0, self.0);
            Self(_mm256_blendv_ps(
                min,
                o.0,
                _mm256_cmp_ps::<_CMP_UNORD_Q>(self.0, self.0),
            ))
        }
    }

    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        unsafe {
            let bit = _mm256_set1_ps(-0.0);
            Self(_mm256_or_ps(
                _mm256_andnot_ps(bit, self.0),
                _mm256_and_ps(bit, sign.0),
            ))
        }
    }

    #[inline(always)]
    fn simd_lt(self, o: Self) -> Avx2Mask {
        Avx2Mask(unsafe { _mm256_cmp_ps::<_CMP_LT_OQ>(self.0, o.0) })
    }

    #[inline(always)]
    fn simd_le(self, o: Self) -> Avx2Mask {
        Avx2Mask(unsafe { _mm256_cmp_ps::<_CMP_LE_OQ>(self.0, o.0) })
    }

    #[inline(always)]
    fn simd_gt(self, o: Self) -> Avx2Mask {
        Avx2Mask(unsafe { _mm256_cmp_ps::<_CMP_GT_OQ>(self.0, o.0) })
    }

    #[inline(always)]
    fn simd_ge(self, o: Self) -> Avx2Mask {
        Avx2Mask(unsafe { _mm256_cmp_ps::<_CMP_GE_OQ>(self.0, o.0) })
    }

    #[inline(always)]
    fn simd_ne(self, o: Self) -> Avx2Mask {
        Avx2Mask(unsafe { _mm256_cmp_ps::<_CMP_NEQ_UQ>(self.0, o.0) })
    }

    #[inline(always)]
    fn select(mask: Avx2Mask, a: Self, b: Self) -> Self {
        Self(unsafe { _mm256_blendv_ps(b.0, a.0, mask.0) })
    }
}

impl Real for Avx512F32 {
    type Mask = Avx512Mask;
    // SAFETY: sixteen f32 are a register of sixteen lanes.
    const ZERO: Self = Self(unsafe { transmute::<[f32; 16], __m512>([0.0; 16]) });
    const ONE: bool = false;

    // SAFETY (the methods below): a value of this type only exists where its instruction set
    // runs.

    #[inline(always)]
    fn splat(x: f32) -> Self {
        Self(unsafe { _mm512_set1_ps(x) })
    }

    #[inline(always)]
    fn sqrt(self) -> Self {
        Self(unsafe { _mm512_sqrt_ps(self.0) })
    }

    #[inline(always)]
    fn simd_max(self, o: Self) -> Self {
        // `vmaxps` gives its second operand if either is NaN; `f32::max` the other value.
        unsafe {
            let max = _mm512_max_ps(o.0, self.0);
            let nan = _mm512_cmp_ps_mask::<_CMP_UNORD_Q>(self.0, self.0);
            Self(_mm512_mask_blend_ps(nan, max, o.0))
        }
    }

    #[inline(always)]
    fn simd_min(self, o: Self) -> Self {
        unsafe {
            let min = _mm512_min_ps(o.0, self.0);
            let nan = _mm512_cmp_ps_mask::<_CMP_UNORD_Q>(self.0, self.0);
            Self(_mm512_mask_blend_ps(nan, min, o.0))
        }
    }

    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        unsafe {
            let bit = _mm512_set1_ps(-0.0);
            Self(_mm512_or_ps(
                _mm512_andnot_ps(bit, self.0),
                _mm512_and_ps(bit, sign.0),
            ))
        }
    }

    #[inline(always)]
    fn simd_lt(self, o: Self) -> Avx512Mask {
        Avx512Mask(unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(self.0, o.0) })
    }

    #[inline(always)]
    fn simd_le(self, o: Self) -> Avx512Mask {
        Avx512Mask(unsafe { _mm512_cmp_ps_mask::<_CMP_LE_OQ>(self.0, o.0) })
    }

    #[inline(always)]
    fn simd_gt(self, o: Self) -> Avx512Mask {
        Avx512Mask(unsafe { _mm512_cmp_ps_mask::<_CMP_GT_OQ>(self.0, o.0) })
    }

    #[inline(always)]
    fn simd_ge(self, o: Self) -> Avx512Mask {
        Avx512Mask(unsafe { _mm512_cmp_ps_mask::<_CMP_GE_OQ>(self.0, o.0) })
    }

    #[inline(always)]
    fn simd_ne(self, o: Self) -> Avx512Mask {
        Avx512Mask(unsafe { _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(self.0, o.0) })
    }

    #[inline(always)]
    fn select(mask: Avx512Mask, a: Self, b: Self) -> Self {
        Self(unsafe { _mm512_mask_blend_ps(mask.0, b.0, a.0) })
    }
}

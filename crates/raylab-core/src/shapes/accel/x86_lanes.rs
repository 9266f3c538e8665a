//! The only x86 code of the kernels: the SIMD registers as [`lanes`](crate::base::lanes), eight
//! `f32` lanes of AVX2 ([`Avx2F32`]) and sixteen of AVX-512 ([`Avx512F32`]), with their masks,
//! implementing [`Real`] and [`Mask`] one instruction an operation; what a packet needs of them
//! beyond ([`InstructionSet`]: the gather of the rays, lane loads and stores, `u32` lanes); the
//! portable set's four-lane SSE register (`quad`); and AVX-512's lane loads and stores for the
//! integrators ([`super::lane_io`]). So the ray–triangle arithmetic
//! ([`crate::shapes::intersect::intersect_lanes`]) is one source for one ray and one triangle (`f32`),
//! for one ray against a packet of triangles ([`super::kernels`]) and for a packet of rays
//! against one triangle ([`super::packet`]).
//!
//! Every operation is the `f32` one in each lane, exactly rounded, never fused: the same bits
//! as the scalar code.
//!
//! **Where they may be used.** Their operations are the instruction set's intrinsics, which only
//! a CPU with it runs. So these types are private to [`super`] and used only in code reached
//! through a kernel proof ([`Avx2`](super::simd::Avx2), [`Avx512`](super::simd::Avx512),
//! whose values exist only on a CPU that runs them): the functions
//! [`InstructionSet::call`] makes and what inlines into them. (`ZERO` and `load` are plain memory; everything else, `splat`
//! included, is an instruction of the set.)

use std::arch::x86_64::*;
use std::mem::transmute;
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

use super::packet::{RAY_FLOATS, SEGMENT_FLOATS};
use super::set::{Compiled, InstructionSet, MAX_WIDTH};
use super::simd::{Avx2, Avx512};
use crate::base::geometry::Ray;
use crate::base::lanes::{Mask, Real, compiled};
use glam::Vec3;

/// Eight `f32` lanes in an AVX register.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub struct Avx2F32(pub(in crate::shapes::accel) __m256);

/// Eight comparison answers in an AVX register: all ones in a lane that is true.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub struct Avx2Mask(pub(in crate::shapes::accel) __m256);

/// Sixteen `f32` lanes in an AVX-512 register.
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub struct Avx512F32(pub(in crate::shapes::accel) __m512);

/// Sixteen comparison answers in an AVX-512 mask register: bit `i` for lane `i`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub struct Avx512Mask(pub(in crate::shapes::accel) __mmask16);

impl Avx2F32 {
    /// The eight floats of `a`.
    #[inline(always)]
    pub(in crate::shapes::accel) fn load(a: &[f32; 8]) -> Self {
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
    pub(in crate::shapes::accel) fn load(a: &[f32; 16]) -> Self {
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

    #[inline(always)]
    fn bitmask(self) -> u32 {
        // SAFETY: as above.
        unsafe { _mm256_movemask_ps(self.0) as u32 }
    }

    #[inline(always)]
    fn from_bitmask(bits: u32) -> Self {
        // SAFETY: as above.
        unsafe {
            let lane_bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
            let set = _mm256_and_si256(_mm256_set1_epi32(bits as i32), lane_bit);
            Self(_mm256_castsi256_ps(_mm256_cmpeq_epi32(set, lane_bit)))
        }
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

    #[inline(always)]
    fn bitmask(self) -> u32 {
        u32::from(self.0)
    }

    #[inline(always)]
    fn from_bitmask(bits: u32) -> Self {
        Self(bits as __mmask16)
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
    fn abs(self) -> Self {
        Self(unsafe { _mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0) })
    }

    #[inline(always)]
    fn max_or_other(self, o: Self) -> Self {
        Self(unsafe { _mm256_max_ps(self.0, o.0) })
    }

    #[inline(always)]
    fn min_or_other(self, o: Self) -> Self {
        Self(unsafe { _mm256_min_ps(self.0, o.0) })
    }

    #[inline(always)]
    fn simd_eq(self, o: Self) -> Avx2Mask {
        Avx2Mask(unsafe { _mm256_cmp_ps::<_CMP_EQ_OQ>(self.0, o.0) })
    }

    #[inline(always)]
    fn simd_ngt(self, o: Self) -> Avx2Mask {
        Avx2Mask(unsafe { _mm256_cmp_ps::<_CMP_NGT_UQ>(self.0, o.0) })
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
    fn abs(self) -> Self {
        Self(unsafe { _mm512_abs_ps(self.0) })
    }

    #[inline(always)]
    fn max_or_other(self, o: Self) -> Self {
        Self(unsafe { _mm512_max_ps(self.0, o.0) })
    }

    #[inline(always)]
    fn min_or_other(self, o: Self) -> Self {
        Self(unsafe { _mm512_min_ps(self.0, o.0) })
    }

    #[inline(always)]
    fn simd_eq(self, o: Self) -> Avx512Mask {
        Avx512Mask(unsafe { _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(self.0, o.0) })
    }

    #[inline(always)]
    fn simd_ngt(self, o: Self) -> Avx512Mask {
        Avx512Mask(unsafe { _mm512_cmp_ps_mask::<_CMP_NGT_UQ>(self.0, o.0) })
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

// Every intrinsic below needs its instruction set enabled, which a value of the proof type
// guarantees (it is made only by `detect`, after checking the CPU): hence the `unsafe`.

/// Floats `stride·i + c` (`c < K`) of `len` records from `base`, record `i` in lane `i`;
/// lanes past `len` repeat the last record.
///
/// # Safety
/// AVX-512 F; `base` points to `len` (1 to 16) records of `stride ≥ K` floats.
#[inline(always)]
pub(super) unsafe fn gather16<const K: usize>(
    base: *const f32,
    stride: i32,
    len: usize,
) -> [__m512; K] {
    // SAFETY: every index gathered is stride·i + c for a record i < len and c < K ≤ stride.
    unsafe {
        let lane = _mm512_min_epi32(
            _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15),
            _mm512_set1_epi32(len as i32 - 1),
        );
        let lane = _mm512_mullo_epi32(lane, _mm512_set1_epi32(stride));
        let mut out = [_mm512_setzero_ps(); K];
        for (c, out) in out.iter_mut().enumerate() {
            let index = _mm512_add_epi32(lane, _mm512_set1_epi32(c as i32));
            *out = _mm512_i32gather_ps::<4>(index, base);
        }
        out
    }
}

/// [`gather16`] for a full packet (`len` = 16) of records of `S` floats (`K ≤ S ≤ 8`), read
/// with `S` plain loads and rearranged in registers: a gather takes one load per lane, which
/// would be the packet paths' bottleneck.
///
/// Lane `i` of output `c` is float `S·i + c`, which lies in loaded vector `(S·i + c) / 16`;
/// `permutex2var` picks lanes from a pair of vectors, so each output is one pick per pair of
/// loaded vectors, merged by mask.
///
/// # Safety
/// AVX-512 F; `base` points to 16 records of `S` floats.
#[inline(always)]
unsafe fn transpose16<const S: usize, const K: usize>(base: *const f32) -> [__m512; K] {
    /// `[c][pair]`: the lanes whose float `s·i + c` lies in the pair of vectors `pair`
    /// (floats 32·pair ..).
    const fn pair_lanes(s: usize) -> [[u16; 4]; 8] {
        let mut table = [[0u16; 4]; 8];
        let mut c = 0;
        while c < 8 {
            let mut i = 0;
            while i < 16 {
                let pair = (s * i + c) / 32;
                if pair < 4 {
                    table[c][pair] |= 1 << i;
                }
                i += 1;
            }
            c += 1;
        }
        table
    }
    let lanes = const { pair_lanes(S) };
    // SAFETY: the loads read floats 0 .. 16·S of `base`, 16 records of S floats.
    unsafe {
        let mut v = [_mm512_setzero_ps(); 8];
        for (j, v) in v.iter_mut().enumerate().take(S) {
            *v = _mm512_loadu_ps(base.add(16 * j));
        }
        let iota = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
        let float = _mm512_mullo_epi32(iota, _mm512_set1_epi32(S as i32));
        let mut out = [_mm512_setzero_ps(); K];
        for (c, out) in out.iter_mut().enumerate() {
            // Index within a pair of vectors: the float's position modulo 32.
            let index = _mm512_and_si512(
                _mm512_add_epi32(float, _mm512_set1_epi32(c as i32)),
                _mm512_set1_epi32(31),
            );
            let mut acc = _mm512_setzero_ps();
            for pair in 0..S.div_ceil(2) {
                let (a, b) = (v[2 * pair], v[(2 * pair + 1).min(7)]);
                let picked = _mm512_permutex2var_ps(a, index, b);
                acc = _mm512_mask_mov_ps(acc, lanes[c][pair], picked);
            }
            *out = acc;
        }
        out
    }
}

/// [`gather8`] for a full packet (`len` = 8) of records of `S` floats (`4 ≤ K ≤ S ≤ 8`), read
/// with sixteen 128-bit loads and rearranged in registers: AVX2's gathers read each lane from
/// memory one at a time, slowly on AMD's cores.
///
/// Register `i` (`i < 4`) holds floats `0..4` of record `i` in its low half and of record
/// `i + 4` in its high half (`a`), likewise floats `S − 4 .. S` (`b`); a 4 × 4 transpose in
/// each half then gives floats `0..4` and `S − 4 .. S` with record `i` in lane `i`.
///
/// # Safety
/// AVX2; `base` points to 8 records of `S` floats.
#[inline(always)]
unsafe fn transpose8<const S: usize, const K: usize>(base: *const f32) -> [__m256; K] {
    const { assert!(4 <= K && K <= S && S <= 8) };
    /// Rows `0..4` of the four registers' 4 × 4 blocks, transposed in each half.
    #[inline(always)]
    unsafe fn transpose4(r: [__m256; 4]) -> [__m256; 4] {
        // SAFETY: AVX (the caller's).
        unsafe {
            let t0 = _mm256_unpacklo_ps(r[0], r[1]);
            let t1 = _mm256_unpacklo_ps(r[2], r[3]);
            let t2 = _mm256_unpackhi_ps(r[0], r[1]);
            let t3 = _mm256_unpackhi_ps(r[2], r[3]);
            [
                _mm256_shuffle_ps::<0b01_00_01_00>(t0, t1),
                _mm256_shuffle_ps::<0b11_10_11_10>(t0, t1),
                _mm256_shuffle_ps::<0b01_00_01_00>(t2, t3),
                _mm256_shuffle_ps::<0b11_10_11_10>(t2, t3),
            ]
        }
    }
    // SAFETY: the loads read floats S·i + c for records i < 8 and c < S, 8 records of S floats.
    unsafe {
        let (mut a, mut b) = ([_mm256_setzero_ps(); 4], [_mm256_setzero_ps(); 4]);
        for (i, (a, b)) in a.iter_mut().zip(&mut b).enumerate() {
            let (low, high) = (base.add(S * i), base.add(S * (i + 4)));
            *a = _mm256_loadu2_m128(high, low);
            *b = _mm256_loadu2_m128(high.add(S - 4), low.add(S - 4));
        }
        let (a, b) = (transpose4(a), transpose4(b));
        let mut out = [_mm256_setzero_ps(); K];
        for (c, out) in out.iter_mut().enumerate() {
            *out = if c < 4 { a[c] } else { b[c + 4 - S] };
        }
        out
    }
}

/// [`gather16`] for eight lanes.
///
/// # Safety
/// AVX2; `base` points to `len` (1 to 8) records of `stride ≥ K` floats.
#[inline(always)]
pub(super) unsafe fn gather8<const K: usize>(
    base: *const f32,
    stride: i32,
    len: usize,
) -> [__m256; K] {
    // SAFETY: every index gathered is stride·i + c for a record i < len and c < K ≤ stride.
    unsafe {
        let lane = _mm256_min_epi32(
            _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
            _mm256_set1_epi32(len as i32 - 1),
        );
        let lane = _mm256_mullo_epi32(lane, _mm256_set1_epi32(stride));
        let mut out = [_mm256_setzero_ps(); K];
        for (c, out) in out.iter_mut().enumerate() {
            let index = _mm256_add_epi32(lane, _mm256_set1_epi32(c as i32));
            *out = _mm256_i32gather_ps::<4>(base, index);
        }
        out
    }
}

impl InstructionSet for Avx512 {
    const WIDTH: usize = 16;
    type F = Avx512F32;
    type U = __m512i;
    type Mask = Avx512Mask;
    type Tree = Avx2;

    #[inline(always)]
    fn tree(self) -> Avx2 {
        self.avx2()
    }

    #[inline(always)]
    fn call<F: Compiled>(self, f: F) -> F::Output {
        compiled!(Avx512: #[inline] fn compiled<F: Compiled>(k: Avx512, f: F) -> F::Output {
            f.run(k)
        });
        // SAFETY: an `Avx512` value exists only on a CPU that runs the features.
        unsafe { compiled(self, f) }
    }

    #[inline(always)]
    fn rays(self, rays: &[Ray]) -> [Avx512F32; 6] {
        debug_assert!(!rays.is_empty() && rays.len() <= Self::WIDTH);
        // SAFETY: AVX-512 F; `rays` holds rays.len() records of RAY_FLOATS floats.
        let v = unsafe {
            if rays.len() == 16 {
                transpose16::<{ RAY_FLOATS as usize }, 6>(rays.as_ptr().cast())
            } else {
                gather16(rays.as_ptr().cast(), RAY_FLOATS, rays.len())
            }
        };
        v.map(Avx512F32)
    }

    #[inline(always)]
    fn segments(self, segments: &[(Ray, f32)]) -> [Avx512F32; 7] {
        debug_assert!(!segments.is_empty() && segments.len() <= Self::WIDTH);
        // SAFETY: AVX-512 F; `segments` holds segments.len() records of SEGMENT_FLOATS floats.
        let v = unsafe {
            if segments.len() == 16 {
                transpose16::<{ SEGMENT_FLOATS as usize }, 7>(segments.as_ptr().cast())
            } else {
                gather16(segments.as_ptr().cast(), SEGMENT_FLOATS, segments.len())
            }
        };
        v.map(Avx512F32)
    }

    #[inline(always)]
    fn load(self, a: &[f32; MAX_WIDTH]) -> Avx512F32 {
        Avx512F32::load(a)
    }
    #[inline(always)]
    fn load_lanes<const N: usize>(self, a: &[f32; N]) -> Avx512F32 {
        Avx512F32::load(a.first_chunk().expect("at least sixteen floats"))
    }
    #[inline(always)]
    fn lane(self, v: Avx512F32, i: usize) -> f32 {
        // SAFETY: AVX-512 F.
        unsafe { _mm512_cvtss_f32(_mm512_permutexvar_ps(_mm512_set1_epi32(i as i32), v.0)) }
    }
    #[inline(always)]
    fn lane_u32(self, v: __m512i, i: usize) -> u32 {
        // SAFETY: AVX-512 F.
        unsafe {
            let v = _mm512_permutexvar_epi32(_mm512_set1_epi32(i as i32), v);
            _mm_cvtsi128_si32(_mm512_castsi512_si128(v)) as u32
        }
    }
    #[inline(always)]
    fn store(self, a: &mut [f32; MAX_WIDTH], v: Avx512F32) {
        // SAFETY: AVX-512 F; `a` is sixteen writable f32.
        unsafe { _mm512_storeu_ps(a.as_mut_ptr(), v.0) }
    }
    #[inline(always)]
    fn plane_distance(
        self,
        plane: Avx512F32,
        _origin: Avx512F32,
        inv: Avx512F32,
        origin_inv: Avx512F32,
    ) -> Avx512F32 {
        // SAFETY: AVX-512 F.
        Avx512F32(unsafe { _mm512_fmsub_ps(plane.0, inv.0, origin_inv.0) })
    }

    #[inline(always)]
    fn min_of(self, m: Avx512Mask, v: Avx512F32) -> f32 {
        // SAFETY: AVX-512 F.
        unsafe { _mm512_mask_reduce_min_ps(m.0, v.0) }
    }

    #[inline(always)]
    fn splat_u32(self, x: u32) -> __m512i {
        // SAFETY: AVX-512 F.
        unsafe { _mm512_set1_epi32(x as i32) }
    }
    #[inline(always)]
    fn load_u32(self, a: &[u32; MAX_WIDTH]) -> __m512i {
        // SAFETY: AVX-512 F; `a` is sixteen readable u32.
        unsafe { _mm512_loadu_si512(a.as_ptr().cast()) }
    }
    #[inline(always)]
    fn store_u32(self, a: &mut [u32; MAX_WIDTH], v: __m512i) {
        // SAFETY: AVX-512 F; `a` is sixteen writable u32.
        unsafe { _mm512_storeu_si512(a.as_mut_ptr().cast(), v) }
    }
    #[inline(always)]
    fn lt_u32(self, a: __m512i, b: __m512i) -> Avx512Mask {
        // SAFETY: AVX-512 F.
        Avx512Mask(unsafe { _mm512_cmplt_epu32_mask(a, b) })
    }
    #[inline(always)]
    fn blend_u32(self, m: Avx512Mask, a: __m512i, b: __m512i) -> __m512i {
        // SAFETY: AVX-512 F.
        unsafe { _mm512_mask_blend_epi32(m.0, a, b) }
    }
}

impl InstructionSet for Avx2 {
    const WIDTH: usize = 8;
    type F = Avx2F32;
    type U = __m256i;
    type Mask = Avx2Mask;
    type Tree = Avx2;

    #[inline(always)]
    fn tree(self) -> Avx2 {
        self
    }

    #[inline(always)]
    fn call<F: Compiled>(self, f: F) -> F::Output {
        compiled!(Avx2: #[inline] fn compiled<F: Compiled>(k: Avx2, f: F) -> F::Output {
            f.run(k)
        });
        // SAFETY: an `Avx2` value exists only on a CPU that runs the features.
        unsafe { compiled(self, f) }
    }

    #[inline(always)]
    fn rays(self, rays: &[Ray]) -> [Avx2F32; 6] {
        debug_assert!(!rays.is_empty() && rays.len() <= Self::WIDTH);
        // SAFETY: AVX2; `rays` holds rays.len() records of RAY_FLOATS floats.
        let v = unsafe {
            if rays.len() == 8 {
                transpose8::<{ RAY_FLOATS as usize }, 6>(rays.as_ptr().cast())
            } else {
                gather8(rays.as_ptr().cast(), RAY_FLOATS, rays.len())
            }
        };
        v.map(Avx2F32)
    }

    #[inline(always)]
    fn segments(self, segments: &[(Ray, f32)]) -> [Avx2F32; 7] {
        debug_assert!(!segments.is_empty() && segments.len() <= Self::WIDTH);
        // SAFETY: AVX2; `segments` holds segments.len() records of SEGMENT_FLOATS floats.
        let v = unsafe {
            if segments.len() == 8 {
                transpose8::<{ SEGMENT_FLOATS as usize }, 7>(segments.as_ptr().cast())
            } else {
                gather8(segments.as_ptr().cast(), SEGMENT_FLOATS, segments.len())
            }
        };
        v.map(Avx2F32)
    }

    #[inline(always)]
    fn load(self, a: &[f32; MAX_WIDTH]) -> Avx2F32 {
        Avx2F32::load(a.first_chunk().expect("sixteen floats hold eight"))
    }
    #[inline(always)]
    fn load_lanes<const N: usize>(self, a: &[f32; N]) -> Avx2F32 {
        Avx2F32::load(a.first_chunk().expect("at least eight floats"))
    }
    #[inline(always)]
    fn lane(self, v: Avx2F32, i: usize) -> f32 {
        // SAFETY: AVX2.
        unsafe { _mm256_cvtss_f32(_mm256_permutevar8x32_ps(v.0, _mm256_set1_epi32(i as i32))) }
    }
    #[inline(always)]
    fn lane_u32(self, v: __m256i, i: usize) -> u32 {
        // SAFETY: AVX2.
        unsafe {
            let v = _mm256_permutevar8x32_epi32(v, _mm256_set1_epi32(i as i32));
            _mm_cvtsi128_si32(_mm256_castsi256_si128(v)) as u32
        }
    }
    #[inline(always)]
    fn store(self, a: &mut [f32; MAX_WIDTH], v: Avx2F32) {
        // SAFETY: AVX; `a` holds at least eight writable f32.
        unsafe { _mm256_storeu_ps(a.as_mut_ptr(), v.0) }
    }
    #[inline(always)]
    fn plane_distance(
        self,
        plane: Avx2F32,
        _origin: Avx2F32,
        inv: Avx2F32,
        origin_inv: Avx2F32,
    ) -> Avx2F32 {
        // SAFETY: FMA.
        Avx2F32(unsafe { _mm256_fmsub_ps(plane.0, inv.0, origin_inv.0) })
    }

    #[inline(always)]
    fn min_of(self, m: Avx2Mask, v: Avx2F32) -> f32 {
        // SAFETY: AVX.
        unsafe {
            let v = _mm256_blendv_ps(_mm256_set1_ps(f32::INFINITY), v.0, m.0);
            let v = _mm256_min_ps(v, _mm256_permute2f128_ps::<1>(v, v));
            let v = _mm256_min_ps(v, _mm256_permute_ps::<0b01_00_11_10>(v));
            let v = _mm256_min_ps(v, _mm256_permute_ps::<0b10_11_00_01>(v));
            _mm256_cvtss_f32(v)
        }
    }

    #[inline(always)]
    fn splat_u32(self, x: u32) -> __m256i {
        // SAFETY: AVX.
        unsafe { _mm256_set1_epi32(x as i32) }
    }
    #[inline(always)]
    fn load_u32(self, a: &[u32; MAX_WIDTH]) -> __m256i {
        // SAFETY: AVX; `a` holds at least eight readable u32.
        unsafe { _mm256_loadu_si256(a.as_ptr().cast()) }
    }
    #[inline(always)]
    fn store_u32(self, a: &mut [u32; MAX_WIDTH], v: __m256i) {
        // SAFETY: AVX; `a` holds at least eight writable u32.
        unsafe { _mm256_storeu_si256(a.as_mut_ptr().cast(), v) }
    }
    #[inline(always)]
    fn lt_u32(self, a: __m256i, b: __m256i) -> Avx2Mask {
        // AVX2 compares signed only: flipping both sign bits orders u32 as i32.
        // SAFETY: AVX2.
        unsafe {
            let flip = _mm256_set1_epi32(i32::MIN);
            let lt = _mm256_cmpgt_epi32(_mm256_xor_si256(b, flip), _mm256_xor_si256(a, flip));
            Avx2Mask(_mm256_castsi256_ps(lt))
        }
    }
    #[inline(always)]
    fn blend_u32(self, m: Avx2Mask, a: __m256i, b: __m256i) -> __m256i {
        // SAFETY: AVX.
        unsafe {
            _mm256_castps_si256(_mm256_blendv_ps(
                _mm256_castsi256_ps(a),
                _mm256_castsi256_ps(b),
                m.0,
            ))
        }
    }
}

compiled!(Avx512:
/// [`super::lane_io::table_lanes`] with AVX-512's `vpermt2ps`.
#[inline]
pub(super) fn permute_avx512(table: &[f32; 32], index: &[u32; 16], lanes: u16) -> [f32; 16] {
    // SAFETY: the loads read `table`'s 128 bytes and `index`'s 64, unaligned.
    unsafe {
        let low = _mm512_loadu_ps(table.as_ptr());
        let high = _mm512_loadu_ps(table.as_ptr().add(16));
        let index = _mm512_loadu_si512(index.as_ptr().cast());
        let values = _mm512_maskz_permutex2var_ps(lanes, low, index, high);
        std::mem::transmute::<__m512, [f32; 16]>(values)
    }
});

compiled!(Avx512:
/// [`super::lane_io::store_vec3s`] with AVX-512. Float `f` of the output (`16k + p` of its
/// vector `k`) is component `f % 3` of vector `f / 3`: the first permute of each output vector
/// picks the `x` and `y` components from those two inputs, the second keeps them and picks `z`.
#[inline]
pub(super) fn store_vec3s_avx512(
    x: &[f32; 16],
    y: &[f32; 16],
    z: &[f32; 16],
    out: &mut [Vec3; 16],
) {
    /// For output vector `k`: the indices into (x, y), then into (that, z).
    const fn picks(k: usize) -> ([i32; 16], [i32; 16]) {
        let (mut xy, mut then_z) = ([0; 16], [0; 16]);
        let mut p = 0;
        while p < 16 {
            let f = 16 * k + p;
            let (vector, component) = ((f / 3) as i32, f % 3);
            xy[p] = if component == 1 { 16 + vector } else { vector };
            then_z[p] = if component == 2 {
                16 + vector
            } else {
                p as i32
            };
            p += 1;
        }
        (xy, then_z)
    }
    const PICKS: [([i32; 16], [i32; 16]); 3] = [picks(0), picks(1), picks(2)];
    // SAFETY: the loads read the three inputs' 64 bytes each and the index tables; the stores
    // write `out`'s 192 bytes (sixteen `Vec3`s of three `f32`, `repr(C)`), unaligned.
    unsafe {
        let (x, y, z) = (
            _mm512_loadu_ps(x.as_ptr()),
            _mm512_loadu_ps(y.as_ptr()),
            _mm512_loadu_ps(z.as_ptr()),
        );
        let base = out.as_mut_ptr().cast::<f32>();
        for (k, (xy, then_z)) in PICKS.iter().enumerate() {
            let xy = _mm512_permutex2var_ps(x, _mm512_loadu_si512(xy.as_ptr().cast()), y);
            let v = _mm512_permutex2var_ps(xy, _mm512_loadu_si512(then_z.as_ptr().cast()), z);
            _mm512_storeu_ps(base.add(16 * k), v);
        }
    }
});

compiled!(Avx2:
/// [`super::lane_io::table_lanes`] with AVX2: each eight lanes pick from the table's four
/// registers of eight with one `vpermps` each (the index's low three bits), and two blends
/// choose among the four by the index's bits 3 and 4 (shifted into the sign bit, which
/// `vblendvps` reads).
#[inline]
pub(super) fn permute_avx2(table: &[f32; 32], index: &[u32; 16], lanes: u16) -> [f32; 16] {
    let mut out = [0.0f32; 16];
    // SAFETY: the loads read `table`'s 128 bytes and `index`'s 64, the stores write `out`'s 64,
    // unaligned.
    unsafe {
        let at = table.as_ptr();
        let t = [
            _mm256_loadu_ps(at),
            _mm256_loadu_ps(at.add(8)),
            _mm256_loadu_ps(at.add(16)),
            _mm256_loadu_ps(at.add(24)),
        ];
        let bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
        for half in 0..2 {
            let index = _mm256_loadu_si256(index.as_ptr().add(8 * half).cast());
            let bit3 = _mm256_castsi256_ps(_mm256_slli_epi32::<28>(index));
            let bit4 = _mm256_castsi256_ps(_mm256_slli_epi32::<27>(index));
            let low = _mm256_blendv_ps(
                _mm256_permutevar8x32_ps(t[0], index),
                _mm256_permutevar8x32_ps(t[1], index),
                bit3,
            );
            let high = _mm256_blendv_ps(
                _mm256_permutevar8x32_ps(t[2], index),
                _mm256_permutevar8x32_ps(t[3], index),
                bit3,
            );
            let value = _mm256_blendv_ps(low, high, bit4);
            let on = _mm256_and_si256(_mm256_set1_epi32(i32::from(lanes >> (8 * half))), bit);
            let on = _mm256_castsi256_ps(_mm256_cmpeq_epi32(on, bit));
            _mm256_storeu_ps(out.as_mut_ptr().add(8 * half), _mm256_and_ps(value, on));
        }
    }
    out
});

compiled!(Avx2:
/// [`super::lane_io::ray_lanes`] with AVX2, for sixteen rays: [`InstructionSet::rays`]'s loads
/// for each eight.
#[inline]
pub(super) fn rays16_avx2(k: Avx2, rays: &[Ray; 16]) -> [[f32; 16]; 6] {
    let mut out = [[0.0; 16]; 6];
    for (half, rays) in rays.chunks_exact(8).enumerate() {
        for (out, v) in out.iter_mut().zip(k.rays(rays)) {
            // SAFETY: AVX; `out` holds sixteen writable f32, eight from 8·half.
            unsafe { _mm256_storeu_ps(out.as_mut_ptr().add(8 * half), v.0) }
        }
    }
    out
});

compiled!(Avx2:
/// [`super::lane_io::store_vec3s`] with AVX2: each eight vectors are three registers, made of
/// the lanes by six in-half shuffles and three half swaps.
#[inline]
pub(super) fn store_vec3s_avx2(x: &[f32; 16], y: &[f32; 16], z: &[f32; 16], out: &mut [Vec3; 16]) {
    // SAFETY: the loads read the three inputs' 64 bytes each; the stores write `out`'s 192
    // bytes (sixteen `Vec3`s of three `f32`, `repr(C)`), unaligned.
    unsafe {
        let base = out.as_mut_ptr().cast::<f32>();
        for half in 0..2 {
            let (x, y, z) = (
                _mm256_loadu_ps(x.as_ptr().add(8 * half)),
                _mm256_loadu_ps(y.as_ptr().add(8 * half)),
                _mm256_loadu_ps(z.as_ptr().add(8 * half)),
            );
            // In each half of four vectors a, b, c, d (the second half: e, f, g, h):
            let xy = _mm256_shuffle_ps::<0b10_00_10_00>(x, y); // xa xc ya yc
            let yz = _mm256_shuffle_ps::<0b11_01_11_01>(y, z); // yb yd zb zd
            let zx = _mm256_shuffle_ps::<0b11_01_10_00>(z, x); // za zc xb xd
            let a = _mm256_shuffle_ps::<0b10_00_10_00>(xy, zx); // xa ya za xb
            let b = _mm256_shuffle_ps::<0b11_01_10_00>(yz, xy); // yb zb xc yc
            let c = _mm256_shuffle_ps::<0b11_01_11_01>(zx, yz); // zc xd yd zd
            let at = base.add(24 * half);
            _mm256_storeu_ps(at, _mm256_permute2f128_ps::<0x20>(a, b));
            _mm256_storeu_ps(at.add(8), _mm256_permute2f128_ps::<0x30>(c, a));
            _mm256_storeu_ps(at.add(16), _mm256_permute2f128_ps::<0x31>(b, c));
        }
    }
});

/// Four lanes for the portable set ([`super::portable`]): an SSE register (SSE and SSE2 are
/// part of x86-64). Comparisons give masks of the
/// same type (all ones in a lane that is true), as SSE does.
pub(super) mod quad {
    use std::arch::x86_64::*;

    #[derive(Clone, Copy, Debug)]
    #[repr(transparent)]
    pub struct Q(__m128);

    /// `$e`, an SSE or SSE2 intrinsic.
    macro_rules! sse {
        ($e:expr) => {
            // SAFETY: SSE and SSE2 are part of x86-64: every x86-64 CPU runs them.
            unsafe { $e }
        };
    }

    impl Q {
        // SAFETY: four u32 are the sixteen bytes of a register.
        pub const ZERO: Q = Q(unsafe { std::mem::transmute::<[u32; 4], __m128>([0; 4]) });
        // SAFETY: as above.
        pub const ONES: Q = Q(unsafe { std::mem::transmute::<[u32; 4], __m128>([!0; 4]) });

        #[inline(always)]
        pub fn splat(x: f32) -> Q {
            Q(sse!(_mm_set1_ps(x)))
        }
        #[inline(always)]
        pub fn splat_u32(x: u32) -> Q {
            Q(sse!(_mm_castsi128_ps(_mm_set1_epi32(x as i32))))
        }
        #[inline(always)]
        pub fn load(a: &[f32; 4]) -> Q {
            // SAFETY: `a` is four readable f32 (SSE, as above).
            Q(unsafe { _mm_loadu_ps(a.as_ptr()) })
        }
        #[inline(always)]
        pub fn store(self, a: &mut [f32; 4]) {
            // SAFETY: `a` is four writable f32 (SSE, as above).
            unsafe { _mm_storeu_ps(a.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        pub fn to_array(self) -> [f32; 4] {
            let mut a = [0.0; 4];
            self.store(&mut a);
            a
        }
        #[inline(always)]
        pub fn add(self, o: Q) -> Q {
            Q(sse!(_mm_add_ps(self.0, o.0)))
        }
        #[inline(always)]
        pub fn sub(self, o: Q) -> Q {
            Q(sse!(_mm_sub_ps(self.0, o.0)))
        }
        #[inline(always)]
        pub fn mul(self, o: Q) -> Q {
            Q(sse!(_mm_mul_ps(self.0, o.0)))
        }
        #[inline(always)]
        pub fn div(self, o: Q) -> Q {
            Q(sse!(_mm_div_ps(self.0, o.0)))
        }
        #[inline(always)]
        pub fn sqrt(self) -> Q {
            Q(sse!(_mm_sqrt_ps(self.0)))
        }
        /// `self > o ? self : o` lane by lane (`o` where either is NaN).
        #[inline(always)]
        pub fn max(self, o: Q) -> Q {
            Q(sse!(_mm_max_ps(self.0, o.0)))
        }
        /// `self < o ? self : o` lane by lane (`o` where either is NaN).
        #[inline(always)]
        pub fn min(self, o: Q) -> Q {
            Q(sse!(_mm_min_ps(self.0, o.0)))
        }
        #[inline(always)]
        pub fn and(self, o: Q) -> Q {
            Q(sse!(_mm_and_ps(self.0, o.0)))
        }
        #[inline(always)]
        pub fn or(self, o: Q) -> Q {
            Q(sse!(_mm_or_ps(self.0, o.0)))
        }
        #[inline(always)]
        pub fn xor(self, o: Q) -> Q {
            Q(sse!(_mm_xor_ps(self.0, o.0)))
        }
        /// `!self & o`, bit by bit.
        #[inline(always)]
        pub fn andnot(self, o: Q) -> Q {
            Q(sse!(_mm_andnot_ps(self.0, o.0)))
        }
        #[inline(always)]
        pub fn eq(self, o: Q) -> Q {
            Q(sse!(_mm_cmpeq_ps(self.0, o.0)))
        }
        #[inline(always)]
        pub fn ne(self, o: Q) -> Q {
            Q(sse!(_mm_cmpneq_ps(self.0, o.0)))
        }
        #[inline(always)]
        pub fn lt(self, o: Q) -> Q {
            Q(sse!(_mm_cmplt_ps(self.0, o.0)))
        }
        #[inline(always)]
        pub fn le(self, o: Q) -> Q {
            Q(sse!(_mm_cmple_ps(self.0, o.0)))
        }
        #[inline(always)]
        pub fn gt(self, o: Q) -> Q {
            Q(sse!(_mm_cmpgt_ps(self.0, o.0)))
        }
        #[inline(always)]
        pub fn ge(self, o: Q) -> Q {
            Q(sse!(_mm_cmpge_ps(self.0, o.0)))
        }
        /// `!(self > o)`: true where either is NaN.
        #[inline(always)]
        pub fn ngt(self, o: Q) -> Q {
            Q(sse!(_mm_cmpngt_ps(self.0, o.0)))
        }
        /// Lane `i`'s sign bit as bit `i`.
        #[inline(always)]
        pub fn bits(self) -> u32 {
            sse!(_mm_movemask_ps(self.0)) as u32
        }
        /// Bit `i` of `bits` as lane `i`, all ones or all zeros.
        #[inline(always)]
        pub fn from_bits(bits: u32) -> Q {
            sse!({
                let lane_bit = _mm_setr_epi32(1, 2, 4, 8);
                let set = _mm_and_si128(_mm_set1_epi32(bits as i32), lane_bit);
                Q(_mm_castsi128_ps(_mm_cmpeq_epi32(set, lane_bit)))
            })
        }
        /// `self < o` as unsigned 32-bit integers.
        #[inline(always)]
        pub fn lt_u32(self, o: Q) -> Q {
            // SSE2 compares signed only: flipping both sign bits orders u32 as i32.
            sse!({
                let flip = _mm_set1_epi32(i32::MIN);
                let a = _mm_xor_si128(_mm_castps_si128(self.0), flip);
                let b = _mm_xor_si128(_mm_castps_si128(o.0), flip);
                Q(_mm_castsi128_ps(_mm_cmplt_epi32(a, b)))
            })
        }
        /// The least lane (by [`Q::min`], in a fixed order).
        #[inline(always)]
        pub fn least(self) -> f32 {
            sse!({
                let m = _mm_min_ps(self.0, _mm_movehl_ps(self.0, self.0));
                let m = _mm_min_ps(m, _mm_shuffle_ps::<0b01>(m, m));
                _mm_cvtss_f32(m)
            })
        }
    }
}

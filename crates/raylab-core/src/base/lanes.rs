//! Lanes: one formula for one value or for sixteen at once.
//!
//! The per-hit formulas (the light at a hit, [`crate::shading::light::DirectLight`]; its shadow ray,
//! [`crate::shading::light::shadow_rays_to`]; both together, [`crate::transport::integrator::Lighting`]) are
//! written once, generic over a [`Vector`]: [`glam::Vec3`] for one hit, [`Vec3x16`] for
//! sixteen side by side (structure of arrays). The scalar API is that generic code at `Vec3`,
//! so the readable form and the fast one cannot drift apart.
//!
//! Why: one hit's terms are a chain of dependent divisions and square roots (about nine
//! divisions and two square roots a pixel in the lab's stage) that the processor runs one at a
//! time; sixteen hits' take the same instructions, sixteen lanes wide. [`F32x16`]'s operations
//! are plain loops over its lanes, which LLVM turns into vector instructions of whatever width
//! the surrounding code is compiled for (one AVX-512 register, two AVX ones, four SSE ones).
//!
//! **Bit for bit.** A lane does exactly what the scalar code does, operation by operation:
//! Rust never fuses a multiply and an add, vector division and square root are exactly rounded
//! like scalar ones, no approximate reciprocal is used, and [`Vector`]'s methods keep glam's
//! order of operations (`dot` is `(x·x′ + y·y′) + z·z′`, `s * v` multiplies each component
//! by `s`). Where the scalar code
//! branches, both sides are computed and [`Real::select`] picks each lane's: the same bits.
//! The tests compare the two on many inputs.

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

use glam::Vec3;

/// How many values a [`F32x16`] holds.
pub const LANES: usize = 16;

/// A comparison's answer, per lane: `bool` for one value, [`M16`] for sixteen.
pub trait Mask:
    Copy
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + Not<Output = Self>
    + std::fmt::Debug
    + PartialEq
{
    /// False in every lane.
    const NONE: Self;
    fn splat(b: bool) -> Self;
    /// Whether any lane is true.
    fn any(self) -> bool;
    /// Lane `i`'s answer as bit `i`.
    fn bitmask(self) -> u32;
    /// Bit `i` as lane `i`'s answer (bits past the last lane are ignored).
    fn from_bitmask(bits: u32) -> Self;
}

/// A number, or sixteen: `f32` or [`F32x16`]. Every operation is the `f32` one, lane by lane.
pub trait Real:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + std::fmt::Debug
    + PartialEq
{
    type Mask: Mask;
    const ZERO: Self;
    fn splat(x: f32) -> Self;
    fn sqrt(self) -> Self;
    /// `f32::max` (a NaN gives the other value).
    fn simd_max(self, other: Self) -> Self;
    /// `f32::min` (a NaN gives the other value).
    fn simd_min(self, other: Self) -> Self;
    /// `f32::copysign`: the magnitude of `self` with the sign of `sign`.
    fn copysign(self, sign: Self) -> Self;
    /// `f32::abs`: the sign bit cleared.
    fn abs(self) -> Self;
    /// The maximum instruction's: `self` where `self > other`, else `other` (so `other` where
    /// either is NaN, unlike [`Real::simd_max`]).
    #[inline(always)]
    fn max_or_other(self, other: Self) -> Self {
        Self::select(self.simd_gt(other), self, other)
    }
    /// The minimum instruction's: `self` where `self < other`, else `other`.
    #[inline(always)]
    fn min_or_other(self, other: Self) -> Self {
        Self::select(self.simd_lt(other), self, other)
    }
    /// `==`: false for a NaN.
    #[inline(always)]
    fn simd_eq(self, other: Self) -> Self::Mask {
        !self.simd_ne(other)
    }
    /// `!(self > other)`: true for a NaN.
    #[inline(always)]
    fn simd_ngt(self, other: Self) -> Self::Mask {
        !self.simd_gt(other)
    }
    fn simd_lt(self, other: Self) -> Self::Mask;
    fn simd_le(self, other: Self) -> Self::Mask;
    fn simd_gt(self, other: Self) -> Self::Mask;
    fn simd_ge(self, other: Self) -> Self::Mask;
    /// `!=`: true for a NaN.
    fn simd_ne(self, other: Self) -> Self::Mask;
    /// `a` where `mask` is true, else `b`: a branch of the scalar code, taken lane by lane.
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self;

    /// Whether this is one value (`f32`): [`select_lazy!`] then computes only the side taken.
    const ONE: bool;
}

/// [`Real::select`] or [`Vector::select`] of two sides — `select_lazy!(Real: T, mask, a, b)`
/// or `select_lazy!(Vector: T, mask, a, b)` — computing only the side taken when `T` is one
/// value, as the scalar code's branch did (computing both would slow the path stage, a hit at
/// a time), and both sides for sixteen lanes, each lane taking its own. The same bits either
/// way: the sides are plain arithmetic. A macro, not closures: a closure too large to inline
/// is compiled without the caller's instruction set (the sixteen-lane sides would run as SSE
/// code; PERFORMANCE.md, "Design choices and what each buys": phase batching).
macro_rules! select_lazy {
    (Real: $t:ty, $mask:expr, $a:expr, $b:expr) => {{
        let mask = $mask;
        if <$t as $crate::base::lanes::Real>::ONE {
            if $crate::base::lanes::Mask::any(mask) {
                $a
            } else {
                $b
            }
        } else {
            <$t as $crate::base::lanes::Real>::select(mask, $a, $b)
        }
    }};
    (Vector: $t:ty, $mask:expr, $a:expr, $b:expr) => {{
        let mask = $mask;
        if <<$t as $crate::base::lanes::Vector>::Real as $crate::base::lanes::Real>::ONE {
            if $crate::base::lanes::Mask::any(mask) {
                $a
            } else {
                $b
            }
        } else {
            <$t as $crate::base::lanes::Vector>::select(mask, $a, $b)
        }
    }};
}
pub(crate) use select_lazy;

/// A function compiled for one instruction set: `compiled!(Avx512: fn …)`,
/// `compiled!(Avx2: fn …)` or `compiled!(Portable: fn …)`, the set named as its proof type
/// (`accel::simd::Avx512`, `Avx2`: a value exists only on a CPU that runs the set) or the
/// portable set every CPU of the architecture runs. The one place that says which features each
/// set enables: the generic code that inlines into the function (the lanes' operations, the
/// kernels, the packet traversal) is compiled with them, so one source serves every set.
///
/// A function for every set is not written with it three times: it is written once as an
/// `accel::set::Compiled` and entered through `Isa::call` (or a proof's
/// `InstructionSet::call`), whose one function per set is made here. This form is for code
/// that exists for one set only (AVX-512's lane permutes).
///
/// `Avx512` and `Avx2` functions exist only on x86-64, and calling one is `unsafe` where the
/// caller is not compiled with the set: its caller holds the proof value (or checks as
/// `detect` does) and says so in a `// SAFETY:` comment. `Portable` functions are ordinary ones.
/// AVX-512 is F, DQ and VL with AVX2 and FMA, what `Avx512::detect` checks; AVX2 is AVX2 and
/// FMA, what `Avx2::detect` checks. Rust never fuses a multiply and an add on its own, so the
/// sets give the same bits (see the module docs).
macro_rules! compiled {
    (Avx512: $(#[$attr:meta])* $vis:vis fn $($rest:tt)*) => {
        $(#[$attr])*
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2,fma")]
        $vis fn $($rest)*
    };
    (Avx2: $(#[$attr:meta])* $vis:vis fn $($rest:tt)*) => {
        $(#[$attr])*
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2,fma")]
        $vis fn $($rest)*
    };
    (Portable: $(#[$attr:meta])* $vis:vis fn $($rest:tt)*) => {
        $(#[$attr])*
        $vis fn $($rest)*
    };
}
pub(crate) use compiled;

/// The mask type of a [`Vector`]'s lanes.
pub type MaskOf<V> = <<V as Vector>::Real as Real>::Mask;

/// A 3-vector, or sixteen: [`glam::Vec3`] or [`Vec3x16`]. Generic code names its numbers
/// `V::Real`, so a call with `Vec3` arguments needs no annotation.
pub trait Vector:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Mul<Self::Real, Output = Self>
    + Div<Self::Real, Output = Self>
    + std::fmt::Debug
    + PartialEq
{
    type Real: Real;
    const ZERO: Self;
    /// `v` in every lane.
    fn splat(v: Vec3) -> Self;
    fn new(x: Self::Real, y: Self::Real, z: Self::Real) -> Self;
    fn x(self) -> Self::Real;
    fn y(self) -> Self::Real;
    fn z(self) -> Self::Real;

    /// `s · v`, the number on the left (glam's `f32 * Vec3`).
    #[inline(always)]
    fn scale(s: Self::Real, v: Self) -> Self {
        Self::new(s * v.x(), s * v.y(), s * v.z())
    }

    /// glam's `dot`: `(x·x′ + y·y′) + z·z′`.
    #[inline(always)]
    fn dot(self, o: Self) -> Self::Real {
        self.x() * o.x() + self.y() * o.y() + self.z() * o.z()
    }

    /// glam's `cross`: `(y·z′ − y′·z, z·x′ − z′·x, x·y′ − x′·y)`.
    #[inline(always)]
    fn cross(self, o: Self) -> Self {
        Self::new(
            self.y() * o.z() - o.y() * self.z(),
            self.z() * o.x() - o.z() * self.x(),
            self.x() * o.y() - o.x() * self.y(),
        )
    }

    #[inline(always)]
    fn length_squared(self) -> Self::Real {
        self.dot(self)
    }

    #[inline(always)]
    fn length(self) -> Self::Real {
        self.dot(self).sqrt()
    }

    /// glam's `max_element`: `max(x, max(y, z))`, where `max(a, b)` is `a` if `a > b`, else `b`.
    #[inline(always)]
    fn max_element(self) -> Self::Real {
        let (x, y, z) = (self.x(), self.y(), self.z());
        let yz = Self::Real::select(y.simd_gt(z), y, z);
        Self::Real::select(x.simd_gt(yz), x, yz)
    }

    /// `!=`: whether any component differs (glam's `PartialEq`, negated).
    #[inline(always)]
    fn simd_ne(self, o: Self) -> MaskOf<Self> {
        self.x().simd_ne(o.x()) | self.y().simd_ne(o.y()) | self.z().simd_ne(o.z())
    }

    #[inline(always)]
    fn select(mask: MaskOf<Self>, a: Self, b: Self) -> Self {
        Self::new(
            Self::Real::select(mask, a.x(), b.x()),
            Self::Real::select(mask, a.y(), b.y()),
            Self::Real::select(mask, a.z(), b.z()),
        )
    }
}

impl Mask for bool {
    const NONE: Self = false;
    #[inline(always)]
    fn splat(b: bool) -> Self {
        b
    }

    #[inline(always)]
    fn any(self) -> bool {
        self
    }

    #[inline(always)]
    fn bitmask(self) -> u32 {
        u32::from(self)
    }

    #[inline(always)]
    fn from_bitmask(bits: u32) -> Self {
        bits & 1 != 0
    }
}

impl Real for f32 {
    type Mask = bool;
    const ZERO: Self = 0.0;

    #[inline(always)]
    fn splat(x: f32) -> Self {
        x
    }

    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }

    #[inline(always)]
    fn simd_max(self, other: Self) -> Self {
        f32::max(self, other)
    }

    #[inline(always)]
    fn simd_min(self, other: Self) -> Self {
        f32::min(self, other)
    }

    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        f32::copysign(self, sign)
    }

    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }

    #[inline(always)]
    fn simd_lt(self, other: Self) -> bool {
        self < other
    }

    #[inline(always)]
    fn simd_le(self, other: Self) -> bool {
        self <= other
    }

    #[inline(always)]
    fn simd_gt(self, other: Self) -> bool {
        self > other
    }

    #[inline(always)]
    fn simd_ge(self, other: Self) -> bool {
        self >= other
    }

    #[inline(always)]
    fn simd_ne(self, other: Self) -> bool {
        self != other
    }

    #[inline(always)]
    fn select(mask: bool, a: Self, b: Self) -> Self {
        if mask { a } else { b }
    }

    const ONE: bool = true;
}

/// One value: glam's own operations (the generic code at `Vec3` *is* the scalar code).
impl Vector for Vec3 {
    type Real = f32;
    const ZERO: Self = Vec3::ZERO;

    #[inline(always)]
    fn splat(v: Vec3) -> Self {
        v
    }

    #[inline(always)]
    fn new(x: f32, y: f32, z: f32) -> Self {
        Vec3::new(x, y, z)
    }

    #[inline(always)]
    fn x(self) -> f32 {
        self.x
    }

    #[inline(always)]
    fn y(self) -> f32 {
        self.y
    }

    #[inline(always)]
    fn z(self) -> f32 {
        self.z
    }

    #[inline(always)]
    fn scale(s: f32, v: Self) -> Self {
        s * v
    }

    #[inline(always)]
    fn dot(self, o: Self) -> f32 {
        Vec3::dot(self, o)
    }

    #[inline(always)]
    fn cross(self, o: Self) -> Self {
        Vec3::cross(self, o)
    }

    #[inline(always)]
    fn length_squared(self) -> f32 {
        Vec3::length_squared(self)
    }

    #[inline(always)]
    fn length(self) -> f32 {
        Vec3::length(self)
    }

    #[inline(always)]
    fn max_element(self) -> f32 {
        Vec3::max_element(self)
    }

    #[inline(always)]
    fn simd_ne(self, o: Self) -> bool {
        self != o
    }
}

/// Sixteen `f32`s, one per lane; every operation is the `f32` one in each lane.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct F32x16(pub [f32; LANES]);

/// Sixteen comparison answers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct M16(pub [bool; LANES]);

/// Applies `f` lane by lane.
#[inline(always)]
fn lanewise<T: Copy, U>(a: [T; LANES], b: [T; LANES], f: impl Fn(T, T) -> U) -> [U; LANES] {
    std::array::from_fn(|i| f(a[i], b[i]))
}

macro_rules! lanes_op {
    ($trait:ident, $method:ident, $op:tt) => {
        impl $trait for F32x16 {
            type Output = Self;

            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                Self(lanewise(self.0, o.0, |a, b| a $op b))
            }
        }
    };
}

lanes_op!(Add, add, +);
lanes_op!(Sub, sub, -);
lanes_op!(Mul, mul, *);
lanes_op!(Div, div, /);

macro_rules! mask_op {
    ($trait:ident, $method:ident, $op:tt) => {
        impl $trait for M16 {
            type Output = Self;

            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                Self(lanewise(self.0, o.0, |a, b| a $op b))
            }
        }
    };
}

mask_op!(BitAnd, bitand, &);
mask_op!(BitOr, bitor, |);

impl Neg for F32x16 {
    type Output = Self;

    #[inline(always)]
    fn neg(self) -> Self {
        Self(self.0.map(|x| -x))
    }
}

impl Not for M16 {
    type Output = Self;

    #[inline(always)]
    fn not(self) -> Self {
        Self(self.0.map(|b| !b))
    }
}

impl M16 {
    /// Lane `i` as bit `i`.
    #[inline(always)]
    pub fn bits(self) -> u16 {
        // A plain loop, no closure: a closure inside the code compiled for the CPU may be
        // called out of line, compiled without the CPU's instruction set.
        let mut bits = 0;
        for (i, &b) in self.0.iter().enumerate() {
            bits |= u16::from(b) << i;
        }
        bits
    }

    /// Bit `i` as lane `i`.
    #[inline(always)]
    pub fn from_bits(bits: u16) -> Self {
        Self(std::array::from_fn(|i| bits & (1 << i) != 0))
    }
}

impl Mask for M16 {
    const NONE: Self = Self([false; LANES]);
    #[inline(always)]
    fn splat(b: bool) -> Self {
        Self([b; LANES])
    }

    #[inline(always)]
    fn any(self) -> bool {
        // `|` over all lanes, no early exit: one vector test.
        self.0.iter().fold(false, |a, &b| a | b)
    }

    #[inline(always)]
    fn bitmask(self) -> u32 {
        u32::from(self.bits())
    }

    #[inline(always)]
    fn from_bitmask(bits: u32) -> Self {
        Self::from_bits(bits as u16)
    }
}

impl Real for F32x16 {
    type Mask = M16;
    const ZERO: Self = Self([0.0; LANES]);
    const ONE: bool = false;

    #[inline(always)]
    fn splat(x: f32) -> Self {
        Self([x; LANES])
    }

    #[inline(always)]
    fn sqrt(self) -> Self {
        Self(self.0.map(f32::sqrt))
    }

    #[inline(always)]
    fn simd_max(self, other: Self) -> Self {
        Self(lanewise(self.0, other.0, f32::max))
    }

    #[inline(always)]
    fn simd_min(self, other: Self) -> Self {
        Self(lanewise(self.0, other.0, f32::min))
    }

    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        Self(lanewise(self.0, sign.0, f32::copysign))
    }

    #[inline(always)]
    fn abs(self) -> Self {
        Self(self.0.map(f32::abs))
    }

    #[inline(always)]
    fn simd_lt(self, other: Self) -> M16 {
        M16(lanewise(self.0, other.0, |a, b| a < b))
    }

    #[inline(always)]
    fn simd_le(self, other: Self) -> M16 {
        M16(lanewise(self.0, other.0, |a, b| a <= b))
    }

    #[inline(always)]
    fn simd_gt(self, other: Self) -> M16 {
        M16(lanewise(self.0, other.0, |a, b| a > b))
    }

    #[inline(always)]
    fn simd_ge(self, other: Self) -> M16 {
        M16(lanewise(self.0, other.0, |a, b| a >= b))
    }

    #[inline(always)]
    fn simd_ne(self, other: Self) -> M16 {
        M16(lanewise(self.0, other.0, |a, b| a != b))
    }

    #[inline(always)]
    fn select(mask: M16, a: Self, b: Self) -> Self {
        Self(std::array::from_fn(
            |i| {
                if mask.0[i] { a.0[i] } else { b.0[i] }
            },
        ))
    }
}

/// 3-vectors in lanes: three `R`s, structure of arrays (lane `i` is `(x[i], y[i], z[i])`). At
/// [`F32x16`] it is [`Vec3x16`], the shading's sixteen hits; the ray–triangle kernels use it at
/// their SIMD registers' width too ([`crate::shapes::intersect::hits`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vec3x<R> {
    pub x: R,
    pub y: R,
    pub z: R,
}

/// Sixteen 3-vectors as three [`F32x16`]s.
pub type Vec3x16 = Vec3x<F32x16>;

impl Vec3x16 {
    /// Lane `i` as a `Vec3`.
    #[inline(always)]
    pub fn lane(&self, i: usize) -> Vec3 {
        Vec3::new(self.x.0[i], self.y.0[i], self.z.0[i])
    }

    /// Sets lane `i` to `v`.
    #[inline(always)]
    pub fn set_lane(&mut self, i: usize, v: Vec3) {
        self.x.0[i] = v.x;
        self.y.0[i] = v.y;
        self.z.0[i] = v.z;
    }
}

macro_rules! vec_op {
    ($trait:ident, $method:ident, $op:tt) => {
        impl<R: Real> $trait for Vec3x<R> {
            type Output = Self;

            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                Self { x: self.x $op o.x, y: self.y $op o.y, z: self.z $op o.z }
            }
        }
    };
}

vec_op!(Add, add, +);
vec_op!(Sub, sub, -);
vec_op!(Mul, mul, *);

/// `v · s`, component by component (glam's `Vec3 * f32`).
impl<R: Real> Mul<R> for Vec3x<R> {
    type Output = Self;

    #[inline(always)]
    fn mul(self, s: R) -> Self {
        Self {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

/// `v / s`, component by component (glam's `Vec3 / f32`).
impl<R: Real> Div<R> for Vec3x<R> {
    type Output = Self;

    #[inline(always)]
    fn div(self, s: R) -> Self {
        Self {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }
}

impl<R: Real> Vector for Vec3x<R> {
    type Real = R;
    const ZERO: Self = Self {
        x: R::ZERO,
        y: R::ZERO,
        z: R::ZERO,
    };

    #[inline(always)]
    fn splat(v: Vec3) -> Self {
        Self {
            x: R::splat(v.x),
            y: R::splat(v.y),
            z: R::splat(v.z),
        }
    }

    #[inline(always)]
    fn new(x: R, y: R, z: R) -> Self {
        Self { x, y, z }
    }

    #[inline(always)]
    fn x(self) -> R {
        self.x
    }

    #[inline(always)]
    fn y(self) -> R {
        self.y
    }

    #[inline(always)]
    fn z(self) -> R {
        self.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lane operations the path tracer's roulette uses, lane by lane as glam and `f32`
    /// compute them: `max_element` (ties, zeros of both signs), `simd_min` and `copysign`.
    #[test]
    fn lanes_reduce_and_compare_as_one_value_does() {
        let values = [
            0.0,
            -0.0,
            0.5,
            0.95,
            1.0,
            0.25,
            3.0,
            -2.0,
            f32::MIN_POSITIVE,
        ];
        let mut v = Vec3x16::ZERO;
        let mut lane = 0;
        let mut expected = Vec::new();
        for &x in &values {
            for &y in &values {
                for &z in &[0.5, -0.0, 3.0] {
                    let one = Vec3::new(x, y, z);
                    v.set_lane(lane, one);
                    expected.push(one);
                    lane += 1;
                    if lane == LANES {
                        let max = v.max_element();
                        let min = max.simd_min(F32x16::splat(0.95));
                        let sign = F32x16::splat(1.0).copysign(v.z);
                        for (i, e) in expected.iter().enumerate() {
                            assert_eq!(max.0[i].to_bits(), e.max_element().to_bits(), "{e}");
                            assert_eq!(min.0[i].to_bits(), e.max_element().min(0.95).to_bits());
                            assert_eq!(sign.0[i].to_bits(), 1f32.copysign(e.z).to_bits());
                        }
                        lane = 0;
                        expected.clear();
                    }
                }
            }
        }
    }
}

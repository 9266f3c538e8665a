//! The portable kernels ([`Portable`]): the SIMD sets' algorithm — packets of rays through the
//! wide BVH, the flat list culled per batch, shadow rays straight from the integrators' lanes,
//! one ray against eight boxes or eight triangles at once — run eight lanes wide on any CPU.
//!
//! A lane value ([`F8`]) is two registers of four `f32`: SSE2 on x86-64, which every x86-64
//! CPU runs (so nothing is detected and no `#[target_feature]` is needed), and four plain
//! `f32`s elsewhere, which the compiler turns into the CPU's own four-lane vectors (NEON on
//! aarch64). The traversals, the culling and the triangle test are the generic code the SIMD
//! sets run ([`InstructionSet`], [`crate::shapes::intersect::intersect_lanes`]); this module only says
//! what one lane operation is.
//!
//! **Bit for bit.** Every arithmetic operation is the `f32` one in each lane, exactly rounded
//! and never fused, so the triangle test's `t`, `u`, `v` are those of the scalar test. The box
//! test computes `(plane − o)·inv` as the readable traversal does; boxes only decide which
//! triangles are tested, never what a test returns.

use super::set::{Compiled, InstructionSet, MAX_WIDTH};
use super::simd::LANES;
use crate::base::geometry::Ray;
use crate::base::lanes::{Mask, Real, compiled};

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

use quad::Q;

// Four lanes: on x86-64 an SSE register (`x86_lanes`), elsewhere four `f32` (below).
#[cfg(target_arch = "x86_64")]
use super::x86_lanes::quad;

/// Four lanes as four `f32` (their bits for the logic), each operation a loop the compiler
/// vectorises.
#[cfg(not(target_arch = "x86_64"))]
mod quad {
    #[derive(Clone, Copy, Debug)]
    pub struct Q([f32; 4]);

    #[inline(always)]
    fn mask(b: bool) -> f32 {
        f32::from_bits(if b { !0 } else { 0 })
    }

    impl Q {
        pub const ZERO: Q = Q([0.0; 4]);
        pub const ONES: Q = Q([f32::from_bits(!0); 4]);

        #[inline(always)]
        fn map(self, o: Q, f: impl Fn(f32, f32) -> f32) -> Q {
            Q([
                f(self.0[0], o.0[0]),
                f(self.0[1], o.0[1]),
                f(self.0[2], o.0[2]),
                f(self.0[3], o.0[3]),
            ])
        }
        #[inline(always)]
        fn bitwise(self, o: Q, f: impl Fn(u32, u32) -> u32) -> Q {
            self.map(o, |a, b| f32::from_bits(f(a.to_bits(), b.to_bits())))
        }
        #[inline(always)]
        pub fn splat(x: f32) -> Q {
            Q([x; 4])
        }
        #[inline(always)]
        pub fn splat_u32(x: u32) -> Q {
            Q([f32::from_bits(x); 4])
        }
        #[inline(always)]
        pub fn load(a: &[f32; 4]) -> Q {
            Q(*a)
        }
        #[inline(always)]
        pub fn store(self, a: &mut [f32; 4]) {
            *a = self.0;
        }
        #[inline(always)]
        pub fn to_array(self) -> [f32; 4] {
            self.0
        }
        #[inline(always)]
        pub fn add(self, o: Q) -> Q {
            self.map(o, |a, b| a + b)
        }
        #[inline(always)]
        pub fn sub(self, o: Q) -> Q {
            self.map(o, |a, b| a - b)
        }
        #[inline(always)]
        pub fn mul(self, o: Q) -> Q {
            self.map(o, |a, b| a * b)
        }
        #[inline(always)]
        pub fn div(self, o: Q) -> Q {
            self.map(o, |a, b| a / b)
        }
        #[inline(always)]
        pub fn sqrt(self) -> Q {
            Q(self.0.map(f32::sqrt))
        }
        #[inline(always)]
        pub fn max(self, o: Q) -> Q {
            self.map(o, |a, b| if a > b { a } else { b })
        }
        #[inline(always)]
        pub fn min(self, o: Q) -> Q {
            self.map(o, |a, b| if a < b { a } else { b })
        }
        #[inline(always)]
        pub fn and(self, o: Q) -> Q {
            self.bitwise(o, |a, b| a & b)
        }
        #[inline(always)]
        pub fn or(self, o: Q) -> Q {
            self.bitwise(o, |a, b| a | b)
        }
        #[inline(always)]
        pub fn xor(self, o: Q) -> Q {
            self.bitwise(o, |a, b| a ^ b)
        }
        #[inline(always)]
        pub fn andnot(self, o: Q) -> Q {
            self.bitwise(o, |a, b| !a & b)
        }
        #[inline(always)]
        pub fn eq(self, o: Q) -> Q {
            self.map(o, |a, b| mask(a == b))
        }
        #[inline(always)]
        pub fn ne(self, o: Q) -> Q {
            self.map(o, |a, b| mask(a != b))
        }
        #[inline(always)]
        pub fn lt(self, o: Q) -> Q {
            self.map(o, |a, b| mask(a < b))
        }
        #[inline(always)]
        pub fn le(self, o: Q) -> Q {
            self.map(o, |a, b| mask(a <= b))
        }
        #[inline(always)]
        pub fn gt(self, o: Q) -> Q {
            self.map(o, |a, b| mask(a > b))
        }
        #[inline(always)]
        pub fn ge(self, o: Q) -> Q {
            self.map(o, |a, b| mask(a >= b))
        }
        #[inline(always)]
        pub fn ngt(self, o: Q) -> Q {
            self.map(o, |a, b| mask(!(a > b)))
        }
        #[inline(always)]
        pub fn bits(self) -> u32 {
            let mut bits = 0;
            for (i, x) in self.0.iter().enumerate() {
                bits |= (x.to_bits() >> 31) << i;
            }
            bits
        }
        #[inline(always)]
        pub fn from_bits(bits: u32) -> Q {
            Q([
                mask(bits & 1 != 0),
                mask(bits & 2 != 0),
                mask(bits & 4 != 0),
                mask(bits & 8 != 0),
            ])
        }
        #[inline(always)]
        pub fn lt_u32(self, o: Q) -> Q {
            self.map(o, |a, b| mask(a.to_bits() < b.to_bits()))
        }
        #[inline(always)]
        pub fn least(self) -> f32 {
            let [a, b, c, d] = self.0;
            let (ac, bd) = (if a < c { a } else { c }, if b < d { b } else { d });
            if ac < bd { ac } else { bd }
        }
    }
}

/// Eight `f32` lanes: two [`Q`]s.
#[derive(Clone, Copy, Debug)]
pub struct F8([Q; 2]);

/// Eight comparison answers: all ones in a lane that is true.
#[derive(Clone, Copy, Debug)]
pub struct M8([Q; 2]);

/// Eight `u32` lanes (their bits in two [`Q`]s).
#[derive(Clone, Copy, Debug)]
pub struct U8([Q; 2]);

impl F8 {
    #[inline(always)]
    pub fn load8(a: &[f32; 8]) -> F8 {
        let (lo, hi) = a.split_at(4);
        F8([
            Q::load(lo.try_into().expect("four")),
            Q::load(hi.try_into().expect("four")),
        ])
    }

    #[inline(always)]
    pub fn to_array(self) -> [f32; 8] {
        let ([a, b, c, d], [e, f, g, h]) = (self.0[0].to_array(), self.0[1].to_array());
        [a, b, c, d, e, f, g, h]
    }

    #[inline(always)]
    fn zip(self, o: F8, f: impl Fn(Q, Q) -> Q) -> F8 {
        F8([f(self.0[0], o.0[0]), f(self.0[1], o.0[1])])
    }

    #[inline(always)]
    fn test(self, o: F8, f: impl Fn(Q, Q) -> Q) -> M8 {
        M8([f(self.0[0], o.0[0]), f(self.0[1], o.0[1])])
    }
}

impl M8 {
    #[inline(always)]
    fn bits(self) -> u32 {
        self.0[0].bits() | (self.0[1].bits() << 4)
    }

    #[inline(always)]
    fn from_bits(bits: u32) -> M8 {
        M8([Q::from_bits(bits), Q::from_bits(bits >> 4)])
    }

    /// `b` where the mask is set, `a` elsewhere (bit by bit).
    #[inline(always)]
    fn blend(self, a: [Q; 2], b: [Q; 2]) -> [Q; 2] {
        let one = |m: Q, a: Q, b: Q| m.and(b).or(m.andnot(a));
        [one(self.0[0], a[0], b[0]), one(self.0[1], a[1], b[1])]
    }
}

impl PartialEq for F8 {
    fn eq(&self, o: &Self) -> bool {
        self.to_array() == o.to_array()
    }
}

impl PartialEq for M8 {
    fn eq(&self, o: &Self) -> bool {
        self.bits() == o.bits()
    }
}

macro_rules! arithmetic {
    ($($trait:ident $method:ident),*) => {$(
        impl $trait for F8 {
            type Output = Self;

            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                self.zip(o, Q::$method)
            }
        }
    )*};
}

arithmetic!(Add add, Sub sub, Mul mul, Div div);

impl Neg for F8 {
    type Output = Self;

    /// The sign bit flipped, as `-x` on an `f32`.
    #[inline(always)]
    fn neg(self) -> Self {
        self.zip(F8::splat(-0.0), Q::xor)
    }
}

impl BitAnd for M8 {
    type Output = Self;

    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        M8([self.0[0].and(o.0[0]), self.0[1].and(o.0[1])])
    }
}

impl BitOr for M8 {
    type Output = Self;

    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        M8([self.0[0].or(o.0[0]), self.0[1].or(o.0[1])])
    }
}

impl Not for M8 {
    type Output = Self;

    #[inline(always)]
    fn not(self) -> Self {
        M8([self.0[0].xor(Q::ONES), self.0[1].xor(Q::ONES)])
    }
}

impl Mask for M8 {
    const NONE: Self = M8([Q::ZERO; 2]);

    #[inline(always)]
    fn splat(b: bool) -> Self {
        M8([if b { Q::ONES } else { Q::ZERO }; 2])
    }

    #[inline(always)]
    fn any(self) -> bool {
        self.0[0].or(self.0[1]).bits() != 0
    }

    #[inline(always)]
    fn bitmask(self) -> u32 {
        self.bits()
    }

    #[inline(always)]
    fn from_bitmask(bits: u32) -> M8 {
        M8::from_bits(bits)
    }
}

impl Real for F8 {
    type Mask = M8;
    const ZERO: Self = F8([Q::ZERO; 2]);
    const ONE: bool = false;

    #[inline(always)]
    fn splat(x: f32) -> Self {
        F8([Q::splat(x); 2])
    }

    #[inline(always)]
    fn sqrt(self) -> Self {
        F8([self.0[0].sqrt(), self.0[1].sqrt()])
    }

    #[inline(always)]
    fn simd_max(self, o: Self) -> Self {
        // `o > self ? o : self` gives `self` where `o` is NaN; `f32::max` gives `o` where
        // `self` is.
        let max = o.zip(self, Q::max);
        F8(self.test(self, Q::ne).blend(max.0, o.0))
    }

    #[inline(always)]
    fn simd_min(self, o: Self) -> Self {
        let min = o.zip(self, Q::min);
        F8(self.test(self, Q::ne).blend(min.0, o.0))
    }

    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        let bit = F8::splat(-0.0);
        bit.zip(self, Q::andnot).zip(bit.zip(sign, Q::and), Q::or)
    }

    #[inline(always)]
    fn abs(self) -> Self {
        F8::splat(-0.0).zip(self, Q::andnot)
    }

    #[inline(always)]
    fn max_or_other(self, o: Self) -> Self {
        self.zip(o, Q::max)
    }

    #[inline(always)]
    fn min_or_other(self, o: Self) -> Self {
        self.zip(o, Q::min)
    }

    #[inline(always)]
    fn simd_eq(self, o: Self) -> M8 {
        self.test(o, Q::eq)
    }

    #[inline(always)]
    fn simd_ngt(self, o: Self) -> M8 {
        self.test(o, Q::ngt)
    }

    #[inline(always)]
    fn simd_lt(self, o: Self) -> M8 {
        self.test(o, Q::lt)
    }

    #[inline(always)]
    fn simd_le(self, o: Self) -> M8 {
        self.test(o, Q::le)
    }

    #[inline(always)]
    fn simd_gt(self, o: Self) -> M8 {
        self.test(o, Q::gt)
    }

    #[inline(always)]
    fn simd_ge(self, o: Self) -> M8 {
        self.test(o, Q::ge)
    }

    #[inline(always)]
    fn simd_ne(self, o: Self) -> M8 {
        self.test(o, Q::ne)
    }

    #[inline(always)]
    fn select(mask: M8, a: Self, b: Self) -> Self {
        F8(mask.blend(b.0, a.0))
    }
}

/// The kernel set every CPU runs: the SIMD sets' algorithm eight lanes wide, in the registers
/// every CPU of its architecture has (see the module docs).
#[derive(Clone, Copy, Debug, Default)]
pub struct Portable;

/// Eight records of `K ≤ S` floats of `S`-float records from `base` (`len` of them, lanes past
/// `len` repeating the last), record `i` in lane `i`.
#[inline(always)]
fn lanes_of_records<T, const K: usize>(records: &[T], float: impl Fn(&T, usize) -> f32) -> [F8; K] {
    let last = records.len() - 1;
    let mut rows = [[0.0f32; LANES]; K];
    for lane in 0..LANES {
        let r = &records[lane.min(last)];
        for (c, row) in rows.iter_mut().enumerate() {
            row[lane] = float(r, c);
        }
    }
    rows.map(|row| F8::load8(&row))
}

/// Float `c` of a ray: origin x, y, z, then direction x, y, z.
#[inline(always)]
fn ray_float(r: &Ray, c: usize) -> f32 {
    if c < 3 {
        r.origin[c]
    } else {
        r.direction[c - 3]
    }
}

impl InstructionSet for Portable {
    const WIDTH: usize = LANES;
    type F = F8;
    type U = U8;
    type Mask = M8;
    type Tree = Portable;

    #[inline(always)]
    fn tree(self) -> Portable {
        self
    }

    #[inline(always)]
    fn call<F: Compiled>(self, f: F) -> F::Output {
        compiled!(Portable: #[inline] fn compiled<F: Compiled>(k: Portable, f: F) -> F::Output {
            f.run(k)
        });
        compiled(self, f)
    }

    #[inline(always)]
    fn rays(self, rays: &[Ray]) -> [F8; 6] {
        debug_assert!(!rays.is_empty() && rays.len() <= Self::WIDTH);
        lanes_of_records(rays, ray_float)
    }

    #[inline(always)]
    fn segments(self, segments: &[(Ray, f32)]) -> [F8; 7] {
        debug_assert!(!segments.is_empty() && segments.len() <= Self::WIDTH);
        lanes_of_records(
            segments,
            |(r, t), c| if c < 6 { ray_float(r, c) } else { *t },
        )
    }

    #[inline(always)]
    fn load(self, a: &[f32; MAX_WIDTH]) -> F8 {
        F8::load8(a.first_chunk().expect("sixteen floats hold eight"))
    }
    #[inline(always)]
    fn store(self, a: &mut [f32; MAX_WIDTH], v: F8) {
        let (lo, hi) = a.split_at_mut(4);
        v.0[0].store(lo.first_chunk_mut().expect("four"));
        v.0[1].store(hi.first_chunk_mut().expect("four"));
    }
    #[inline(always)]
    fn load_lanes<const N: usize>(self, a: &[f32; N]) -> F8 {
        F8::load8(a.first_chunk().expect("at least eight floats"))
    }
    #[inline(always)]
    fn lane(self, v: F8, i: usize) -> f32 {
        v.to_array()[i & (LANES - 1)]
    }
    #[inline(always)]
    fn lane_u32(self, v: U8, i: usize) -> u32 {
        F8(v.0).to_array()[i & (LANES - 1)].to_bits()
    }
    #[inline(always)]
    fn plane_distance(self, plane: F8, origin: F8, inv: F8, _origin_inv: F8) -> F8 {
        (plane - origin) * inv
    }

    #[inline(always)]
    fn min_of(self, m: M8, v: F8) -> f32 {
        let v = m.blend(F8::splat(f32::INFINITY).0, v.0);
        v[0].min(v[1]).least()
    }

    #[inline(always)]
    fn splat_u32(self, x: u32) -> U8 {
        U8([Q::splat_u32(x); 2])
    }
    #[inline(always)]
    fn load_u32(self, a: &[u32; MAX_WIDTH]) -> U8 {
        let f: [f32; MAX_WIDTH] = a.map(f32::from_bits);
        U8(self.load(&f).0)
    }
    #[inline(always)]
    fn store_u32(self, a: &mut [u32; MAX_WIDTH], v: U8) {
        let mut f = [0.0f32; MAX_WIDTH];
        self.store(&mut f, F8(v.0));
        for (a, f) in a.iter_mut().zip(&f[..LANES]) {
            *a = f.to_bits();
        }
    }
    #[inline(always)]
    fn lt_u32(self, a: U8, b: U8) -> M8 {
        M8([a.0[0].lt_u32(b.0[0]), a.0[1].lt_u32(b.0[1])])
    }
    #[inline(always)]
    fn blend_u32(self, m: M8, a: U8, b: U8) -> U8 {
        U8(m.blend(a.0, b.0))
    }
}

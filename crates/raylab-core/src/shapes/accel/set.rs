//! The instruction sets as generic code sees them: [`InstructionSet`], implemented by the
//! three proof types (`Avx512` and `Avx2` in [`super::x86_lanes`], whose values exist only on a
//! CPU that runs them, and [`super::portable::Portable`], which every CPU runs), and
//! [`Compiled`], a function written once and compiled for each of them.
//!
//! **One dispatch.** A function that runs with each set is written once, as a [`Compiled`]: its
//! arguments a value, its body [`Compiled::run`], generic over the set and `#[inline(always)]`.
//! [`super::Isa::call`] picks the set from the runtime choice, once; [`InstructionSet::call`] enters
//! one function compiled with the set's features ([`crate::base::lanes::compiled!`], the one
//! place they are named), into which the body and everything generic it calls inline: the
//! lanes' operations, the kernels ([`super::kernels`]), the packet traversal
//! ([`super::packet`]), the culling ([`super::cull`]), an integrator's batch code.

use crate::base::geometry::Ray;
use crate::base::lanes::{Mask, Real};

/// The most lanes of any set (AVX-512's sixteen `f32`): the length of the per-lane arrays,
/// whatever the width.
pub const MAX_WIDTH: usize = 16;

/// A function written once for every instruction set: its arguments as the value, its body as
/// [`Compiled::run`], which is `#[inline(always)]` so that it is compiled inside the function
/// [`InstructionSet::call`] makes for the set. Called as `isa.call(Function { … })`.
pub trait Compiled {
    type Output;
    /// The body, with `set` the instruction set it is compiled for.
    fn run<S: InstructionSet>(self, set: S) -> Self::Output;
}

/// An instruction set: its lanes and the few operations generic code needs of it beyond the
/// lanes' arithmetic, and the entry into code compiled for it ([`InstructionSet::call`]).
///
/// The lanes are one register of `f32` ([`Real`]: the arithmetic, comparisons, `max`/`min` and
/// `select` of [`crate::base::lanes`], each declared there once), its comparisons' results
/// ([`Mask`], as bits too) and a register of `u32` (the best triangle's index); the operations
/// below are each one instruction or a short fixed sequence. AVX-512 has sixteen lanes, masks
/// in mask registers; AVX2 eight, masks as all-ones lanes; the portable set eight, in two
/// four-lane registers.
///
/// Every method is `#[inline(always)]`, and so is every generic caller: they are compiled
/// inside the functions [`InstructionSet::call`] makes, where the intrinsics inline.
pub trait InstructionSet: Copy {
    /// Lanes, so rays in a packet.
    const WIDTH: usize;
    /// `WIDTH` lanes of `f32`.
    type F: Real<Mask = Self::Mask>;
    /// `WIDTH` lanes of `u32`.
    type U: Copy;
    /// A comparison's result, lane by lane.
    type Mask: Mask;
    /// The eight-lane set of the wide BVH's single-ray kernels (its nodes and leaves are eight
    /// wide): the set itself where it is eight wide; AVX2 for AVX-512, which the CPU also runs.
    type Tree: InstructionSet;

    /// [`InstructionSet::Tree`]'s proof.
    fn tree(self) -> Self::Tree;

    /// `f` run in a function compiled for this set, the proof passed on: the one entry from
    /// code compiled for any CPU into code compiled for the set.
    fn call<F: Compiled>(self, f: F) -> F::Output;

    /// The rays' origins and directions (x, y, z, dx, dy, dz), one ray a lane; lanes past
    /// `rays.len()` (at least one, at most `WIDTH`) repeat the last ray.
    fn rays(self, rays: &[Ray]) -> [Self::F; 6];
    /// [`InstructionSet::rays`] for shadow rays: (x, y, z, dx, dy, dz, t_max).
    fn segments(self, segments: &[(Ray, f32)]) -> [Self::F; 7];

    #[inline(always)]
    fn splat(self, x: f32) -> Self::F {
        Self::F::splat(x)
    }
    /// The first `WIDTH` floats of `a`.
    fn load(self, a: &[f32; MAX_WIDTH]) -> Self::F;
    /// The first `WIDTH` floats of `a` (`N ≥ WIDTH`: checked).
    fn load_lanes<const N: usize>(self, a: &[f32; N]) -> Self::F;
    /// Lane `i` of `v` (`i < WIDTH`), moved to lane 0 in registers where the set can: a
    /// store and a read back of one float would stall on the store (store forwarding).
    fn lane(self, v: Self::F, i: usize) -> f32;
    /// Lane `i` of `v` (`i < WIDTH`).
    fn lane_u32(self, v: Self::U, i: usize) -> u32;
    /// Into the first `WIDTH` floats of `a`.
    fn store(self, a: &mut [f32; MAX_WIDTH], v: Self::F);
    /// Each lane's distance along its ray to the plane `plane` (of the axis whose origin,
    /// reciprocal direction and their product are given): `plane·inv − o·inv` in one rounding
    /// where the set has a fused multiply-subtract, else `(plane − o)·inv`. Either way close
    /// enough for the padding of the boxes (`bvh`).
    fn plane_distance(
        self,
        plane: Self::F,
        origin: Self::F,
        inv: Self::F,
        origin_inv: Self::F,
    ) -> Self::F;

    /// The least of the lanes of `m` (at least one).
    fn min_of(self, m: Self::Mask, v: Self::F) -> f32;

    fn splat_u32(self, x: u32) -> Self::U;
    fn load_u32(self, a: &[u32; MAX_WIDTH]) -> Self::U;
    fn store_u32(self, a: &mut [u32; MAX_WIDTH], v: Self::U);
    /// Lane by lane `a < b`, unsigned.
    fn lt_u32(self, a: Self::U, b: Self::U) -> Self::Mask;
    fn blend_u32(self, m: Self::Mask, a: Self::U, b: Self::U) -> Self::U;
}

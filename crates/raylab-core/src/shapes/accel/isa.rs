//! [`Isa`], the kernel sets this CPU runs by name, and the one dispatch from the runtime choice
//! to code compiled for the set ([`Isa::call`]).

use super::portable::Portable;
use super::set::{Compiled, InstructionSet};
use super::simd::{Avx2, Avx512};

/// Which kernels run the flat list and the wide BVH.
#[derive(Clone, Copy, Debug)]
pub enum Isa {
    /// The portable kernels ([`super::portable`], named `scalar` on the command line): the SIMD sets'
    /// packets, culling and batches, eight lanes wide in the registers every CPU of the
    /// architecture has (SSE2 on x86-64).
    Scalar,
    /// AVX2 + FMA: 8-wide everything.
    Avx2(Avx2),
    /// AVX-512: the flat list 16 wide; the 8-wide BVH keeps its AVX2 kernels for single rays
    /// and traces coherent batches as packets of 16 rays.
    Avx512(Avx512),
}

/// For tests of a kernel set this CPU does not run (`set`: `avx2` or `avx512`), which return
/// without checking it: says so on the terminal (past the test harness's capture of output, so
/// a passing run shows the skip), and fails instead when the `RAYLAB_REQUIRE_ISA` environment
/// variable names the set (a comma-separated list: CI names each set its CPU has, so a kernel
/// set it can test is never skipped unnoticed).
#[doc(hidden)]
pub fn skip_unless_required(set: &str, test: &str) {
    use std::io::Write as _;
    let required = std::env::var("RAYLAB_REQUIRE_ISA").unwrap_or_default();
    if names(&required, set) {
        panic!("{test}: RAYLAB_REQUIRE_ISA names {set}, but this CPU does not run it");
    }
    let _ = writeln!(
        std::io::stderr(),
        "note: {test}: the {set} kernels are not tested: this CPU does not run them"
    );
}

/// Whether the comma-separated `list` names `set`.
fn names(list: &str, set: &str) -> bool {
    list.split(',').map(str::trim).any(|r| r == set)
}

impl Isa {
    /// The widest kernels this CPU runs: AVX-512, else AVX2 + FMA, else scalar.
    pub fn widest() -> Self {
        match (Avx512::detect(), Avx2::detect()) {
            (Some(k), _) => Isa::Avx512(k),
            (None, Some(k)) => Isa::Avx2(k),
            (None, None) => Isa::Scalar,
        }
    }

    /// Every kernel set this CPU runs, scalar first.
    pub fn available() -> Vec<Isa> {
        let mut out = vec![Isa::Scalar];
        out.extend(Avx2::detect().map(Isa::Avx2));
        out.extend(Avx512::detect().map(Isa::Avx512));
        out
    }

    /// For tests: every kernel set this CPU runs ([`Isa::available`]), each set it does not
    /// run reported by [`skip_unless_required`] under the name `test`.
    #[doc(hidden)]
    pub fn available_for_tests(test: &str) -> Vec<Isa> {
        if Avx2::detect().is_none() {
            skip_unless_required("avx2", test);
        }
        if Avx512::detect().is_none() {
            skip_unless_required("avx512", test);
        }
        Isa::available()
    }

    /// The named kernel set, if this CPU runs it: `scalar`, `avx2` or `avx512`.
    pub fn by_name(name: &str) -> Option<Isa> {
        match name {
            "scalar" => Some(Isa::Scalar),
            "avx2" => Avx2::detect().map(Isa::Avx2),
            "avx512" => Avx512::detect().map(Isa::Avx512),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Isa::Scalar => "scalar",
            Isa::Avx2(_) => "avx2",
            Isa::Avx512(_) => "avx512",
        }
    }

    /// `f` compiled for this set ([`InstructionSet::call`]): the one match from the runtime
    /// choice to the generic code. Elsewhere than x86-64 the x86 sets are never detected, and
    /// only the portable arm is compiled.
    #[inline(always)]
    pub fn call<F: Compiled>(self, f: F) -> F::Output {
        match self {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512(k) => k.call(f),
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2(k) => k.call(f),
            _ => Portable.call(f),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `RAYLAB_REQUIRE_ISA=avx2,avx512` turns the skip of either set into a failure; a set it
    /// does not name is skipped with a note.
    #[test]
    fn a_required_kernel_set_cannot_be_skipped() {
        assert!(names("avx2,avx512", "avx512") && names(" avx2 ", "avx2"));
        assert!(!names("avx2", "avx512") && !names("", "avx2"));
        let required = std::env::var("RAYLAB_REQUIRE_ISA").unwrap_or_default();
        if !names(&required, "made-up") {
            skip_unless_required("made-up", "a_required_kernel_set_cannot_be_skipped");
        }
    }

    #[test]
    fn kernel_sets_are_named_only_where_the_cpu_runs_them() {
        // A set the CPU lacks is not offered (so `--isa` refuses it) and never chosen: the
        // choice falls back to what the CPU has.
        assert_eq!(Isa::by_name("avx512").is_some(), Avx512::detect().is_some());
        assert_eq!(Isa::by_name("avx2").is_some(), Avx2::detect().is_some());
        assert!(Isa::by_name("scalar").is_some() && Isa::by_name("sse9").is_none());
        let available: Vec<&str> = Isa::available().into_iter().map(Isa::name).collect();
        assert!(
            available.contains(&crate::shapes::scene::best_isa().name()),
            "{available:?}"
        );
        assert!(available.contains(&Isa::widest().name()));
        // AVX-512 implies AVX2 (its kernels use both).
        if Avx512::detect().is_some() {
            assert!(available.contains(&"avx2"));
        }
        // Forcing the set already chosen is accepted; another one is refused.
        assert!(crate::shapes::scene::best_isa().force().is_ok());
        if let Some(other) = Isa::available()
            .into_iter()
            .find(|i| i.name() != crate::shapes::scene::best_isa().name())
        {
            assert!(other.force().is_err());
        }
    }
}

//! Sixteen values into SIMD lanes, or out of them, at once, for an integrator that holds
//! sixteen hits side by side ([`super::HitLanes`]): their rays ([`ray_lanes`]), each hit's
//! entry of a per-triangle table in a scene of at most 32 triangles ([`table_lanes`]), and
//! sixteen values stored back as `Vec3`s ([`store_vec3s`]). With AVX-512 each is a few register
//! operations (loads, permutes, stores); elsewhere lane by lane. Both give the same values.
//!
//! Why: filled lane by lane, sixteen hits' fields went through the stack one `f32` at a time,
//! and the vector loads that then read them back waited for those stores (a store-forwarding
//! stall). Gathers avoid the stall but read each lane from memory one at a time, which is
//! slower still.

use glam::Vec3;

use super::Isa;
#[cfg(target_arch = "x86_64")]
use super::packet::PacketIsa;
#[cfg(target_arch = "x86_64")]
use super::simd::Avx512;
#[cfg(target_arch = "x86_64")]
use super::x86_lanes::Avx512F32;
use crate::geometry::Ray;
use crate::lanes::compiled;

/// The entries of a table of at most 32 at `index[i]` (its low five bits) for each lane set in
/// `lanes`, 0 in the others: one two-register permute with AVX-512, where a gather reads each
/// lane from memory.
#[inline(always)]
pub fn table_lanes(isa: Isa, table: &[f32; 32], index: &[u32; 16], lanes: u16) -> [f32; 16] {
    #[cfg(target_arch = "x86_64")]
    if let Isa::Avx512(_) = isa {
        // SAFETY: `Isa::Avx512` exists only on a CPU with the features `permute_avx512` is
        // compiled with; nothing is read from memory but `table` and `index`, whole.
        return unsafe { permute_avx512(table, index, lanes) };
    }
    let _ = isa;
    std::array::from_fn(|lane| match lanes & (1 << lane) {
        0 => 0.0,
        _ => table[index[lane] as usize % 32],
    })
}

compiled!(Avx512:
/// [`table_lanes`] with AVX-512's `vpermt2ps`.
#[inline]
fn permute_avx512(table: &[f32; 32], index: &[u32; 16], lanes: u16) -> [f32; 16] {
    use std::arch::x86_64::*;
    // SAFETY: the loads read `table`'s 128 bytes and `index`'s 64, unaligned.
    unsafe {
        let low = _mm512_loadu_ps(table.as_ptr());
        let high = _mm512_loadu_ps(table.as_ptr().add(16));
        let index = _mm512_loadu_si512(index.as_ptr().cast());
        let values = _mm512_maskz_permutex2var_ps(lanes, low, index, high);
        std::mem::transmute::<__m512, [f32; 16]>(values)
    }
});

/// Up to sixteen rays in lanes: `[origin x, y, z, direction x, y, z]`, ray `i` in lane `i`,
/// the lanes past the last ray repeating it. With AVX-512, the packet traversal's own loads
/// ([`PacketIsa::rays`]: six loads rearranged in registers for sixteen rays).
#[inline(always)]
pub fn ray_lanes(isa: Isa, rays: &[Ray]) -> [[f32; 16]; 6] {
    assert!(!rays.is_empty() && rays.len() <= 16);
    #[cfg(target_arch = "x86_64")]
    if let Isa::Avx512(k) = isa {
        // SAFETY: `k` proves the CPU runs AVX-512 F, DQ and VL, AVX2 and FMA.
        return unsafe { rays_avx512(k, rays) };
    }
    let _ = isa;
    let last = rays.len() - 1;
    let ray = |lane: usize| rays[lane.min(last)];
    let o = |c: usize| std::array::from_fn(|lane| ray(lane).origin[c]);
    let d = |c: usize| std::array::from_fn(|lane| ray(lane).direction[c]);
    [o(0), o(1), o(2), d(0), d(1), d(2)]
}

compiled!(Avx512:
/// [`ray_lanes`] with AVX-512.
#[inline]
fn rays_avx512(k: Avx512, rays: &[Ray]) -> [[f32; 16]; 6] {
    // SAFETY: an `Avx512F32` is an `__m512` (`repr(transparent)`), the same 64 bytes as
    // `[f32; 16]`.
    unsafe { std::mem::transmute::<[Avx512F32; 6], [[f32; 16]; 6]>(k.rays(rays)) }
});

/// Sixteen 3-vectors given as lanes (`x`, `y`, `z`) stored one after another into `out`, as
/// an array of `Vec3`: with AVX-512, six register permutes and three stores, where lane by lane
/// it is forty-eight scalar moves.
#[inline(always)]
pub fn store_vec3s(isa: Isa, x: &[f32; 16], y: &[f32; 16], z: &[f32; 16], out: &mut [Vec3; 16]) {
    #[cfg(target_arch = "x86_64")]
    if let Isa::Avx512(_) = isa {
        // SAFETY: `Isa::Avx512` exists only on a CPU with the features of `compiled!(Avx512)`.
        return unsafe { store_vec3s_avx512(x, y, z, out) };
    }
    let _ = isa;
    for (lane, v) in out.iter_mut().enumerate() {
        *v = Vec3::new(x[lane], y[lane], z[lane]);
    }
}

compiled!(Avx512:
/// [`store_vec3s`] with AVX-512. Float `f` of the output (`16k + p` of its vector `k`) is
/// component `f % 3` of vector `f / 3`: the first permute of each output vector picks the `x`
/// and `y` components from those two inputs, the second keeps them and picks `z`.
#[inline]
fn store_vec3s_avx512(x: &[f32; 16], y: &[f32; 16], z: &[f32; 16], out: &mut [Vec3; 16]) {
    use std::arch::x86_64::*;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Every kernel set puts the same rays in lanes, for every count.
    #[test]
    fn rays_in_lanes_are_the_rays() {
        let rays: Vec<Ray> = (0..16)
            .map(|i| {
                let f = i as f32;
                Ray::new(
                    Vec3::new(f, -f, 0.5 * f),
                    Vec3::new(1.0, f, -2.0 * f).normalize(),
                )
            })
            .collect();
        for isa in Isa::available() {
            for n in 1..=16 {
                let lanes = ray_lanes(isa, &rays[..n]);
                for lane in 0..16 {
                    let r = rays[lane.min(n - 1)];
                    let expected = [r.origin.to_array(), r.direction.to_array()].concat();
                    for c in 0..6 {
                        assert_eq!(lanes[c][lane].to_bits(), expected[c].to_bits(), "{isa:?}");
                    }
                }
            }
        }
    }

    /// Every kernel set stores the same sixteen vectors.
    #[test]
    fn stored_vectors_are_the_lanes() {
        let x: [f32; 16] = std::array::from_fn(|i| i as f32);
        let y: [f32; 16] = std::array::from_fn(|i| 100.0 + i as f32);
        let z: [f32; 16] = std::array::from_fn(|i| -0.5 * i as f32);
        for isa in Isa::available() {
            let mut out = [Vec3::splat(f32::NAN); 16];
            store_vec3s(isa, &x, &y, &z, &mut out);
            for (lane, v) in out.iter().enumerate() {
                assert_eq!(*v, Vec3::new(x[lane], y[lane], z[lane]), "{isa:?} {lane}");
            }
        }
    }

    /// Every kernel set picks the same entries of a table of 32.
    #[test]
    fn table_lanes_are_the_tables_entries() {
        let table: [f32; 32] = std::array::from_fn(|i| i as f32 * 1.5 - 7.0);
        let index: [u32; 16] = std::array::from_fn(|lane| (lane as u32 * 13 + 5) % 32);
        let lanes = 0b0111_1011_1110_1101;
        for isa in Isa::available() {
            let got = table_lanes(isa, &table, &index, lanes);
            for lane in 0..16 {
                let expected = match lanes & (1 << lane) {
                    0 => 0.0,
                    _ => table[index[lane] as usize],
                };
                assert_eq!(got[lane].to_bits(), expected.to_bits(), "{isa:?} {lane}");
            }
        }
    }
}

//! Sixteen values into SIMD lanes, or out of them, at once, for an integrator that holds
//! sixteen hits side by side ([`super::HitLanes`]): their rays ([`ray_lanes`]), each hit's
//! entry of a per-triangle table in a scene of at most 32 triangles ([`table_lanes`]), and
//! sixteen values stored back as `Vec3`s ([`store_vec3s`]). With AVX-512 or AVX2 each is a few
//! register operations (loads, permutes, shuffles, stores); elsewhere lane by lane. All give the
//! same values.
//!
//! Why: filled lane by lane, sixteen hits' fields went through the stack one `f32` at a time,
//! and the vector loads that then read them back waited for those stores (a store-forwarding
//! stall). Gathers avoid the stall but read each lane from memory one at a time, which is
//! slower still.

use glam::Vec3;

use super::Isa;
#[cfg(target_arch = "x86_64")]
use super::set::InstructionSet;
#[cfg(target_arch = "x86_64")]
use super::simd::Avx512;
#[cfg(target_arch = "x86_64")]
use super::x86_lanes;
use crate::base::geometry::Ray;
use crate::base::lanes::compiled;

/// The entries of a table of at most 32 at `index[i]` (its low five bits) for each lane set in
/// `lanes`, 0 in the others: one two-register permute with AVX-512, where a gather reads each
/// lane from memory.
#[inline(always)]
pub fn table_lanes(isa: Isa, table: &[f32; 32], index: &[u32; 16], lanes: u16) -> [f32; 16] {
    #[cfg(target_arch = "x86_64")]
    if let Isa::Avx512(_) = isa {
        // SAFETY: `Isa::Avx512` exists only on a CPU with the features `permute_avx512` is
        // compiled with; nothing is read from memory but `table` and `index`, whole.
        return unsafe { x86_lanes::permute_avx512(table, index, lanes) };
    }
    #[cfg(target_arch = "x86_64")]
    if let Isa::Avx2(_) = isa {
        // SAFETY: `Isa::Avx2` exists only on a CPU with the features `permute_avx2` is compiled
        // with; nothing is read from memory but `table` and `index`, whole.
        return unsafe { x86_lanes::permute_avx2(table, index, lanes) };
    }
    let _ = isa;
    std::array::from_fn(|lane| match lanes & (1 << lane) {
        0 => 0.0,
        _ => table[index[lane] as usize % 32],
    })
}

/// Up to sixteen rays in lanes: `[origin x, y, z, direction x, y, z]`, ray `i` in lane `i`,
/// the lanes past the last ray repeating it. With AVX-512, the packet traversal's own loads
/// ([`InstructionSet::rays`]: six loads rearranged in registers for sixteen rays).
#[inline(always)]
pub fn ray_lanes(isa: Isa, rays: &[Ray]) -> [[f32; 16]; 6] {
    assert!(!rays.is_empty() && rays.len() <= 16);
    #[cfg(target_arch = "x86_64")]
    if let Isa::Avx512(k) = isa {
        // SAFETY: `k` proves the CPU runs AVX-512 F, DQ and VL, AVX2 and FMA.
        return unsafe { rays_avx512(k, rays) };
    }
    #[cfg(target_arch = "x86_64")]
    if let (Isa::Avx2(k), Ok(rays)) = (isa, <&[Ray; 16]>::try_from(rays)) {
        // SAFETY: `k` proves the CPU runs AVX2 and FMA.
        return unsafe { x86_lanes::rays16_avx2(k, rays) };
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
    let lanes = k.rays(rays);
    let mut out = [[0.0; 16]; 6];
    for (out, &v) in out.iter_mut().zip(&lanes) {
        k.store(out, v);
    }
    out
});

/// Sixteen 3-vectors given as lanes (`x`, `y`, `z`) stored one after another into `out`, as
/// an array of `Vec3`: with AVX-512, six register permutes and three stores, where lane by lane
/// it is forty-eight scalar moves.
#[inline(always)]
pub fn store_vec3s(isa: Isa, x: &[f32; 16], y: &[f32; 16], z: &[f32; 16], out: &mut [Vec3; 16]) {
    #[cfg(target_arch = "x86_64")]
    if let Isa::Avx512(_) = isa {
        // SAFETY: `Isa::Avx512` exists only on a CPU with the features of `compiled!(Avx512)`.
        return unsafe { x86_lanes::store_vec3s_avx512(x, y, z, out) };
    }
    #[cfg(target_arch = "x86_64")]
    if let Isa::Avx2(_) = isa {
        // SAFETY: `Isa::Avx2` exists only on a CPU with the features of `compiled!(Avx2)`.
        return unsafe { x86_lanes::store_vec3s_avx2(x, y, z, out) };
    }
    let _ = isa;
    for (lane, v) in out.iter_mut().enumerate() {
        *v = Vec3::new(x[lane], y[lane], z[lane]);
    }
}

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

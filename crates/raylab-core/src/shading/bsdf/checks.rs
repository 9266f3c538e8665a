//! The BSDFs' tests' shared helpers: directions and numbers, reciprocity, the weight of a
//! sample against eval and pdf, Nori's χ² test of sampling against the pdf, quadratures over
//! the sphere and over microfacet normals (the white furnace's albedo).

use std::f64::consts::{FRAC_PI_2 as FRAC_PI_2_F64, TAU as TAU_F64};

use glam::{Vec2, Vec3};

use super::{Bsdf, BsdfSample, Ggx, flip_z};
use crate::base::sampling::{Rng, uniform_hemisphere};

/// The unit direction at polar angle `theta` and azimuth `phi` (radians), local frame.
pub(super) fn dir(theta: f32, phi: f32) -> Vec3 {
    let (sin_t, cos_t) = theta.sin_cos();
    let (sin_p, cos_p) = phi.sin_cos();
    Vec3::new(sin_t * cos_p, sin_t * sin_p, cos_t)
}

/// [`dir`] from angles in f64 (the quadratures' grids).
fn dir64(theta: f64, phi: f64) -> Vec3 {
    dir(theta as f32, phi as f32)
}

/// Two uniform numbers for [`Bsdf::sample`]'s `u`.
pub(super) fn u2(rng: &mut Rng) -> Vec2 {
    Vec2::new(rng.next_f32(), rng.next_f32())
}

/// A colour with three different channels, to catch a channel mixed up.
pub(super) const COLOUR: Vec3 = Vec3::new(0.9, 0.6, 0.3);

/// Whether `a` and `b` agree to `rel` relative to the larger (and 1e-12 absolute).
pub(super) fn close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + 1e-12
}

/// Whether every channel of `a` and `b` agrees to `rel` ([`close`]).
pub(super) fn close3(a: Vec3, b: Vec3, rel: f32) -> bool {
    (0..3).all(|i| close(a[i], b[i], rel))
}

/// Reciprocity (Helmholtz): f(wo, wi) = f(wi, wo) for 20,000 random pairs, a quarter of them
/// on opposite sides (f = 0 both ways) and a quarter both below (the two-sided mirror image),
/// to 1e-6 relative. Most pairs must be nonzero.
pub(super) fn assert_reciprocal(bsdf: Bsdf, rng: &mut Rng) {
    let mut nonzero = 0;
    for k in 0..20_000 {
        let mut wo = uniform_hemisphere(rng.next_f32(), rng.next_f32());
        let mut wi = uniform_hemisphere(rng.next_f32(), rng.next_f32());
        match k % 4 {
            0 => wi = flip_z(wi),
            1 => (wo, wi) = (flip_z(wo), flip_z(wi)),
            _ => {}
        }
        let (there, back) = (bsdf.eval(wo, wi), bsdf.eval(wi, wo));
        assert!(
            close3(there, back, 1e-6),
            "{bsdf:?} {wo} {wi}: {there} vs {back}"
        );
        assert!(there.is_finite() && there.min_element() >= 0.0);
        if k % 4 == 0 {
            assert_eq!(there, Vec3::ZERO, "opposite sides");
        } else if there.max_element() > 0.0 {
            nonzero += 1;
        }
    }
    assert!(nonzero > 14_000, "{bsdf:?}: {nonzero}");
}

/// One sample each for 1,000 random `wo` above the surface (below with `below`), none refused:
/// a white furnace's samples, for a BSDF that reflects everything and samples exactly.
pub(super) fn white_samples(bsdf: Bsdf, below: bool) -> Vec<BsdfSample> {
    let mut rng = Rng::new(5);
    (0..1000)
        .map(|_| {
            let mut wo = uniform_hemisphere(rng.next_f32(), rng.next_f32());
            if below {
                wo = flip_z(wo);
            }
            let uc = rng.next_f32();
            bsdf.sample(wo, uc, u2(&mut rng))
                .unwrap_or_else(|| panic!("{bsdf:?} {wo}: refused"))
        })
        .collect()
}

/// Every non-delta sample's weight is eval·|cos θ_i|/pdf and its pdf is [`Bsdf::pdf`]'s, to
/// 1e-3 relative (a sampled microfacet normal and the one recomputed from wo + wi differ by
/// rounding), wo from normal incidence to 89° and below the surface; reflections below the
/// horizon are refused, but most samples are taken.
pub(super) fn assert_sample_weights(bsdf: Bsdf, rng: &mut Rng) {
    let wos = [
        Vec3::Z,
        dir(0.5, 1.0),
        dir(1.3, 2.0),
        dir(89f32.to_radians(), 0.5),
        flip_z(dir(0.9, 3.0)),
    ];
    for wo in wos {
        let mut accepted = 0;
        for _ in 0..2_000 {
            let uc = rng.next_f32();
            let Some(s) = bsdf.sample(wo, uc, u2(rng)) else {
                continue;
            };
            accepted += 1;
            assert!(!s.is_delta && s.wi.z * wo.z > 0.0);
            let f = bsdf.eval(wo, s.wi);
            let pdf = bsdf.pdf(wo, s.wi);
            assert!(close(s.pdf, pdf, 1e-3), "{bsdf:?} {wo}: {} vs {pdf}", s.pdf);
            let expected = f * s.wi.z.abs() / pdf;
            assert!(
                close3(s.weight, expected, 1e-3),
                "{bsdf:?} {wo} {}: {} vs {expected}",
                s.wi,
                s.weight
            );
        }
        // Reflections below the horizon are refused: at normal incidence a share
        // α²/(1 + α²) of them (the rough conductor's pdf test), half at α = 1.
        assert!(accepted > 900, "{bsdf:?} {wo}: {accepted}");
    }
}

/// The 0.999 quantile of χ² with `k` degrees of freedom by Wilson and Hilferty's cube-root
/// approximation (1931): χ²_p ≈ k (1 − 2/(9k) + z_p √(2/(9k)))³ with z_0.999 = 3.090232,
/// the standard normal's 0.999 quantile. For k = 19 it gives 43.95 (exact 43.82), for
/// k = 99 148.29 (exact 148.23).
fn chi_square_quantile_999(k: usize) -> f64 {
    let k = k as f64;
    let c = 2.0 / (9.0 * k);
    k * (1.0 - c + 3.090_232 * c.sqrt()).powi(3)
}

/// Pearson's statistic Σ (O − E)²/E over `cells` of (expected, observed) counts, with the
/// cells expected fewer than 5 pooled, smallest first, until each pool expects at least 5
/// (as Nori's χ² test does); returns it and its degrees of freedom (cells − 1). A cell
/// observed but expected exactly 0 fails at once.
fn chi_square(mut cells: Vec<(f64, f64)>) -> (f64, usize) {
    for &(e, o) in &cells {
        assert!(
            !(e <= 0.0 && o > 0.0),
            "{o} samples where none were expected"
        );
    }
    cells.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut statistic, mut n) = (0.0, 0);
    let (mut pool_e, mut pool_o) = (0.0, 0.0);
    for (e, o) in cells {
        pool_e += e;
        pool_o += o;
        if pool_e >= 5.0 {
            statistic += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
            n += 1;
            (pool_e, pool_o) = (0.0, 0.0);
        }
    }
    if pool_e > 0.0 {
        statistic += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        n += 1;
    }
    (statistic, n - 1)
}

/// Nori-style χ² test of [`Bsdf::sample`] against [`Bsdf::pdf`] for `wo`: 200,000
/// samples into 10 θ bins over wo's hemisphere × 20 φ bins, plus one cell for the samples
/// refused (`None`). A bin's expected count is N × the pdf integrated over it by a 24 × 24
/// midpoint rule in (θ, φ) with dω = sin θ dθ dφ; the refusals' is N × (1 − the sum).
/// The statistic must be below the 0.999 quantile ([`chi_square_quantile_999`]).
pub(super) fn assert_sampling_matches_pdf(bsdf: Bsdf, wo: Vec3, seed: u64) {
    const THETA: usize = 10;
    const PHI: usize = 20;
    const SUB: usize = 24;
    const N: usize = 200_000;
    let below = wo.z < 0.0;
    let mut observed = vec![0.0f64; THETA * PHI + 1];
    let mut rng = Rng::new(seed);
    for _ in 0..N {
        let uc = rng.next_f32();
        match bsdf.sample(wo, uc, u2(&mut rng)) {
            None => observed[THETA * PHI] += 1.0,
            Some(s) => {
                assert!(!s.is_delta && s.pdf > 0.0);
                assert!((s.wi.length() - 1.0).abs() < 1e-4, "{}", s.wi);
                assert!(s.wi.z * wo.z > 0.0, "on the side of wo: {}", s.wi);
                let w = if below { flip_z(s.wi) } else { s.wi };
                let theta = f64::from(w.z.clamp(-1.0, 1.0)).acos();
                let phi = f64::from(w.y).atan2(f64::from(w.x)).rem_euclid(TAU_F64);
                let i = ((theta / FRAC_PI_2_F64 * THETA as f64) as usize).min(THETA - 1);
                let j = ((phi / TAU_F64 * PHI as f64) as usize).min(PHI - 1);
                observed[i * PHI + j] += 1.0;
            }
        }
    }
    let (d_theta, d_phi) = (FRAC_PI_2_F64 / THETA as f64, TAU_F64 / PHI as f64);
    let mut expected = vec![0.0f64; THETA * PHI + 1];
    for i in 0..THETA {
        for j in 0..PHI {
            let mut sum = 0.0;
            for a in 0..SUB {
                let theta = (i as f64 + (a as f64 + 0.5) / SUB as f64) * d_theta;
                for b in 0..SUB {
                    let phi = (j as f64 + (b as f64 + 0.5) / SUB as f64) * d_phi;
                    let w = dir64(theta, phi);
                    let w = if below { flip_z(w) } else { w };
                    sum += f64::from(bsdf.pdf(wo, w)) * theta.sin();
                }
            }
            expected[i * PHI + j] = sum * (d_theta / SUB as f64) * (d_phi / SUB as f64);
        }
    }
    let inside: f64 = expected.iter().sum();
    expected[THETA * PHI] = (1.0 - inside).max(0.0);
    let cells = expected
        .iter()
        .zip(&observed)
        .map(|(&e, &o)| (e * N as f64, o))
        .collect();
    let (statistic, dof) = chi_square(cells);
    let limit = chi_square_quantile_999(dof);
    assert!(
        statistic < limit,
        "{bsdf:?} wo {wo}: χ² = {statistic:.1} with {dof} dof, limit {limit:.1}"
    );
}

/// ∫ g(ω) dω over the sphere, or over the upper hemisphere with `upper_only`, by the
/// midpoint rule in (θ, φ) with dω = sin θ dθ dφ, in f64.
pub(super) fn integrate(
    g: impl Fn(Vec3) -> f64,
    upper_only: bool,
    n_theta: usize,
    n_phi: usize,
) -> f64 {
    let top = if upper_only {
        FRAC_PI_2_F64
    } else {
        std::f64::consts::PI
    };
    let (d_theta, d_phi) = (top / n_theta as f64, TAU_F64 / n_phi as f64);
    let mut sum = 0.0;
    for i in 0..n_theta {
        let theta = (i as f64 + 0.5) * d_theta;
        let mut ring = 0.0;
        for j in 0..n_phi {
            ring += g(dir64(theta, (j as f64 + 0.5) * d_phi));
        }
        sum += ring * theta.sin();
    }
    sum * d_theta * d_phi
}

/// The rough conductor's directional albedo ∫ f(wo, wi) cos θ_i dω_i over the upper
/// hemisphere, integrated over microfacet normals rather than directions, where D's peak
/// makes no trouble: with wi the mirror direction of wo about h, dω_i = 4 (wo·h) dω_h, and
/// with ξ defined by tan²θ_h = α² ξ/(1 − ξ) (the GGX normals' own distribution),
/// D(h) cos θ_h dω_h = dξ dφ/(2π). So the albedo is the mean over (ξ, φ) ∈ [0,1)×[0,2π)
/// of f·cos θ_i·4 (wo·h)/(D(h) cos θ_h), by a 600 × 600 midpoint rule.
pub(super) fn rough_albedo(bsdf: Bsdf, alpha: f32, wo: Vec3) -> f64 {
    const N: usize = 600;
    let ggx = Ggx::new(alpha);
    let a2 = f64::from(ggx.alpha * ggx.alpha);
    let mut sum = 0.0;
    for i in 0..N {
        let xi = (i as f64 + 0.5) / N as f64;
        let theta = (a2 * xi / (1.0 - xi)).sqrt().atan();
        for j in 0..N {
            let h = dir64(theta, (j as f64 + 0.5) / N as f64 * TAU_F64);
            let wo_h = wo.dot(h);
            let wi = 2.0 * wo_h * h - wo;
            if wo_h <= 0.0 || wi.z <= 0.0 {
                continue;
            }
            let f = f64::from(bsdf.eval(wo, wi).x);
            let jacobian = 4.0 * f64::from(wo_h) / f64::from(ggx.d(h) * h.z);
            sum += f * f64::from(wi.z) * jacobian;
        }
    }
    sum / (N * N) as f64
}

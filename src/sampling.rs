//! Deterministic random numbers for Monte Carlo sampling.
//!
//! As in pbrt, every random number a pixel sample uses comes from a generator started from
//! `(seed, pixel, sample index)` alone: any pixel of any pass can be re-rendered by itself, and
//! the image is the same whatever the number of threads or the order rows are traced in.

/// A small, fast generator (PCG-XSH-RR 32 on a 64-bit state).
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
}

const PCG_MULTIPLIER: u64 = 6_364_136_223_846_793_005;
const PCG_INCREMENT: u64 = 1_442_695_040_888_963_407;

/// SplitMix64's finaliser: mixes the bits of `x` thoroughly, so nearby inputs (neighbouring
/// pixels, consecutive sample indices) start unrelated streams.
fn mix64(mut x: u64) -> u64 {
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

impl Rng {
    /// A placeholder for a slot whose generator is never drawn from (the lab stages draw
    /// nothing); cheaper than seeding one.
    pub const UNUSED: Rng = Rng { state: 0 };

    pub fn new(seed: u64) -> Self {
        let mut rng = Self {
            state: mix64(seed).wrapping_add(PCG_INCREMENT),
        };
        rng.next_u32();
        rng
    }

    /// The generator for one sample of one pixel.
    pub fn for_pixel_sample(seed: u64, x: u32, y: u32, sample: u32) -> Self {
        let pixel = (u64::from(y) << 32) | u64::from(x);
        Self::new(mix64(seed ^ mix64(pixel)) ^ u64::from(sample).wrapping_mul(PCG_MULTIPLIER))
    }

    #[inline(always)]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(PCG_MULTIPLIER).wrapping_add(PCG_INCREMENT);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1): the top 24 bits, so every value is exactly representable and 1.0 is
    /// never returned.
    #[inline(always)]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }
}

/// Where in pixel `(x, y)` sample `sample` looks, as an offset in [0, 1)² from its top-left
/// corner. Sample 0 is the pixel centre, so a one-sample render is exactly the lab's image;
/// later samples are uniformly jittered and average to an anti-aliased pixel.
pub fn pixel_offset(seed: u64, x: u32, y: u32, sample: u32) -> (f32, f32) {
    if sample == 0 {
        return (0.5, 0.5);
    }
    pixel_sample(seed, x, y, sample).0
}

/// [`pixel_offset`] and the generator the rest of the sample draws from (the path tracer's
/// bounces), positioned after the jitter: one stream per (seed, pixel, sample), so any pixel
/// can be recomputed exactly on its own.
pub fn pixel_sample(seed: u64, x: u32, y: u32, sample: u32) -> ((f32, f32), Rng) {
    let mut rng = Rng::for_pixel_sample(seed, x, y, sample);
    if sample == 0 {
        return ((0.5, 0.5), rng);
    }
    let offset = (rng.next_f32(), rng.next_f32());
    (offset, rng)
}

/// A direction on the hemisphere around +z with density cos θ / π (Malley's method: a uniform
/// point on the unit disk, lifted onto the hemisphere), from two uniform numbers in [0, 1).
///
/// For a diffuse surface this density is proportional to what the rendering equation weighs
/// each direction by, so a sample's weight is the constant ρ (see [`crate::material`]).
pub fn cosine_hemisphere(u1: f32, u2: f32) -> glam::Vec3 {
    let r = u1.sqrt();
    let phi = 2.0 * std::f32::consts::PI * u2;
    let (sin, cos) = phi.sin_cos();
    glam::Vec3::new(r * cos, r * sin, (1.0 - u1).max(0.0).sqrt())
}

/// [`cosine_hemisphere`]'s density without its sine and cosine: a point uniform in the unit
/// disk by rejection from the square around it (π/4 of the tries are kept, so 2.5 numbers are
/// drawn on average), lifted onto the hemisphere. The path tracer's diffuse bounces use it:
/// it is faster, and exactly as cosine-distributed.
#[inline(always)]
pub fn cosine_hemisphere_by_rejection(rng: &mut Rng) -> glam::Vec3 {
    loop {
        let x = 2.0 * rng.next_f32() - 1.0;
        let y = 2.0 * rng.next_f32() - 1.0;
        let r2 = x * x + y * y;
        if r2 < 1.0 {
            return glam::Vec3::new(x, y, (1.0 - r2).sqrt());
        }
    }
}

/// A direction on the hemisphere around +z with constant density 1 / (2π).
pub fn uniform_hemisphere(u1: f32, u2: f32) -> glam::Vec3 {
    let z = u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u2;
    let (sin, cos) = phi.sin_cos();
    glam::Vec3::new(r * cos, r * sin, z)
}

/// A direction uniformly distributed over the cone of directions within angle θmax of +z
/// (density 1 / (2π(1 − cos θmax))), from two uniform numbers: cos θ = 1 − u1·(1 − cos θmax).
/// A sphere seen from outside fills such a cone; sampling it picks points of the sphere's
/// visible cap in proportion to the solid angle they cover.
#[inline(always)]
pub fn uniform_cone(u1: f32, u2: f32, cos_max: f32) -> glam::Vec3 {
    let z = 1.0 - u1 * (1.0 - cos_max);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u2;
    let (sin, cos) = phi.sin_cos();
    glam::Vec3::new(r * cos, r * sin, z)
}

/// A point uniformly distributed on the unit disk, from two uniform numbers, by Shirley and
/// Chiu's concentric map ("A Low Distortion Map Between Disk and Square", 1997): squares map to
/// rings, so stratified numbers stay well spread on the disk. The thin-lens camera's aperture
/// is sampled with it.
pub fn concentric_disk(u1: f32, u2: f32) -> glam::Vec2 {
    let a = 2.0 * u1 - 1.0;
    let b = 2.0 * u2 - 1.0;
    if a == 0.0 && b == 0.0 {
        return glam::Vec2::ZERO;
    }
    let quarter = std::f32::consts::FRAC_PI_4;
    let (r, phi) = if a.abs() > b.abs() {
        (a, quarter * (b / a))
    } else {
        (b, 2.0 * quarter - quarter * (a / b))
    };
    let (sin, cos) = phi.sin_cos();
    glam::Vec2::new(r * cos, r * sin)
}

/// Two unit vectors that make a right-handed orthonormal basis with the unit vector `n`
/// (Duff et al., "Building an Orthonormal Basis, Revisited", 2017: no branch on a near-axis
/// `n` apart from its sign).
#[inline(always)]
pub fn orthonormal_basis(n: glam::Vec3) -> (glam::Vec3, glam::Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        glam::Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        glam::Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_stream() {
        let a: Vec<u32> = (0..8)
            .scan(Rng::new(42), |r, _| Some(r.next_u32()))
            .collect();
        let b: Vec<u32> = (0..8)
            .scan(Rng::new(42), |r, _| Some(r.next_u32()))
            .collect();
        let c: Vec<u32> = (0..8)
            .scan(Rng::new(43), |r, _| Some(r.next_u32()))
            .collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn first_sample_is_the_pixel_centre_and_later_ones_jitter() {
        assert_eq!(pixel_offset(1, 10, 20, 0), (0.5, 0.5));
        let (a, b) = pixel_offset(1, 10, 20, 1);
        assert!((0.0..1.0).contains(&a) && (0.0..1.0).contains(&b));
        assert_ne!(pixel_offset(1, 10, 20, 1), pixel_offset(1, 10, 20, 2));
        assert_ne!(pixel_offset(1, 10, 20, 1), pixel_offset(1, 11, 20, 1));
        assert_eq!(pixel_offset(1, 10, 20, 3), pixel_offset(1, 10, 20, 3));
    }

    /// The jitter covers the pixel evenly: 10 × 10 cells, 100,000 samples over many pixels and
    /// sample indices. With 99 degrees of freedom the 99.9% quantile of χ² is 148.2.
    #[test]
    fn pixel_offsets_are_uniform_by_chi_squared() {
        let mut cells = [0u32; 100];
        let mut n = 0;
        for sample in 1..=40 {
            for y in 0..50 {
                for x in 0..50 {
                    let (u, v) = pixel_offset(7, x, y, sample);
                    assert!((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v));
                    cells[(v * 10.0) as usize * 10 + (u * 10.0) as usize] += 1;
                    n += 1;
                }
            }
        }
        let expected = n as f64 / 100.0;
        let chi2: f64 = cells
            .iter()
            .map(|&o| (o as f64 - expected).powi(2) / expected)
            .sum();
        assert!(chi2 < 148.2, "chi² = {chi2}");
    }

    #[test]
    fn pixel_sample_continues_the_jitters_stream() {
        for sample in [0, 1, 7] {
            let (offset, mut rng) = pixel_sample(3, 4, 5, sample);
            assert_eq!(offset, pixel_offset(3, 4, 5, sample));
            let mut again = Rng::for_pixel_sample(3, 4, 5, sample);
            if sample > 0 {
                again.next_u32();
                again.next_u32();
            }
            assert_eq!(rng.next_u32(), again.next_u32());
        }
    }

    #[test]
    fn bases_are_orthonormal() {
        let mut rng = Rng::new(11);
        for _ in 0..1000 {
            let n = glam::Vec3::new(
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
            )
            .normalize();
            let (t, b) = orthonormal_basis(n);
            for (p, q) in [(t, b), (t, n), (b, n)] {
                assert!(p.dot(q).abs() < 1e-5);
            }
            assert!((t.length() - 1.0).abs() < 1e-5 && (b.length() - 1.0).abs() < 1e-5);
            assert!((t.cross(b) - n).length() < 1e-5, "right-handed");
        }
        let (t, b) = orthonormal_basis(-glam::Vec3::Z);
        assert!(t.is_finite() && b.is_finite());
    }

    /// Cosine-weighted directions by χ², both ways of drawing them: with density cos θ/π,
    /// P(cos θ ≤ c) = c², so the 20 bins of c² = cos²θ are equally likely; φ's 20 bins too.
    #[test]
    fn cosine_hemisphere_is_cosine_distributed_by_chi_squared() {
        let mut rng = Rng::new(77);
        let n: i32 = 100_000;
        for rejection in [false, true] {
            let (mut by_cos, mut by_phi) = ([0u32; 20], [0u32; 20]);
            for _ in 0..n {
                let d = if rejection {
                    cosine_hemisphere_by_rejection(&mut rng)
                } else {
                    cosine_hemisphere(rng.next_f32(), rng.next_f32())
                };
                assert!(d.z >= 0.0 && (d.length() - 1.0).abs() < 1e-5);
                by_cos[((d.z * d.z) * 20.0).min(19.0) as usize] += 1;
                let phi = d.y.atan2(d.x).rem_euclid(std::f32::consts::TAU);
                by_phi[(phi / std::f32::consts::TAU * 20.0).min(19.0) as usize] += 1;
            }
            for bins in [by_cos, by_phi] {
                let expected = n as f64 / 20.0;
                let chi2: f64 = bins
                    .iter()
                    .map(|&o| (o as f64 - expected).powi(2) / expected)
                    .sum();
                // 19 degrees of freedom: the 99.9% quantile is 43.8.
                assert!(chi2 < 43.8, "chi² = {chi2} (rejection: {rejection})");
            }
        }
    }

    /// A chi-squared test of uniformity (Nori's statistical tests): 100,000 draws into 20 bins.
    /// With 19 degrees of freedom the 99.9% quantile is 43.8; the stream is fixed by its seed,
    /// so this is deterministic.
    #[test]
    fn next_f32_is_uniform_by_chi_squared() {
        let mut rng = Rng::new(2024);
        let n: i32 = 100_000;
        let mut bins = [0u32; 20];
        for _ in 0..n {
            let x = rng.next_f32();
            assert!((0.0..1.0).contains(&x));
            bins[(x * 20.0) as usize] += 1;
        }
        let expected = n as f64 / 20.0;
        let chi2: f64 = bins
            .iter()
            .map(|&o| (o as f64 - expected).powi(2) / expected)
            .sum();
        assert!(chi2 < 43.8, "chi² = {chi2}");
    }

    /// The cone sampler stays inside its cone and covers it evenly: the share of samples within
    /// half the cone's solid angle is 1/2. For θmax = 30°, 1 − cos θmax = 0.133975; half of it,
    /// 0.0669873, is the cap up to cos θ = 0.9330127 (θ = 21.1°).
    #[test]
    fn cone_samples_fill_the_cone_evenly() {
        let cos_max = 30f32.to_radians().cos();
        let mut rng = Rng::new(9);
        let n: i32 = 100_000;
        let mut inner: i32 = 0;
        for _ in 0..n {
            let d = uniform_cone(rng.next_f32(), rng.next_f32(), cos_max);
            assert!((d.length() - 1.0).abs() < 1e-5);
            assert!(d.z >= cos_max - 1e-6, "{d}");
            if d.z >= 0.933_012_7 {
                inner += 1;
            }
        }
        // Binomial, p = 1/2: standard deviation 158 of 100,000; 4σ.
        assert!((inner - n / 2).abs() < 632, "{inner}");
        // cos θmax = 1 is a single direction, +z.
        assert_eq!(uniform_cone(0.3, 0.7, 1.0), glam::Vec3::Z);
    }

    /// The concentric map keeps points in the unit disk, maps the square's centre to the disk's
    /// centre and its edge midpoints to the circle, and is uniform: a quarter of the points fall
    /// within radius 1/2.
    #[test]
    fn concentric_disk_is_uniform_on_the_disk() {
        assert_eq!(concentric_disk(0.5, 0.5), glam::Vec2::ZERO);
        let right = concentric_disk(1.0, 0.5);
        assert!((right - glam::Vec2::X).length() < 1e-6, "{right}");
        let top = concentric_disk(0.5, 1.0);
        assert!((top - glam::Vec2::Y).length() < 1e-6, "{top}");
        let mut rng = Rng::new(3);
        let n: i32 = 100_000;
        let mut inner: i32 = 0;
        for _ in 0..n {
            let p = concentric_disk(rng.next_f32(), rng.next_f32());
            assert!(p.length() <= 1.0 + 1e-6);
            if p.length() < 0.5 {
                inner += 1;
            }
        }
        // Binomial, p = 1/4: standard deviation 137 of 100,000; 4σ.
        assert!((inner - n / 4).abs() < 548, "{inner}");
    }
}

//! Deterministic random numbers for Monte Carlo sampling.
//!
//! As in pbrt, every random number a pixel sample uses comes from a generator started from
//! `(seed, pixel, sample index)` alone: any pixel of any pass can be re-rendered by itself, and
//! the image is the same whatever the number of threads or the order rows are traced in.

use crate::base::lanes::{F32x16, LANES, M16, Mask, MaskOf, Real, Vector};

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
        let (state, out) = pcg_step(self.state);
        self.state = state;
        out
    }

    /// Uniform in [0, 1): the top 24 bits, so every value is exactly representable and 1.0 is
    /// never returned.
    #[inline(always)]
    pub fn next_f32(&mut self) -> f32 {
        unit_f32(self.next_u32())
    }

    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }
}

/// One step of PCG-XSH-RR: the next state and the output of this one.
#[inline(always)]
fn pcg_step(old: u64) -> (u64, u32) {
    let state = old.wrapping_mul(PCG_MULTIPLIER).wrapping_add(PCG_INCREMENT);
    let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
    let rot = (old >> 59) as u32;
    (state, xorshifted.rotate_right(rot))
}

/// [`Rng::next_f32`]'s number from a generator's output.
#[inline(always)]
fn unit_f32(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Uniform numbers for one lane or sixteen: [`Rng`] for one, [`Rng16`] for sixteen.
pub trait Uniform<R: Real> {
    /// [`Rng::next_f32`] in the lanes where `wanted` holds; the other lanes draw nothing (and
    /// hold 0).
    fn draw(&mut self, wanted: R::Mask) -> R;
}

impl Uniform<f32> for Rng {
    #[inline(always)]
    fn draw(&mut self, wanted: bool) -> f32 {
        if wanted { self.next_f32() } else { 0.0 }
    }
}

/// Sixteen generators side by side, one a lane, each drawing exactly the numbers it would
/// draw alone ([`Rng`]): the path tracer's vertices draw their bounces and roulette sixteen
/// paths at a time. The generators are copied in and back out ([`Rng16::set`],
/// [`Rng16::get`]).
#[derive(Clone, Copy, Debug)]
pub struct Rng16 {
    state: [u64; LANES],
}

impl Rng16 {
    pub const UNUSED: Self = Self { state: [0; LANES] };

    /// Lane `i` becomes `rng`.
    #[inline(always)]
    pub fn set(&mut self, i: usize, rng: &Rng) {
        self.state[i] = rng.state;
    }

    /// The generator of lane `i`, as far as it has drawn.
    #[inline(always)]
    pub fn get(&self, i: usize) -> Rng {
        Rng {
            state: self.state[i],
        }
    }
}

impl Uniform<F32x16> for Rng16 {
    // The index walks the state, mask and output arrays in step: the form LLVM vectorises.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn draw(&mut self, wanted: M16) -> F32x16 {
        // Every lane steps (one vector step); the lanes not wanted keep their state and draw
        // 0. A plain loop over the arrays: LLVM vectorises it (through `array::from_fn` and its
        // closure it did not, quite).
        let mut out = [0.0; LANES];
        // The new states go into a copy stored whole: stored lane by lane under the mask (as
        // LLVM made the update in place), the next draw's load of the states waited for it.
        let mut next = [0; LANES];
        #[allow(clippy::needless_range_loop)] // four arrays indexed alike: the vectorised form
        for i in 0..LANES {
            let (state, bits) = pcg_step(self.state[i]);
            let wanted = wanted.0[i];
            next[i] = if wanted { state } else { self.state[i] };
            out[i] = if wanted { unit_f32(bits) } else { 0.0 };
        }
        self.state = next;
        F32x16(out)
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
/// each direction by, so a sample's weight is the constant ρ (see [`crate::shading::material`]).
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
///
/// Generic over [`Uniform`]: one direction (`rng` an [`Rng`], `wanted` true), or sixteen
/// ([`Rng16`]: each lane draws until its own point falls inside, exactly the numbers it would
/// draw alone). The lanes not `wanted` draw nothing and hold 0.
#[inline(always)]
pub fn cosine_hemisphere_by_rejection<V: Vector>(
    rng: &mut impl Uniform<V::Real>,
    wanted: MaskOf<V>,
) -> V {
    let (one, two) = (V::Real::splat(1.0), V::Real::splat(2.0));
    let mut todo = wanted;
    let mut local = V::ZERO;
    while todo.any() {
        let x = two * rng.draw(todo) - one;
        let y = two * rng.draw(todo) - one;
        let r2 = x * x + y * y;
        let inside = todo & r2.simd_lt(one);
        local = V::select(inside, V::new(x, y, (one - r2).sqrt()), local);
        todo = todo & !inside;
    }
    local
}

/// A direction on the whole unit sphere with constant density 1 / (4π): cos θ = 1 − 2·u1 is
/// uniform in [−1, 1] (Archimedes: equal heights cut equal areas), φ = 2π·u2.
pub fn uniform_sphere(u1: f32, u2: f32) -> glam::Vec3 {
    let z = 1.0 - 2.0 * u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u2;
    let (sin, cos) = phi.sin_cos();
    glam::Vec3::new(r * cos, r * sin, z)
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
/// `n` apart from its sign). Generic over [`Vector`]: one normal, or sixteen side by side (the
/// path tracer's vertices), the same bits.
#[inline(always)]
pub fn orthonormal_basis<V: Vector>(n: V) -> (V, V) {
    let (x, y, z) = (n.x(), n.y(), n.z());
    let one = V::Real::splat(1.0);
    let sign = one.copysign(z);
    let a = V::Real::splat(-1.0) / (sign + z);
    let b = x * y * a;
    (
        V::new(one + sign * x * x * a, sign * b, -sign * x),
        V::new(b, sign + y * y * a, -y),
    )
}

/// `local`, a direction in the frame where `normal` is +z (as [`cosine_hemisphere`] and
/// [`cosine_hemisphere_by_rejection`] give them), in the scene's frame
/// ([`orthonormal_basis`]). Unit length up to rounding: the basis is orthonormal and `local` a
/// unit vector, so no normalisation (a square root and a division) is needed.
#[inline(always)]
pub fn hemisphere_around<V: Vector>(normal: V, local: V) -> V {
    let (t, b) = orthonormal_basis(normal);
    t * local.x() + b * local.y() + normal * local.z()
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

    /// A unit vector from a point uniform in the cube [-1, 1)³.
    fn random_direction(rng: &mut Rng) -> glam::Vec3 {
        glam::Vec3::new(
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
        )
        .normalize()
    }

    #[test]
    fn bases_are_orthonormal() {
        let mut rng = Rng::new(11);
        for _ in 0..1000 {
            let n = random_direction(&mut rng);
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
                    cosine_hemisphere_by_rejection(&mut rng, true)
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
    /// Sixteen random masks, one a round.
    fn masks(rng: &mut Rng, rounds: usize) -> Vec<M16> {
        (0..rounds)
            .map(|_| M16::from_bits(rng.next_u32() as u16))
            .collect()
    }

    /// Sixteen generators, alone and side by side in an [`Rng16`].
    fn sixteen_generators(seed: u64) -> (Vec<Rng>, Rng16) {
        let alone: Vec<Rng> = (0..16).map(|i| Rng::new(seed + i)).collect();
        let mut lanes = Rng16::UNUSED;
        for (i, rng) in alone.iter().enumerate() {
            lanes.set(i, rng);
        }
        (alone, lanes)
    }

    /// Each lane of [`Rng16`] draws what its generator draws alone, and only where wanted.
    #[test]
    fn sixteen_generators_draw_what_each_draws_alone() {
        let (mut alone, mut lanes) = sixteen_generators(1000);
        for wanted in masks(&mut Rng::new(5), 200) {
            let drawn = lanes.draw(wanted);
            for (i, rng) in alone.iter_mut().enumerate() {
                let expected = rng.draw(wanted.0[i]);
                assert_eq!(drawn.0[i].to_bits(), expected.to_bits(), "lane {i}");
            }
        }
        for (i, rng) in alone.iter_mut().enumerate() {
            assert_eq!(
                lanes.get(i).next_u32(),
                rng.next_u32(),
                "lane {i} ends where it would"
            );
        }
    }

    /// Directions by rejection sixteen at a time: each lane the very direction, and the very
    /// numbers drawn, of its generator alone; lanes not wanted draw nothing.
    #[test]
    fn cosine_directions_sixteen_at_a_time_equal_one_at_a_time() {
        let (mut alone, mut lanes) = sixteen_generators(77);
        for wanted in masks(&mut Rng::new(6), 500) {
            let local: crate::base::lanes::Vec3x16 =
                cosine_hemisphere_by_rejection(&mut lanes, wanted);
            for (i, rng) in alone.iter_mut().enumerate() {
                let expected = if wanted.0[i] {
                    cosine_hemisphere_by_rejection(rng, true)
                } else {
                    glam::Vec3::ZERO
                };
                assert_eq!(
                    local.lane(i).to_array().map(f32::to_bits),
                    expected.to_array().map(f32::to_bits)
                );
            }
        }
        for (i, rng) in alone.iter_mut().enumerate() {
            assert_eq!(lanes.get(i).next_u32(), rng.next_u32(), "lane {i}");
        }
    }

    /// The basis and [`hemisphere_around`] for sixteen normals at a time, bit for bit one at a
    /// time, including normals along ±z and with a negative zero.
    #[test]
    fn bases_sixteen_at_a_time_equal_one_at_a_time() {
        use crate::base::lanes::Vec3x16;
        let mut rng = Rng::new(12);
        let special = [
            glam::Vec3::Z,
            -glam::Vec3::Z,
            glam::Vec3::new(0.0, 0.0, -0.0),
            glam::Vec3::new(1.0, 0.0, -0.0),
            glam::Vec3::X,
            -glam::Vec3::Y,
        ];
        for round in 0..200 {
            let (mut normals, mut locals) = (Vec3x16::ZERO, Vec3x16::ZERO);
            for i in 0..16 {
                let random = random_direction(&mut rng);
                let n = if round == 0 && i < special.len() {
                    special[i]
                } else {
                    random
                };
                normals.set_lane(i, n);
                locals.set_lane(i, cosine_hemisphere_by_rejection(&mut rng, true));
            }
            let (t, b) = orthonormal_basis(normals);
            let around = hemisphere_around(normals, locals);
            for i in 0..16 {
                let bits = |v: glam::Vec3| v.to_array().map(f32::to_bits);
                let (t1, b1) = orthonormal_basis(normals.lane(i));
                assert_eq!((bits(t.lane(i)), bits(b.lane(i))), (bits(t1), bits(b1)));
                let one = hemisphere_around(normals.lane(i), locals.lane(i));
                assert_eq!(bits(around.lane(i)), bits(one));
            }
        }
    }
}

//! Noise for fractal geometry and textures (the lab's extension "using fractals to
//! automatically generate geometry and textures for mountains, clouds and water"): a lattice
//! hash, value noise, Perlin's gradient noise, and fractional Brownian motion (fBm) — octaves
//! of noise, each `lacunarity` times finer and `gain` times weaker than the last.
//!
//! The same seed gives the same values on every machine, bit for bit: the lattice is an
//! integer hash, and the rest is f32 addition, subtraction, multiplication and `floor`, each
//! correctly rounded by IEEE 754 (no transcendental functions, whose last bit differs between
//! libraries, and no fused multiply-adds, which Rust never forms on its own).

use glam::Vec2;

/// A 64-bit hash of a lattice point (splitmix64's finaliser over the mixed coordinates).
#[inline]
pub fn hash2(seed: u64, x: i64, z: i64) -> u64 {
    let mut h = seed ^ (x as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    h ^= (z as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f);
    h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^ (h >> 31)
}

/// Uniform in [0, 1) from a lattice point: 24 bits of its hash, so any point can be evaluated
/// alone.
#[inline]
pub fn lattice(seed: u64, x: i64, z: i64) -> f32 {
    (hash2(seed, x, z) >> 40) as f32 / (1u64 << 24) as f32
}

/// 3t² − 2t³: value noise's blend, flat at both ends.
#[inline]
fn smooth(t: f32) -> f32 {
    t * t * (3.0 - 2.0 * t)
}

/// 6t⁵ − 15t⁴ + 10t³: Perlin's improved blend, whose second derivative vanishes at the
/// lattice too, so the noise's normals have no creases along the cell borders.
#[inline]
fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

/// Smoothly interpolated value noise in [0, 1): the lattice's values blended across each cell.
pub fn value_noise(seed: u64, x: f32, z: f32) -> f32 {
    let (xf, zf) = (x.floor(), z.floor());
    let (xi, zi) = (xf as i64, zf as i64);
    let (sx, sz) = (smooth(x - xf), smooth(z - zf));
    let a = lattice(seed, xi, zi);
    let b = lattice(seed, xi + 1, zi);
    let c = lattice(seed, xi, zi + 1);
    let d = lattice(seed, xi + 1, zi + 1);
    let top = a + (b - a) * sx;
    let bottom = c + (d - c) * sx;
    top + (bottom - top) * sz
}

/// The gradient at a lattice point: one of the eight directions (±1, 0), (0, ±1), (±1, ±1),
/// chosen by its hash.
#[inline]
fn gradient(seed: u64, x: i64, y: i64) -> Vec2 {
    const G: [Vec2; 8] = [
        Vec2::new(1.0, 0.0),
        Vec2::new(-1.0, 0.0),
        Vec2::new(0.0, 1.0),
        Vec2::new(0.0, -1.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(-1.0, 1.0),
        Vec2::new(1.0, -1.0),
        Vec2::new(-1.0, -1.0),
    ];
    G[(hash2(seed, x, y) >> 61) as usize]
}

/// Perlin's gradient noise at `p`: 0 at every lattice point, within [−1, 1] elsewhere (each
/// corner's gradient dotted with the offset to it, blended with [`fade`]).
pub fn perlin(seed: u64, p: Vec2) -> f32 {
    let f = p.floor();
    let (xi, yi) = (f.x as i64, f.y as i64);
    let d = p - f;
    let corner = |cx: i64, cy: i64| {
        let g = gradient(seed, xi + cx, yi + cy);
        g.x * (d.x - cx as f32) + g.y * (d.y - cy as f32)
    };
    let (u, v) = (fade(d.x), fade(d.y));
    let bottom = corner(0, 0) + (corner(1, 0) - corner(0, 0)) * u;
    let top = corner(0, 1) + (corner(1, 1) - corner(0, 1)) * u;
    bottom + (top - bottom) * v
}

/// [`perlin`] that repeats every `period` lattice cells in x and y (the lattice's
/// coordinates taken modulo the period): a tile whose copies meet without a seam.
pub fn perlin_periodic(seed: u64, p: Vec2, period: i64) -> f32 {
    let period = period.max(1);
    let f = p.floor();
    let (xi, yi) = (f.x as i64, f.y as i64);
    let d = p - f;
    let corner = |cx: i64, cy: i64| {
        let g = gradient(
            seed,
            (xi + cx).rem_euclid(period),
            (yi + cy).rem_euclid(period),
        );
        g.x * (d.x - cx as f32) + g.y * (d.y - cy as f32)
    };
    let (u, v) = (fade(d.x), fade(d.y));
    let bottom = corner(0, 0) + (corner(1, 0) - corner(0, 0)) * u;
    let top = corner(0, 1) + (corner(1, 1) - corner(0, 1)) * u;
    bottom + (top - bottom) * v
}

/// Fractional Brownian motion: `octaves` octaves of [`perlin`] noise, octave k at frequency
/// lacunarityᵏ with amplitude gainᵏ, each with its own seed, normalised by the sum of the
/// amplitudes so the result stays within [−1, 1].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Fbm {
    pub seed: u64,
    pub octaves: u32,
    /// How much finer each octave is than the last (2: an octave in the musical sense).
    pub lacunarity: f32,
    /// How much weaker each octave is than the last (0.5: the classic 1/f spectrum).
    pub gain: f32,
}

impl Default for Fbm {
    fn default() -> Self {
        Self {
            seed: 1,
            octaves: 6,
            lacunarity: 2.0,
            gain: 0.5,
        }
    }
}

/// The most octaves an fBm may sum (finer ones are far below a pixel).
pub const MAX_OCTAVES: u32 = 16;

impl Fbm {
    /// The noise at `p`, in [−1, 1].
    pub fn at(&self, p: Vec2) -> f32 {
        self.sum_octaves(|_, seed, frequency| perlin(seed, p * frequency))
    }

    /// The octaves' weighted sum over the sum of their weights: `octave(k, seed, frequency)`
    /// is octave k's noise (its own seed; amplitude gainᵏ, frequency lacunarityᵏ). What every
    /// fBm here is; only the noise of an octave differs.
    fn sum_octaves(&self, mut octave: impl FnMut(u32, u64, f32) -> f32) -> f32 {
        let (mut sum, mut norm) = (0.0, 0.0);
        let (mut amplitude, mut frequency) = (1.0f32, 1.0f32);
        for k in 0..self.octaves.clamp(1, MAX_OCTAVES) {
            let seed = self
                .seed
                .wrapping_add(u64::from(k).wrapping_mul(0x632b_e59b_d9b4_e019));
            sum += amplitude * octave(k, seed, frequency);
            norm += amplitude;
            amplitude *= self.gain;
            frequency *= self.lacunarity;
        }
        if norm > 0.0 { sum / norm } else { 0.0 }
    }

    /// The noise at `p` in [0, 1)² of a tile that repeats with period 1, octave k drifting by
    /// `drift[k % 4] · time` (each octave along its own direction, so the pattern changes as
    /// it moves, as waves do): every octave is [`perlin_periodic`] with `cells · ⌊lacunarityᵏ⌉`
    /// lattice cells across the tile, so the lacunarity is rounded to whole numbers of cells.
    pub fn tile_at(&self, p: Vec2, cells: u32, time: f32, drift: [Vec2; 4]) -> f32 {
        self.sum_octaves(|k, seed, frequency| {
            let n = (cells as f32 * frequency).round().max(1.0);
            let q = (p + drift[k as usize % 4] * time) * n;
            perlin_periodic(seed, q, n as i64)
        })
    }

    /// The gradient (∂/∂x, ∂/∂y) at `p`, by central differences over `h`: what turns a noise
    /// used as a height into a normal.
    pub fn gradient(&self, p: Vec2, h: f32) -> Vec2 {
        let dx = self.at(p + Vec2::new(h, 0.0)) - self.at(p - Vec2::new(h, 0.0));
        let dy = self.at(p + Vec2::new(0.0, h)) - self.at(p - Vec2::new(0.0, h));
        Vec2::new(dx, dy) / (2.0 * h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Perlin noise is 0 at every lattice point: each corner's offset there is zero.
    #[test]
    fn perlin_vanishes_on_the_lattice() {
        for (x, y) in [(0, 0), (3, -7), (-12, 5), (1000, 1000)] {
            assert_eq!(perlin(9, Vec2::new(x as f32, y as f32)), 0.0, "({x}, {y})");
        }
    }

    /// At a cell's centre every corner's offset is (±½, ±½) and both blends are ½, so the
    /// noise is the mean of the four corner gradients dotted with their offsets, computed here
    /// by hand from the gradients the hash picks.
    #[test]
    fn perlin_at_a_cell_centre_by_hand() {
        let seed = 4;
        let p = Vec2::new(2.5, -3.5);
        let mut want = 0.0;
        for (cx, cy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let g = gradient(seed, 2 + cx, -4 + cy);
            let offset = Vec2::new(0.5 - cx as f32, 0.5 - cy as f32);
            want += 0.25 * g.dot(offset);
        }
        assert_eq!(fade(0.5), 0.5);
        assert!(
            (perlin(seed, p) - want).abs() < 1e-7,
            "{} {want}",
            perlin(seed, p)
        );
    }

    /// The noise is continuous across cell borders (the blend reaches each corner's value)
    /// and stays within [−1, 1]; fBm too, and its mean over many points is near 0.
    #[test]
    fn noise_is_continuous_and_bounded() {
        let fbm = Fbm::default();
        let mut sum = 0.0f64;
        let n = 20_000;
        for i in 0..n {
            let p = Vec2::new(i as f32 * 0.137 - 600.0, (i % 97) as f32 * 0.291 - 13.0);
            let v = perlin(7, p);
            assert!((-1.0..=1.0).contains(&v), "{p} {v}");
            let f = fbm.at(p);
            assert!((-1.0..=1.0).contains(&f), "{p} {f}");
            sum += f64::from(f);
        }
        assert!((sum / f64::from(n)).abs() < 0.02, "{}", sum / f64::from(n));
        // Across the border x = 3: the values either side of it differ by a slope's worth.
        let e = 1e-3;
        for y in [0.1f32, 0.5, 0.9] {
            let (a, b) = (
                perlin(3, Vec2::new(3.0 - e, y)),
                perlin(3, Vec2::new(3.0 + e, y)),
            );
            assert!((a - b).abs() < 4.0 * e, "{a} {b}");
        }
    }

    /// The same seed gives the same values; another seed other values. The value at a point
    /// depends on nothing but the noise and the point: a second noise of the same seed, on
    /// another thread, after other points were evaluated, gives the same bits (state kept
    /// between calls, per thread or global, would change them). The bits of a few values are
    /// fixed here: a change to the hash or the arithmetic that would give another machine or
    /// another version other clouds fails this test.
    #[test]
    fn the_seed_fixes_the_values_bit_for_bit() {
        let a = Fbm::default();
        let b = Fbm { seed: 2, ..a };
        let p = Vec2::new(0.3, 0.7);
        let first = a.at(p).to_bits();
        let again = std::thread::spawn(move || {
            let same_seed = Fbm {
                seed: 1,
                ..Fbm::default()
            };
            for i in 0..100 {
                std::hint::black_box(same_seed.at(Vec2::new(i as f32 * 0.37, -(i as f32))));
            }
            same_seed.at(p).to_bits()
        })
        .join()
        .unwrap();
        assert_eq!(first, again);
        assert_eq!(a.at(p).to_bits(), first, "evaluated again on this thread");
        assert_ne!(a.at(p), b.at(p));
        let bits: Vec<u32> = [p, Vec2::new(-5.25, 11.125), Vec2::new(100.0, -0.001)]
            .iter()
            .map(|&q| a.at(q).to_bits())
            .collect();
        assert_eq!(
            bits,
            FIXED_BITS,
            "{:?}",
            bits.iter().map(|b| f32::from_bits(*b)).collect::<Vec<_>>()
        );
    }

    /// Recorded from this implementation (0.10740814, −0.03639459, 0.001015129): a pin, not a
    /// derivation; the values' correctness is what the other tests check.
    const FIXED_BITS: [u32; 3] = [1037826253, 3172274814, 981798420];

    /// The gradient is the noise's slope in both directions: each component equals a
    /// difference quotient of [`Fbm::at`] along its own axis, at points across several cells
    /// and for one octave and six, and the slope along any direction `d` is `gradient · d`.
    /// The quotients are central over 10⁻³, the gradient's over 5·10⁻⁴: their truncation
    /// errors (`h² f‴ / 6`) stay under 0.01 for six octaves' third derivatives (the finest
    /// octave's is 32³ times a Perlin noise's, weighed 1/63), and the rounding of f32 points
    /// within 6 of the origin under 0.002; components swapped, of the wrong sign or scaled
    /// differ by far more than the 0.02 allowed.
    #[test]
    fn the_gradient_is_the_slope() {
        let h = 1e-3;
        let quotient =
            |fbm: &Fbm, p: Vec2, d: Vec2| (fbm.at(p + h * d) - fbm.at(p - h * d)) / (2.0 * h);
        for octaves in [1, 6] {
            let fbm = Fbm {
                octaves,
                ..Fbm::default()
            };
            for p in [
                Vec2::new(0.37, 0.61),
                Vec2::new(-2.2, 5.7),
                Vec2::new(4.8, -0.45),
                Vec2::new(3.05, 3.9),
            ] {
                let g = fbm.gradient(p, 5e-4);
                let (sx, sy) = (quotient(&fbm, p, Vec2::X), quotient(&fbm, p, Vec2::Y));
                assert!(
                    (g.x - sx).abs() < 0.02,
                    "{octaves} octaves at {p}: x {} {sx}",
                    g.x
                );
                assert!(
                    (g.y - sy).abs() < 0.02,
                    "{octaves} octaves at {p}: y {} {sy}",
                    g.y
                );
                let d = Vec2::new(0.6, -0.8);
                let sd = quotient(&fbm, p, d);
                assert!(
                    (g.dot(d) - sd).abs() < 0.02,
                    "{octaves} octaves at {p}: along {d}"
                );
            }
        }
        // A noise of one octave is exactly the Perlin noise of its seed.
        let fbm = Fbm {
            octaves: 1,
            ..Fbm::default()
        };
        let p = Vec2::new(0.37, 0.61);
        assert_eq!(fbm.at(p), perlin(fbm.seed, p));
    }

    /// A tile repeats: its values at p and p + (1, 0) or (0, 1) are the same, at any time.
    #[test]
    fn a_tile_repeats_without_a_seam() {
        let fbm = Fbm::default();
        let drift = [
            Vec2::new(0.1, 0.0),
            Vec2::new(0.0, 0.13),
            Vec2::new(-0.07, 0.05),
            Vec2::ZERO,
        ];
        for (i, time) in [0.0f32, 0.7, 3.25].into_iter().enumerate() {
            let p = Vec2::new(0.123 + i as f32 * 0.2, 0.456);
            let a = fbm.tile_at(p, 4, time, drift);
            for shift in [Vec2::X, Vec2::Y, Vec2::new(-2.0, 3.0)] {
                let b = fbm.tile_at(p + shift, 4, time, drift);
                assert!((a - b).abs() < 1e-5, "{a} {b} at {p} + {shift}");
            }
        }
        // The periodic noise is Perlin's inside the first period.
        let q = Vec2::new(1.3, 2.7);
        assert_eq!(perlin_periodic(3, q, 8), perlin(3, q));
    }

    /// Value noise reaches the lattice's values at its points and stays in [0, 1).
    #[test]
    fn value_noise_interpolates_the_lattice() {
        assert_eq!(value_noise(5, 3.0, -2.0), lattice(5, 3, -2));
        for i in 0..1000 {
            let v = value_noise(5, i as f32 * 0.173, i as f32 * -0.077);
            assert!((0.0..1.0).contains(&v));
        }
    }
}

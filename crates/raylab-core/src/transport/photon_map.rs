//! The caustic photon map: stored photons, the uniform hash grid that finds those near a point,
//! the density estimate, and the radius that shrinks from pass to pass (progressive photon
//! mapping). The photons themselves are shot by [`crate::transport::integrator::photons`].
//!
//! **Density estimate.** A photon is a packet of power Φ (watts per channel) that arrived at a
//! surface point from the direction `wi`. Photons within a disc of radius r around a point x
//! estimate the radiance leaving x toward `wo` as
//!
//! ```text
//! L(x, wo) ≈ Σ_p f(wo, wi_p) · Φ_p / (π r²)
//! ```
//!
//! (Jensen, *Realistic Image Synthesis Using Photon Mapping*, eq. 7.6). raylab's images are in
//! π × radiance (see [`crate::transport::integrator`]), so the value added to a pixel is
//! `π L = Σ f · Φ / r²` ([`PhotonMap::gather`]).
//!
//! **Progressive radius.** Each render pass shoots a new map; pass `i` (from 0) gathers with
//! `r_i² = r_0² · Π_{j=1..i} (j + α)/(j + 1)` ([`radius_at_pass`]: Hachisuka and Jensen's
//! global radius, as in Knaus and Zwicker's probabilistic PPM, with α = 2/3). The radius
//! shrinks like `i^((α−1)/2)`, slowly enough that the noise of the average over passes still
//! falls while its bias (the blur of the disc) vanishes: the image converges as samples grow.

use glam::Vec3;

/// α of progressive photon mapping: the share of the photons kept from pass to pass. 2/3 is
/// Hachisuka and Jensen's and Knaus and Zwicker's choice.
pub const ALPHA: f32 = 2.0 / 3.0;

/// The cosine a photon's surface normal must make at least with the gathering point's for the
/// photon to count: photons on a wall meeting the floor at a corner (cosine 0), or on the far
/// side of a thin surface (cosine −1), lit a different surface and are left out.
pub const SAME_SURFACE_COS: f32 = 0.5;

/// One stored photon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    /// Where it landed.
    pub position: Vec3,
    /// The unit direction it came from (pointing away from the surface, as a BSDF's `wi`).
    pub wi: Vec3,
    /// The geometric normal at the landing point, on the side the photon arrived from.
    pub normal: Vec3,
    /// Its power per channel, in watts: the light's P/N times the tints it passed through.
    pub power: Vec3,
}

/// The radius pass `pass` (from 0) gathers with, from `initial` (pass 0's):
/// `r² = initial² · Π_{j=1..pass} (j + α)/(j + 1)`, multiplied out in order (the same bits on
/// every machine and thread count).
pub fn radius_at_pass(initial: f32, pass: u32) -> f32 {
    let mut r2 = f64::from(initial) * f64::from(initial);
    let alpha = f64::from(ALPHA);
    for j in 1..=pass {
        let j = f64::from(j);
        r2 *= (j + alpha) / (j + 1.0);
    }
    r2.sqrt() as f32
}

/// What a gather found: the value it adds (π × radiance, before the path's throughput), how
/// many photons lay within the radius (and on the same surface), and the radius.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Gathered {
    pub value: Vec3,
    pub photons: u32,
    pub radius: f32,
}

/// A uniform grid over space whose cells are hashed into a table of buckets: points are
/// sorted by bucket (a counting sort, stable, so the order is the points' order: the same
/// grid however the points were made), and [`HashGrid::within`] visits the buckets of the
/// cells a query's ball overlaps. Cells are `2r` wide for a query radius `r`, so a ball meets
/// at most 2 × 2 × 2 of them.
#[derive(Clone, Debug, Default)]
pub struct HashGrid {
    /// 1 / the cell size.
    inverse_cell: f32,
    /// The table's size less one (a power of two).
    mask: u32,
    /// Where each bucket's points start in `order`; `starts[b + 1]` is where they end.
    starts: Vec<u32>,
    /// Point indices, bucket by bucket.
    order: Vec<u32>,
}

/// The most cells a query visits one by one; a ball wider than that (a radius far above the
/// one the grid was built for) is answered by visiting every point instead.
const MAX_CELLS: i64 = 64;

impl HashGrid {
    /// A grid of `points` for queries of radius up to `radius` (above 0 and finite; else every
    /// query visits every point). The table has about twice as many buckets as points.
    pub fn build(points: &[Vec3], radius: f32) -> Self {
        let cell = 2.0 * radius;
        let inverse_cell = if cell > 0.0 && cell.is_finite() {
            1.0 / cell
        } else {
            0.0
        };
        let buckets = (2 * points.len()).next_power_of_two().clamp(1, 1 << 30);
        let mut grid = HashGrid {
            inverse_cell,
            mask: (buckets - 1) as u32,
            starts: vec![0; buckets + 1],
            order: vec![0; points.len()],
        };
        let keys: Vec<u32> = points.iter().map(|&p| grid.bucket_of(p)).collect();
        for &k in &keys {
            grid.starts[k as usize + 1] += 1;
        }
        for b in 0..buckets {
            grid.starts[b + 1] += grid.starts[b];
        }
        let mut next = grid.starts.clone();
        for (i, &k) in keys.iter().enumerate() {
            grid.order[next[k as usize] as usize] = i as u32;
            next[k as usize] += 1;
        }
        grid
    }

    /// The cell holding `p`, per axis (saturating: far or non-finite points land in the
    /// outermost cells, still visited by any query that could reach them).
    #[inline]
    fn cell_of(&self, p: Vec3) -> [i32; 3] {
        let c = (p * self.inverse_cell).floor();
        [c.x as i32, c.y as i32, c.z as i32]
    }

    /// The bucket of cell `c` (Teschner et al.'s spatial hash: three large primes).
    #[inline]
    fn bucket_of_cell(&self, c: [i32; 3]) -> u32 {
        let h = (c[0] as u32).wrapping_mul(73_856_093)
            ^ (c[1] as u32).wrapping_mul(19_349_663)
            ^ (c[2] as u32).wrapping_mul(83_492_791);
        h & self.mask
    }

    #[inline]
    fn bucket_of(&self, p: Vec3) -> u32 {
        self.bucket_of_cell(self.cell_of(p))
    }

    /// Calls `visit(i)` once for every point `i` of `points` (the points the grid was built
    /// from) within `radius` of `p` (distance² ≤ radius²), in bucket order.
    pub fn within(&self, points: &[Vec3], p: Vec3, radius: f32, mut visit: impl FnMut(usize)) {
        let r2 = radius * radius;
        let mut check = |i: u32| {
            let i = i as usize;
            if (points[i] - p).length_squared() <= r2 {
                visit(i);
            }
        };
        let lo = self.cell_of(p - Vec3::splat(radius));
        let hi = self.cell_of(p + Vec3::splat(radius));
        let span = |a: i32, b: i32| i64::from(b) - i64::from(a) + 1;
        let cells = span(lo[0], hi[0]) * span(lo[1], hi[1]) * span(lo[2], hi[2]);
        if self.inverse_cell == 0.0 || !(1..=MAX_CELLS).contains(&cells) || !p.is_finite() {
            (0..points.len() as u32).for_each(check);
            return;
        }
        // Each bucket once: two cells may hash to the same bucket.
        let mut buckets = [0u32; MAX_CELLS as usize];
        let mut n = 0;
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    buckets[n] = self.bucket_of_cell([x, y, z]);
                    n += 1;
                }
            }
        }
        let buckets = &mut buckets[..n];
        buckets.sort_unstable();
        let mut previous = None;
        for &b in buckets.iter() {
            if previous == Some(b) {
                continue;
            }
            previous = Some(b);
            let (start, end) = (self.starts[b as usize], self.starts[b as usize + 1]);
            for &i in &self.order[start as usize..end as usize] {
                check(i);
            }
        }
    }
}

/// One pass's caustic photons, their grid and the radius they are gathered with.
#[derive(Clone, Default)]
pub struct PhotonMap {
    photons: Vec<Photon>,
    positions: Vec<Vec3>,
    grid: HashGrid,
    radius: f32,
    emitted: u64,
}

/// A photon map prints as its counts: its photons would fill a screen.
impl std::fmt::Debug for PhotonMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PhotonMap")
            .field("stored", &self.photons.len())
            .field("emitted", &self.emitted)
            .field("radius", &self.radius)
            .finish()
    }
}

impl PhotonMap {
    /// The map of `photons` (of `emitted` shot from the light), gathered within `radius`.
    pub fn new(photons: Vec<Photon>, emitted: u64, radius: f32) -> Self {
        let positions: Vec<Vec3> = photons.iter().map(|p| p.position).collect();
        let grid = HashGrid::build(&positions, radius);
        Self {
            photons,
            positions,
            grid,
            radius,
            emitted,
        }
    }

    /// The stored photons, in the order they were shot.
    pub fn photons(&self) -> &[Photon] {
        &self.photons
    }

    /// How many photons left the light for this map (stored or not).
    pub fn emitted(&self) -> u64 {
        self.emitted
    }

    /// The gather radius.
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// The density estimate at `position` on a surface whose geometric normal (on the
    /// viewer's side) is `normal`: `Σ f(wi_p) · Φ_p / r²` (π × radiance, see the module's
    /// documentation) over the photons within the radius whose normal agrees with `normal`
    /// ([`SAME_SURFACE_COS`]); `f(wi)` is the surface's BSDF toward the viewer for light from
    /// `wi`.
    pub fn gather(&self, position: Vec3, normal: Vec3, f: impl Fn(Vec3) -> Vec3) -> Gathered {
        let mut sum = Vec3::ZERO;
        let mut found = 0u32;
        self.grid
            .within(&self.positions, position, self.radius, |i| {
                let photon = &self.photons[i];
                if photon.normal.dot(normal) >= SAME_SURFACE_COS {
                    sum += f(photon.wi) * photon.power;
                    found += 1;
                }
            });
        let r2 = self.radius * self.radius;
        Gathered {
            value: if found > 0 && r2 > 0.0 {
                sum / r2
            } else {
                Vec3::ZERO
            },
            photons: found,
            radius: self.radius,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::sampling::Rng;

    /// The grid finds exactly the brute-force neighbours: 20,000 random points (a dense
    /// cluster and a sparse spread), 2,000 random queries at the built radius and at smaller
    /// and larger ones (up to the all-points fallback), compared as sorted index lists.
    #[test]
    fn the_hash_grid_finds_exactly_the_brute_force_neighbours() {
        let mut rng = Rng::new(11);
        let mut point = |scale: f32| {
            Vec3::new(
                rng.uniform(-scale, scale),
                rng.uniform(-scale, scale),
                rng.uniform(-scale, scale),
            )
        };
        let mut points: Vec<Vec3> = (0..15_000).map(|_| point(0.3)).collect();
        points.extend((0..5_000).map(|_| point(3.0)));
        let built = 0.05;
        let grid = HashGrid::build(&points, built);
        let mut total = 0;
        for q in 0..2_000 {
            let p = point(if q % 2 == 0 { 0.4 } else { 3.5 });
            for radius in [built, 0.5 * built, 2.0 * built, 40.0 * built, 0.0] {
                let mut found = Vec::new();
                grid.within(&points, p, radius, |i| found.push(i));
                found.sort_unstable();
                let brute: Vec<usize> = (0..points.len())
                    .filter(|&i| (points[i] - p).length_squared() <= radius * radius)
                    .collect();
                assert_eq!(found, brute, "query {q} at {p}, radius {radius}");
                total += found.len();
            }
        }
        assert!(total > 100_000, "the queries found neighbours: {total}");
        // Degenerate grids answer by visiting everything, and never panic.
        for radius in [0.0, f32::NAN, f32::INFINITY, -1.0] {
            let grid = HashGrid::build(&points[..50], radius);
            let mut found = 0;
            grid.within(&points[..50], Vec3::ZERO, 10.0, |_| found += 1);
            assert_eq!(found, 50);
        }
        let empty = HashGrid::build(&[], 0.1);
        empty.within(&[], Vec3::ZERO, 0.1, |_| panic!("no point"));
        let mut nan = 0;
        grid.within(&points, Vec3::NAN, 0.1, |_| nan += 1);
        assert_eq!(nan, 0);
    }

    /// Hand-placed photons on the floor (normal −y, the lab's up): three of 0.5, 0.25 and
    /// 0.125 W within r = 0.1 of the origin, one just outside, one inside but on a wall
    /// (normal +x). A white Lambertian floor, f = 1/π: π L = Σ f Φ / r² = (0.875/π) / 0.01
    /// = 27.852 per channel, from 3 photons.
    #[test]
    fn a_gather_of_hand_placed_photons_is_their_density() {
        let up = -Vec3::Y;
        let photon = |x: f32, z: f32, power: f32, normal: Vec3| Photon {
            position: Vec3::new(x, 0.0, z),
            wi: up,
            normal,
            power: Vec3::splat(power),
        };
        let map = PhotonMap::new(
            vec![
                photon(0.0, 0.0, 0.5, up),
                photon(0.05, 0.05, 0.25, up),
                photon(-0.099, 0.0, 0.125, up),
                photon(0.0, 0.1001, 8.0, up),
                photon(0.02, 0.0, 8.0, Vec3::X),
            ],
            1000,
            0.1,
        );
        let g = map.gather(Vec3::ZERO, up, |_| Vec3::splat(std::f32::consts::FRAC_1_PI));
        assert_eq!(g.photons, 3);
        assert_eq!(g.radius, 0.1);
        let expected = 0.875 / std::f32::consts::PI / 0.01;
        assert!((g.value.x - expected).abs() < 1e-4 * expected, "{g:?}");
        assert!((expected - 27.852).abs() < 1e-3);
        // f is asked of each photon's own direction; nothing is found far away.
        let away = map.gather(Vec3::new(5.0, 0.0, 0.0), up, |_| Vec3::ONE);
        assert_eq!((away.photons, away.value), (0, Vec3::ZERO));
        assert_eq!(map.emitted(), 1000);
        assert_eq!(map.photons().len(), 5);
    }

    /// r_i² = r_0² Π (j + α)/(j + 1): by hand, r_1² = r_0² · (5/3)/2 = 0.8333 r_0², r_2² =
    /// r_1² · (8/3)/3; the radius shrinks at every pass and like i^((α − 1)/2) = i^(−1/6).
    #[test]
    fn the_radius_shrinks_as_progressive_photon_mapping_says() {
        assert_eq!(radius_at_pass(0.1, 0), 0.1);
        let r1 = radius_at_pass(0.1, 1);
        assert!((r1 * r1 - 0.01 * 5.0 / 6.0).abs() < 1e-9, "{r1}");
        let r2 = radius_at_pass(0.1, 2);
        assert!(
            (r2 * r2 - 0.01 * 5.0 / 6.0 * 8.0 / 9.0).abs() < 1e-9,
            "{r2}"
        );
        let mut last = 0.1;
        for pass in 1..200 {
            let r = radius_at_pass(0.1, pass);
            assert!(r < last);
            last = r;
        }
        let ratio = radius_at_pass(0.1, 4000) / radius_at_pass(0.1, 1000);
        assert!((ratio - 4f32.powf(-1.0 / 6.0)).abs() < 1e-3, "{ratio}");
    }
}

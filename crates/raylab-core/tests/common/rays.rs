//! The random rays the structure tests share (tests/bvh.rs, tests/views.rs).

use glam::Vec3;
use raylab_core::base::geometry::{Ray, Triangle};
use raylab_core::base::sampling::Rng;

pub fn random_dir(rng: &mut Rng) -> Vec3 {
    loop {
        let d = Vec3::new(
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
        );
        if d.length_squared() > 1e-4 && d.length_squared() <= 1.0 {
            return d;
        }
    }
}

/// Rays from inside (and a little around) the scene's bounds, from the default camera through
/// random pixels, and some axis-aligned ones (zero direction components).
pub fn rays(triangles: &[Triangle], count: usize, seed: u64) -> Vec<(Ray, f32)> {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for t in triangles {
        for p in [t.v0, t.v1, t.v2] {
            if p.is_finite() {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
    }
    if !lo.is_finite() {
        lo = Vec3::splat(-1.0);
        hi = Vec3::splat(1.0);
    }
    let margin = 0.1 * (hi - lo).max_element().max(1e-3);
    let (lo, hi) = (lo - margin, hi + margin);
    let mut rng = Rng::new(seed);
    let camera = raylab_core::Camera::default_for(512, 512);
    (0..count)
        .map(|i| {
            let t_max = if i % 3 == 0 {
                f32::INFINITY
            } else {
                rng.uniform(0.0, 2.0 * (hi - lo).max_element())
            };
            let ray = match i % 10 {
                0..=5 => {
                    let o = Vec3::new(
                        rng.uniform(lo.x, hi.x),
                        rng.uniform(lo.y, hi.y),
                        rng.uniform(lo.z, hi.z),
                    );
                    Ray::new(o, random_dir(&mut rng))
                }
                6..=8 => camera.primary_ray(rng.uniform(0.0, 512.0), rng.uniform(0.0, 512.0)),
                _ => {
                    let o = Vec3::new(
                        rng.uniform(lo.x, hi.x),
                        rng.uniform(lo.y, hi.y),
                        rng.uniform(lo.z, hi.z),
                    );
                    let axis = (rng.next_u32() % 6) as usize;
                    let d = [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z][axis];
                    Ray::new(o, d)
                }
            };
            (ray, t_max)
        })
        .collect()
}

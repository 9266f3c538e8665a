//! A batch's diffuse hits, sixteen to a lane group, and whose each is.
//!
//! Both integrators compute the lab's terms at a batch's diffuse hits sixteen at a time
//! ([`Lighting::at`] at [`Vec3x16`]) and hand their shadow rays to the tracer as lanes
//! ([`Scene::occluded_lanes`]). Hit `k` sits in lane `k % 16` of group `k / 16`, and each
//! group's [`DiffuseHits::active`] says which lanes hold one. The lab puts each ray's hit in the
//! ray's own lane, leaving empty those of rays that left the scene or met a mirror or glass; so
//! a group can be filled whole: where the tracer is plain (no texture, relief or smooth normal
//! anywhere), [`DiffuseHits::fill_plain`] reads sixteen hits' triangles and materials and makes
//! their surfaces in lanes, the values [`Tracer::surface_with`] gives one hit at a time, bit for
//! bit (tested). One at a time, each surface went through the stack field by field, with a
//! branch for the edge test (PERFORMANCE.md). The path tracer packs its diffuse hits one after
//! another instead: its rays that leave the box would leave their lanes empty, and empty lanes
//! cost their group's light and shadow rays as full ones do (a pass took 11 % longer).

use glam::Vec3;

use super::{BATCH, HitTerms, Lighting, Surface, Surfaces, Tracer, light_point};
use crate::accel::SegmentLanes;
use crate::intersect::Intersection;
use crate::lanes::{F32x16, LANES, M16, Mask, Real, Vec3x16, Vector};
use crate::light::near_an_edge;
use crate::sampling::Rng;
use crate::scene::Scene;

// A batch's rays fill whole lane groups.
const _: () = assert!(BATCH.is_multiple_of(LANES));

/// Lane groups in a batch.
pub(crate) const GROUPS: usize = BATCH / LANES;

/// The lanes whose bits are set in `mask`, in order.
#[inline(always)]
pub(crate) fn lanes_of(mut mask: u16) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let lane = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            lane
        })
    })
}

/// The diffuse hits of a batch of rays, in lanes, and whose each is.
pub(crate) struct DiffuseHits {
    pub surfaces: [Surfaces<Vec3x16>; GROUPS],
    /// Which lanes of each group hold a hit (bit `lane`). The other lanes hold what they held,
    /// never read.
    pub active: [u16; GROUPS],
    /// Whose each hit is, by its place: the index of its ray (lab) or path (path) in the batch.
    owner: [u8; BATCH],
    /// The groups up to the last that holds a hit.
    groups: usize,
}

impl DiffuseHits {
    #[inline(always)]
    pub fn new() -> Self {
        Self {
            surfaces: [Surfaces::ZERO; GROUPS],
            active: [0; GROUPS],
            owner: [0; BATCH],
            groups: 0,
        }
    }

    /// No hits.
    #[inline(always)]
    pub fn clear(&mut self) {
        self.groups = 0;
        self.active = [0; GROUPS];
    }

    /// Hit `k` (lane `k % 16` of group `k / 16`) is at `surface`, and `owner`'s.
    #[inline(always)]
    pub fn push(&mut self, k: usize, surface: Surface, owner: usize) {
        let (g, lane) = (k / LANES, k % LANES);
        self.surfaces[g].set(lane, surface);
        self.active[g] |= 1 << lane;
        self.owner[k] = owner as u8;
        self.groups = self.groups.max(g + 1);
    }

    /// Group `g` filled at once with the hits of the batch's rays `16g ..`, each in its ray's
    /// lane and its ray's (`hit_of(lane)`: the hit, if the ray met something, and the ray's
    /// direction), where `tracer` is plain: each diffuse hit's surface is
    /// [`Tracer::surface_with`]'s, its `at_edge` asked when `at_edges` (as [`Tracer::surface`]
    /// asks it). Returns the lanes whose ray met a surface that is not diffuse, for the caller
    /// to take one at a time.
    #[inline(always)]
    pub fn fill_plain(
        &mut self,
        g: usize,
        tracer: &Tracer,
        at_edges: bool,
        hit_of: impl Fn(usize) -> Option<(Intersection, Vec3)>,
    ) -> u16 {
        debug_assert!(tracer.plain && g < GROUPS);
        let scene = tracer.scene;
        let all_diffuse = tracer.all_diffuse;
        let (mut diffuse, mut other) = (0u16, 0u16);
        let surfaces = &mut self.surfaces[g];
        let (mut u, mut v, mut zones) = (F32x16::ZERO, F32x16::ZERO, [F32x16::ZERO; 3]);
        let mut incoming = Vec3x16::ZERO;
        // Lane by lane, what each hit reads: its triangle's normal and zones, its material's ρ.
        for lane in 0..LANES {
            let Some((hit, direction)) = hit_of(lane) else {
                continue;
            };
            let triangle = &scene.triangles[hit.triangle_index];
            let material = &tracer.materials[triangle.material as usize];
            // Asked only where some material is not diffuse: the answer would wait on two
            // loads one after the other, and the lab's box has no other.
            if !all_diffuse && !material.is_diffuse() {
                other |= 1 << lane;
                continue;
            }
            diffuse |= 1 << lane;
            surfaces.position.set_lane(lane, hit.position);
            surfaces.geometric.set_lane(lane, triangle.normal);
            surfaces.rho.set_lane(lane, material.reflectance);
            incoming.set_lane(lane, direction);
            (u.0[lane], v.0[lane]) = (hit.u, hit.v);
            let z = scene.edge_zones(hit.triangle_index);
            (zones[0].0[lane], zones[1].0[lane], zones[2].0[lane]) = (z[0], z[1], z[2]);
            self.owner[g * LANES + lane] = (g * LANES + lane) as u8;
        }
        // Then sixteen at a time: which lie at an edge ([`Scene::approach_at_edge`]); the
        // shading normal is the triangle's own.
        surfaces.near_edge = M16::splat(at_edges) & near_an_edge(zones, u, v);
        surfaces.incoming = Vec3x16::select(surfaces.near_edge, incoming, Vec3x16::ZERO);
        surfaces.normal = surfaces.geometric;
        surfaces.relief_visibility = F32x16::splat(1.0);
        self.active[g] = diffuse;
        if diffuse != 0 {
            self.groups = self.groups.max(g + 1);
        }
        other
    }

    /// The groups the batch spans, each with its hits' lanes ([`DiffuseHits::active`]).
    #[inline(always)]
    pub fn groups(&self) -> impl Iterator<Item = (u16, &Surfaces<Vec3x16>)> {
        (0..self.groups).map(|g| (self.active[g], &self.surfaces[g]))
    }

    /// Group `g`'s hits: each lane holding one, and whose it is, in lane order.
    #[inline(always)]
    pub fn owners(&self, g: usize) -> impl Iterator<Item = (usize, u8)> + '_ {
        lanes_of(self.active[g]).map(move |lane| (lane, self.owner[g * LANES + lane]))
    }

    /// The light at every hit, sixteen at a time, in the order of the hits. With `SPHERE`
    /// (a spherical light) the shadow rays go to points of the light drawn from
    /// `rngs[rng_of(owner)]` ([`light_point`]), in that order; otherwise nothing is drawn.
    /// `SPHERE` is a constant so that, for a point light, the closure that finds the points
    /// is small enough to inline into the code compiled for the CPU (as a run-time flag it was
    /// not, and the lab pass took 8 % longer: measured).
    #[inline(always)]
    pub fn light<const SPHERE: bool>(
        &self,
        tracer: &Tracer,
        rngs: &mut [Rng],
        rng_of: impl Fn(u8) -> usize,
    ) -> [Lighting<Vec3x16>; GROUPS] {
        let (light, shading) = (&tracer.light, &tracer.shading);
        let mut lit = [Lighting::NONE; GROUPS];
        for (g, (active, surfaces)) in self.groups().enumerate() {
            if active == 0 {
                continue;
            }
            lit[g] = Lighting::at(
                light,
                shading.stage,
                shading.shadows,
                surfaces,
                |positions, wanted| {
                    let mut target = Vec3x16::splat(light.position);
                    if SPHERE {
                        for (lane, i) in self.owners(g) {
                            if wanted.0[lane] {
                                let rng = &mut rngs[rng_of(i)];
                                let point = light_point(light, positions.lane(lane), rng);
                                target.set_lane(lane, point);
                            }
                        }
                    }
                    target
                },
            );
        }
        lit
    }

    /// Which shadow rays of `lit` (the hits' [`DiffuseHits::light`]) are blocked: bit `lane`
    /// of group `g`'s mask.
    #[inline(always)]
    pub fn blocked(&self, scene: &Scene, lit: &[Lighting<Vec3x16>; GROUPS]) -> [u16; GROUPS] {
        // Every group's lanes, those without a hit casting nothing (a fixed array: collecting
        // the groups in use into an `ArrayVec` cost 8 instructions a pixel of the lab pass).
        let shadows: [SegmentLanes; GROUPS] =
            std::array::from_fn(|g| lit[g].shadow.segment_lanes(self.active[g]));
        let mut blocked = [0u16; GROUPS];
        scene.occluded_lanes(&shadows[..self.groups], &mut blocked[..self.groups]);
        blocked
    }

    /// Hit `lane` of group `g` as [`HitTerms::at`] gives it, its shadow ray answered: what the
    /// pixel inspector is told.
    pub fn terms(&self, g: usize, lane: usize, lit: &Lighting<Vec3x16>, blocked: u16) -> HitTerms {
        let s = &self.surfaces[g];
        HitTerms {
            position: s.position.lane(lane),
            normal: s.normal.lane(lane),
            rho: s.rho.lane(lane),
            d: lit.d.lane(lane),
            relief_shadowed: s.relief_visibility.0[lane] == 0.0,
            shadow_ray: lit.shadow.lane(lane),
            blocked: blocked & (1 << lane) != 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::MaterialPreset;
    use crate::sampling::Rng;
    use crate::scene::cornell_box;
    use crate::{Camera, RenderSettings};

    #[test]
    fn lanes_of_a_mask_in_order() {
        assert_eq!(lanes_of(0).count(), 0);
        assert_eq!(lanes_of(0b1010_0001).collect::<Vec<_>>(), [0, 5, 7]);
        assert_eq!(
            lanes_of(u16::MAX).collect::<Vec<_>>(),
            (0..16).collect::<Vec<_>>()
        );
    }

    /// Rays from the camera and from random points in the box in random directions: every
    /// kind of hit, on every wall and block, at its edges and from behind.
    fn rays_in_the_box(n: usize) -> Vec<crate::geometry::Ray> {
        let camera = Camera::default_for(32, 32);
        let mut rng = Rng::for_pixel_sample(11, 0, 0, 0);
        let mut rays: Vec<_> = (0..n / 2)
            .map(|i| camera.pixel_ray((i % 32) as u32, (i / 32 % 32) as u32))
            .collect();
        while rays.len() < n {
            let origin = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            let d = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            if let Some(direction) = d.try_normalize() {
                rays.push(crate::geometry::Ray { origin, direction });
            }
        }
        rays
    }

    /// Filling a group at once gives each lane the surface [`Tracer::surface_with`] gives its
    /// hit, bit for bit, with and without `at_edge`, in the lab's box (every material diffuse)
    /// and with the mirror and glass blocks, whose lanes are left to the caller, as are those
    /// that missed.
    #[test]
    fn a_plain_group_equals_its_hits_one_at_a_time() {
        for preset in [MaterialPreset::None, MaterialPreset::Both] {
            let others = plain_groups_equal_their_hits(preset);
            match preset {
                MaterialPreset::None => assert_eq!(others, 0),
                _ => assert!(others > 100, "{others}"),
            }
        }
    }

    /// [`a_plain_group_equals_its_hits_one_at_a_time`] with `preset`: how many hits were on
    /// mirror or glass.
    fn plain_groups_equal_their_hits(preset: MaterialPreset) -> usize {
        let scene = cornell_box();
        let settings = RenderSettings {
            material_preset: preset,
            ..RenderSettings::default()
        };
        let tracer = Tracer::new(&scene, &settings);
        assert!(tracer.plain);
        let rays = rays_in_the_box(4096);
        let mut hits = vec![None; rays.len()];
        scene.closest_intersections(&rays, f32::INFINITY, &mut hits);
        let (mut edges, mut others) = (0, 0);
        for at_edges in [true, false] {
            for (rays, hits) in rays.chunks(LANES).zip(hits.chunks(LANES)) {
                let mut group = DiffuseHits::new();
                group.clear();
                let hit_of = |lane: usize| hits[lane].map(|h| (h, rays[lane].direction));
                let other = group.fill_plain(0, &tracer, at_edges, hit_of);
                for (lane, (ray, hit)) in rays.iter().zip(hits).enumerate() {
                    let bit = 1 << lane;
                    let Some(hit) = hit else {
                        assert_eq!((group.active[0] | other) & bit, 0);
                        continue;
                    };
                    let material = tracer.material_of(hit.triangle_index);
                    if !material.is_diffuse() {
                        assert_eq!((group.active[0] & bit, other & bit), (0, bit));
                        others += 1;
                        continue;
                    }
                    assert_eq!((group.active[0] & bit, other & bit), (bit, 0));
                    let at_edge = match at_edges {
                        true => {
                            scene.approach_at_edge(hit.triangle_index, hit.u, hit.v, ray.direction)
                        }
                        false => None,
                    };
                    let expected = tracer.surface_with(hit, material, ray.direction, at_edge);
                    edges += usize::from(at_edge.is_some());
                    let mut one = DiffuseHits::new();
                    one.clear();
                    one.push(lane, expected, lane);
                    let (a, b) = (&group.surfaces[0], &one.surfaces[0]);
                    assert_eq!(a.position.lane(lane), b.position.lane(lane));
                    assert_eq!(a.normal.lane(lane), b.normal.lane(lane));
                    assert_eq!(a.geometric.lane(lane), b.geometric.lane(lane));
                    assert_eq!(a.rho.lane(lane), b.rho.lane(lane));
                    assert_eq!(a.near_edge.0[lane], b.near_edge.0[lane]);
                    assert_eq!(a.incoming.lane(lane), b.incoming.lane(lane));
                    assert_eq!(a.relief_visibility.0[lane], 1.0);
                    assert_eq!(
                        group.owners(0).find(|o| o.0 == lane),
                        Some((lane, lane as u8))
                    );
                }
            }
        }
        // The rays met the triangles' edges.
        assert!(edges > 20, "{edges}");
        others
    }
}

//! A batch's diffuse hits, sixteen to a lane group, and whose each is.
//!
//! Both integrators compute the lab's terms at a batch's diffuse hits sixteen at a time
//! ([`Lighting::at`] at [`Vec3x16`]) and hand their shadow rays to the tracer as lanes
//! ([`Scene::occluded_lanes`]). Hit `k` sits in lane `k % 16` of group `k / 16`, and each
//! group's [`DiffuseHits::active`] says which lanes hold one. The lab puts each ray's hit in the
//! ray's own lane, leaving empty those of rays that left the scene or met a mirror or glass; so
//! a group can be filled whole: where the tracer is plain (no texture, relief or smooth normal
//! anywhere), [`DiffuseHits::fill_plain`] takes sixteen hits in lanes ([`HitLanes`]), reads
//! their rays and, in a scene of at most 32 triangles, their triangles' [`TriangleTable`]
//! entries in registers, and makes their surfaces in lanes: the values [`Tracer::surface_with`]
//! gives one hit at a time, bit for bit (tested). One at a time, each surface went through the
//! stack field by field, with a branch for the edge test (PERFORMANCE.md, "Design choices and
//! what each buys"). The path tracer packs its diffuse hits one after another instead: its
//! rays that leave the box would leave their lanes empty, and empty lanes cost their group's
//! light and shadow rays as full ones do.

use super::{BATCH, HitTerms, Lighting, PATH_BATCH, Surface, Surfaces, Tracer, light_point};
use crate::base::geometry::Ray;
use crate::base::lanes::{F32x16, LANES, M16, Mask, Real, Vec3x16, Vector};
use crate::base::sampling::Rng;
use crate::shading::light::near_an_edge;
use crate::shading::material::Material;
use crate::shapes::accel::lane_io::{ray_lanes, table_lanes};
use crate::shapes::accel::{HitLanes, Isa};
use crate::shapes::scene::Scene;

// A batch's rays fill whole lane groups.
const _: () = assert!(BATCH.is_multiple_of(LANES));

/// Lane groups in a batch.
pub(crate) const GROUPS: usize = BATCH / LANES;

/// Lane groups in a batch of the path tracer's paths ([`PATH_BATCH`]).
pub(crate) const PATH_GROUPS: usize = PATH_BATCH / LANES;

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

/// A scene of at most 32 triangles, plain (flat, constant ρ), as tables by triangle index: each
/// triangle's normal, ρ (its material's, the preset applied) and edge zones. Sixteen hits read
/// them with one permute per table ([`table_lanes`]) where they would gather each lane from the
/// triangles (PERFORMANCE.md, "Design choices and what each buys").
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct TriangleTable {
    normal: [[f32; 32]; 3],
    rho: [[f32; 32]; 3],
    zones: [[f32; 32]; 3],
}

impl TriangleTable {
    /// The tables of `scene` with `materials`, if it has at most 32 triangles.
    pub fn new(scene: &Scene, materials: &[Material]) -> Option<Self> {
        let n = scene.triangles.len();
        if n > 32 {
            return None;
        }
        let mut table = Self {
            normal: [[0.0; 32]; 3],
            rho: [[0.0; 32]; 3],
            zones: [[0.0; 32]; 3],
        };
        for i in 0..n {
            let [normal, rho, zones] = Self::entry(scene, materials, i);
            for axis in 0..3 {
                table.normal[axis][i] = normal[axis];
                table.rho[axis][i] = rho[axis];
                table.zones[axis][i] = zones[axis];
            }
        }
        Some(table)
    }

    /// What the table holds of triangle `i`: its normal, its material's ρ, its edge zones.
    #[inline(always)]
    fn entry(scene: &Scene, materials: &[Material], i: usize) -> [glam::Vec3; 3] {
        let triangle = &scene.triangles[i];
        let rho = materials[triangle.material as usize].reflectance;
        [triangle.normal, rho, scene.edge_zones(i).into()]
    }

    /// The normal, ρ and edge zones of triangles `index` in the lanes of `lanes` (0 in the
    /// others).
    #[inline(always)]
    fn lanes(&self, isa: Isa, index: &[u32; LANES], lanes: u16) -> (Vec3x16, Vec3x16, Vec3x16) {
        (
            Self::read(&self.normal, isa, index, lanes),
            Self::read(&self.rho, isa, index, lanes),
            Self::read(&self.zones, isa, index, lanes),
        )
    }

    /// A table of vectors' entries for `index`, in the lanes of `lanes`.
    #[inline(always)]
    fn read(rows: &[[f32; 32]; 3], isa: Isa, index: &[u32; LANES], lanes: u16) -> Vec3x16 {
        Vec3x16::new(
            F32x16(table_lanes(isa, &rows[0], index, lanes)),
            F32x16(table_lanes(isa, &rows[1], index, lanes)),
            F32x16(table_lanes(isa, &rows[2], index, lanes)),
        )
    }
}

/// The part of [`super::Scratch`] an integrator works in: the diffuse hits of `G` lane groups
/// and the light at them ([`super::GROUPS`] for the lab's batches, [`PATH_GROUPS`] for the path
/// tracer's).
pub(crate) struct HitScratch<const G: usize> {
    pub(super) diffuse: DiffuseHits<G>,
    pub(super) lit: [Lighting<Vec3x16>; G],
}

impl<const G: usize> HitScratch<G> {
    pub fn new() -> Self {
        Self {
            diffuse: DiffuseHits::new(),
            lit: [Lighting::NONE; G],
        }
    }
}

/// The diffuse hits of a batch of rays, in lanes, and whose each is.
pub(crate) struct DiffuseHits<const G: usize> {
    pub surfaces: [Surfaces<Vec3x16>; G],
    /// Which lanes of each group hold a hit (bit `lane`). The other lanes hold what they held,
    /// never read.
    pub active: [u16; G],
    /// Whose each hit is, by its place: the index of its ray (lab) or path (path) in the batch.
    owner: [[u16; LANES]; G],
    /// The groups up to the last that holds a hit.
    groups: usize,
}

impl<const G: usize> DiffuseHits<G> {
    #[inline(always)]
    pub fn new() -> Self {
        Self {
            surfaces: [Surfaces::ZERO; G],
            active: [0; G],
            owner: [[0; LANES]; G],
            groups: 0,
        }
    }

    /// No hits.
    #[inline(always)]
    pub fn clear(&mut self) {
        self.groups = 0;
        self.active = [0; G];
    }

    /// Hit `k` (lane `k % 16` of group `k / 16`) is at `surface`, and `owner`'s.
    #[inline(always)]
    pub fn push(&mut self, k: usize, surface: Surface, owner: usize) {
        let (g, lane) = (k / LANES, k % LANES);
        self.surfaces[g].set(lane, surface);
        self.active[g] |= 1 << lane;
        self.owner[g][lane] = owner as u16;
        self.groups = self.groups.max(g + 1);
    }

    /// Group `g` filled at once with the hits of the batch's rays `16g ..` (`rays`, and their
    /// closest hits `hits` in the same lanes), each in its ray's lane, where `tracer` is plain:
    /// each diffuse hit's surface is [`Tracer::surface_with`]'s for
    /// [`crate::shapes::scene::intersection`] of its ray and hit, its `at_edge` asked when `at_edges`
    /// (as [`Tracer::surface`] asks it). The hits' normals, ρ and edge zones come from the
    /// tracer's [`TriangleTable`], sixteen lanes a permute (lane by lane from the triangles in
    /// a larger scene), their rays from [`ray_lanes`]. Returns the lanes whose ray met a
    /// surface that is not diffuse, for the caller to take one at a time.
    #[inline(always)]
    pub fn fill_plain(
        &mut self,
        g: usize,
        tracer: &Tracer,
        at_edges: bool,
        rays: &[Ray],
        hits: &HitLanes,
    ) -> u16 {
        debug_assert!(tracer.plain && g < G && !rays.is_empty() && rays.len() <= LANES);
        let scene = tracer.scene;
        let isa = scene.accel().isa();
        let met = hits.hits() & (u32::MAX >> (32 - rays.len())) as u16;
        // Asked only where some material is not diffuse: the answer waits on two loads one
        // after the other, and the lab's box has no other.
        let mut other = 0u16;
        if !tracer.all_diffuse {
            for lane in lanes_of(met) {
                if !tracer.material_of(hits.index[lane] as usize).is_diffuse() {
                    other |= 1 << lane;
                }
            }
        }
        let diffuse = met & !other;
        let index = &hits.index;
        let (geometric, rho, zones) = match &tracer.triangle_table {
            Some(table) => table.lanes(isa, index, diffuse),
            None => {
                // Lane by lane, the same entries from the triangles.
                let (mut geometric, mut rho, mut zones) =
                    (Vec3x16::ZERO, Vec3x16::ZERO, Vec3x16::ZERO);
                for lane in lanes_of(diffuse) {
                    let i = index[lane] as usize;
                    let [normal, reflectance, z] =
                        TriangleTable::entry(scene, &tracer.materials, i);
                    geometric.set_lane(lane, normal);
                    rho.set_lane(lane, reflectance);
                    zones.set_lane(lane, z);
                }
                (geometric, rho, zones)
            }
        };
        let zones = [zones.x, zones.y, zones.z];
        let [ox, oy, oz, dx, dy, dz] = ray_lanes(isa, rays);
        let origin = Vec3x16::new(F32x16(ox), F32x16(oy), F32x16(oz));
        let direction = Vec3x16::new(F32x16(dx), F32x16(dy), F32x16(dz));
        let active = M16::from_bits(diffuse);
        let t = F32x16::select(active, F32x16(hits.t), F32x16::ZERO);
        let (u, v) = (F32x16(hits.u), F32x16(hits.v));
        // Then sixteen at a time: the position `ray.at(t)`, which lie at an edge
        // ([`Scene::approach_at_edge`]); the shading normal is the triangle's own.
        let surfaces = &mut self.surfaces[g];
        surfaces.position = origin + Vec3x16::scale(t, direction);
        surfaces.geometric = geometric;
        surfaces.normal = geometric;
        surfaces.rho = rho;
        surfaces.near_edge = M16::splat(at_edges) & near_an_edge(zones, u, v);
        surfaces.incoming = Vec3x16::select(surfaces.near_edge, direction, Vec3x16::ZERO);
        surfaces.relief_visibility = F32x16::splat(1.0);
        for (lane, owner) in self.owner[g].iter_mut().enumerate() {
            *owner = (g * LANES + lane) as u16;
        }
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
    pub fn owners(&self, g: usize) -> impl Iterator<Item = (usize, u16)> + '_ {
        lanes_of(self.active[g]).map(move |lane| (lane, self.owner[g][lane]))
    }

    /// The light at every hit, sixteen at a time, in the order of the hits. With `SPHERE`
    /// (a spherical light) the shadow rays go to points of the light drawn from
    /// `rngs[rng_of(owner)]` ([`light_point`]), in that order; otherwise nothing is drawn.
    /// `SPHERE` is a constant so that, for a point light, the closure that finds the points
    /// is small enough to inline into the code compiled for the CPU (as a run-time flag it is
    /// not, and the lab's loop pays for the call). Into `lit`, one per group up to
    /// the last with a hit ([`Lighting::NONE`] for a group without).
    #[inline(always)]
    pub fn light<const SPHERE: bool>(
        &self,
        tracer: &Tracer,
        rngs: &mut [Rng],
        rng_of: impl Fn(u16) -> usize,
        lit: &mut [Lighting<Vec3x16>; G],
    ) {
        let (light, shading) = (&tracer.light, &tracer.shading);
        for (g, (active, surfaces)) in self.groups().enumerate() {
            if active == 0 {
                lit[g] = Lighting::NONE;
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
    }

    /// Which shadow rays of `lit` (the hits' [`DiffuseHits::light`]) are blocked: bit `lane`
    /// of group `g`'s mask. `neighbours`: whether the hits are those of neighbouring pixels'
    /// rays ([`crate::shapes::accel::Accel::occluded_lanes`]); their shadow rays are then asked a
    /// batch of [`BATCH`] at a time, each bounded by its own cone (the path tracer's batch of
    /// [`PATH_BATCH`] spans four times the fan, whose cone would keep more triangles).
    #[inline(always)]
    pub fn blocked(
        &self,
        scene: &Scene,
        lit: &[Lighting<Vec3x16>; G],
        neighbours: bool,
    ) -> [u16; G] {
        // Every group's lanes, those without a hit casting nothing (a fixed array: collecting
        // the groups in use into an `ArrayVec` costs instructions at every pixel of the lab
        // pass, and `array::from_fn`'s closure is called out of line). Past the last group in
        // use the copies of the first are never read.
        let mut shadows = [lit[0].shadow.segment_lanes(self.active[0]); G];
        for (g, shadows) in shadows.iter_mut().enumerate().take(self.groups).skip(1) {
            *shadows = lit[g].shadow.segment_lanes(self.active[g]);
        }
        let mut blocked = [0u16; G];
        let (shadows, answers) = (&shadows[..self.groups], &mut blocked[..self.groups]);
        let each = if neighbours { GROUPS } else { G };
        for (shadows, answers) in shadows.chunks(each).zip(answers.chunks_mut(each)) {
            scene.occluded_lanes(shadows, neighbours, answers);
        }
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
    use glam::Vec3;

    use super::*;
    use crate::base::sampling::Rng;
    use crate::shading::material::MaterialPreset;
    use crate::shapes::scene::cornell_box;
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
    fn rays_in_the_box(n: usize) -> Vec<crate::base::geometry::Ray> {
        let camera = Camera::default_for(32, 32);
        let mut rng = Rng::for_pixel_sample(11, 0, 0, 0);
        let mut rays: Vec<_> = (0..n / 2)
            .map(|i| camera.pixel_ray((i % 32) as u32, (i / 32 % 32) as u32))
            .collect();
        while rays.len() < n {
            let origin = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            let d = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            if let Some(direction) = d.try_normalize() {
                rays.push(crate::base::geometry::Ray { origin, direction });
            }
        }
        rays
    }

    /// Filling a group at once gives each lane the surface [`Tracer::surface_with`] gives its
    /// hit, bit for bit, with and without `at_edge`, in the lab's box (every material diffuse)
    /// and with the mirror and glass blocks, whose lanes are left to the caller, as are those
    /// that missed; read from the box's [`TriangleTable`] and, as a larger scene reads them,
    /// lane by lane from the triangles.
    #[test]
    fn a_plain_group_equals_its_hits_one_at_a_time() {
        for preset in [MaterialPreset::None, MaterialPreset::Both] {
            for table in [true, false] {
                let others = plain_groups_equal_their_hits(preset, table);
                match preset {
                    MaterialPreset::None => assert_eq!(others, 0),
                    _ => assert!(others > 100, "{others}"),
                }
            }
        }
    }

    /// The triangle table of the box: each triangle's normal, its material's ρ and its zones.
    #[test]
    fn the_table_holds_each_triangles_normal_reflectance_and_zones() {
        let scene = cornell_box();
        let table = TriangleTable::new(&scene, &scene.materials).expect("30 triangles");
        for (i, t) in scene.triangles.iter().enumerate() {
            let rho = scene.materials[t.material as usize].reflectance;
            let zones = scene.edge_zones(i);
            for axis in 0..3 {
                assert_eq!(table.normal[axis][i], t.normal[axis]);
                assert_eq!(table.rho[axis][i], rho[axis]);
                assert_eq!(table.zones[axis][i], zones[axis]);
            }
        }
        let mut grown = scene.clone();
        grown.triangles.extend_from_slice(&scene.triangles[..3]);
        assert_eq!(
            TriangleTable::new(&grown, &grown.materials),
            None,
            "33 triangles"
        );
    }

    /// [`a_plain_group_equals_its_hits_one_at_a_time`] with `preset`, with or without the
    /// triangle table: how many hits were on mirror or glass.
    fn plain_groups_equal_their_hits(preset: MaterialPreset, table: bool) -> usize {
        let scene = cornell_box();
        let settings = RenderSettings {
            material_preset: preset,
            ..RenderSettings::default()
        };
        let mut tracer = Tracer::new(&scene, &settings);
        assert!(tracer.plain && tracer.triangle_table.is_some());
        if !table {
            tracer.triangle_table = None;
        }
        // 4,091 rays: the last group holds eleven.
        let rays = rays_in_the_box(4091);
        let mut hits = vec![None; rays.len()];
        scene.closest_intersections(&rays, f32::INFINITY, &mut hits);
        let (mut edges, mut others) = (0, 0);
        for at_edges in [true, false] {
            for (rays, hits) in rays.chunks(LANES).zip(hits.chunks(LANES)) {
                let mut lanes = HitLanes::new(f32::INFINITY);
                for (lane, hit) in hits.iter().enumerate() {
                    let hit = hit.map(|h| crate::shapes::accel::Hit {
                        index: h.triangle_index as u32,
                        t: h.distance,
                        u: h.u,
                        v: h.v,
                    });
                    lanes.set(lane, hit);
                }
                let mut group = DiffuseHits::<GROUPS>::new();
                group.clear();
                let other = group.fill_plain(0, &tracer, at_edges, rays, &lanes);
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
                    let mut one = DiffuseHits::<GROUPS>::new();
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
                        Some((lane, lane as u16))
                    );
                }
            }
        }
        // The rays met the triangles' edges.
        assert!(edges > 20, "{edges}");
        others
    }
}

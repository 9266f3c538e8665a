//! `Tracer`: one pass's scene, materials, light and switches, and the integrators' entry
//! points (`trace`, `trace_recorded`, `trace_camera`).

use std::borrow::Cow;

use glam::Vec3;

use super::*;
use crate::base::camera::ImagePoints;
use crate::base::geometry::Ray;
use crate::base::sampling::Rng;
use crate::shading::bsdf::{Bsdf, ShadingFrame};
use crate::shading::light::{AnyLight, LightSpec};
use crate::shading::material::{Material, MaterialPreset, TexturePreset};
use crate::shading::texture::planar_uv;
use crate::shapes::accel::set::{Compiled, InstructionSet};
use crate::shapes::intersect::Intersection;
use crate::shapes::scene::Scene;
use crate::shapes::scene::spec::PartMaterial;
use crate::transport::film::Seen;
use crate::transport::photon_map::PhotonMap;
use crate::transport::settings::RenderSettings;

/// What a batch of rays starts from, handed to the code compiled for the CPU as data.
#[derive(Clone, Copy)]
pub(super) enum Primary<'a> {
    Rays(&'a [Ray]),
    /// Camera rays, made from their image points ([`ImagePoints::rays`]).
    Camera(&'a ImagePoints<'a>),
}

/// [`Tracer::trace_primary`] compiled for each instruction set ([`Compiled`]): with AVX-512's
/// 32 vector registers instead of 16, the long body of a path vertex spills less; with AVX2
/// and FMA, or the portable baseline. (A closure handed to the compiled function would stay
/// out of line, compiled without the set; so the camera rays come as data, [`Primary`].)
pub(super) struct TracePrimary<'t, 'a> {
    pub(super) tracer: &'t Tracer<'a>,
    pub(super) primary: Primary<'t>,
    pub(super) rngs: &'t mut [Rng],
    pub(super) out: &'t mut [Vec3],
    pub(super) seen: &'t mut [Option<Seen>],
    pub(super) scratch: &'t mut Scratch,
}

impl Compiled for TracePrimary<'_, '_> {
    type Output = ();
    #[inline(always)]
    fn run<S: InstructionSet>(self, _set: S) {
        let t = self.tracer;
        t.trace_primary(self.primary, self.rngs, self.out, self.seen, self.scratch);
    }
}

/// Everything an integrator needs for one pass: the scene, its materials with the preset
/// applied, the light and the shading switches.
#[derive(Debug)]
pub struct Tracer<'a> {
    pub scene: &'a Scene,
    pub materials: Cow<'a, [Material]>,
    pub light: LightSpec,
    /// The light as an emitter ([`Light`]): what the general path tracer samples and sees.
    pub(super) emitter: AnyLight,
    /// Whether the path tracer takes its diffuse vertices sixteen at a time with the lab's
    /// direct term ([`path`]): under a point light (the lab's, or a sphere or square of size
    /// 0), without a photon map.
    pub(super) lane_light: bool,
    pub shading: Shading,
    /// Whether anything draws random numbers: the path tracer, a spherical light's soft
    /// shadows, a thin lens's aperture.
    pub(super) random: bool,
    /// No texture and no smooth normal anywhere: every surface is the lab's (flat, constant ρ).
    pub(super) plain: bool,
    /// Every material diffuse (no mirror, glass or rough metal).
    pub(super) all_diffuse: bool,
    /// A plain scene's triangles as tables, if it has at most 32 ([`hits::TriangleTable`]).
    pub(super) triangle_table: Option<hits::TriangleTable>,
    /// The pass's caustic photon map, when the path stage gathers caustics from photons
    /// ([`Tracer::for_pass`]).
    pub(super) photons: Option<PhotonMap>,
}

impl<'a> Tracer<'a> {
    pub fn new(scene: &'a Scene, settings: &RenderSettings) -> Self {
        let mut materials = match settings.material_preset {
            MaterialPreset::None => Cow::Borrowed(scene.materials.as_slice()),
            preset => Cow::Owned(preset.apply(&scene.materials, settings.roughness)),
        };
        if !settings.part_materials.is_empty() {
            let mut own = materials.into_owned();
            PartMaterial::apply(&settings.part_materials, &mut own);
            materials = Cow::Owned(own);
        }
        if settings.texture_preset != TexturePreset::None {
            materials = Cow::Owned(settings.texture_preset.apply(&materials));
        }
        let random = settings.is_stochastic();
        // The lab's direct term in lanes is the light sample of a point light; a photon map
        // is gathered at the diffuse vertices one at a time.
        let point_light = matches!(settings.light.emitter(), AnyLight::Point(_));
        let lane_light = point_light && !settings.shading.photon_caustics();
        let plain = materials
            .iter()
            .all(|m| m.texture.is_none() && m.relief.is_none())
            && (scene.vertex_normals.is_empty() || !settings.shading.smooth);
        let all_diffuse = materials.iter().all(Material::is_diffuse);
        let triangle_table = match plain {
            true => hits::TriangleTable::new(scene, &materials),
            false => None,
        };
        Self {
            scene,
            materials,
            light: settings.light,
            emitter: settings.light.emitter(),
            lane_light,
            shading: settings.shading,
            random,
            plain,
            all_diffuse,
            triangle_table,
            photons: None,
        }
    }

    /// The tracer of pass (sample) `pass`: [`Tracer::new`], with the pass's caustic photon
    /// map shot when the path stage gathers caustics from photons ([`photons::shoot`], seeded
    /// by the settings' seed and `pass`).
    pub fn for_pass(scene: &'a Scene, settings: &RenderSettings, pass: u32) -> Self {
        let mut tracer = Self::new(scene, settings);
        if settings.shading.photon_caustics() {
            let map = photons::shoot(&tracer, settings.shading.photons, settings.seed, pass);
            tracer.photons = Some(map);
        }
        tracer
    }

    /// The pass's caustic photon map, if it has one ([`Tracer::for_pass`]).
    #[inline]
    pub fn photon_map(&self) -> Option<&PhotonMap> {
        self.photons.as_ref()
    }

    /// The surface at a diffuse hit found by a ray going along `incoming`: its shading normal
    /// (smooth or flat, as the switch and the mesh say), its own normal, ρ (textured: at the
    /// mesh's texture coordinates, or at a planar projection of the hit for surfaces without
    /// them, such as the box's walls), and whether it lies at an edge of its triangle (asked
    /// only when shadow rays are cast, which alone need it).
    #[inline(always)]
    pub fn surface(&self, hit: &Intersection, material: &Material, incoming: Vec3) -> Surface {
        let at_edge = if self.shading.shadows {
            let (index, u, v) = (hit.triangle_index, hit.u, hit.v);
            self.scene.approach_at_edge(index, u, v, incoming)
        } else {
            None
        };
        self.surface_with(hit, material, incoming, at_edge)
    }

    /// What a path or a photon scatters with at `hit`, reached along `direction`: the hit's
    /// surface (its relief applied, `at_edge` found), the material's BSDF for its ρ, and the
    /// shading frame toward `wo = −direction` ([`ShadingFrame::new`]).
    #[inline(always)]
    pub fn scattering(&self, hit: &Intersection, direction: Vec3) -> Scattering {
        let scene = self.scene;
        let material = self.material_of(hit.triangle_index);
        let at_edge = scene.approach_at_edge(hit.triangle_index, hit.u, hit.v, direction);
        self.scattering_with(hit, material, direction, at_edge)
    }

    /// [`Tracer::scattering`] with the hit's `material` and `at_edge` given. A mirror or
    /// glass scatters about [`Tracer::specular_normal`] (a smooth normal could send its
    /// reflection below the surface), as the lab's stages follow it.
    #[inline(always)]
    pub fn scattering_with(
        &self,
        hit: &Intersection,
        material: &Material,
        direction: Vec3,
        at_edge: Option<Vec3>,
    ) -> Scattering {
        let mut surface = self.surface_with(hit, material, direction, at_edge);
        if material.is_specular() && material.relief.is_none() {
            surface.normal = surface.geometric;
        }
        let wo = -direction;
        Scattering {
            bsdf: material.bsdf(surface.rho),
            frame: ShadingFrame::new(surface.normal, surface.geometric, wo),
            surface,
            wo,
        }
    }

    /// [`Tracer::surface`] with `at_edge` given: the path tracer asks it of every hit anyway,
    /// for the ray that leaves it ([`continue_ray`]).
    ///
    /// A material with a relief ([`crate::shading::relief`]: a normal map, parallax occlusion mapping)
    /// changes the texture coordinates ρ is looked up at and the shading normal, here for
    /// every integrator. The map's tilt is held to the shading frame's rules toward the
    /// viewer, `-incoming` ([`ShadingFrame::bent_normal`]), with the normal it tilts (the
    /// triangle's own, or smooth shading's) in the geometric normal's place: the map never
    /// turns the normal further from the viewer than it was (no black patches), and a flat
    /// map leaves it as it was. The triangle's own normal then rules as it does for any
    /// smooth normal: [`Lighting::at`] gives no light from behind the surface, and the path
    /// tracers' [`ShadingFrame::new`] bends it again where needed (no light leaks).
    #[inline(always)]
    pub fn surface_with(
        &self,
        hit: &Intersection,
        material: &Material,
        incoming: Vec3,
        at_edge: Option<Vec3>,
    ) -> Surface {
        let (index, u, v) = (hit.triangle_index, hit.u, hit.v);
        let scene = self.scene;
        let geometric = scene.triangles[index].normal;
        if self.plain {
            // The same values as below (flat normal, constant ρ) without asking per hit, in the
            // lab pass's inner loop (PERFORMANCE.md, "Design choices and what each buys").
            return Surface {
                position: hit.position,
                normal: geometric,
                geometric,
                rho: material.reflectance,
                at_edge,
                relief_visibility: 1.0,
            };
        }
        let normal = scene.shading_normal(index, u, v, self.shading.smooth);
        let uv = || {
            scene
                .uv(index, u, v)
                .unwrap_or_else(|| planar_uv(hit.position, geometric))
        };
        let Some(relief) = &material.relief else {
            return Surface {
                position: hit.position,
                normal,
                geometric,
                rho: material.reflectance_at(uv, hit.position, normal),
                at_edge,
                relief_visibility: 1.0,
            };
        };
        let wo = -incoming;
        let frame = scene.tangent_frame(index, normal);
        let (uv, bumped) = relief.at(&frame, uv(), wo);
        let normal = if relief.normal.is_some() {
            ShadingFrame::bent_normal(bumped, normal, wo)
        } else {
            normal
        };
        // Parallax self-shadowing, toward the light's centre as D is (equation 27).
        let relief_visibility = if self.shading.parallax_shadows {
            let to_light = (self.light.position - hit.position).normalize_or_zero();
            relief.visibility(&frame, uv, to_light)
        } else {
            1.0
        };
        Surface {
            position: hit.position,
            normal,
            geometric,
            rho: material.reflectance_at(|| uv, hit.position, normal),
            at_edge,
            relief_visibility,
        }
    }

    /// The normal a mirror or glass `material` reflects and refracts about at `hit`, reached
    /// along `incoming`: the triangle's own (a smooth normal could send a reflection below the
    /// surface), or, where the material has a relief (a normal map, the water's waves), the
    /// relief's bent normal, [`Tracer::surface_with`]'s. The lab's stages and the sixteen-lane
    /// path tracer both ask it here; the general path tracer's [`Tracer::scattering`] holds
    /// the same bent normal in its frame.
    #[inline(always)]
    pub fn specular_normal(&self, hit: &Intersection, material: &Material, incoming: Vec3) -> Vec3 {
        match &material.relief {
            None => self.scene.triangles[hit.triangle_index].normal,
            Some(_) => self.surface_with(hit, material, incoming, None).normal,
        }
    }

    /// What the lab's stages use as ρ at a glossy hit (the rough metal): π·f(wo, wi), with wo
    /// toward the viewer and wi toward the light's centre, evaluated in the hit's shading
    /// frame ([`ShadingFrame::eval_world`]); for a diffuse surface this would be ρ itself.
    /// Multiplied by D (equation 27) it is the light the surface reflects toward the viewer.
    pub fn glossy_reflectance(
        &self,
        material: &Material,
        surface: &Surface,
        incoming: Vec3,
    ) -> Vec3 {
        let wo = -incoming;
        let wi = (self.light.position - surface.position).normalize_or_zero();
        let frame = ShadingFrame::new(surface.normal, surface.geometric, wo);
        let (f, _) = frame.eval_world(&material.bsdf(surface.rho), wo, wi);
        std::f32::consts::PI * f
    }

    /// [`Tracer::glossy_reflectance`]'s two parts, π·f_s (the microfacet highlight: a
    /// plastic's coating, all of a rough metal) and π·f_d (a plastic's diffuse base), each
    /// evaluated as the whole is: for the inspector.
    pub fn glossy_parts(
        &self,
        material: &Material,
        surface: &Surface,
        incoming: Vec3,
    ) -> (Vec3, Vec3) {
        let wo = -incoming;
        let wi = (self.light.position - surface.position).normalize_or_zero();
        let frame = ShadingFrame::new(surface.normal, surface.geometric, wo);
        let pi_f = |bsdf: &crate::shading::bsdf::Bsdf| {
            std::f32::consts::PI * frame.eval_world(bsdf, wo, wi).0
        };
        match material.bsdf(surface.rho) {
            crate::shading::bsdf::Bsdf::Plastic(plastic) => {
                let (coating, base) = plastic.lobes();
                (pi_f(&coating), pi_f(&base))
            }
            bsdf @ (crate::shading::bsdf::Bsdf::RoughConductor { .. }
            | crate::shading::bsdf::Bsdf::Lambertian { .. }
            | crate::shading::bsdf::Bsdf::Mirror { .. }
            | crate::shading::bsdf::Bsdf::Glass { .. }) => (pi_f(&bsdf), Vec3::ZERO),
        }
    }

    /// The scene's light as an emitter.
    #[inline]
    pub fn emitter(&self) -> &AnyLight {
        &self.emitter
    }

    /// The material of triangle `index`.
    #[inline]
    pub fn material_of(&self, triangle_index: usize) -> &Material {
        &self.materials[self.scene.triangles[triangle_index].material as usize]
    }

    /// What a camera ray whose first hit is `hit`, a mirror or glass, sees through it ([`Seen`]),
    /// the same for every sample along that ray: both specular branches are followed at each
    /// mirror and glass hit, Whitted-style with their weights ([`Material::specular_branches`],
    /// as the lab's stages trace them), to the first surface that is not a perfect specular one
    /// or the one reached after [`FEATURE_SPECULAR_BOUNCES`]. The albedo is the sum of those
    /// surfaces' reflectances times their branches' weights: the mean of what the path tracer's
    /// samples see along one lobe each, without its noise. The normal and the distance are
    /// the surfaces' averaged by their branches' weights; `None` if every branch leaves the
    /// scene.
    pub fn seen_through_specular(&self, ray: Ray, hit: Intersection) -> Option<Seen> {
        // Depth first: at most one pending branch a bounce, plus the one being followed.
        let mut stack =
            [(ray, hit, Vec3::ONE, 0u32, 0.0f32); FEATURE_SPECULAR_BOUNCES as usize + 2];
        let mut pending = 1;
        let (mut albedo, mut normal, mut depth, mut weights) = (Vec3::ZERO, Vec3::ZERO, 0.0, 0.0);
        while pending > 0 {
            pending -= 1;
            let (ray, hit, weight, bounces, travelled) = stack[pending];
            let travelled = travelled + hit.distance;
            let material = self.material_of(hit.triangle_index);
            if !material.is_specular() || bounces == FEATURE_SPECULAR_BOUNCES {
                let scattering = self.scattering(&hit, ray.direction);
                let rho = match scattering.bsdf {
                    Bsdf::RoughConductor { tint, .. } => tint,
                    Bsdf::Lambertian { .. }
                    | Bsdf::Mirror { .. }
                    | Bsdf::Glass { .. }
                    | Bsdf::Plastic(_) => scattering.surface.rho,
                };
                let normal_there = scattering.frame.shading_normal();
                let seen = Seen::at(weight, rho, normal_there, scattering.wo, travelled);
                let w = (weight.x + weight.y + weight.z) / 3.0;
                albedo += seen.albedo;
                normal += w * seen.normal;
                depth += w * seen.depth;
                weights += w;
                continue;
            }
            let d = ray.direction;
            let surface_normal = self.specular_normal(&hit, material, d);
            let at_edge = self
                .scene
                .approach_at_edge(hit.triangle_index, hit.u, hit.v, d);
            for &(direction, w) in material.specular_branches(d, surface_normal).as_slice() {
                let weight = weight * w;
                if weight.max_element() <= 0.0 {
                    continue;
                }
                let next = continue_ray(hit.position, surface_normal, direction, at_edge);
                if let Some(next_hit) = self.scene.closest_intersection(&next, f32::INFINITY) {
                    stack[pending] = (next, next_hit, weight, bounces + 1, travelled);
                    pending += 1;
                }
            }
        }
        if weights > 0.0 {
            Some(Seen {
                albedo,
                normal: normal / weights,
                depth: depth / weights,
            })
        } else {
            None
        }
    }

    /// Whether the integrator draws random numbers (and so needs each ray's generator).
    pub fn uses_random_numbers(&self) -> bool {
        self.random
    }

    /// Whether the integrator tells what each camera sample sees ([`Seen`]) as it traces it:
    /// the path tracer does, at no extra ray but those of the specular branches of a camera
    /// ray that meets a mirror or glass first. For the lab's stages the denoiser's features
    /// are traced apart ([`crate::transport::denoise::Features::trace`]).
    pub fn records_features(&self) -> bool {
        self.shading.stage.integrator() == Integrator::Path
    }

    /// How many camera rays to hand [`Tracer::trace_camera`] at a time: [`PATH_BATCH`] for
    /// the path tracer, [`BATCH`] for the lab's stages.
    pub fn batch_len(&self) -> usize {
        if self.records_features() {
            PATH_BATCH
        } else {
            BATCH
        }
    }

    /// The value of each ray, into `out`. `rngs` holds each ray's random stream (from
    /// [`crate::base::sampling::pixel_sample`]); where nothing is random
    /// ([`Tracer::uses_random_numbers`] is false) it may be empty.
    ///
    /// On a CPU with AVX2 and FMA, or AVX-512 (where the scene's kernels use them), the same
    /// code is compiled for that instruction set: the results are the same bit for bit (Rust never
    /// fuses a multiply and an add on its own, and every operation here is exactly rounded), and
    /// the path tracer runs faster (PERFORMANCE.md, "Design choices and what each buys").
    pub fn trace(&self, rays: &[Ray], rngs: &mut [Rng], out: &mut [Vec3]) {
        debug_assert_eq!(rays.len(), out.len());
        Scratch::with_thread(|scratch| {
            self.trace_for_cpu(Primary::Rays(rays), rngs, out, &mut [], scratch)
        });
    }

    /// [`Tracer::trace`] for the camera rays through `points`, made here
    /// ([`ImagePoints::rays`]) so that they too are made with the CPU's instruction set,
    /// sixteen at a time. The same rays as [`crate::Camera::primary_ray_rotated`] (or
    /// [`crate::Camera::lens_ray_rotated`]) makes one at a time, bit for bit.
    ///
    /// If `seen` is not empty (one per ray) and the integrator [records
    /// features](Tracer::records_features), each ray's [`Seen`] goes there (`None`: it left
    /// the scene); otherwise `seen` is left as it is. The batches work in `scratch`, which a
    /// caller tracing many batches (the rows of the image) makes once and hands to each.
    pub fn trace_camera(
        &self,
        points: &ImagePoints,
        rngs: &mut [Rng],
        out: &mut [Vec3],
        seen: &mut [Option<Seen>],
        scratch: &mut Scratch,
    ) {
        debug_assert_eq!(points.len(), out.len());
        debug_assert!(seen.is_empty() || seen.len() == out.len());
        self.trace_for_cpu(Primary::Camera(points), rngs, out, seen, scratch);
    }

    /// [`Tracer::trace_primary`] in the code compiled for the CPU's instruction set
    /// ([`TracePrimary`]).
    #[inline(always)]
    pub(super) fn trace_for_cpu(
        &self,
        primary: Primary,
        rngs: &mut [Rng],
        out: &mut [Vec3],
        seen: &mut [Option<Seen>],
        scratch: &mut Scratch,
    ) {
        self.scene.accel().isa().call(TracePrimary {
            tracer: self,
            primary,
            rngs,
            out,
            seen,
            scratch,
        });
    }

    /// The rays of `primary`, made in batches of [`Tracer::batch_len`] if they come as image
    /// points, traced by [`Tracer::trace_seen`].
    #[inline(always)]
    pub(super) fn trace_primary(
        &self,
        primary: Primary,
        rngs: &mut [Rng],
        out: &mut [Vec3],
        seen: &mut [Option<Seen>],
        scratch: &mut Scratch,
    ) {
        match primary {
            Primary::Rays(rays) => {
                let working = (&mut scratch.lab, &mut scratch.path);
                self.trace_seen(rays, rngs, out, seen, working, &mut ())
            }
            // The batch's length a constant in each: as a run-time value the loops around it
            // compile less tightly.
            Primary::Camera(points) if self.batch_len() == PATH_BATCH => {
                self.camera_batches::<PATH_BATCH>(points, rngs, out, seen, scratch)
            }
            Primary::Camera(points) => {
                self.camera_batches::<BATCH>(points, rngs, out, seen, scratch)
            }
        }
    }

    /// The camera rays through `points` made and traced `LEN` at a time ([`Tracer::batch_len`]).
    #[inline(always)]
    pub(super) fn camera_batches<const LEN: usize>(
        &self,
        points: &ImagePoints,
        rngs: &mut [Rng],
        out: &mut [Vec3],
        seen: &mut [Option<Seen>],
        scratch: &mut Scratch,
    ) {
        let Scratch { lab, path, rays } = scratch;
        for (c, out) in out.chunks_mut(LEN).enumerate() {
            let rays = &mut rays[..out.len()];
            for (k, rays) in rays.chunks_mut(ImagePoints::MAX_RAYS).enumerate() {
                points.rays(c * LEN + k * ImagePoints::MAX_RAYS, rays);
            }
            // Each ray's generator (none if nothing is random) and features (none if not asked
            // for).
            let part = |all: usize| {
                let start = (c * LEN).min(all);
                start..(start + LEN).min(all)
            };
            let (r, s) = (part(rngs.len()), part(seen.len()));
            let (rngs, seen) = (&mut rngs[r], &mut seen[s]);
            self.trace_seen(rays, rngs, out, seen, (lab, path), &mut ());
        }
    }

    /// [`Tracer::trace`] for any CPU; inlined into the AVX2 version.
    #[inline(always)]
    pub fn trace_portable(&self, rays: &[Ray], rngs: &mut [Rng], out: &mut [Vec3]) {
        Scratch::with_thread(|Scratch { lab, path, .. }| {
            self.trace_seen(rays, rngs, out, &mut [], (lab, path), &mut ())
        });
    }

    /// [`Tracer::trace_portable`], telling `recorder` every step (see [`Recorder`]): what the
    /// pixel inspector runs. With `()` it is `trace_portable` itself.
    #[inline(always)]
    pub fn trace_recorded<R: Recorder>(
        &self,
        rays: &[Ray],
        rngs: &mut [Rng],
        out: &mut [Vec3],
        recorder: &mut R,
    ) {
        Scratch::with_thread(|Scratch { lab, path, .. }| {
            self.trace_seen(rays, rngs, out, &mut [], (lab, path), recorder)
        });
    }

    /// [`Tracer::trace_recorded`], and what each ray sees into `seen` as
    /// [`Tracer::trace_camera`] says.
    #[inline(always)]
    pub(super) fn trace_seen<R: Recorder>(
        &self,
        rays: &[Ray],
        rngs: &mut [Rng],
        out: &mut [Vec3],
        seen: &mut [Option<Seen>],
        (lab, path): Working,
        recorder: &mut R,
    ) {
        match self.shading.stage.integrator() {
            Integrator::Lab => {
                assert!(
                    !self.random || rngs.len() == rays.len(),
                    "soft shadows and the lens need a generator per ray"
                );
                lab::trace(self, rays, rngs, out, lab, recorder);
            }
            Integrator::Path => {
                assert_eq!(
                    rngs.len(),
                    rays.len(),
                    "the path tracer needs a generator per ray"
                );
                path::trace(self, rays, rngs, out, seen, path, recorder);
            }
        }
    }
}

//! The inspector's [`Recorder`]: every step the integrator takes, in order, and the
//! [`Inspection`] made from them.

use glam::{Vec2, Vec3};

use super::*;
use crate::shading::material::{MaterialKind, Scatter};
use crate::shapes::intersect::Intersection;
use crate::transport::integrator::{HitTerms, Recorder, path, path_mis};

/// A step the integrator took, as told to [`Recording`].
#[derive(Clone, Debug)]
pub(super) enum Event {
    Hit {
        ray: Ray,
        hit: Option<Intersection>,
        weight: Vec3,
        depth: u32,
    },
    Specular {
        hit: Intersection,
        weight: Vec3,
        depth: u32,
        branches: Vec<(Vec3, Vec3)>,
    },
    Shaded {
        terms: HitTerms,
        n: Vec3,
        value: Vec3,
        weight: Vec3,
    },
    Scattered {
        scatter: Scatter,
        survival: f32,
        beta: Vec3,
        survives: bool,
    },
    Vertex(path_mis::PathVertex),
}

/// The inspector's [`Recorder`]: every step, in order.
#[derive(Debug, Default)]
pub(super) struct Recording {
    pub(super) events: Vec<Event>,
}

impl Recorder for Recording {
    const ENABLED: bool = true;

    fn closest_hit(&mut self, ray: &Ray, hit: Option<&Intersection>, weight: Vec3, depth: u32) {
        self.events.push(Event::Hit {
            ray: *ray,
            hit: hit.copied(),
            weight,
            depth,
        });
    }

    fn specular_hit(
        &mut self,
        hit: &Intersection,
        weight: Vec3,
        depth: u32,
        branches: &[(Vec3, Vec3)],
    ) {
        self.events.push(Event::Specular {
            hit: *hit,
            weight,
            depth,
            branches: branches.to_vec(),
        });
    }

    fn shaded(&mut self, terms: &HitTerms, n: Vec3, value: Vec3, weight: Vec3) {
        self.events.push(Event::Shaded {
            terms: *terms,
            n,
            value,
            weight,
        });
    }

    fn scattered(&mut self, scatter: &Scatter, survival: f32, beta: Vec3, survives: bool) {
        self.events.push(Event::Scattered {
            scatter: *scatter,
            survival,
            beta,
            survives,
        });
    }

    fn path_vertex(&mut self, vertex: &path_mis::PathVertex) {
        self.events.push(Event::Vertex(*vertex));
    }
}

/// How a ray arriving along `incoming` left a surface of `kind` along `outgoing`: a diffuse
/// bounce, a reflection (back to the side it came from) or a refraction (through).
fn scatter_kind(kind: &MaterialKind, incoming: Vec3, outgoing: Vec3, normal: Vec3) -> &'static str {
    if matches!(kind, MaterialKind::Diffuse) {
        "cosine-weighted bounce"
    } else if outgoing.dot(normal) * incoming.dot(normal) < 0.0 {
        "reflection"
    } else {
        "refraction"
    }
}

impl Inspection {
    #[allow(clippy::too_many_arguments)]
    pub(super) fn from_recording(
        tracer: &Tracer,
        settings: &RenderSettings,
        pixel: [u32; 2],
        image_point: [f32; 2],
        lens_point: Option<Vec2>,
        camera_ray: Ray,
        events: &[Event],
        r: Vec3,
    ) -> Self {
        let scene = tracer.scene;
        let shading = &tracer.shading;
        let stage = shading.stage;
        let camera = &settings.camera;
        let mut inspection = Inspection {
            pixel,
            stage,
            computes: shading.description(settings.material_preset),
            shadows: shading.shadows && stage != Stage::Flat,
            image: [camera.width, camera.height],
            focal_length: camera.focal_length,
            image_point,
            lens_point,
            origin: camera_ray.origin,
            direction: camera_ray.direction,
            triangle: None,
            surface: None,
            kind: None,
            t: None,
            u: None,
            v: None,
            position: None,
            normal: None,
            back_facing: None,
            shading_normal: None,
            normal_mapped: false,
            light: tracer.light,
            terms: LightTerms::default(),
            n: shading.indirect_term(),
            r,
            specular_chain: Vec::new(),
            escaped: Vec::new(),
            shaded: Vec::new(),
            bounces: Vec::new(),
        };
        // The diffuse hits waiting for their terms, in the order the integrator shades them,
        // and the latest hit (a specular hit's or a path scattering's own).
        let mut waiting: std::collections::VecDeque<(Ray, Intersection, u32)> = Default::default();
        let mut latest: Option<(Ray, Intersection)> = None;
        for (index, event) in events.iter().enumerate() {
            match event {
                Event::Hit {
                    ray,
                    hit,
                    weight,
                    depth,
                } => {
                    let first = index == 0;
                    let Some(hit) = hit else {
                        if stage == Stage::Path {
                            if let Some(last) = inspection.bounces.last_mut() {
                                last.ends = Some("the next ray leaves the scene".to_owned());
                            }
                        } else if !first {
                            inspection.escaped.push(EscapedBranch {
                                depth: *depth,
                                weight: *weight,
                            });
                        }
                        continue;
                    };
                    let material = tracer.material_of(hit.triangle_index);
                    let geometric = scene.triangles[hit.triangle_index].normal;
                    if first {
                        inspection.triangle = Some(hit.triangle_index);
                        inspection.surface = Some(material.name.clone());
                        inspection.kind = Some(material.kind.name());
                        inspection.t = Some(hit.distance);
                        inspection.u = Some(hit.u);
                        inspection.v = Some(hit.v);
                        inspection.position = Some(hit.position);
                        inspection.normal = Some(geometric);
                        inspection.back_facing = Some(ray.direction.dot(geometric) > 0.0);
                        inspection.normal_mapped =
                            material.relief.as_ref().is_some_and(|r| r.normal.is_some());
                    }
                    if stage == Stage::Path {
                        inspection.bounces.push(PathVertex {
                            depth: *depth,
                            triangle: hit.triangle_index,
                            surface: material.name.clone(),
                            kind: material.kind.name(),
                            position: hit.position,
                            beta: *weight,
                            light_added: Vec3::ZERO,
                            direction_out: None,
                            scatter: None,
                            scatter_weight: None,
                            survival: None,
                            beta_after: None,
                            ends: None,
                            light_sample: None,
                            photons: None,
                        });
                    }
                    // Diffuse hits and, in the lab's stages, glossy ones are shaded; the path
                    // tracer tells the others' light as a vertex.
                    if !material.is_specular() && (stage != Stage::Path || material.is_diffuse()) {
                        waiting.push_back((*ray, *hit, *depth));
                    }
                    latest = Some((*ray, *hit));
                }
                Event::Specular {
                    hit,
                    weight,
                    depth,
                    branches,
                } => {
                    let material = tracer.material_of(hit.triangle_index);
                    let normal = scene.triangles[hit.triangle_index].normal;
                    let incoming = latest.map_or(camera_ray.direction, |(ray, _)| ray.direction);
                    let step = |branch, direction, w: Vec3| SpecularStep {
                        depth: *depth,
                        triangle: hit.triangle_index,
                        surface: material.name.clone(),
                        kind: material.kind.name(),
                        position: hit.position,
                        branch,
                        direction,
                        weight: w,
                        total_weight: *weight * w,
                    };
                    if branches.is_empty() {
                        inspection
                            .specular_chain
                            .push(step("given up", None, Vec3::ZERO));
                    }
                    for &(direction, w) in branches {
                        let kind = match scatter_kind(&material.kind, incoming, direction, normal) {
                            "reflection"
                                if branches.len() == 1
                                    && matches!(material.kind, MaterialKind::Glass { .. }) =>
                            {
                                "total internal reflection"
                            }
                            kind => kind,
                        };
                        inspection
                            .specular_chain
                            .push(step(kind, Some(direction), w));
                    }
                }
                Event::Shaded {
                    terms,
                    n,
                    value,
                    weight,
                } => {
                    let Some((ray, hit, depth)) = waiting.pop_front() else {
                        continue;
                    };
                    let material = tracer.material_of(hit.triangle_index);
                    let glossy = (!material.is_diffuse()).then(|| {
                        let surface = tracer.surface(&hit, material, ray.direction);
                        let (specular, diffuse) =
                            tracer.glossy_parts(material, &surface, ray.direction);
                        GlossyTerms { specular, diffuse }
                    });
                    let contribution = *weight * *value;
                    let shaded = ShadedHit {
                        depth,
                        triangle: hit.triangle_index,
                        surface: material.name.clone(),
                        t: hit.distance,
                        u: hit.u,
                        v: hit.v,
                        position: terms.position,
                        normal: terms.normal,
                        terms: LightTerms::of(tracer, stage, terms, material, glossy),
                        n: *n,
                        value: *value,
                        weight: *weight,
                        contribution,
                    };
                    if stage == Stage::Path
                        && let Some(vertex) = inspection
                            .bounces
                            .iter_mut()
                            .rev()
                            .find(|v| v.position == terms.position)
                    {
                        vertex.light_added = contribution;
                    }
                    if inspection.shaded.is_empty() {
                        inspection.terms = shaded.terms.clone();
                        if inspection.triangle == Some(hit.triangle_index)
                            && inspection.position == Some(terms.position)
                            && inspection.normal != Some(terms.normal)
                        {
                            inspection.shading_normal = Some(terms.normal);
                        }
                    }
                    inspection.shaded.push(shaded);
                }
                Event::Vertex(v) => {
                    if let (Some(vertex), Some(l)) = (inspection.bounces.last_mut(), v.light) {
                        vertex.light_added = l.added;
                        vertex.light_sample = Some(l);
                    }
                    if let (Some(vertex), Some(g)) = (inspection.bounces.last_mut(), v.photons) {
                        vertex.photons = Some(PhotonGather {
                            photons: g.photons,
                            radius: g.radius,
                            added: g.value,
                        });
                    }
                }
                Event::Scattered {
                    scatter,
                    survival,
                    beta,
                    survives,
                } => {
                    if let (Some(vertex), Some((ray, hit))) =
                        (inspection.bounces.last_mut(), latest)
                    {
                        let (incoming, hit) = (ray.direction, hit.triangle_index);
                        vertex.scatter = Some(scatter_kind(
                            &tracer.material_of(hit).kind,
                            incoming,
                            scatter.direction,
                            scene.triangles[hit].normal,
                        ));
                        vertex.direction_out = Some(scatter.direction);
                        vertex.scatter_weight = Some(scatter.weight);
                        vertex.survival = Some(*survival);
                        vertex.beta_after = Some(*beta);
                        if !survives {
                            vertex.ends = Some(if vertex.depth + 1 >= path::MAX_DEPTH {
                                format!("{} vertices, the most a path makes", path::MAX_DEPTH)
                            } else {
                                "Russian roulette ends the path".to_owned()
                            });
                        }
                    }
                }
            }
        }
        if stage == Stage::Path
            && let Some(last) = inspection.bounces.last_mut()
            && last.ends.is_none()
            && last.direction_out.is_none()
        {
            last.ends = Some(match shading.max_bounces() {
                0 => "no bounces (indirect off or bounces 0): direct light only".to_owned(),
                n => format!("the bounce cap ({n}) is reached"),
            });
        }
        inspection
    }
}

//! The quantities bound to the tracer: the camera rays traced (with the student's `d`), each
//! diffuse hit's terms recorded once with its shadow ray's answer ([`Recording`]), then
//! `shadowed`, `D` and `R` evaluated over the recorded terms, sixteen hits at a time, without
//! tracing again ([`Recording::evaluate`]).
//!
//! The hits are the lab integrator's own ([`pixel_hits`], which [`check`]'s formula mistakes
//! use too): a pixel whose camera ray meets mirror or glass is the sum of its Whitted
//! branches' diffuse hits, each times its weight. Where the student writes no quantity, it is
//! the lab's, with the renderer's bits:
//!
//! * `d`: `right·(x + ½ − W/2) + down·(y + ½ − H/2) + forward·f` ([`Camera::primary_ray`]);
//! * `shadowStart`: the lab's shadow ray's start, [`SHADOW_OFFSET`] off the surface on the
//!   light's side ([`shadow_ray`]);
//! * `shadowed`: the shadow ray blocked before the light, tested (with shadows on) where light
//!   arrives: where the lab's D is not 0, or the student's D would not be 0 unshadowed;
//! * `D`: `shadowed ? 0 : D` of equation 27 as the lab computes it ([`DirectLight::at`]);
//! * `R`: equations 28–30 as the stage combines them ([`shaded_value`]).
//!
//! `shadowDistance` is the distance along the shadow ray from `shadowStart` to the nearest
//! surface (infinity when none). With the lab's start the lab's test, `shadowDistance <
//! length(lightPos - shadowStart)`, is the renderer's up to a surface within 2·10⁻⁴ of the
//! light.
//!
//! [`check`]: crate::teaching::check
//! [`Camera::primary_ray`]: crate::Camera::primary_ray
//! [`DirectLight::at`]: crate::shading::light::DirectLight::at
//! [`SHADOW_OFFSET`]: crate::shading::light::SHADOW_OFFSET

use glam::{Mat3, Vec3};
use rayon::prelude::*;

use super::explain::{Explanation, HitValues, QuantityValue, Term, Value};
use super::{INPUT_COMPONENTS, INPUTS, Quantity, compile::Equations, offset};
use crate::base::camera::Camera;
use crate::base::geometry::Ray;
use crate::shading::light::shadow_ray;
use crate::shapes::scene::Scene;
use crate::teaching::check::mistakes::{PixelHits, ShadedHit, pixel_hits};
use crate::transport::film::Image;
use crate::transport::integrator::{Stage, Tracer, shaded_value};
use crate::transport::settings::RenderSettings;

/// The colour of a pixel that came out NaN or infinite.
pub const MAGENTA: Vec3 = Vec3::new(1.0, 0.0, 1.0);

/// A diffuse hit's terms, as the student's quantities read them.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Hit {
    position: Vec3,
    normal: Vec3,
    distance: f32,
    color: Vec3,
    shadow_start: Vec3,
    shadow_distance: f32,
    /// The lab's shadow ray's start (the hit's position where it has none).
    lab_shadow_start: Vec3,
    /// D of equation 27 before shadows, as the lab computed it.
    lab_d: Vec3,
    /// Whether the lab cast a shadow ray here (shadows on, light arriving).
    lab_cast: bool,
    /// The shadow test's answer from `shadow_start`: the lab's own where it cast one.
    blocked: bool,
    /// What the pixel gets this hit's value times.
    weight: Vec3,
}

/// What a pixel is made of.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Pixel {
    Miss,
    /// The camera ray's direction was not finite, or 0: the pixel is counted as NaN.
    BadRay,
    /// One diffuse hit, `hits[first]`: the pixel is its value.
    Diffuse {
        first: u32,
    },
    /// Mirror or glass: the sum of `hits[first..first + count]`, each times its weight.
    Specular {
        first: u32,
        count: u32,
    },
}

/// The values the quantities read that are one for the whole image.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Uniforms {
    width: f32,
    height: f32,
    focal_length: f32,
    camera: Vec3,
    right: Vec3,
    down: Vec3,
    forward: Vec3,
    light: Vec3,
    light_color: Vec3,
    indirect: Vec3,
    stage: Stage,
    shadows: bool,
    /// The camera and its rotation: the lab's ray through a pixel.
    lens: Camera,
    rotation: Mat3,
}

/// Every pixel's diffuse hits and their terms, traced once with the student's `d` and
/// `shadowStart` (or the lab's): what `shadowed`, `D` and `R` are evaluated over.
#[derive(Clone, Debug, PartialEq)]
pub struct Recording {
    width: u32,
    height: u32,
    pixels: Vec<Pixel>,
    hits: Vec<Hit>,
    uniforms: Uniforms,
    /// The `d` and `shadowStart` it was traced with (`None`: the lab's).
    traced_with: Equations,
}

/// An image the student's quantities made.
#[derive(Clone, Debug, PartialEq)]
pub struct Rendered {
    /// Linear, as the renderer's; pixels that came out NaN or infinite are [`MAGENTA`].
    pub image: Image,
    /// How many pixels came out NaN or infinite.
    pub non_finite: usize,
}

/// [`record`] then [`Recording::evaluate`].
pub fn render(scene: &Scene, settings: &RenderSettings, equations: &Equations) -> Rendered {
    record(scene, settings, equations).evaluate(equations)
}

/// Traces the camera rays (with `equations`' `d`) through the lab's integrator and records
/// every pixel's diffuse hits with their shadow rays (from `equations`' `shadowStart`)
/// answered, rows in parallel.
pub fn record(scene: &Scene, settings: &RenderSettings, equations: &Equations) -> Recording {
    let camera = &settings.camera;
    let rotation = camera.rotation();
    let uniforms = Uniforms {
        width: camera.width as f32,
        height: camera.height as f32,
        focal_length: camera.focal_length,
        camera: camera.position,
        right: rotation.x_axis,
        down: rotation.y_axis,
        forward: rotation.z_axis,
        light: settings.light.position,
        light_color: settings.light.channel_power(),
        indirect: settings.shading.indirect_term(),
        stage: settings.shading.stage,
        shadows: settings.shading.shadows,
        lens: *camera,
        rotation,
    };
    let tracer = Tracer::new(scene, settings);
    let (w, h) = (camera.width as usize, camera.height as usize);
    let rows: Vec<(Vec<Pixel>, Vec<Hit>)> = (0..h)
        .into_par_iter()
        .map(|y| {
            let rays = camera_rays(equations, &uniforms, y, w, |x| {
                camera.primary_ray_rotated(&rotation, x as f32 + 0.5, y as f32 + 0.5)
            });
            let good: Vec<Ray> = rays
                .iter()
                .map(|r| r.unwrap_or(Ray::new(Vec3::ZERO, Vec3::Z)))
                .collect();
            let traced = pixel_hits(&tracer, &good);
            let mut pixels = Vec::with_capacity(w);
            let mut hits = Vec::new();
            let mut slots = Vec::new();
            for (ray, pixel) in rays.iter().zip(&traced) {
                let first = hits.len() as u32;
                let mut add = |s: &ShadedHit| {
                    hits.push(hit_of(scene, settings, equations, &uniforms, s, &mut slots));
                };
                pixels.push(match (ray, pixel) {
                    (None, _) => Pixel::BadRay,
                    (_, PixelHits::Miss) => Pixel::Miss,
                    (_, PixelHits::Diffuse(s)) => {
                        add(s);
                        Pixel::Diffuse { first }
                    }
                    (_, PixelHits::Specular(branches)) => {
                        branches.iter().for_each(&mut add);
                        Pixel::Specular {
                            first,
                            count: branches.len() as u32,
                        }
                    }
                });
            }
            (pixels, hits)
        })
        .collect();
    let mut pixels = Vec::with_capacity(w * h);
    let mut hits = Vec::new();
    for (row, row_hits) in rows {
        let base = hits.len() as u32;
        pixels.extend(row.into_iter().map(|p| match p {
            Pixel::Diffuse { first } => Pixel::Diffuse {
                first: first + base,
            },
            Pixel::Specular { first, count } => Pixel::Specular {
                first: first + base,
                count,
            },
            other => other,
        }));
        hits.extend(row_hits);
    }
    Recording {
        width: camera.width,
        height: camera.height,
        pixels,
        hits,
        uniforms,
        traced_with: retraced_part(equations),
    }
}

/// Only the quantities that change what is traced.
fn retraced_part(equations: &Equations) -> Equations {
    let mut e = equations.clone();
    e.keep_only(Quantity::retraces);
    e
}

/// Row `y`'s camera rays: the lab's (`lab(x)`), or along the student's `d`, sixteen pixels at
/// a time; `None` where `d` is not finite or is 0.
fn camera_rays(
    equations: &Equations,
    u: &Uniforms,
    y: usize,
    w: usize,
    lab: impl Fn(usize) -> Ray,
) -> Vec<Option<Ray>> {
    let Some(tape) = equations.tape(Quantity::Direction) else {
        return (0..w).map(|x| Some(lab(x))).collect();
    };
    let mut inputs = direction_inputs::<16>(u, y);
    let mut slots = Vec::new();
    let mut rays = Vec::with_capacity(w);
    for x0 in (0..w).step_by(16) {
        inputs[offset("x")] = std::array::from_fn(|i| (x0 + i) as f32);
        let d = tape.run::<16>(&inputs, &mut slots);
        for i in 0..16.min(w - x0) {
            let d = Vec3::new(d[0][i], d[1][i], d[2][i]);
            rays.push((d.is_finite() && d != Vec3::ZERO).then(|| Ray::new(u.camera, d)));
        }
    }
    rays
}

/// The inputs `d` reads in row `y`, `N` pixels at a time (`x` left 0, for the caller to set).
fn direction_inputs<const N: usize>(u: &Uniforms, y: usize) -> [[f32; N]; INPUT_COMPONENTS] {
    let mut inputs = [[0.0f32; N]; INPUT_COMPONENTS];
    let mut put = |name: &str, v: &[f32]| {
        for (k, c) in v.iter().enumerate() {
            inputs[offset(name) + k] = [*c; N];
        }
    };
    put("y", &[y as f32]);
    put("W", &[u.width]);
    put("H", &[u.height]);
    put("focalLength", &[u.focal_length]);
    put("cameraPos", &u.camera.to_array());
    put("right", &u.right.to_array());
    put("down", &u.down.to_array());
    put("forward", &u.forward.to_array());
    inputs
}

/// A shaded hit's terms, its shadow ray cast from the student's `shadowStart` or the lab's.
fn hit_of(
    scene: &Scene,
    settings: &RenderSettings,
    equations: &Equations,
    u: &Uniforms,
    s: &ShadedHit,
    slots: &mut Vec<[f32; 1]>,
) -> Hit {
    let t = &s.terms;
    let mut hit = Hit {
        position: t.position,
        normal: t.normal,
        distance: s.hit.distance,
        color: t.rho,
        shadow_start: t.position,
        shadow_distance: f32::INFINITY,
        lab_shadow_start: t.position,
        lab_d: t.d,
        lab_cast: t.shadow_ray.is_some(),
        blocked: false,
        weight: s.weight,
    };
    let nearest = |ray: &Ray| {
        scene
            .closest_intersection(ray, f32::INFINITY)
            .map_or(f32::INFINITY, |h| h.distance)
    };
    // The lab's shadow ray: the one it cast, or (where it cast none, as no light arrived) the
    // one it would have ([`crate::shapes::scene::in_shadow`]).
    let lab_ray = t.shadow_ray.or_else(|| {
        let at_edge = scene.approach_at_edge(s.hit.triangle_index, s.hit.u, s.hit.v, s.incoming);
        shadow_ray(&settings.light, t.position, t.normal, at_edge)
    });
    if let Some((ray, _)) = lab_ray {
        hit.lab_shadow_start = ray.origin;
    }
    if let Some(tape) = equations.tape(Quantity::ShadowStart) {
        let start = Vec3::from_array(tape.run_one(&shadow_start_inputs(&hit, u), slots));
        hit.shadow_start = start;
        let to_light = u.light - start;
        if start.is_finite() && to_light != Vec3::ZERO {
            hit.shadow_distance = nearest(&Ray::new(start, to_light));
            hit.blocked = hit.shadow_distance < to_light.length();
        } else {
            hit.shadow_distance = f32::NAN;
        }
        return hit;
    }
    if let Some((ray, t_max)) = lab_ray {
        hit.shadow_start = ray.origin;
        hit.shadow_distance = nearest(&ray);
        hit.blocked = if hit.lab_cast {
            t.blocked
        } else {
            hit.shadow_distance < t_max
        };
    }
    hit
}

/// The inputs `shadowStart` reads at `hit` (its shadow ray not yet cast).
fn shadow_start_inputs(hit: &Hit, u: &Uniforms) -> [f32; INPUT_COMPONENTS] {
    let unanswered = Hit {
        shadow_start: hit.position,
        shadow_distance: f32::INFINITY,
        ..*hit
    };
    let mut inputs = [0.0f32; INPUT_COMPONENTS];
    hit_inputs(&unanswered, u, |k, v| inputs[k] = v);
    inputs
}

/// Calls `put(component, value)` for every input a hit gives (all but `x`, `y`, `shadowed`
/// and `D`).
fn hit_inputs(hit: &Hit, u: &Uniforms, mut put: impl FnMut(usize, f32)) {
    uniform_inputs(u, &mut put);
    own_inputs(hit, put);
}

/// Calls `put(component, value)` for the inputs that are one for the whole image: the
/// camera's, the light's, N and the image's size.
fn uniform_inputs(u: &Uniforms, mut put: impl FnMut(usize, f32)) {
    let mut vec = |first: usize, v: Vec3| {
        for (k, c) in v.to_array().into_iter().enumerate() {
            put(first + k, c);
        }
    };
    vec(const { offset("cameraPos") }, u.camera);
    vec(const { offset("right") }, u.right);
    vec(const { offset("down") }, u.down);
    vec(const { offset("forward") }, u.forward);
    vec(const { offset("lightPos") }, u.light);
    vec(const { offset("lightColor") }, u.light_color);
    vec(const { offset("indirectLight") }, u.indirect);
    for (k, v) in [
        (const { offset("W") }, u.width),
        (const { offset("H") }, u.height),
        (const { offset("focalLength") }, u.focal_length),
    ] {
        put(k, v);
    }
}

/// Calls `put(component, value)` for the inputs that are the hit's own.
fn own_inputs(hit: &Hit, mut put: impl FnMut(usize, f32)) {
    let mut vec = |first: usize, v: Vec3| {
        for (k, c) in v.to_array().into_iter().enumerate() {
            put(first + k, c);
        }
    };
    vec(const { offset("position") }, hit.position);
    vec(const { offset("normal") }, hit.normal);
    vec(const { offset("color") }, hit.color);
    vec(const { offset("shadowStart") }, hit.shadow_start);
    put(const { offset("distance") }, hit.distance);
    put(const { offset("shadowDistance") }, hit.shadow_distance);
}

impl Recording {
    /// Whether `equations` can be evaluated over this recording, or need tracing again (their
    /// `d` or `shadowStart` differ from those it was traced with).
    pub fn fits(&self, equations: &Equations) -> bool {
        !self.traced_with.retraces_from(equations)
    }

    pub fn hits(&self) -> usize {
        self.hits.len()
    }

    /// The image of `equations`' `shadowed`, `D` and `R` (the lab's where not written) over
    /// the recorded hits, sixteen at a time. `equations` should [`Recording::fits`] it: their
    /// `d` and `shadowStart` are those traced.
    pub fn evaluate(&self, equations: &Equations) -> Rendered {
        self.evaluate_lanes::<16>(equations)
    }

    /// [`Recording::evaluate`] `N` hits at a time: 16, or 1 (the same bits).
    pub fn evaluate_lanes<const N: usize>(&self, equations: &Equations) -> Rendered {
        let values: Vec<Vec3> = self
            .hits
            .par_chunks(CHUNK)
            .flat_map_iter(|chunk| {
                let mut slots = Vec::new();
                let mut out = vec![Vec3::ZERO; chunk.len()];
                for (group, out) in chunk.chunks(N).zip(out.chunks_mut(N)) {
                    self.values::<N>(equations, group, &mut slots, out, None);
                }
                out
            })
            .collect();
        let mut pixels: Vec<Vec3> = self
            .pixels
            .par_iter()
            .map(|p| self.pixel_value(*p, |i| values[i]))
            .collect();
        let non_finite = pixels
            .par_iter_mut()
            .map(|v| {
                let bad = !v.is_finite();
                if bad {
                    *v = MAGENTA;
                }
                usize::from(bad)
            })
            .sum();
        Rendered {
            image: Image {
                width: self.width,
                height: self.height,
                pixels,
            },
            non_finite,
        }
    }

    /// A pixel's value from its hits' values (`value(i)`: R at hit `i`): black for a miss, NaN
    /// for a bad ray, the sum of the hits' values times their weights behind mirror or glass.
    fn pixel_value(&self, p: Pixel, value: impl Fn(usize) -> Vec3) -> Vec3 {
        match p {
            Pixel::Miss => Vec3::ZERO,
            Pixel::BadRay => Vec3::NAN,
            Pixel::Diffuse { first } => value(first as usize),
            Pixel::Specular { first, count } => (first as usize..(first + count) as usize)
                .fold(Vec3::ZERO, |sum, i| sum + self.hits[i].weight * value(i)),
        }
    }

    /// Pixel `(x, y)` explained: its value and, at each diffuse hit it is made of, the lab's
    /// terms and every quantity, the student's value and each part of their text beside the
    /// lab's value from the same inputs. Evaluated by the image's own code, one hit at a time
    /// (whose bits are the sixteen-lane form's): the value is the image's pixel, bit for bit.
    /// `equations` should [`Recording::fits`] the recording. `None` outside the image.
    pub fn explain(&self, equations: &Equations, x: u32, y: u32) -> Option<Explanation> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let u = &self.uniforms;
        let pixel = self.pixels[y as usize * self.width as usize + x as usize];
        // d: the student's run over this pixel as `camera_rays` runs it, or the lab's ray.
        let mut inputs = direction_inputs::<1>(u, y as usize);
        inputs[offset("x")] = [x as f32];
        let mut slots = Vec::new();
        if let Some(tape) = equations.tape(Quantity::Direction) {
            tape.run::<1>(&inputs, &mut slots);
        }
        let lab_ray = u
            .lens
            .primary_ray_rotated(&u.rotation, x as f32 + 0.5, y as f32 + 0.5);
        let direction = QuantityValue::new(
            equations,
            Quantity::Direction,
            &slots,
            Value::Vec3(lab_ray.direction.to_array()),
        );
        let direction_terms = terms(&inputs, false);
        let range = match pixel {
            Pixel::Miss | Pixel::BadRay => 0..0,
            Pixel::Diffuse { first } => first as usize..first as usize + 1,
            Pixel::Specular { first, count } => first as usize..(first + count) as usize,
        };
        let mut values = Vec::new();
        let mut hits = Vec::new();
        for hit in &self.hits[range.clone()] {
            let mut quantities = Vec::new();
            let start = match equations.tape(Quantity::ShadowStart) {
                Some(tape) => {
                    let start = shadow_start_inputs(hit, u).map(|v| [v]);
                    tape.run::<1>(&start, &mut slots);
                    &slots[..]
                }
                None => &[],
            };
            quantities.push(QuantityValue::new(
                equations,
                Quantity::ShadowStart,
                start,
                Value::Vec3(hit.lab_shadow_start.to_array()),
            ));
            let mut hit_terms = Vec::new();
            let mut watch =
                |q: Quantity, inputs: &[[f32; 1]], slots: &[[f32; 1]], lab: &[[f32; 3]]| {
                    quantities.push(QuantityValue::new(
                        equations,
                        q,
                        slots,
                        Value::of(q.ty(), lab[0]),
                    ));
                    if q == Quantity::Value {
                        hit_terms = terms(inputs, true);
                    }
                };
            let mut value = [Vec3::ZERO];
            self.values::<1>(
                equations,
                std::slice::from_ref(hit),
                &mut Vec::new(),
                &mut value,
                Some(&mut watch),
            );
            values.push(value[0]);
            hits.push(HitValues {
                weight: hit.weight.to_array(),
                terms: hit_terms,
                quantities,
            });
        }
        let value = self.pixel_value(pixel, |i| values[i - range.start]);
        Some(Explanation {
            pixel: [x, y],
            made_of: match pixel {
                Pixel::Miss => "miss",
                Pixel::BadRay => "bad ray",
                Pixel::Diffuse { .. } => "diffuse",
                Pixel::Specular { .. } => "specular",
            },
            value: value.to_array(),
            finite: value.is_finite(),
            direction,
            direction_terms,
            hits,
        })
    }

    /// R at each hit of `group` (at most `N`) into `out` (as long as `group`). `watch`, if
    /// given, is told each of `shadowed`, `D` and `R` as it is computed: the inputs it read,
    /// the slots the student's tape left (empty where they wrote none) and the lab's value at
    /// each hit from those inputs.
    fn values<const N: usize>(
        &self,
        equations: &Equations,
        group: &[Hit],
        slots: &mut Vec<[f32; N]>,
        out: &mut [Vec3],
        mut watch: Option<&mut Watch<'_, N>>,
    ) {
        let u = &self.uniforms;
        // Lanes past the group's hits hold the uniforms and zeros: computed, never read.
        let mut inputs = [[0.0f32; N]; INPUT_COMPONENTS];
        uniform_inputs(u, |k, v| inputs[k] = [v; N]);
        for (i, hit) in group.iter().enumerate() {
            own_inputs(hit, |k, v| inputs[k][i] = v);
        }
        let lanes = group.len();
        let vec3s = |v: [[f32; N]; 3]| -> [Vec3; N] {
            std::array::from_fn(|i| Vec3::new(v[0][i], v[1][i], v[2][i]))
        };
        let d_tape = equations.tape(Quantity::Direct);
        let shadowed_tape = equations.tape(Quantity::Shadowed);
        // The lab's shadowed: its test where light arrives. Where the lab cast no shadow ray
        // (and the ray it would have cast is blocked), light arrives if the student's D,
        // unshadowed, is not 0.
        let mut lab_shadowed = [false; N];
        if shadowed_tape.is_none() || watch.is_some() {
            let ask = |h: &Hit| u.shadows && !h.lab_cast && h.blocked;
            let unshadowed = match d_tape {
                Some(tape) if group.iter().any(ask) => {
                    inputs[const { offset("shadowed") }] = [0.0; N];
                    Some(vec3s(tape.run::<N>(&inputs, slots)))
                }
                _ => None,
            };
            for (i, h) in group.iter().enumerate() {
                let arrives = h.lab_cast || unshadowed.is_some_and(|d| d[i] != Vec3::ZERO);
                lab_shadowed[i] = u.shadows && arrives && h.blocked;
            }
        }
        let shadowed = match shadowed_tape {
            Some(tape) => {
                let s = tape.run::<N>(&inputs, slots);
                s[0].map(|v| v != 0.0)
            }
            None => lab_shadowed,
        };
        if let Some(w) = watch.as_deref_mut() {
            let lab: Vec<[f32; 3]> = lab_shadowed[..lanes]
                .iter()
                .map(|&b| [truth(b); 3])
                .collect();
            let slots = if shadowed_tape.is_some() {
                &slots[..]
            } else {
                &[]
            };
            w(Quantity::Shadowed, &inputs, slots, &lab);
        }
        inputs[const { offset("shadowed") }] = shadowed.map(truth);
        let lab_d = |i: usize| {
            if shadowed[i] {
                Vec3::ZERO
            } else {
                group[i].lab_d
            }
        };
        let d: [Vec3; N] = match d_tape {
            Some(tape) => vec3s(tape.run::<N>(&inputs, slots)),
            None => std::array::from_fn(|i| if i < lanes { lab_d(i) } else { Vec3::ZERO }),
        };
        if let Some(w) = watch.as_deref_mut() {
            let lab: Vec<[f32; 3]> = (0..lanes).map(|i| lab_d(i).to_array()).collect();
            let slots = if d_tape.is_some() { &slots[..] } else { &[] };
            w(Quantity::Direct, &inputs, slots, &lab);
        }
        for (k, lanes) in inputs[const { offset("D") }..][..3].iter_mut().enumerate() {
            *lanes = d.map(|d| d[k]);
        }
        let lab_r = |i: usize| shaded_value(u.stage, group[i].color, d[i], false, u.indirect);
        let r_tape = equations.tape(Quantity::Value);
        match r_tape {
            Some(tape) => {
                let r = vec3s(tape.run::<N>(&inputs, slots));
                out.copy_from_slice(&r[..lanes]);
            }
            None => {
                for (i, o) in out.iter_mut().enumerate() {
                    *o = lab_r(i);
                }
            }
        }
        if let Some(w) = watch {
            let lab: Vec<[f32; 3]> = (0..lanes).map(|i| lab_r(i).to_array()).collect();
            let slots = if r_tape.is_some() { &slots[..] } else { &[] };
            w(Quantity::Value, &inputs, slots, &lab);
        }
    }
}

/// How many hits a parallel task evaluates.
const CHUNK: usize = 1024;

/// What [`Recording::values`] tells: a quantity, the inputs it read, the slots the student's
/// tape left (empty where they wrote none), and the lab's value at each hit.
type Watch<'a, const N: usize> = dyn FnMut(Quantity, &[[f32; N]], &[[f32; N]], &[[f32; 3]]) + 'a;

fn truth(b: bool) -> f32 {
    if b { 1.0 } else { 0.0 }
}

/// The inputs `d` reads (`hit: false`: the pixel's and the camera's) or those a hit gives
/// (`hit: true`, but `shadowed` and `D`), and their values in lane 0 of `inputs`.
fn terms<const N: usize>(inputs: &[[f32; N]], hit: bool) -> Vec<Term> {
    INPUTS
        .iter()
        .filter(|i| (i.from != Quantity::Direction) == hit && !["shadowed", "D"].contains(&i.name))
        .map(|i| {
            let at = usize::from(i.offset);
            let c = [0, 1, 2].map(|k| {
                inputs
                    .get(at + k.min(i.ty.width() - 1))
                    .map_or(f32::NAN, |l| l[0])
            });
            Term {
                name: i.name,
                value: Value::of(i.ty, c),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::scene::cornell_box;
    use crate::teaching::check::mistakes::{self, Mistake, Recombined};
    use crate::teaching::sandbox::{compile, examples};
    use crate::transport::render::render as render_figure;
    use crate::transport::settings::Shading;
    use std::f32::consts::PI as PI_F32;

    fn settings(stage: Stage, side: u32) -> RenderSettings {
        let mut s = RenderSettings::default();
        s.camera = s.camera.with_resolution(side, side);
        s.shading = Shading::for_stage(stage);
        s
    }

    /// Every pixel of `got` within `tolerance` relative of `want`'s.
    fn assert_close(got: &Image, want: &Image, tolerance: f32, what: &str) {
        assert_eq!((got.width, got.height), (want.width, want.height), "{what}");
        let mut worst = (0.0f32, 0);
        for (i, (g, w)) in got.pixels.iter().zip(&want.pixels).enumerate() {
            for (a, b) in g.to_array().into_iter().zip(w.to_array()) {
                let error = (a - b).abs() / a.abs().max(b.abs()).max(f32::MIN_POSITIVE);
                if !(a == b || error <= tolerance) && (error > worst.0 || error.is_nan()) {
                    worst = (error, i);
                }
            }
        }
        let i = worst.1;
        assert!(
            worst.0 == 0.0,
            "{what}: pixel {i} ({}, {}) is {} where {} (relative error {})",
            i % got.width as usize,
            i / got.width as usize,
            got.pixels[i],
            want.pixels[i],
            worst.0
        );
    }

    /// The lab's quantities as [`examples::lab_text`] types them, for `stage`'s figure: `d`,
    /// `D` and `R`, and `shadowed` when the figure has shadows (a `shadowed` written is used
    /// whatever the switch; unwritten, it is the lab's, off without shadows).
    fn lab_file(stage: Stage) -> String {
        let shading = Shading::for_stage(stage);
        let mut quantities = vec![Quantity::Direction];
        if shading.shadows {
            quantities.push(Quantity::Shadowed);
        }
        quantities.extend([Quantity::Direct, Quantity::Value]);
        quantities
            .into_iter()
            .map(|q| examples::lab_text(q, &shading))
            .collect::<Vec<_>>()
            .join("\n")
    }

    /// The lab's own equations typed in the language give figures 2 to 7 within 10⁻⁶
    /// relative in every pixel.
    #[test]
    fn the_labs_equations_typed_give_figures_2_to_7() {
        let scene = cornell_box();
        for stage in Stage::LAB {
            let s = settings(stage, 64);
            let text = lab_file(stage);
            let equations = compile(&text).unwrap_or_else(|e| panic!("{text}: {e:?}"));
            let shadowed = usize::from(Shading::for_stage(stage).shadows);
            assert_eq!(equations.written().count(), 3 + shadowed);
            let got = render(&scene, &s, &equations);
            assert_eq!(got.non_finite, 0);
            let figure = render_figure(&scene, &s);
            assert_close(&got.image, &figure, 1e-6, &format!("{stage}"));
            // With nothing written, the lab's own quantities: the figure bit for bit.
            let lab = render(&scene, &s, &Equations::lab());
            assert_eq!(lab.image, figure, "{stage}");
        }
    }

    /// Typing each formula mistake of the catalogue (and the pixel's corner) gives the image
    /// `check` renders for it, and `check` names that mistake on the typed image (where it
    /// shows in the lab's box).
    #[test]
    fn typed_mistakes_give_the_catalogues_figures() {
        let scene = cornell_box();
        let s = settings(Stage::Lab, 64);
        let mut typed = 0;
        for m in Mistake::catalogue() {
            let Some((_, text)) = examples::mistake_text(m) else {
                assert_ne!(m.kind(), mistakes::Kind::Formula, "{m} has no text");
                continue;
            };
            let equations = compile(text).unwrap_or_else(|e| panic!("{m}: {e:?}"));
            let got = render(&scene, &s, &equations);
            let want = match m.kind() {
                mistakes::Kind::Formula => {
                    mistakes::formula_figures(&scene, &s, &[Recombined::Mistake(m)]).remove(0)
                }
                _ => mistakes::settings_figure(&scene, &s, m),
            };
            // Where the mistake shows in the catalogue's figure, it shows in the typed one
            // (an unclamped cosine does not show in the lab's box: the faces turned away from
            // the light are in shadow).
            let shows = want != render_figure(&scene, &s);
            if shows {
                assert!(
                    got.image != render_figure(&scene, &s),
                    "{m} shows no mistake"
                );
            }
            assert_close(&got.image, &want, 1e-6, &format!("{m}"));
            let checked = crate::teaching::check::check(
                &scene,
                &s,
                &crate::teaching::check::Rgb8::from_linear(&got.image),
            )
            .unwrap_or_else(|e| panic!("{m}: {e}"));
            let named = if shows { m.name() } else { "none" };
            assert_eq!(checked.report.best.mistake, named, "{m}");
            typed += 1;
        }
        assert_eq!(typed, 10);
    }

    /// Evaluating one hit at a time gives the sixteen-lane image's bits.
    #[test]
    fn one_lane_and_sixteen_give_the_same_image() {
        let scene = cornell_box();
        let s = settings(Stage::Lab, 48);
        let text = format!(
            "{}\nlet k = pow(abs(dot(normal, normalize(position))), 0.7)\nR = mix(color * (D + indirectLight), vec3(k), 0.3)",
            lab_file(Stage::Lab)
                .lines()
                .filter(|l| !l.starts_with('R'))
                .collect::<Vec<_>>()
                .join("\n")
        );
        let equations = compile(&text).unwrap();
        let recording = record(&scene, &s, &equations);
        let sixteen = recording.evaluate_lanes::<16>(&equations);
        let one = recording.evaluate_lanes::<1>(&equations);
        let bits = |r: &Rendered| -> Vec<u32> {
            r.image
                .pixels
                .iter()
                .flat_map(|p| p.to_array().map(f32::to_bits))
                .collect()
        };
        assert_eq!(bits(&sixteen), bits(&one));
    }

    /// Pixels that come out NaN or infinite are counted and drawn magenta; a camera ray with
    /// no direction is one of them.
    #[test]
    fn nan_and_infinity_are_counted() {
        let scene = cornell_box();
        let s = settings(Stage::Lab, 32);
        let all = render(&scene, &s, &compile("R = vec3(sqrt(-1.0))").unwrap());
        assert_eq!(all.non_finite, 32 * 32);
        assert!(all.image.pixels.iter().all(|p| *p == MAGENTA));
        let infinite = render(&scene, &s, &compile("R = color / 0").unwrap());
        assert_eq!(infinite.non_finite, 32 * 32);
        let half = "d = x < W / 2 ? vec3(0) : right * (x + 0.5 - W / 2) + down * (y + 0.5 - H / 2) + forward * focalLength";
        let half = render(&scene, &s, &compile(half).unwrap());
        assert_eq!(half.non_finite, 32 * 16);
        let figure = render_figure(&scene, &s);
        for (i, (p, f)) in half.image.pixels.iter().zip(&figure.pixels).enumerate() {
            let want = if i % 32 < 16 { MAGENTA } else { *f };
            assert_eq!(*p, want, "pixel {i}");
        }
    }

    /// Every pixel's explanation has the image's value, bit for bit: misses, the box's
    /// diffuse hits, the mirror's and the glass's branches, NaN pixels, rays with no
    /// direction; with the student's `d` and `shadowStart` traced too. At a diffuse hit, the
    /// student's R is the pixel and each statement's last part is its quantity's value.
    #[test]
    fn the_explanation_has_the_images_value_at_every_pixel() {
        let scene = cornell_box();
        let mut s = settings(Stage::Lab, 24);
        s.material_preset = crate::shading::material::MaterialPreset::Both;
        // Rows 0–3 look back, out of the box (misses); rows 4 and 5 have no direction.
        let d = "d = y < 4 ? -forward : (y < 6 ? vec3(0) : right * (x + 0.5 - W / 2) + \
                 down * (y + 0.5 - H / 2) + forward * focalLength)";
        let texts = [
            lab_file(Stage::Lab).replace(
                "d = right * (x + 0.5 - W / 2) + down * (y + 0.5 - H / 2) + forward * focalLength",
                d,
            ),
            format!(
                "{}\nshadowStart = position + normal * 1e-3",
                lab_file(Stage::Lab)
            ),
            "let k = position.x > 0 ? 1 : 0 / 0\nR = color * (D + indirectLight) * k".to_owned(),
            String::new(),
        ];
        let mut kinds = std::collections::BTreeSet::new();
        for text in &texts {
            let equations = compile(text).unwrap_or_else(|e| panic!("{text}: {e:?}"));
            let recording = record(&scene, &s, &equations);
            let image = recording.evaluate(&equations);
            for y in 0..24 {
                for x in 0..24 {
                    let e = recording.explain(&equations, x, y).unwrap();
                    let pixel = image.image.pixels[(y * 24 + x) as usize];
                    kinds.insert((e.made_of, e.finite));
                    if e.finite {
                        assert_eq!(
                            e.value.map(f32::to_bits),
                            pixel.to_array().map(f32::to_bits),
                            "{text}: ({x}, {y})"
                        );
                    } else {
                        assert_eq!(pixel, MAGENTA, "{text}: ({x}, {y})");
                    }
                    if e.made_of == "diffuse" {
                        let r = e.hits[0].quantities.last().unwrap();
                        assert_eq!(r.name, "R");
                        let v = r.yours.unwrap_or(r.lab);
                        let bits = |v: Value| match v {
                            Value::Vec3(v) => v.map(f32::to_bits),
                            other => panic!("R is {other:?}"),
                        };
                        assert_eq!(bits(v), e.value.map(f32::to_bits), "{text}: ({x}, {y})");
                        for q in &e.hits[0].quantities {
                            if let (Some(yours), Some(last)) = (q.yours, q.parts.last()) {
                                assert_eq!(last.name.as_deref(), Some(q.name));
                                assert_eq!(format!("{:?}", last.value), format!("{yours:?}"));
                            }
                        }
                    }
                }
            }
            assert!(recording.explain(&equations, 24, 0).is_none());
        }
        for kind in [
            ("miss", true),
            ("diffuse", true),
            ("specular", true),
            ("diffuse", false),
            ("bad ray", false),
        ] {
            assert!(kinds.contains(&kind), "no {kind:?} pixel: {kinds:?}");
        }
    }

    /// At a lit pixel of the lab's box, each part of the student's text is the value glam gives
    /// from the lab's terms shown beside it, the lab's own equations typed equal the lab's
    /// values, and a mistake's D differs from the lab's; the lines say so.
    #[test]
    fn the_explanation_shows_each_part_beside_the_labs_terms() {
        let scene = cornell_box();
        let s = settings(Stage::Lab, 32);
        // A lit pixel of the floor.
        let (x, y) = (8, 28);
        // The lab's d, shadowed, D and R as a student may type them in C++: D over a named
        // r2, with `M_PI` and `0.0f`, so that named parts show.
        let text = "d = right * (x + 0.5 - W / 2) + down * (y + 0.5 - H / 2) + forward * focalLength\n\
                    vec3 r = lightPos - position; // from the surface to the light\n\
                    float r2 = dot(r, r);\n\
                    shadowed = shadowDistance < length(lightPos - shadowStart)\n\
                    D = shadowed ? vec3(0) : lightColor * max(dot(r / sqrt(r2), normal), 0.0f) / (4 * M_PI * r2)\n\
                    R = color * (D + indirectLight)";
        let equations = compile(text).unwrap();
        let e = record(&scene, &s, &equations)
            .explain(&equations, x, y)
            .unwrap();
        assert_eq!(e.made_of, "diffuse");
        let hit = &e.hits[0];
        let term = |name: &str| -> Vec3 {
            match hit.terms.iter().find(|t| t.name == name).unwrap().value {
                Value::Vec3(v) => Vec3::from_array(v),
                other => panic!("{name} is {other:?}"),
            }
        };
        let (light, position, normal) = (term("lightPos"), term("position"), term("normal"));
        let quantity = |name: &str| hit.quantities.iter().find(|q| q.name == name).unwrap();
        let d = quantity("D");
        assert_eq!(d.parts.first().unwrap().name.as_deref(), Some("r"));
        let part = |text: &str| {
            d.parts
                .iter()
                .find(|p| p.text == text)
                .unwrap_or_else(|| panic!("no part {text:?}: {:?}", d.parts))
        };
        let r = light - position;
        assert_eq!(part("lightPos - position").value, Value::Vec3(r.to_array()));
        assert_eq!(part("lightPos - position").name.as_deref(), Some("r"));
        assert_eq!(
            (
                part("lightPos - position").line,
                part("lightPos - position").column
            ),
            (2, 6)
        );
        assert_eq!(part("dot(r, r)").value, Value::Number(r.dot(r)));
        assert_eq!(part("dot(r, r)").name.as_deref(), Some("r2"));
        let cos = (r / r.dot(r).sqrt()).dot(normal);
        assert!(cos > 0.0, "the pixel is lit");
        assert_eq!(part("dot(r / sqrt(r2), normal)").value, Value::Number(cos));
        assert_eq!(
            part("(4 * M_PI * r2)").value,
            Value::Number(4.0 * PI_F32 * r.dot(r))
        );
        assert_eq!(quantity("shadowed").yours, Some(Value::Bool(false)));
        assert_eq!(quantity("shadowed").lab, Value::Bool(false));
        let (Some(Value::Vec3(yours)), Value::Vec3(lab)) = (d.yours, d.lab) else {
            panic!("{d:?}");
        };
        for (a, b) in yours.into_iter().zip(lab) {
            assert!((a - b).abs() <= 1e-6 * b.abs(), "{yours:?} against {lab:?}");
        }
        let lines = e.to_text();
        let has = |equation: &str, text: &str| {
            lines
                .lines()
                .any(|l| l.trim_start().starts_with(equation) && l.contains(text))
        };
        assert!(has("line 2:6 ", "  r = lightPos - position = ("), "{lines}");
        assert!(has("line 3:7 ", "  r2 = dot(r, r) = "), "{lines}");
        assert!(has("the lab's terms", "position = ("), "{lines}");
        assert!(has("D ", "yours ("), "{lines}");
        // r is computed once, shown once, though D uses it twice.
        assert_eq!(
            lines.matches("r = lightPos - position").count(),
            1,
            "{lines}"
        );

        let (_, typed) = examples::mistake_text(Mistake::No4Pi).unwrap();
        let no_4pi = compile(typed).unwrap();
        let e = record(&scene, &s, &no_4pi).explain(&no_4pi, x, y).unwrap();
        let d = e.hits[0].quantities.iter().find(|q| q.name == "D").unwrap();
        let (Some(Value::Vec3(yours)), Value::Vec3(lab)) = (d.yours, d.lab) else {
            panic!("{d:?}");
        };
        assert!(
            (yours[0] / lab[0] - 4.0 * PI_F32).abs() < 1e-3,
            "{yours:?} {lab:?}"
        );
        let text = e.to_text();
        assert!(text.contains("(they differ)"), "{text}");
        assert!(text.contains("(the lab's)"), "{text}");
    }

    /// A recording is evaluated again for a new `shadowed`, `D` or `R`; a new `d` or
    /// `shadowStart` needs tracing again.
    #[test]
    fn only_d_and_shadow_start_retrace() {
        let scene = cornell_box();
        let s = settings(Stage::Lab, 16);
        let first = compile("R = color").unwrap();
        let recording = record(&scene, &s, &first);
        assert!(recording.fits(&compile("D = vec3(1)\nR = D\nshadowed = true").unwrap()));
        assert!(recording.fits(&Equations::lab()));
        assert!(!recording.fits(&compile("shadowStart = position").unwrap()));
        assert!(!recording.fits(&compile("d = forward").unwrap()));
    }
}

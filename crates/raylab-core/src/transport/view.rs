//! Debug views: what the tracer sees at each pixel, shown in place of the shaded image, each
//! with a [`Legend`] saying what its colours mean and over what range.
//!
//! The views are computed by the tracer from each pixel's primary ray, not by post-processing
//! the shaded image: the normal, distance, barycentric coordinates and triangle come from the
//! same [`Scene::closest_intersection`] the integrator asks, the shadow view casts the lab's
//! shadow ray ([`in_shadow`]), and the BVH-cost view counts the work of the very traversal the
//! scene's acceleration structure runs ([`crate::shapes::accel::Accel::closest_counting`]). Each
//! [`ViewImage`] also holds the raw per-pixel values ([`ViewValues`]), for tests and for an
//! inspector to read.
//!
//! The shaded image and the variance map come from the renderer and its [`Film`] instead
//! ([`variance_view`] for the workbench's progressive film); [`render_view`] renders
//! them from scratch only so that it answers for every view.

use std::collections::HashSet;

use glam::Vec3;
use rayon::prelude::*;

use crate::base::geometry::Ray;
use crate::shading::light::{LightSpec, direct_light};
use crate::shapes::accel::{AccelKind, TraversalCost};
use crate::shapes::intersect::Intersection;
use crate::shapes::scene::Scene;
use crate::shapes::scene::in_shadow;
use crate::transport::film::{Film, Image};
use crate::transport::render::{Cancelled, render_pass};
use crate::transport::settings::RenderSettings;

pub use crate::transport::settings::View;

/// What a view's colours mean: shown beside the image (and printed by `raylab render --view`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Legend {
    pub title: String,
    /// The mapping, one sentence a line: which colour is which value, what black means.
    pub lines: Vec<String>,
    /// The values mapped onto the colour scale, low to high, where the view has one (depth:
    /// the nearest and farthest `t`; the heat maps: 0 and their maximum).
    pub range: Option<(f32, f32)>,
}

/// What the shadow view found at a pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ShadowState {
    /// The primary ray hits nothing.
    #[default]
    NoHit,
    /// The surface faces away from the light: no light arrives, so there is none to block (the
    /// lab's D is 0 and no shadow ray is cast).
    FacesAway,
    /// The shadow ray toward the light's centre reaches it.
    Lit,
    /// Something lies between the point and the light's centre.
    Blocked,
}

/// A view's raw per-pixel values, rows top to bottom as in [`Image`] (`None`: nothing hit).
#[derive(Clone, Debug, PartialEq)]
pub enum ViewValues {
    /// The shaded image: its pixels are the values.
    Shaded,
    /// The shading normal (unit).
    Normals(Vec<Option<Vec3>>),
    /// `t`, the distance along the (unit) primary ray.
    Depth(Vec<Option<f32>>),
    /// `(1 − u − v, u, v)`.
    Barycentric(Vec<Option<Vec3>>),
    /// The triangle's index in the scene.
    Triangle(Vec<Option<u32>>),
    /// The closest-hit query's work (a ray that hits nothing still costs).
    BvhCost(Vec<TraversalCost>),
    Shadow(Vec<ShadowState>),
    /// The variance of each pixel's mean (see [`Film::variance`]).
    Variance(Vec<f32>),
    /// How many caustic photons the camera sees in each pixel.
    Photons(Vec<u32>),
}

/// A view of the scene: the image to show, its legend, and the values it was made from.
///
/// The image is linear RGB meant for the lab's clamp display ([`crate::transport::display::Display`]'s
/// default): the debug views' colours lie in [0, 1] (barycentric coordinates up to the edge
/// tolerance beyond), and exposure or a curve would change the colours the legend names.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewImage {
    pub image: Image,
    pub legend: Legend,
    pub values: ViewValues,
}

/// Black: nothing hit (the normals, barycentric, triangle and shadow views).
pub const NO_HIT: Vec3 = Vec3::ZERO;
/// The depth view's colour where nothing is hit: dark blue, apart from the grey scale.
pub const DEPTH_NO_HIT: Vec3 = Vec3::new(0.0, 0.0, 0.35);
/// The shadow view's colours.
pub const SHADOW_LIT: Vec3 = Vec3::ONE;
pub const SHADOW_BLOCKED: Vec3 = Vec3::new(0.55, 0.0, 0.0);
pub const SHADOW_FACES_AWAY: Vec3 = Vec3::splat(0.4);

/// Renders `view` of the scene as `settings` describe it, or [`Cancelled`] as soon as
/// `cancelled()` says so (checked before every row, as [`render_pass`] does).
///
/// The traced views ([`View::is_traced`]) follow one ray per pixel, through the pixel's centre
/// from the pinhole: the ray of sample 0 with the lens aperture ignored. With an aperture the
/// shaded image blurs what is out of focus, but a debug view is meant to say what each pixel
/// looks at, and a lens ray would make that a random choice. Rows are traced in parallel on
/// the current rayon pool; the result does not depend on the thread count.
///
/// [`View::Shaded`] renders `samples_per_pixel` passes, exactly [`crate::transport::render::render`]'s
/// image; [`View::Variance`] renders them too (at least 2: a variance needs two samples) into a
/// film that tracks the noise, and gives its [`variance_view`].
pub fn render_view(
    scene: &Scene,
    settings: &RenderSettings,
    view: View,
    cancelled: &(dyn Fn() -> bool + Sync),
) -> Result<ViewImage, Cancelled> {
    let smooth = settings.shading.smooth;
    let closest = |ray: &Ray| scene.closest_intersection(ray, f32::INFINITY);
    match view {
        View::Shaded | View::Variance => from_film(scene, settings, view, cancelled),
        View::Normals => {
            // The normal the integrators shade with: smooth or flat, and tilted where a
            // material has a normal map (the texture preset's too).
            let tracer = crate::transport::integrator::Tracer::new(scene, settings);
            let normals = per_pixel(settings, cancelled, |ray| {
                closest(ray).map(|h| {
                    let material = tracer.material_of(h.triangle_index);
                    tracer
                        .surface_with(&h, material, ray.direction, None)
                        .normal
                })
            })?;
            Ok(normals_view(settings, normals))
        }
        View::Depth => {
            let depths = per_pixel(settings, cancelled, |ray| closest(ray).map(|h| h.distance))?;
            Ok(depth_view(settings, depths))
        }
        View::Barycentric => {
            let coords = per_pixel(settings, cancelled, |ray| {
                closest(ray).map(|h| Vec3::new(1.0 - h.u - h.v, h.u, h.v))
            })?;
            Ok(barycentric_view(settings, coords))
        }
        View::Triangle => {
            let ids = per_pixel(settings, cancelled, |ray| {
                closest(ray).map(|h| h.triangle_index as u32)
            })?;
            Ok(triangle_view(scene, settings, ids))
        }
        View::BvhCost => {
            let accel = scene.accel();
            let built = accel.built_for(scene.triangles.len());
            // A scene whose structure no longer fits falls back to the brute-force loop.
            let every = TraversalCost {
                nodes: 0,
                triangles: scene.triangles.len() as u32,
            };
            let costs = per_pixel(settings, cancelled, |ray| {
                if built {
                    accel
                        .closest_counting(&scene.triangles, ray, f32::INFINITY)
                        .1
                } else {
                    every
                }
            })?;
            Ok(bvh_cost_view(scene, settings, costs))
        }
        View::Shadow => {
            let light = &settings.light;
            let states = per_pixel(settings, cancelled, |ray| match closest(ray) {
                None => ShadowState::NoHit,
                Some(hit) => shadow_state(scene, light, &hit, ray.direction, smooth),
            })?;
            Ok(shadow_view(settings, states))
        }
        View::Photons => {
            if cancelled() {
                return Err(Cancelled);
            }
            Ok(photons_view(scene, settings))
        }
    }
}

/// The caustic photons of pass 0 ([`crate::transport::integrator::photons::shoot`], with the settings'
/// photon count and seed, shot whether or not the render gathers them), each projected
/// through the pinhole camera ([`crate::Camera::project`]) and kept where nothing stands
/// between the camera and it: a dot in its pixel coloured by its power over the brightest
/// photon's, the brightest photon seen there winning.
fn photons_view(scene: &Scene, settings: &RenderSettings) -> ViewImage {
    let mut with_photons = settings.clone();
    with_photons.shading.stage = crate::transport::settings::Stage::Path;
    with_photons.shading.caustics = crate::transport::settings::Caustics::Photons;
    let tracer = crate::transport::integrator::Tracer::for_pass(scene, &with_photons, 0);
    let camera = &settings.camera;
    let (width, height) = (camera.width as usize, camera.height as usize);
    let mut counts = vec![0u32; width * height];
    let mut image = Image::new(camera.width, camera.height);
    let photons: Vec<crate::transport::photon_map::Photon> = tracer
        .photon_map()
        .map(|m| m.photons().to_vec())
        .unwrap_or_default();
    let brightest = photons
        .iter()
        .map(|p| p.power.max_element())
        .fold(0.0f32, f32::max);
    let mut seen = 0usize;
    for photon in &photons {
        let Some((px, py, _)) = camera.project(photon.position) else {
            continue;
        };
        if !(px >= 0.0 && py >= 0.0 && px < width as f32 && py < height as f32) {
            continue;
        }
        let to_photon = photon.position - camera.position;
        let distance = to_photon.length();
        let ray = Ray::new(camera.position, to_photon / distance);
        if scene.occluded(&ray, distance * (1.0 - 1e-4)) {
            continue;
        }
        let i = py as usize * width + px as usize;
        counts[i] += 1;
        seen += 1;
        let colour = photon.power / brightest;
        if colour.max_element() > image.pixels[i].max_element() {
            image.pixels[i] = colour;
        }
    }
    let lines = vec![
        format!(
            "a dot per caustic photon of the first pass the camera sees ({seen} of {} stored, \
             {} shot)",
            photons.len(),
            settings.shading.photons
        ),
        "colour: the photon's power over the brightest photon's (the glass's and mirror's \
         tints show)"
            .into(),
        "black: no photon (direct light is not stored: only light through mirror or glass)".into(),
    ];
    ViewImage {
        image,
        legend: Legend {
            title: "Photons".into(),
            lines,
            range: None,
        },
        values: ViewValues::Photons(counts),
    }
}

/// The shadow view at a hit, by the integrator's rules ([`crate::transport::integrator::HitTerms::at`]):
/// no light arrives where the lab's D is 0 for the shading normal, or (with a smooth normal)
/// where the triangle itself faces away; elsewhere the shadow ray leaves from the side of the
/// triangle's own normal, as [`in_shadow`] casts it toward the light's centre. `incoming` is
/// the direction of the ray that found the hit (the shadow ray of a hit at an edge of its
/// triangle needs it: [`crate::shading::light::shadow_ray`]).
pub fn shadow_state(
    scene: &Scene,
    light: &LightSpec,
    hit: &Intersection,
    incoming: Vec3,
    smooth: bool,
) -> ShadowState {
    let (index, p) = (hit.triangle_index, hit.position);
    let normal = scene.shading_normal(index, hit.u, hit.v, smooth);
    let geometric = scene.triangles[index].normal;
    // D for a light of unit power: zero exactly where equation 27 gives none, whatever the
    // light's real power (a light of power 0 still has a side it would light).
    let unit = LightSpec {
        power: 1.0,
        colour: Vec3::ONE,
        ..*light
    };
    let faces_away = direct_light(&unit, p, normal) == Vec3::ZERO
        || (normal != geometric && (light.position - p).dot(geometric) <= 0.0);
    if faces_away {
        ShadowState::FacesAway
    } else if in_shadow(
        scene,
        light,
        p,
        geometric,
        scene.approach_at_edge(index, hit.u, hit.v, incoming),
    ) {
        ShadowState::Blocked
    } else {
        ShadowState::Lit
    }
}

/// `f` of every pixel's centre ray (the pinhole's), rows in parallel, cancellable per row.
fn per_pixel<T: Send + Clone + Default>(
    settings: &RenderSettings,
    cancelled: &(dyn Fn() -> bool + Sync),
    f: impl Fn(&Ray) -> T + Sync,
) -> Result<Vec<T>, Cancelled> {
    let camera = &settings.camera;
    let (width, height) = (camera.width as usize, camera.height as usize);
    let mut values = vec![T::default(); width * height];
    if width == 0 {
        return Ok(values);
    }
    let rotation = camera.rotation();
    values
        .par_chunks_mut(width)
        .enumerate()
        .try_for_each(|(y, row)| {
            if cancelled() {
                return Err(Cancelled);
            }
            for (x, value) in row.iter_mut().enumerate() {
                let ray = camera.primary_ray_rotated(&rotation, x as f32 + 0.5, y as f32 + 0.5);
                *value = f(&ray);
            }
            Ok(())
        })?;
    Ok(values)
}

/// An image of `settings`' size with pixel `i` = `colour(values[i])`.
fn image_of<T>(settings: &RenderSettings, values: &[T], colour: impl Fn(&T) -> Vec3) -> Image {
    Image {
        width: settings.camera.width,
        height: settings.camera.height,
        pixels: values.iter().map(colour).collect(),
    }
}

fn normals_view(settings: &RenderSettings, normals: Vec<Option<Vec3>>) -> ViewImage {
    let image = image_of(settings, &normals, |n| {
        n.map_or(NO_HIT, |n| (n + Vec3::ONE) * 0.5)
    });
    let smooth = if settings.shading.smooth {
        "interpolated from the vertex normals where a model has them (smooth shading), else the \
         triangle's own"
    } else {
        "the triangle's own (smooth shading is off)"
    };
    ViewImage {
        image,
        legend: Legend {
            title: "Normals".into(),
            lines: vec![
                format!("the shading normal n at the first hit, {smooth}"),
                "colour (n + 1)/2: x as red, y as green, z as blue; −1 is 0, 0 is ½, +1 is full"
                    .into(),
                "y points down (the lab's axes): a floor facing up, n = (0, −1, 0), is purple \
                 (½, 0, ½)"
                    .into(),
                "black: nothing hit".into(),
            ],
            range: Some((-1.0, 1.0)),
        },
        values: ViewValues::Normals(normals),
    }
}

fn depth_view(settings: &RenderSettings, depths: Vec<Option<f32>>) -> ViewImage {
    let (near, far) = depths
        .iter()
        .flatten()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &t| {
            (lo.min(t), hi.max(t))
        });
    let range = (near <= far).then_some((near, far));
    let image = image_of(settings, &depths, |t| match (t, range) {
        (Some(t), Some((near, far))) if far > near => Vec3::splat(1.0 - (t - near) / (far - near)),
        (Some(_), _) => Vec3::ONE,
        (None, _) => DEPTH_NO_HIT,
    });
    let mut lines = vec![
        "t, the distance along each pixel's primary ray to the first hit (not the depth along \
         the view direction)"
            .to_string(),
    ];
    match range {
        Some((near, far)) => lines.push(format!(
            "t from {} (white) to {} (black), linear: this image's nearest and farthest hits",
            number(near),
            number(far)
        )),
        None => lines.push("nothing is hit anywhere".into()),
    }
    lines.push("dark blue: nothing hit".into());
    ViewImage {
        image,
        legend: Legend {
            title: "Depth".into(),
            lines,
            range,
        },
        values: ViewValues::Depth(depths),
    }
}

fn barycentric_view(settings: &RenderSettings, coords: Vec<Option<Vec3>>) -> ViewImage {
    let image = image_of(settings, &coords, |c| c.unwrap_or(NO_HIT));
    ViewImage {
        image,
        legend: Legend {
            title: "Barycentric".into(),
            lines: vec![
                "(1 − u − v, u, v) at the first hit as (red, green, blue), where the hit point is \
                 v0 + u·e1 + v·e2 (equation 6)"
                    .into(),
                "red at vertex v0, green at v1, blue at v2; a channel is 0 along the opposite edge"
                    .into(),
                "black: nothing hit".into(),
            ],
            range: Some((0.0, 1.0)),
        },
        values: ViewValues::Barycentric(coords),
    }
}

/// The triangle view's colour of triangle `index`: three bytes of a hash of the index, each
/// channel in [0.2, 1] so that no triangle is black (nothing hit). Deterministic, and
/// neighbouring indices get unrelated colours, so neighbouring triangles stand apart.
pub fn triangle_colour(index: u32) -> Vec3 {
    // A 32-bit integer hash (Chris Wellons' "lowbias32"), offset so that index 0 is mixed too.
    let mut h = index.wrapping_add(0x9e37_79b9);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^= h >> 16;
    let channel = |shift: u32| 0.2 + 0.8 * ((h >> shift) & 0xff) as f32 / 255.0;
    Vec3::new(channel(0), channel(8), channel(16))
}

fn triangle_view(scene: &Scene, settings: &RenderSettings, ids: Vec<Option<u32>>) -> ViewImage {
    let image = image_of(settings, &ids, |i| i.map_or(NO_HIT, triangle_colour));
    let seen: HashSet<u32> = ids.iter().flatten().copied().collect();
    ViewImage {
        image,
        legend: Legend {
            title: "Triangle".into(),
            lines: vec![
                "a colour per triangle index, from a hash of the index: the same triangle always \
                 has the same colour, neighbouring indices unrelated ones"
                    .into(),
                format!(
                    "{} of the scene's {} triangles are seen",
                    seen.len(),
                    scene.triangles.len()
                ),
                "black: nothing hit".into(),
            ],
            range: None,
        },
        values: ViewValues::Triangle(ids),
    }
}

fn bvh_cost_view(scene: &Scene, settings: &RenderSettings, costs: Vec<TraversalCost>) -> ViewImage {
    let max = costs.iter().map(|c| c.total()).max().unwrap_or(0);
    let n = costs.len().max(1) as f64;
    let mean =
        |f: fn(&TraversalCost) -> u32| costs.iter().map(|c| f64::from(f(c))).sum::<f64>() / n;
    let (nodes, triangles) = (mean(|c| c.nodes), mean(|c| c.triangles));
    let image = image_of(settings, &costs, |c| {
        heat(if max == 0 {
            0.0
        } else {
            c.total() as f32 / max as f32
        })
    });
    let accel = scene.accel();
    let built = accel.built_for(scene.triangles.len());
    let kind = if built {
        accel.kind()
    } else {
        AccelKind::BruteForce
    };
    let mut lines = vec![
        format!(
            "nodes visited + triangles tested by each primary ray's closest-hit query, counted in \
             the traversal the renderer runs ({kind}, {} kernels)",
            accel.isa().name()
        ),
        format!("{HEAT_RAMP} {max}"),
        format!(
            "mean {:.1} per ray: {nodes:.1} nodes + {triangles:.1} triangles; max {max}",
            nodes + triangles
        ),
    ];
    if matches!(kind, AccelKind::Flat | AccelKind::BruteForce) {
        lines.push(format!(
            "no tree: the loop tests all {} triangles for every ray, so the cost is the same \
             everywhere",
            scene.triangles.len()
        ));
    }
    ViewImage {
        image,
        legend: Legend {
            title: "BVH cost".into(),
            lines,
            range: Some((0.0, max as f32)),
        },
        values: ViewValues::BvhCost(costs),
    }
}

fn shadow_view(settings: &RenderSettings, states: Vec<ShadowState>) -> ViewImage {
    let image = image_of(settings, &states, |s| match s {
        ShadowState::NoHit => NO_HIT,
        ShadowState::FacesAway => SHADOW_FACES_AWAY,
        ShadowState::Lit => SHADOW_LIT,
        ShadowState::Blocked => SHADOW_BLOCKED,
    });
    let share = |state: ShadowState| {
        let count = states.iter().filter(|&&s| s == state).count();
        100.0 * count as f64 / states.len().max(1) as f64
    };
    let mut lines = vec![
        format!(
            "white: lit, the shadow ray from the first hit to the light's centre is clear \
             ({:.1}% of pixels)",
            share(ShadowState::Lit)
        ),
        format!(
            "dark red: in shadow, something blocks that ray ({:.1}%)",
            share(ShadowState::Blocked)
        ),
        format!(
            "grey: faces away from the light, no light to block ({:.1}%)",
            share(ShadowState::FacesAway)
        ),
        format!("black: nothing hit ({:.1}%)", share(ShadowState::NoHit)),
    ];
    if settings.light.is_area() {
        lines.push(
            "the light's centre only: a sphere light's soft shadow shows as its centre's hard one"
                .into(),
        );
    }
    lines.push(
        "at the primary hit whatever its material (mirror and glass are not followed)".into(),
    );
    ViewImage {
        image,
        legend: Legend {
            title: "Shadow".into(),
            lines,
            range: None,
        },
        values: ViewValues::Shadow(states),
    }
}

/// The shaded image and the variance map: `samples_per_pixel` passes into a film that tracks
/// the noise (at least two for the variance), cancellable within every pass.
fn from_film(
    scene: &Scene,
    settings: &RenderSettings,
    view: View,
    cancelled: &(dyn Fn() -> bool + Sync),
) -> Result<ViewImage, Cancelled> {
    let (width, height) = (settings.camera.width, settings.camera.height);
    let mut film = Film::with_noise(width, height);
    let samples = match view {
        View::Variance => settings.samples_per_pixel.max(2),
        View::Shaded
        | View::Normals
        | View::Depth
        | View::Barycentric
        | View::Triangle
        | View::BvhCost
        | View::Shadow
        | View::Photons => settings.samples_per_pixel.max(1),
    };
    for sample in 0..samples {
        film.add_pass(&render_pass(scene, settings, sample, cancelled)?);
    }
    if view == View::Variance
        && let Some(variance) = variance_view(&film)
    {
        return Ok(variance);
    }
    Ok(ViewImage {
        image: film.resolve(),
        legend: Legend {
            title: "Shaded".into(),
            lines: vec![format!(
                "the {} stage, {samples} sample{} per pixel",
                settings.shading.stage,
                if samples == 1 { "" } else { "s" }
            )],
            range: None,
        },
        values: ViewValues::Shaded,
    })
}

/// The variance view of a film that tracks the noise: [`Film::variance`] as a heat map over 0 to
/// its maximum, with its legend and the raw values (`None` before two samples, or when the film
/// does not track the noise). The workbench's progressive film and `from_film` both use it.
pub fn variance_view(film: &Film) -> Option<ViewImage> {
    let variance = film.variance()?;
    let max = variance.iter().copied().fold(0.0f32, f32::max);
    let mean = variance.iter().map(|&v| f64::from(v)).sum::<f64>() / variance.len().max(1) as f64;
    let image = Image {
        width: film.width(),
        height: film.height(),
        pixels: variance
            .iter()
            .map(|&v| heat(if max > 0.0 { v / max } else { 0.0 }))
            .collect(),
    };
    let legend = Legend {
        title: "Variance".into(),
        lines: vec![
            format!(
                "variance of each pixel's mean, from n = {} samples: s²/n, s² the spread of \
                 its samples (each the mean of R, G and B)",
                film.samples()
            ),
            format!("{HEAT_RAMP} {}", number(max)),
            format!(
                "mean {}; it falls as 1/n: 4× the samples halve the noise",
                number(mean as f32)
            ),
        ],
        range: Some((0.0, max)),
    };
    Some(ViewImage {
        image,
        legend,
        values: ViewValues::Variance(variance),
    })
}

/// The heat maps' colour scale, in words, before its maximum.
pub const HEAT_RAMP: &str = "black at 0, then blue, magenta, yellow, and white at the maximum,";

/// The heat maps' colour for `x` in [0, 1] (clamped; NaN is black): black → blue → magenta →
/// yellow → white at 0, ¼, ½, ¾, 1, linear in between. Its brightness rises all the way
/// (luminance 0, 0.07, 0.28, 0.93, 1), so the scale reads the same in grey.
pub fn heat(x: f32) -> Vec3 {
    const STOPS: [Vec3; 5] = [
        Vec3::ZERO,
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::ONE,
    ];
    #[allow(clippy::manual_clamp)]
    let x = x.max(0.0).min(1.0) * 4.0;
    let i = (x as usize).min(3);
    STOPS[i].lerp(STOPS[i + 1], x - i as f32)
}

/// A value for a legend: three decimals, or three significant digits in scientific notation
/// for the very small and the very large.
pub fn number(x: f32) -> String {
    if x == 0.0 {
        "0".into()
    } else if (0.01..10_000.0).contains(&x.abs()) {
        format!("{x:.3}")
    } else {
        format!("{x:.2e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three pixels over four passes, by hand (grey values, so the channel mean is the value):
    /// 1, 1, 1, 1 has no spread: 0. 1, 3, 1, 3: mean 2, s² = (1 + 1 + 1 + 1)/3 = 4/3, s²/n =
    /// 1/3, the maximum (white). 0, 0, 0, 2: mean ½, s² = (3·¼ + 9/4)/3 = 1, s²/n = ¼, which is
    /// ¾ of the maximum: yellow.
    #[test]
    fn variance_image_by_hand() {
        let mut film = Film::with_noise(3, 1);
        assert!(variance_view(&film).is_none(), "no samples");
        for (b, c) in [(1.0, 0.0), (3.0, 0.0), (1.0, 0.0), (3.0, 2.0)] {
            let mut pass = Image::new(3, 1);
            pass.pixels = vec![Vec3::ONE, Vec3::splat(b), Vec3::splat(c)];
            film.add_pass(&pass);
            if film.samples() == 1 {
                assert!(film.variance().is_none(), "one sample has no spread");
            }
        }
        let v = film.variance().unwrap();
        assert_eq!(v[0], 0.0);
        assert!((v[1] - 1.0 / 3.0).abs() < 1e-6, "{v:?}");
        assert!((v[2] - 0.25).abs() < 1e-6, "{v:?}");
        let ViewImage { image, legend, .. } = variance_view(&film).unwrap();
        assert_eq!(image.pixels[0], Vec3::ZERO);
        assert_eq!(image.pixels[1], Vec3::ONE);
        assert!(
            (image.pixels[2] - Vec3::new(1.0, 1.0, 0.0))
                .abs()
                .max_element()
                < 1e-5
        );
        let (lo, hi) = legend.range.unwrap();
        assert_eq!(lo, 0.0);
        assert!((hi - 1.0 / 3.0).abs() < 1e-6);
        assert!(legend.lines[0].contains("n = 4 samples"), "{legend:?}");
        assert!(legend.lines[1].contains("0.333"), "{legend:?}");
        assert!(variance_view(&Film::new(3, 1)).is_none(), "not tracked");
    }

    #[test]
    fn names_parse_and_round_trip_through_json() {
        for v in View::ALL {
            assert_eq!(v.name().parse::<View>(), Ok(v));
            assert_eq!(
                serde_json::to_string(&v).unwrap(),
                format!("\"{}\"", v.name())
            );
            assert_eq!(
                serde_json::from_str::<View>(&format!("\"{v}\"")).unwrap(),
                v
            );
        }
        let e = "bvh".parse::<View>().unwrap_err();
        assert!(e.contains("'bvh'") && e.contains("bvh-cost"), "{e}");
        assert_eq!(View::default(), View::Shaded);
        assert!(View::Depth.is_traced() && !View::Variance.is_traced());
    }

    /// The stops exactly, and halfway between black and blue, magenta and yellow.
    #[test]
    fn heat_ramp_by_hand() {
        assert_eq!(heat(0.0), Vec3::ZERO);
        assert_eq!(heat(0.25), Vec3::new(0.0, 0.0, 1.0));
        assert_eq!(heat(0.5), Vec3::new(1.0, 0.0, 1.0));
        assert_eq!(heat(0.75), Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(heat(1.0), Vec3::ONE);
        assert_eq!(heat(0.125), Vec3::new(0.0, 0.0, 0.5));
        assert_eq!(heat(0.625), Vec3::new(1.0, 0.5, 0.5));
        assert_eq!(heat(-1.0), Vec3::ZERO);
        assert_eq!(heat(7.0), Vec3::ONE);
        assert_eq!(heat(f32::NAN), Vec3::ZERO);
    }

    #[test]
    fn triangle_colours_are_fixed_bright_and_unrelated_for_neighbours() {
        for i in [0, 1, 2, 1000, u32::MAX] {
            let c = triangle_colour(i);
            assert_eq!(c, triangle_colour(i));
            assert!(c.min_element() >= 0.2 && c.max_element() <= 1.0, "{c}");
        }
        // Neighbouring indices differ clearly, not by a small step.
        for i in 0..100 {
            let d = (triangle_colour(i) - triangle_colour(i + 1))
                .abs()
                .max_element();
            assert!(d > 0.05, "{i}: {d}");
        }
    }

    #[test]
    fn legend_numbers() {
        assert_eq!(number(0.0), "0");
        assert_eq!(number(1.23456), "1.235");
        assert_eq!(number(0.000_123_4), "1.23e-4");
        assert_eq!(number(123_456.0), "1.23e5");
    }
}

//! The classic mistakes of the lab, and the figure as each would render it.
//!
//! Three kinds, each made from what the renderer already computes:
//!
//! * **Formula mistakes** (the 4π forgotten, 1/r, the cosine unclamped, the normal's sign, ρ
//!   forgotten or applied to D alone, and the shadow ray's mistakes) change how a hit's terms
//!   combine. The camera rays are traced by the lab's own integrator
//!   ([`Tracer::trace_recorded`]), which tells a [`Recorder`] every hit's [`HitTerms`] (D of
//!   equation 27, ρ, N, the shadow ray and whether it was blocked); [`Recombine`] puts those
//!   terms together again with the mistake, through the lab's own [`DirectLight::at`] (the
//!   parts of equation 27) and [`HitTerms::value`] (equations 28–30). With no mistake the
//!   recombination is the renderer's image bit for bit (tested).
//! * **Settings mistakes** (the focal length, the yaw's sign, the light's y, the pixel's corner,
//!   equation 24's printed `y − W/2`) are ordinary renders ([`render`]) with other settings,
//!   cropped where the camera had to see more.
//! * **Picture mistakes** (upside down, a gamma curve, red and blue swapped) transform the
//!   figure's pixels.

use std::f32::consts::PI;

use glam::Vec3;
use rayon::prelude::*;

use super::compare::Rgb8;
use crate::base::geometry::Ray;
use crate::base::named::named_enum;
use crate::shading::light::{DirectLight, LightSpec};
use crate::shading::material::Scatter;
use crate::shapes::intersect::Intersection;
use crate::shapes::scene::{Scene, in_shadow};
use crate::transport::display::{Display, DisplayTransform};
use crate::transport::film::Image;
use crate::transport::integrator::{BATCH, HitTerms, Recorder, Stage, Tracer};
use crate::transport::render::render;
use crate::transport::settings::RenderSettings;

/// A classic mistake of the lab, or none.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mistake {
    /// The lab done right: the exact figure.
    None,
    No4Pi,
    InverseR,
    UnclampedCos,
    FlippedNormal,
    NoRho,
    IndirectOutsideRho,
    ShadowAcne,
    ShadowBeyondLight,
    ShadowDropsIndirect,
    FocalHalf,
    YawSign,
    LightYFlipped,
    PixelCorner,
    Eq24Typo,
    UpsideDown,
    Gamma,
    Bgr,
}

named_enum!(Mistake as "mistake" {
    None => "none", "the exact figure";
    No4Pi => "no-4pi", "D = P·max(r̂·n̂, 0)/r²: the 4π forgotten";
    InverseR => "inverse-r", "D = P·max(r̂·n̂, 0)/(4πr): 1/r instead of 1/r²";
    UnclampedCos => "unclamped-cos", "r̂·n̂ not clamped at 0: surfaces facing away from the light subtract light";
    FlippedNormal => "flipped-normal", "the normal's sign flipped (−n̂): the lit sides go dark, the sides facing away light up";
    NoRho => "no-rho", "D + N drawn instead of ρ·(D + N): the surface's colour ρ forgotten";
    IndirectOutsideRho => "indirect-outside-rho", "ρ·D + N instead of ρ·(D + N)";
    ShadowAcne => "shadow-acne", "the shadow ray starts on the surface with no offset: in single precision, points find their own surface in the way";
    ShadowBeyondLight => "shadow-beyond-light", "anything along the shadow ray's line blocks, even beyond the light";
    ShadowDropsIndirect => "shadow-drops-indirect", "a point in shadow drawn black: N dropped along with D";
    FocalHalf => "focal-half", "focal length W/2 instead of W: a 90° field of view";
    YawSign => "yaw-sign", "the camera turns the other way (−yaw)";
    LightYFlipped => "light-y-flipped", "the light at y = +0.5 instead of −0.5, near the floor";
    PixelCorner => "pixel-corner", "rays through the pixel's corner (x, y) instead of its centre (x + ½, y + ½)";
    Eq24Typo => "eq24-typo", "d = (x − W/2, y − W/2, f), equation 24 as printed: rows shifted when H ≠ W";
    UpsideDown => "upside-down", "rows drawn bottom to top";
    Gamma => "gamma", "an sRGB (or 1/2.2 power) curve applied to the output";
    Bgr => "bgr", "red and blue swapped";
});

/// How a mistake's figure is made (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Formula,
    Settings,
    Picture,
}

impl Mistake {
    /// Every mistake of the catalogue: [`Mistake::ALL`] but `none`.
    pub fn catalogue() -> impl Iterator<Item = Mistake> {
        Mistake::ALL.into_iter().filter(|m| *m != Mistake::None)
    }

    pub fn kind(self) -> Kind {
        use Mistake::*;
        match self {
            None | No4Pi | InverseR | UnclampedCos | FlippedNormal | NoRho | IndirectOutsideRho
            | ShadowAcne | ShadowBeyondLight | ShadowDropsIndirect => Kind::Formula,
            FocalHalf | YawSign | LightYFlipped | PixelCorner | Eq24Typo => Kind::Settings,
            UpsideDown | Gamma | Bgr => Kind::Picture,
        }
    }

    /// What the mistake is, in a line.
    pub fn what(self) -> &'static str {
        self.label()
    }

    /// The lab's equation or section the mistake concerns.
    pub fn equation(self) -> &'static str {
        use Mistake::*;
        match self {
            None => "",
            No4Pi => "equation 27: D = P·max(r̂·n̂, 0)/(4πr²) (the sphere's area, equation 25)",
            InverseR => "equation 27: D = P·max(r̂·n̂, 0)/(4πr²) (equations 25–26: B = P/(4πr²))",
            UnclampedCos => "equation 27: D = P·max(r̂·n̂, 0)/(4πr²)",
            FlippedNormal => {
                "equation 27: n̂ is the normal pointing out from the surface (section 1; the test \
                 model's normalize(cross(e2, e1)))"
            }
            NoRho => "equation 28: R = ρ·D (equation 30 with N: R = ρ·(D + N))",
            IndirectOutsideRho => "equation 30: R = ρ·(D + N)",
            ShadowAcne => "section 5.1 (direct shadows): the ray from the surface to the light",
            ShadowBeyondLight => {
                "section 5.1: in shadow only if the closest hit is closer than the light"
            }
            ShadowDropsIndirect => {
                "section 5.2, equation 30: in shadow D = 0, but R = ρ·(0 + N) remains"
            }
            FocalHalf => "equation 24 and section 3: f = W, a 53.13° field of view",
            YawSign => "section 4: the rotation R about the y axis by the yaw",
            LightYFlipped => "section 5: lightPos = (0, −0.5, −0.7), with y pointing down",
            PixelCorner => "equation 24: d = (x − W/2, y − H/2, f), at the pixel's centre",
            Eq24Typo => "equation 24: its printed y − W/2 is a typo for y − H/2",
            UpsideDown => "section 3: y points down, row y = 0 at the top (equation 24)",
            Gamma => "the lab writes R as it is, each channel clamped to [0, 1]: no gamma",
            Bgr => "section 3: the pixel's colour (R, G, B) as the screen takes it",
        }
    }

    /// One sentence on how to fix it.
    pub fn fix(self) -> &'static str {
        use Mistake::*;
        match self {
            None => "",
            No4Pi => {
                "Divide by 4πr², the area of the sphere the light's power spreads over, not by r² \
                 alone."
            }
            InverseR => {
                "Square the distance: D falls as 1/r² (r² is the dot product of the vector to the \
                 light with itself)."
            }
            UnclampedCos => {
                "Clamp the cosine, max(r̂·n̂, 0): a surface facing away from the light receives \
                 nothing, never negative light."
            }
            FlippedNormal => {
                "Use the normal pointing out of the surface, normalize(cross(e2, e1)) with \
                 e1 = v1 − v0 and e2 = v2 − v0, or negate yours."
            }
            NoRho => {
                "Multiply the light by the triangle's colour ρ, channel by channel: R = ρ·D, or \
                 ρ·(D + N) with indirect light."
            }
            IndirectOutsideRho => {
                "Add N to D before multiplying by ρ: the surface reflects the indirect light too, \
                 R = ρ·(D + N)."
            }
            ShadowAcne => {
                "Start the shadow ray a little off the surface (p + 1e-4·n̂ on the light's side), \
                 or ignore hits closer than a small ε."
            }
            ShadowBeyondLight => {
                "Compare the closest hit's distance with the distance to the light: only a surface \
                 between the point and the light casts a shadow."
            }
            ShadowDropsIndirect => {
                "In shadow set only D to 0 and still add N: R = ρ·(0 + N), so shadows are dim, not \
                 black."
            }
            FocalHalf => "Set the focal length f to the image width W in pixels, not W/2.",
            YawSign => {
                "Build R with forward = (sin yaw, 0, cos yaw) and right = (cos yaw, 0, −sin yaw), \
                 so a positive yaw turns right, or negate the angle."
            }
            LightYFlipped => {
                "Put the light at (0, −0.5, −0.7): y points down, so −0.5 is toward the ceiling."
            }
            PixelCorner => {
                "Trace through the pixel's centre, x + 0.5 and y + 0.5: a half-pixel shift, \
                 harmless, but the figures are traced at the centre."
            }
            Eq24Typo => "Centre the rows on H/2: d = (x − W/2, y − H/2, f).",
            UpsideDown => {
                "Write pixel (x, y) to row y from the top and keep y pointing down in \
                 d = (x − W/2, y − H/2, f)."
            }
            Gamma => {
                "Write each channel clamped to [0, 1] times 255 with no gamma curve (drop the \
                 pow(c, 1/2.2) or sRGB conversion)."
            }
            Bgr => {
                "Write the channels as R, G, B (let SDL_MapRGB pack the pixel rather than packing \
                 the bytes yourself)."
            }
        }
    }

    /// Whether the mistake can change the figure of these settings at all: a shadow mistake
    /// needs shadows, an indirect one N, the yaw's sign a yaw, the flat stage (ρ alone) no
    /// light. Those that pass are rendered, and offered only if their figure differs from the
    /// exact one (the check's own test).
    pub fn applies(self, settings: &RenderSettings) -> bool {
        use Mistake::*;
        let s = &settings.shading;
        let lit = s.stage != Stage::Flat;
        let reflected = s.stage.reflects_light();
        match self {
            None | FocalHalf | PixelCorner | UpsideDown | Gamma | Bgr => true,
            No4Pi | InverseR | UnclampedCos | FlippedNormal => lit,
            NoRho => reflected,
            IndirectOutsideRho => reflected && s.indirect,
            ShadowAcne | ShadowBeyondLight => lit && s.shadows,
            ShadowDropsIndirect => lit && s.shadows && s.indirect,
            YawSign => settings.camera.yaw != 0.0,
            LightYFlipped => lit && settings.light.position.y != 0.0,
            Eq24Typo => settings.camera.width != settings.camera.height,
        }
    }
}

/// The figure as `mistake` renders it at `settings`, through the lab's display: one look, or
/// for `gamma` two (the sRGB curve and the power 1/2.2), any of which explains a pixel. What
/// [`super::check`] compares with, one mistake at a time.
pub fn looks(scene: &Scene, settings: &RenderSettings, mistake: Mistake) -> Vec<Rgb8> {
    match mistake.kind() {
        Kind::Formula => {
            let linear = formula_figures(scene, settings, &[Recombined::Mistake(mistake)]);
            vec![Rgb8::from_linear(&linear[0])]
        }
        Kind::Settings => vec![Rgb8::from_linear(&settings_figure(
            scene, settings, mistake,
        ))],
        Kind::Picture => {
            let linear = formula_figures(scene, settings, &[Recombined::Mistake(Mistake::None)]);
            picture_looks(mistake, &linear[0], &Rgb8::from_linear(&linear[0]))
        }
    }
}

/// What a formula pass recombines: a mistake, or (for telling shadow acne from other shadows)
/// the figure with every shadow ray blocked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Recombined {
    Mistake(Mistake),
    EveryShadowRayBlocked,
}

/// The figures of formula mistakes (`Kind::Formula`) and other recombinations, linear, in the
/// order asked: one pass of the lab's integrator over the image, rows in parallel, each hit's
/// terms recombined once for each.
///
/// The camera rays are the renderer's for sample 0 (through each pixel's centre,
/// [`crate::Camera::primary_ray_rotated`]); pixels whose ray hits nothing are black, as there.
/// A pixel whose camera ray meets mirror or glass is the sum of what its Whitted branches find
/// (`lab.rs`): each diffuse hit along them recombined with the mistake, times the branch's
/// weight, added in the integrator's order, so that with no mistake it is the render's pixel
/// bit for bit there too.
pub fn formula_figures(
    scene: &Scene,
    settings: &RenderSettings,
    wanted: &[Recombined],
) -> Vec<Image> {
    let camera = &settings.camera;
    let (w, h) = (camera.width as usize, camera.height as usize);
    let tracer = Tracer::new(scene, settings);
    let rotation = camera.rotation();
    let recombine = Recombine {
        scene,
        light: settings.light,
        stage: settings.shading.stage,
        shadows: settings.shading.shadows,
        n: settings.shading.indirect_term(),
    };
    let rows: Vec<Vec<Vec3>> = (0..h)
        .into_par_iter()
        .map(|y| {
            let rays: Vec<Ray> = (0..w)
                .map(|x| camera.primary_ray_rotated(&rotation, x as f32 + 0.5, y as f32 + 0.5))
                .collect();
            let mut row = vec![Vec3::ZERO; w * wanted.len()];
            for (x, pixel) in pixel_hits(&tracer, &rays).iter().enumerate() {
                for (k, r) in wanted.iter().enumerate() {
                    let value = |s: &ShadedHit| recombine.value(*r, &s.hit, s.incoming, &s.terms);
                    row[k * w + x] = pixel.value(value);
                }
            }
            row
        })
        .collect();
    wanted
        .iter()
        .enumerate()
        .map(|(k, _)| Image {
            width: camera.width,
            height: camera.height,
            pixels: rows
                .iter()
                .flat_map(|row| row[k * w..(k + 1) * w].iter().copied())
                .collect(),
        })
        .collect()
}

/// What a camera ray's pixel is, as the lab's integrator shades it.
pub(crate) enum PixelHits {
    /// The ray leaves the scene: black.
    Miss,
    /// A diffuse hit: the pixel is its value.
    Diffuse(ShadedHit),
    /// Mirror or glass: the pixel is the sum of the diffuse hits its Whitted branches find,
    /// each times its weight, in the integrator's order.
    Specular(Vec<ShadedHit>),
}

impl PixelHits {
    /// The pixel's value with each shaded hit valued by `value`: as the integrator writes it
    /// when `value` is [`HitTerms::value`].
    pub(crate) fn value(&self, mut value: impl FnMut(&ShadedHit) -> Vec3) -> Vec3 {
        match self {
            PixelHits::Miss => Vec3::ZERO,
            PixelHits::Diffuse(s) => value(s),
            PixelHits::Specular(branches) => branches
                .iter()
                .fold(Vec3::ZERO, |sum, s| sum + s.weight * value(s)),
        }
    }
}

/// The shaded hits of each of `rays` (camera rays, a row's or fewer), traced by the lab's own
/// integrator a batch at a time and recorded ([`Tracer::trace_recorded`]).
pub(crate) fn pixel_hits(tracer: &Tracer, rays: &[Ray]) -> Vec<PixelHits> {
    let mut pixels: Vec<PixelHits> = rays.iter().map(|_| PixelHits::Miss).collect();
    let mut out = vec![Vec3::ZERO; BATCH];
    // A batch at a time, as the integrator takes them: its camera rays are traced first, so
    // the first hits recorded are theirs, in order.
    for (c, rays) in rays.chunks(BATCH).enumerate() {
        let mut recording = HitRecording::default();
        tracer.trace_recorded(rays, &mut [], &mut out[..rays.len()], &mut recording);
        let camera_hits = &recording.hits[..rays.len()];
        let mut shaded = recording.shaded_hits().into_iter();
        for (i, traced) in camera_hits.iter().enumerate() {
            let x = c * BATCH + i;
            if traced.specular {
                // Its branches' hits are recorded among the others' in waves: the pixel is
                // traced again alone, where every hit recorded is its own.
                let mut alone = HitRecording::default();
                tracer.trace_recorded(&rays[i..=i], &mut [], &mut out[..1], &mut alone);
                pixels[x] = PixelHits::Specular(alone.shaded_hits());
            } else if traced.hit.is_some() {
                // A diffuse hit, whose terms are the next recorded: its value is the pixel's,
                // as the integrator writes a camera ray's.
                let Some(s) = shaded.next() else { break };
                pixels[x] = PixelHits::Diffuse(s);
            }
        }
    }
    pixels
}

/// One ray traced by a formula pass: its closest hit (and direction), and whether that hit
/// was mirror or glass (followed by branches, not shaded).
struct Traced {
    hit: Option<(Intersection, Vec3)>,
    specular: bool,
}

/// What a formula pass records: every ray's hit in the order traced, and each shaded hit's
/// terms with its shadow ray answered and the weight its pixel gets them with.
#[derive(Default)]
struct HitRecording {
    hits: Vec<Traced>,
    shaded: Vec<(HitTerms, Vec3)>,
}

/// A shaded hit: where, found by a ray going which way, its terms, and its weight (1 for a
/// camera ray; the product of the specular weights along a Whitted branch).
pub(crate) struct ShadedHit {
    pub(crate) hit: Intersection,
    pub(crate) incoming: Vec3,
    pub(crate) terms: HitTerms,
    pub(crate) weight: Vec3,
}

impl HitRecording {
    /// The shaded hits in the order shaded, each with the hit it was shaded at. The integrator
    /// shades a wave's hits that are not mirror or glass, in the order of its rays, after
    /// finding them all, wave after wave: so the hits that are neither mirror, glass nor
    /// misses, in the order found, are the shaded ones in the order shaded.
    fn shaded_hits(&self) -> Vec<ShadedHit> {
        let mut found = self
            .hits
            .iter()
            .filter(|t| !t.specular)
            .filter_map(|t| t.hit);
        self.shaded
            .iter()
            .map_while(|&(terms, weight)| {
                let (hit, incoming) = found.next()?;
                debug_assert_eq!(terms.position, hit.position, "terms paired with their hit");
                Some(ShadedHit {
                    hit,
                    incoming,
                    terms,
                    weight,
                })
            })
            .collect()
    }
}

impl Recorder for HitRecording {
    const ENABLED: bool = true;

    fn closest_hit(&mut self, ray: &Ray, hit: Option<&Intersection>, _: Vec3, _: u32) {
        self.hits.push(Traced {
            hit: hit.map(|h| (*h, ray.direction)),
            specular: false,
        });
    }

    fn specular_hit(&mut self, hit: &Intersection, _: Vec3, _: u32, _: &[(Vec3, Vec3)]) {
        // Told right after the same ray's closest hit.
        if let Some(last) = self.hits.last_mut() {
            debug_assert_eq!(last.hit.map(|(h, _)| h.position), Some(hit.position));
            last.specular = true;
        }
    }

    fn shaded(&mut self, terms: &HitTerms, _: Vec3, _: Vec3, weight: Vec3) {
        self.shaded.push((*terms, weight));
    }

    fn scattered(&mut self, _: &Scatter, _: f32, _: Vec3, _: bool) {}
}

/// A hit's terms put together again, with a mistake.
struct Recombine<'a> {
    scene: &'a Scene,
    light: LightSpec,
    stage: Stage,
    shadows: bool,
    /// N, the constant indirect term in force (0 when off).
    n: Vec3,
}

impl Recombine<'_> {
    /// The value of a hit (`incoming`: the direction of the camera ray that found it) with
    /// `terms` as the lab computed them, recombined as `what` says.
    fn value(
        &self,
        what: Recombined,
        hit: &Intersection,
        incoming: Vec3,
        terms: &HitTerms,
    ) -> Vec3 {
        use Mistake::*;
        let (stage, n) = (self.stage, self.n);
        let mistake = match what {
            Recombined::Mistake(m) => m,
            Recombined::EveryShadowRayBlocked => {
                let blocked = terms.blocked || terms.shadow_ray.is_some();
                return HitTerms { blocked, ..*terms }.value(stage, n);
            }
        };
        let reflected = stage.reflects_light();
        match mistake {
            None => terms.value(stage, n),
            No4Pi | InverseR | UnclampedCos | FlippedNormal => {
                let normal = if mistake == FlippedNormal {
                    -terms.normal
                } else {
                    terms.normal
                };
                let d = mistaken_direct(&self.light, mistake, terms.position, normal);
                let blocked = self.blocked_with(d, hit, incoming, terms);
                HitTerms {
                    d,
                    blocked,
                    ..*terms
                }
                .value(stage, n)
            }
            // The incoming stage's formula, D + N, where ρ·(D + N) belongs.
            NoRho if reflected => terms.value(Stage::Incoming, n),
            IndirectOutsideRho if reflected => terms.rho * terms.d_after_shadows() + n,
            ShadowAcne => {
                let blocked = self.acne_blocked(terms);
                HitTerms { blocked, ..*terms }.value(stage, n)
            }
            ShadowBeyondLight => {
                let blocked = terms.shadow_ray.map_or(terms.blocked, |(ray, _)| {
                    self.scene.occluded(&ray, f32::INFINITY)
                });
                HitTerms { blocked, ..*terms }.value(stage, n)
            }
            ShadowDropsIndirect if terms.blocked => Vec3::ZERO,
            _ => terms.value(stage, n),
        }
    }

    /// Whether a hit given a mistaken D is in shadow: the lab's answer where it cast a shadow
    /// ray; where it cast none because no light arrived (D = 0, facing away) but the mistaken
    /// D is not 0, the lab's shadow ray cast now ([`in_shadow`], section 5.1).
    fn blocked_with(&self, d: Vec3, hit: &Intersection, incoming: Vec3, terms: &HitTerms) -> bool {
        if terms.shadow_ray.is_some() || !self.shadows || d == Vec3::ZERO {
            return terms.blocked;
        }
        let at_edge = self
            .scene
            .approach_at_edge(hit.triangle_index, hit.u, hit.v, incoming);
        in_shadow(
            self.scene,
            &self.light,
            terms.position,
            terms.normal,
            at_edge,
        )
    }

    /// The shadow test of a student who starts the shadow ray at the hit point itself, with no
    /// offset, and counts any surface nearer than the light (section 5.1). In single precision
    /// the hit point lies a rounding error off its own surface, on either side: where it lies
    /// behind, the surface itself is found in the way.
    fn acne_blocked(&self, terms: &HitTerms) -> bool {
        if terms.shadow_ray.is_none() {
            // No shadow ray: no light arrives to be blocked.
            return terms.blocked;
        }
        let to_light = self.light.position - terms.position;
        let distance = to_light.length();
        self.scene
            .occluded(&Ray::new(terms.position, to_light), distance)
    }
}

/// D (equation 27) as `mistake` (`no-4pi`, `inverse-r`, `unclamped-cos`; any other gives the
/// lab's) computes it, from the lab's own parts of the equation ([`DirectLight::at`]: r², r̂·n̂,
/// 4πr² and a spot's falloff) with `normal`.
pub(crate) fn mistaken_direct(
    light: &LightSpec,
    mistake: Mistake,
    position: Vec3,
    normal: Vec3,
) -> Vec3 {
    let parts = DirectLight::at(light, position, normal);
    let cos = match mistake {
        Mistake::UnclampedCos => parts.cos,
        _ => parts.cos.max(0.0),
    };
    let area = match mistake {
        Mistake::No4Pi => parts.r2,
        Mistake::InverseR => 4.0 * PI * parts.r2.sqrt(),
        _ => parts.four_pi_r2,
    };
    // A spot's falloff is 1 for every other light: the product is `cos` itself.
    light.channel_power() * (parts.falloff * cos) / area
}

/// The settings a settings mistake renders with, and the part of that render the student's
/// image is: `(x0, y0)`, the top-left corner of a crop of the exact image's size.
pub fn mistaken_settings(
    settings: &RenderSettings,
    mistake: Mistake,
) -> (RenderSettings, (u32, u32)) {
    let mut s = settings.clone();
    let c = &mut s.camera;
    let mut corner = (0, 0);
    match mistake {
        Mistake::FocalHalf => c.focal_length /= 2.0,
        Mistake::YawSign => c.yaw = -c.yaw,
        Mistake::LightYFlipped => s.light.position.y = -s.light.position.y,
        // d_x = (x + ½) − (W + 1)/2 = x − W/2 on a camera one pixel wider (the focal length
        // kept), and the same for rows: the rays through the pixels' corners.
        Mistake::PixelCorner => {
            c.width += 1;
            c.height += 1;
        }
        // d_y = y + ½ − W/2: a camera Hc rows high, seen from row (Hc − W)/2, with
        // Hc = max(W, 2H − W), which holds every row of the student's image.
        Mistake::Eq24Typo => {
            let (w, h) = (c.width, c.height);
            let tall = w.max((2 * h).saturating_sub(w));
            c.height = tall;
            corner = (0, (tall - w) / 2);
        }
        _ => {}
    }
    (s, corner)
}

/// The figure a settings mistake (`Kind::Settings`) renders: [`render`] with
/// [`mistaken_settings`], cropped to the exact image's size.
pub fn settings_figure(scene: &Scene, settings: &RenderSettings, mistake: Mistake) -> Image {
    let (s, (x0, y0)) = mistaken_settings(settings, mistake);
    let image = render(scene, &s);
    let (w, h) = (settings.camera.width, settings.camera.height);
    if (image.width, image.height) == (w, h) {
        return image;
    }
    Image {
        width: w,
        height: h,
        pixels: (y0..y0 + h)
            .flat_map(|y| (x0..x0 + w).map(move |x| (x, y)))
            .map(|(x, y)| image.get(x, y))
            .collect(),
    }
}

/// The exact figure with a pixel more on every side (its pixel (x + 1, y + 1) is the figure's
/// (x, y), up to rounding): a camera two pixels wider and taller with the same focal length,
/// d_x = (x + 1 + ½) − (W + 2)/2 = x + ½ − W/2. What the figure's border pixels' neighbours
/// see, for telling anti-aliasing ([`super::compare::share_explained_with_edges`]).
pub fn figure_with_margin(scene: &Scene, settings: &RenderSettings) -> Image {
    let mut s = settings.clone();
    s.camera.width += 2;
    s.camera.height += 2;
    render(scene, &s)
}

/// The looks a picture mistake (`Kind::Picture`) gives the exact figure (`linear`, and
/// `figure`, the same through the lab's display): any of them explains a pixel. A gamma curve
/// is the sRGB curve or the plain power 1/2.2, which differ by up to 6/255 in the shadows.
pub fn picture_looks(mistake: Mistake, linear: &Image, figure: &Rgb8) -> Vec<Rgb8> {
    let (w, h) = (figure.width as usize, figure.height as usize);
    match mistake {
        Mistake::UpsideDown => {
            let rows = figure.data.chunks_exact(3 * w).rev();
            vec![Rgb8 {
                data: rows.flatten().copied().collect(),
                ..figure.clone()
            }]
        }
        Mistake::Bgr => vec![Rgb8 {
            data: figure
                .data
                .chunks_exact(3)
                .flat_map(|p| [p[2], p[1], p[0]])
                .collect(),
            ..figure.clone()
        }],
        Mistake::Gamma => {
            let srgb = Display {
                transform: DisplayTransform::Srgb,
                exposure: 0.0,
            };
            let power =
                |v: f32| (f64::from(v.clamp(0.0, 1.0)).powf(1.0 / 2.2) * 255.0).round() as u8;
            vec![
                Rgb8 {
                    data: srgb.to_rgb8(&linear.pixels),
                    ..figure.clone()
                },
                Rgb8 {
                    data: linear
                        .pixels
                        .iter()
                        .flat_map(|p| p.to_array().map(power))
                        .collect(),
                    ..figure.clone()
                },
            ]
        }
        _ => {
            debug_assert!(false, "{mistake} is not a picture mistake ({w}×{h})");
            vec![figure.clone()]
        }
    }
}

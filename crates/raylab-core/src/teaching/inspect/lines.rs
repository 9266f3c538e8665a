//! An [`Inspection`] in the lab's words: one line a step, beside the equation it evaluates,
//! with the numbers substituted.

use std::fmt::Write as _;

use glam::Vec3;

use super::*;
use crate::transport::display::Display;

impl Inspection {
    /// The explanation, one line per step, each beside the lab equation it evaluates.
    pub fn lines(&self) -> Vec<InspectLine> {
        let mut lines = Lines::default();
        let stage = self.stage;
        let figure = match stage.figure() {
            Some(f) => format!("fig. {f}"),
            None => "path".to_owned(),
        };
        lines.push(
            &figure,
            format!(
                "pixel ({}, {}), stage {stage}: {}",
                self.pixel[0], self.pixel[1], self.computes
            ),
        );
        self.camera_lines(&mut lines);
        let Some(triangle) = self.triangle else {
            lines.push(
                "eqs. 7–9, 12",
                "closest intersection: none, the ray leaves the box (nothing is hit)".to_owned(),
            );
            lines.push(
                final_equation(stage, self.n),
                format!("R = {} (black: no surface, no light)", colour(self.r)),
            );
            return lines.0;
        };
        lines.push(
            "eqs. 7–9, 12",
            format!(
                "closest hit: triangle {triangle} ({}, {}) at t = {} units, u = {}, v = {} \
                 (u ≥ 0, v ≥ 0, u + v ≤ 1); point s + t·d̂ = {}",
                self.surface.as_deref().unwrap_or("?"),
                self.kind.unwrap_or("?"),
                num(self.t.unwrap_or(f32::NAN)),
                num(self.u.unwrap_or(f32::NAN)),
                num(self.v.unwrap_or(f32::NAN)),
                vector(self.position.unwrap_or(Vec3::NAN)),
            ),
        );
        if let Some(normal) = self.normal {
            let mut text = format!("surface normal n̂ = {}", vector(normal));
            if self.back_facing == Some(true) {
                text.push_str(&format!(
                    "; the ray meets its back (d̂·n̂ = {} > 0)",
                    num(self.direction.dot(normal))
                ));
            }
            lines.push("", text);
        }
        if let Some(n) = self.shading_normal {
            let why = if stage == Stage::Path && self.normal == Some(-n) {
                "turned to face the ray (two-sided surfaces)"
            } else if self.normal_mapped {
                "tilted by the normal map in the hit's tangent frame (lab §6)"
            } else {
                "smooth shading, interpolated from the vertex normals"
            };
            lines.push("", format!("normal for the light: {} ({why})", vector(n)));
        }
        if stage == Stage::Path {
            self.path_lines(&mut lines);
        } else {
            self.lab_lines(&mut lines);
        }
        lines.0
    }

    /// What the display makes of the pixel, to follow [`Inspection::lines`]: R through
    /// `display` (its exposure and curve) as the 8-bit value a screen or PNG shows; and when the
    /// pixel on screen is not sample 0 alone (`shown`: several samples, or denoised), that R is
    /// sample 0's, and the value shown with its own 8 bits. `shown` is `None` while no image of
    /// these settings is on screen.
    pub fn display_lines(&self, display: &Display, shown: Option<ShownPixel>) -> Vec<InspectLine> {
        let mut lines = Lines::default();
        let curve = match display.exposure {
            0.0 => format!("display {}", display.transform.label()),
            stops => format!(
                "display {}, exposure {stops:+} EV",
                display.transform.label()
            ),
        };
        let eight_bit = |v: Vec3| {
            let [r, g, b] = display.encode(v);
            if r == g && g == b {
                format!("{r}")
            } else {
                format!("({r}, {g}, {b})")
            }
        };
        match shown {
            Some(shown) if shown.samples > 1 || shown.denoised => {
                let origin = if self.lens_point.is_some() {
                    "through the pixel's centre and one point of the lens"
                } else {
                    "through the pixel's centre"
                };
                lines.push(
                    "sample 0",
                    format!(
                        "R above is sample 0's alone (the ray {origin}), {} in 8 bits through the \
                         {curve}: not the pixel on screen",
                        eight_bit(self.r)
                    ),
                );
                let what = if shown.denoised {
                    format!(
                        "the denoised image's value, filtered from the mean of {} samples",
                        shown.samples
                    )
                } else {
                    format!(
                        "the mean of its {} samples (each through another point of the pixel)",
                        shown.samples
                    )
                };
                lines.push(
                    "on screen",
                    format!(
                        "the pixel shown is {what}: {}, shown as {} in 8 bits",
                        colour(shown.value),
                        eight_bit(shown.value)
                    ),
                );
            }
            _ => lines.push(
                "on screen",
                format!(
                    "R = {}, shown as {} in 8 bits through the {curve}",
                    colour(self.r),
                    eight_bit(self.r)
                ),
            ),
        }
        lines.0
    }

    /// [`Inspection::lines`] joined, one per line: the equation, then the text.
    pub fn to_text(&self) -> String {
        lines_text(&self.lines())
    }

    fn camera_lines(&self, lines: &mut Lines) {
        let [px, py] = self.image_point;
        let [w, h] = self.image;
        match self.lens_point {
            None => lines.push(
                "eq. 24",
                format!(
                    "camera ray through image point ({}, {}) of {w}×{h}, f = {} px: d = R·(x − W/2, \
                     y − H/2, f) = R·({}, {}, {}), d̂ = {}, from s = {}",
                    num(px),
                    num(py),
                    num(self.focal_length),
                    num(px - w as f32 / 2.0),
                    num(py - h as f32 / 2.0),
                    num(self.focal_length),
                    vector(self.direction),
                    vector(self.origin),
                ),
            ),
            Some(lens) => lines.push(
                "eq. 24",
                format!(
                    "thin-lens camera ray for image point ({}, {}) of {w}×{h}, f = {} px, from lens \
                     point ({}, {}) of the unit disk: s = {}, d̂ = {}",
                    num(px),
                    num(py),
                    num(self.focal_length),
                    num(lens.x),
                    num(lens.y),
                    vector(self.origin),
                    vector(self.direction),
                ),
            ),
        }
    }

    /// The lab stages: the specular chain, then each diffuse hit's terms and value, then R.
    fn lab_lines(&self, lines: &mut Lines) {
        for step in &self.specular_chain {
            let what = match step.branch {
                "given up" => format!(
                    "depth {}: triangle {} ({}, {}) at {}: the specular depth is reached, the \
                     branch is given up (black)",
                    step.depth + 1,
                    step.triangle,
                    step.surface,
                    step.kind,
                    vector(step.position)
                ),
                branch => {
                    let weight = match (step.kind, branch) {
                        ("glass", "reflection") => "Fresnel's F",
                        ("glass", _) => "(1 − F)·tint",
                        _ => "the tint",
                    };
                    format!(
                        "depth {}: triangle {} ({}, {}) at {}: {branch} along {}, weight {} \
                         ({weight}); the branch carries {}",
                        step.depth + 1,
                        step.triangle,
                        step.surface,
                        step.kind,
                        vector(step.position),
                        vector(step.direction.unwrap_or(Vec3::NAN)),
                        colour(step.weight),
                        colour(step.total_weight),
                    )
                }
            };
            lines.push(step.kind, what);
        }
        for escaped in &self.escaped {
            lines.push(
                "",
                format!(
                    "a branch (weight {}) leaves the box after {} mirror or glass hit(s): it adds 0",
                    colour(escaped.weight),
                    escaped.depth
                ),
            );
        }
        let branched = !self.specular_chain.is_empty();
        for hit in &self.shaded {
            if branched {
                lines.push(
                    "eqs. 7–9, 12",
                    format!(
                        "a branch (weight {}) reaches triangle {} ({}) at t = {} units: point {}, \
                         normal {}",
                        colour(hit.weight),
                        hit.triangle,
                        hit.surface,
                        num(hit.t),
                        vector(hit.position),
                        vector(hit.normal)
                    ),
                );
            }
            self.terms_lines(lines, hit, "");
            let value = self.value_line(hit, if branched { "value" } else { "R" });
            lines.push(value.0, value.1);
            if branched {
                lines.push(
                    "",
                    format!(
                        "× the branch's weight {} = {} added to R",
                        colour(hit.weight),
                        colour(hit.contribution)
                    ),
                );
            }
        }
        if branched || self.shaded.is_empty() {
            let how = if self.shaded.is_empty() {
                "no diffuse surface is reached"
            } else {
                "the sum of what the branches add"
            };
            lines.push(
                final_equation(self.stage, self.n),
                format!("R = {} ({how})", colour(self.r)),
            );
        }
    }

    /// The path stage: every vertex with what it adds and where the path goes, then R.
    fn path_lines(&self, lines: &mut Lines) {
        let mut shaded = self.shaded.iter();
        for vertex in &self.bounces {
            lines.push(
                "path",
                format!(
                    "vertex {}: triangle {} ({}, {}) at {}, throughput β = {}",
                    vertex.depth,
                    vertex.triangle,
                    vertex.surface,
                    vertex.kind,
                    vector(vertex.position),
                    colour(vertex.beta)
                ),
            );
            if let Some(l) = &vertex.light_sample {
                lines.push(
                    "MIS",
                    format!(
                        "  light sample along {}: f = {}, p_light = {}, p_bsdf = {}, MIS weight \
                         p_light²/(p_light² + p_bsdf²) = {}; shadow ray {}; adds β·f·Li·cos θ/p_light·w = {}",
                        vector(l.wi),
                        colour(l.f),
                        num(l.pdf_light),
                        num(l.pdf_bsdf),
                        num(l.mis_weight),
                        if l.blocked { "blocked" } else { "unblocked" },
                        colour(l.added)
                    ),
                );
            } else if vertex.kind == "diffuse"
                && let Some(hit) = shaded.next()
            {
                self.terms_lines(lines, hit, "  ");
                let value = self.value_line(hit, "");
                lines.push(value.0, format!("  {}", value.1));
                lines.push(
                    "",
                    format!(
                        "  adds β·ρ·D = {} · {} = {}",
                        colour(hit.weight),
                        colour(hit.value),
                        colour(hit.contribution)
                    ),
                );
            } else {
                lines.push(
                    "",
                    "  adds nothing: a point light is never seen in a mirror or through glass"
                        .to_owned(),
                );
            }
            if let Some(g) = &vertex.photons {
                lines.push(
                    "photons",
                    format!(
                        "  caustic photons: {} found within r = {}; adds β·Σ f·Φ/r² = {}",
                        g.photons,
                        num(g.radius),
                        colour(g.added)
                    ),
                );
            }
            if let (Some(direction), Some(weight), Some(q), Some(after)) = (
                vertex.direction_out,
                vertex.scatter_weight,
                vertex.survival,
                vertex.beta_after,
            ) {
                let how = match (vertex.kind, vertex.scatter.unwrap_or("")) {
                    ("diffuse", _) => "a cosine-weighted bounce, weight ρ",
                    ("rough", _) => "a GGX visible-normal sample, weight tint·G1(wi)",
                    ("mirror", _) => "the mirror's reflection, weight the tint",
                    ("glass", "reflection") => "reflection off the glass (probability F), weight",
                    _ => "refraction through the glass (probability 1 − F), weight the tint",
                };
                let roulette = if q < 1.0 {
                    format!("; Russian roulette: it survives with q = {}, β ÷ q", num(q))
                } else {
                    String::new()
                };
                lines.push(
                    "",
                    format!(
                        "  continues along {}: {how} = {}{roulette}; β = {}",
                        vector(direction),
                        colour(weight),
                        colour(after)
                    ),
                );
            }
            if let Some(ends) = &vertex.ends {
                lines.push("", format!("  the path ends: {ends}"));
            }
        }
        lines.push(
            "path",
            format!(
                "R = Σ β·ρ·D over the vertices = {} (π × radiance; averaged over samples it \
                 converges)",
                colour(self.r)
            ),
        );
    }

    /// D (equation 27) with its parts, and the shadow ray (§5.1), at one diffuse hit.
    fn terms_lines(&self, lines: &mut Lines, hit: &ShadedHit, indent: &str) {
        let t = &hit.terms;
        let rho = t.rho.unwrap_or(Vec3::NAN);
        let from = if t.textured {
            format!("the {} texture at the hit", hit.surface)
        } else {
            format!("the reflectance of {}", hit.surface)
        };
        match t.glossy {
            None => lines.push("§5", format!("{indent}ρ = {} ({from})", colour(rho))),
            Some(g) => lines.push(
                "§5",
                format!(
                    "{indent}ρ = π·f(toward the viewer, toward the light) = π·f_s + π·f_d = {} \
                     (highlight) + {} (diffuse base) = {} (the glossy {}, in place of the lab's \
                     ρ)",
                    colour(g.specular),
                    colour(g.diffuse),
                    colour(rho),
                    hit.surface
                ),
            ),
        }
        let (Some(r), Some(dist), Some(r2), Some(cos), Some(p), Some(area), Some(d)) = (
            t.to_light,
            t.light_distance,
            t.light_distance_squared,
            t.cos_theta,
            t.power,
            t.four_pi_r2,
            t.d,
        ) else {
            return;
        };
        lines.push(
            "eq. 27",
            format!(
                "{indent}r = light − point = {} − {} = {}, |r| = {} units, r̂·n̂ = {}",
                vector(self.light.position),
                vector(hit.position),
                vector(r),
                num(dist),
                num(cos)
            ),
        );
        let watts = if self.light.colour == Vec3::ONE {
            format!("{} W", num(self.light.power))
        } else {
            format!(
                "{} W × {} = {} W",
                num(self.light.power),
                colour(self.light.colour),
                colour(p)
            )
        };
        // Where the relief hides the light, the equation's own value first, then why it is 0.
        let falloff = t.falloff.unwrap_or(1.0);
        let d = if t.relief_shadowed {
            p * (falloff * cos.max(0.0)) / area
        } else {
            d
        };
        let cos_text = if cos > 0.0 {
            num(cos)
        } else {
            format!("max({}, 0)", num(cos))
        };
        let (formula, falloff_text) = match (t.falloff, self.light.spot()) {
            (Some(f), Some(spot)) => {
                let deg = |a: f32| num(crate::base::camera::degrees(a) as f32);
                let theta = deg(crate::shading::light::acos(
                    -r.normalize_or_zero().dot(spot.axis),
                ));
                let why = if f == 1.0 {
                    format!("θ = {theta}° within the beam, {}°: 1", deg(spot.beam))
                } else if f == 0.0 {
                    format!("θ = {theta}° beyond the cutoff, {}°: 0", deg(spot.cutoff))
                } else {
                    let (c, b) = (deg(spot.cutoff), deg(spot.beam));
                    format!("θ = {theta}°: ({c}° − θ)/({c}° − {b}°) = {}", num(f))
                };
                lines.push(
                    "spot",
                    format!("{indent}the spot's falloff at θ from its axis, {why}"),
                );
                ("P·falloff·max(r̂·n̂, 0)/(4πr²)", format!(" × {}", num(f)))
            }
            _ => ("P·max(r̂·n̂, 0)/(4πr²)", String::new()),
        };
        lines.push(
            "eq. 27",
            format!(
                "{indent}D = {formula} = {watts}{falloff_text} × {cos_text} / (4π × {} units² = \
                 {} units²) = {} W per unit area",
                num(r2),
                num(area),
                colour(d)
            ),
        );
        if t.light_behind_surface {
            lines.push(
                "eq. 27",
                format!(
                    "{indent}but the light is behind the surface itself (its own normal): D = 0"
                ),
            );
        }
        if t.relief_shadowed {
            lines.push(
                "§6",
                format!(
                    "{indent}but the surface's own relief hides the light (parallax \
                     self-shadowing: its height field rises between the point and the light): \
                     D = 0"
                ),
            );
        }
        if !self.shadows {
            return;
        }
        match &t.shadow_ray {
            None => lines.push(
                "§5.1",
                format!("{indent}no shadow ray: no light arrives to be blocked"),
            ),
            Some(ray) => {
                let toward = match self.light.kind {
                    LightKind::Sphere { radius } if radius > 0.0 => format!(
                        "a random point of the light's sphere (radius {}), along {}",
                        num(radius),
                        vector(ray.direction)
                    ),
                    LightKind::Quad { side } if side > 0.0 => format!(
                        "a random point of the light's square (side {}), along {}",
                        num(side),
                        vector(ray.direction)
                    ),
                    LightKind::Point
                    | LightKind::Sphere { .. }
                    | LightKind::Quad { .. }
                    | LightKind::Spot(_) => "the light".to_owned(),
                };
                let answer = if t.shadow_blocked {
                    match &t.blocker {
                        Some(b) => format!(
                            "blocked by triangle {} ({}) at {} units: in shadow, D counts as 0",
                            b.triangle,
                            b.surface,
                            num(b.distance)
                        ),
                        None => "blocked: in shadow, D counts as 0".to_owned(),
                    }
                } else {
                    "nothing in the way: D counts in full".to_owned()
                };
                lines.push(
                    "§5.1",
                    format!(
                        "{indent}shadow ray from {} toward {toward}, {} units long: {answer}",
                        vector(ray.origin),
                        num(ray.length)
                    ),
                );
            }
        }
    }

    /// The hit's value as its stage says, with the numbers; `lhs` names it ("R" when it is the
    /// pixel's value).
    fn value_line(&self, hit: &ShadedHit, lhs: &str) -> (&'static str, String) {
        let t = &hit.terms;
        let rho = colour(t.rho.unwrap_or(Vec3::NAN));
        let d = if t.shadow_blocked || t.light_behind_surface || t.relief_shadowed {
            Vec3::ZERO
        } else {
            t.d.unwrap_or(Vec3::ZERO)
        };
        let n = hit.n;
        let v = colour(hit.value);
        match self.stage {
            Stage::Flat => ("fig. 2", format!("{lhs} = ρ = {v}")),
            Stage::Incoming if n == Vec3::ZERO => ("eq. 27", format!("{lhs} = D = {v}")),
            Stage::Incoming => (
                "eq. 29",
                format!("{lhs} = T = D + N = {} + {} = {v}", colour(d), colour(n)),
            ),
            Stage::Path => ("eq. 28", format!("ρ·D = {rho} · {} = {v}", colour(d))),
            Stage::Direct | Stage::Shadows | Stage::Lab if n == Vec3::ZERO => (
                "eq. 28",
                format!("{lhs} = ρ·D = {rho} · {} = {v}", colour(d)),
            ),
            Stage::Direct | Stage::Shadows | Stage::Lab => (
                "eq. 30",
                format!(
                    "{lhs} = ρ·(D + N) = {rho} · ({} + {}) = {v}",
                    colour(d),
                    colour(n)
                ),
            ),
        }
    }
}

/// The equation a stage's pixel value is.
fn final_equation(stage: Stage, n: Vec3) -> &'static str {
    match stage {
        Stage::Flat => "fig. 2",
        Stage::Incoming if n == Vec3::ZERO => "eq. 27",
        Stage::Incoming => "eq. 29",
        Stage::Path => "path",
        Stage::Direct | Stage::Shadows | Stage::Lab if n == Vec3::ZERO => "eq. 28",
        Stage::Direct | Stage::Shadows | Stage::Lab => "eq. 30",
    }
}

/// Lines joined as [`Inspection::to_text`] joins them, one per line: the equation (padded to
/// the longest), then the text.
pub fn lines_text(lines: &[InspectLine]) -> String {
    let width = lines
        .iter()
        .map(|l| l.equation.chars().count())
        .max()
        .unwrap_or(0);
    let mut text = String::new();
    for line in lines {
        let pad = width - line.equation.chars().count();
        let _ = writeln!(text, "{}{}  {}", line.equation, " ".repeat(pad), line.text);
    }
    text
}

#[derive(Default)]
struct Lines(Vec<InspectLine>);

impl Lines {
    fn push(&mut self, equation: &str, text: String) {
        self.0.push(InspectLine {
            equation: equation.to_owned(),
            text,
        });
    }
}

/// A number as printed: three significant digits below 1, three decimals above (trailing
/// zeros dropped: 14, 0.5, 2.74), scientific notation when very small or large, 0 for zero.
pub(crate) fn num(x: f32) -> String {
    let a = x.abs();
    let text = if x == 0.0 {
        return "0".to_owned();
    } else if !x.is_finite() {
        return format!("{x}");
    } else if !(1e-3..1e5).contains(&a) {
        return format!("{x:.2e}");
    } else if a < 1.0 {
        // Three significant digits: 0.906, 0.0791, 0.00234.
        let decimals = 2 - a.log10().floor() as i32;
        format!("{x:.*}", decimals.clamp(2, 5) as usize)
    } else {
        format!("{x:.3}")
    };
    let trimmed = text.trim_end_matches('0').trim_end_matches('.');
    if trimmed == "-0" {
        "0".to_owned()
    } else {
        trimmed.to_owned()
    }
}

pub(crate) fn vector(v: Vec3) -> String {
    format!("({}, {}, {})", num(v.x), num(v.y), num(v.z))
}

/// A colour: one number when its channels are equal (grey, as the lab's light is), else three.
pub(super) fn colour(v: Vec3) -> String {
    if v.x == v.y && v.y == v.z {
        num(v.x)
    } else {
        vector(v)
    }
}

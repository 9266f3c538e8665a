//! What a pass computes: the lab's stages (figures 2 to 7) or the path tracer, and the switches
//! that change what a stage adds (shadows, the constant indirect term, bounces, smooth normals).
//! Plain choices, read by the integrators ([`crate::transport::integrator`]).

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::base::named::named_enum;
use crate::shading::material::MaterialPreset;

/// A step of the lab, named after what it shows, or the path tracer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Stage {
    /// Figure 2: the colour ρ of the first surface hit.
    Flat,
    /// Figure 3: the incoming light D (equation 27), or T = D + N (equation 29) with indirect.
    Incoming,
    /// Figure 5: reflected direct light ρ ∗ D (equation 28), no shadows.
    Direct,
    /// Figure 6: ρ ∗ D with shadows (section 5.1).
    Shadows,
    /// Figure 7: ρ ∗ (D + N) with shadows (equation 30). The default.
    #[default]
    Lab,
    /// Beyond the lab: path tracing, ρ ∗ D at every bounce plus real indirect light in place of
    /// N (π × radiance, converging as samples accumulate).
    Path,
}

named_enum!(Stage as "stage" {
    Flat => "flat", "Flat colour (figure 2)";
    Incoming => "incoming", "Incoming light (figure 3)";
    Direct => "direct", "Direct light (figure 5)";
    Shadows => "shadows", "Shadows (figure 6)";
    Lab => "lab", "Lab (figure 7)";
    Path => "path", "Path tracing (real light)";
});

impl Stage {
    /// The lab's stages, in the order of its figures.
    pub const LAB: [Stage; 5] = [
        Stage::Flat,
        Stage::Incoming,
        Stage::Direct,
        Stage::Shadows,
        Stage::Lab,
    ];

    /// The lab figure this stage reproduces with its preset switches (`None` for `path`, which
    /// goes beyond the lab).
    pub fn figure(self) -> Option<u32> {
        match self {
            Stage::Flat => Some(2),
            Stage::Incoming => Some(3),
            Stage::Direct => Some(5),
            Stage::Shadows => Some(6),
            Stage::Lab => Some(7),
            Stage::Path => None,
        }
    }

    /// What this stage computes with its preset switches, in the lab's terms and equation
    /// numbers. `·` stands for the lab's element-wise product `∗` (a glyph the workbench's font
    /// lacks). [`Shading::description`] says what is computed with the switches as they are.
    pub fn equation(self) -> &'static str {
        match self {
            Stage::Flat => "ρ, the reflectance",
            Stage::Incoming => "D, the incoming light (eq. 27)",
            Stage::Direct => "ρ·D (eq. 28)",
            Stage::Shadows => "ρ·D with shadows (eq. 28, §5.1)",
            Stage::Lab => "ρ·(D + N) with shadows (eq. 30)",
            Stage::Path => "ρ·D with shadows at every bounce, real indirect light for N",
        }
    }

    /// The shadows and indirect switches as the lab's figure has them (`path`: both on).
    pub fn preset_switches(self) -> (bool, bool) {
        match self {
            Stage::Flat | Stage::Incoming | Stage::Direct => (false, false),
            Stage::Shadows => (true, false),
            Stage::Lab | Stage::Path => (true, true),
        }
    }

    /// Which integrator computes this stage.
    pub fn integrator(self) -> Integrator {
        match self {
            Stage::Path => Integrator::Path,
            Stage::Flat | Stage::Incoming | Stage::Direct | Stage::Shadows | Stage::Lab => {
                Integrator::Lab
            }
        }
    }

    /// Whether the stage is one of the lab's that multiplies the light by ρ (equations 28 and
    /// 30): not the flat colour, the incoming light, or the path tracer.
    pub fn reflects_light(self) -> bool {
        match self {
            Stage::Direct | Stage::Shadows | Stage::Lab => true,
            Stage::Flat | Stage::Incoming | Stage::Path => false,
        }
    }
}

/// The two integrators (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Integrator {
    /// The lab's stages, mirror and glass traced Whitted-style.
    Lab,
    /// Monte Carlo path tracing.
    Path,
}

/// How deep the lab stages follow mirror and glass by default: enough to see through the glass
/// block (in, out, and a few internal reflections).
pub const DEFAULT_SPECULAR_DEPTH: u32 = 6;

/// The deepest [`Shading::specular_depth`] allowed: a glass branch doubles the rays at every
/// level, so 2¹² rays per pixel at the very most.
pub const MAX_SPECULAR_DEPTH: u32 = 12;

/// How the path stage finds caustics: light that reached a diffuse surface through mirrors
/// or glass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Caustics {
    /// The path tracer alone: it finds an area light through mirror and glass, never the
    /// lab's point light. The default.
    #[default]
    Off,
    /// A caustic photon map each pass ([`crate::transport::integrator::photons`]), gathered at the first
    /// diffuse hit of every camera path.
    Photons,
}

named_enum!(Caustics as "caustics" {
    Off => "off", "Off (path tracer alone)";
    Photons => "photons", "Photons (photon map)";
});

/// Photons shot from the light each pass, by default.
pub const DEFAULT_PHOTONS: u32 = 100_000;

/// The most photons a pass may shoot: a bound on a pass's time and its photon map's memory.
pub const MAX_PHOTONS: u32 = 10_000_000;

/// What to compute at a hit: the stage and its switches.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Shading {
    pub stage: Stage,
    /// Cast shadow rays (section 5.1).
    pub shadows: bool,
    /// Lab stages: add the constant indirect term N (section 5.2). `path`: follow bounces of
    /// real indirect light (off: direct light only).
    pub indirect: bool,
    /// N, the constant indirect illumination, per colour channel (the lab's `indirectLight`).
    pub indirect_light: Vec3,
    /// `path`: the most diffuse bounces a path makes; `None` is unlimited, paths ending by
    /// Russian roulette. 0 is direct light only.
    pub bounces: Option<u32>,
    /// Lab stages: how many mirror and glass hits in a row are followed before a branch is
    /// given up (black).
    pub specular_depth: u32,
    /// Smooth shading: light models with their vertex normals interpolated across each
    /// triangle (the box has none and stays flat, the lab's look). Off: every triangle flat.
    pub smooth: bool,
    /// Parallax self-shadowing: where a height map carves a surface, its own relief hides
    /// the light from the points behind it (a groove's wall shadows its floor). Off: the carved
    /// surface is lit as if nothing stood in the way.
    pub parallax_shadows: bool,
    /// `path`: caustics by a photon map, or the path tracer alone.
    pub caustics: Caustics,
    /// `path` with caustics by photons: photons shot from the light each pass.
    pub photons: u32,
}

impl Default for Shading {
    fn default() -> Self {
        Self::for_stage(Stage::Lab)
    }
}

impl Shading {
    /// The lab's constant indirect light, N = 0.5·(1, 1, 1).
    pub const LAB_INDIRECT_LIGHT: Vec3 = Vec3::splat(0.5);

    /// The stage with the switches its figure uses.
    pub fn for_stage(stage: Stage) -> Self {
        let (shadows, indirect) = stage.preset_switches();
        Self {
            stage,
            shadows,
            indirect,
            indirect_light: Self::LAB_INDIRECT_LIGHT,
            bounces: None,
            specular_depth: DEFAULT_SPECULAR_DEPTH,
            smooth: true,
            parallax_shadows: true,
            caustics: Caustics::Off,
            photons: DEFAULT_PHOTONS,
        }
    }

    /// Whether a caustic photon map is shot and gathered: caustics by photons, in the path
    /// stage (the lab's stages follow mirror and glass Whitted-style and gather nothing).
    pub fn photon_caustics(&self) -> bool {
        self.stage == Stage::Path && self.caustics == Caustics::Photons
    }

    /// The switches set otherwise than the lab figure of the stage has them, each named as the
    /// lab does ("shadows", then "N") with its setting: what makes a lit stage's image another
    /// than its figure. None for the flat stage, whose figure (ρ alone) no switch changes. The
    /// window's heading ("not figure 7: shadows off") and the check's names ("figure 7 without
    /// shadows") both say these.
    pub fn switches_unlike_figure(&self) -> Vec<(&'static str, bool)> {
        let lit = match self.stage {
            Stage::Flat => false,
            Stage::Incoming | Stage::Direct | Stage::Shadows | Stage::Lab | Stage::Path => true,
        };
        let (shadows, indirect) = self.stage.preset_switches();
        [
            ("shadows", self.shadows, shadows),
            ("N", self.indirect, indirect),
        ]
        .into_iter()
        .filter(|&(_, on, figure)| lit && on != figure)
        .map(|(what, on, _)| (what, on))
        .collect()
    }

    /// N if the indirect switch is on (and the stage is one of the lab's), else 0.
    pub fn indirect_term(&self) -> Vec3 {
        if self.indirect && self.stage != Stage::Path {
            self.indirect_light
        } else {
            Vec3::ZERO
        }
    }

    /// The most diffuse bounces a path makes (`path` stage): 0 with indirect off.
    pub fn max_bounces(&self) -> u32 {
        if self.indirect {
            self.bounces.unwrap_or(u32::MAX)
        } else {
            0
        }
    }

    /// What is computed with the switches as they are, in the lab's terms (`·` is its `∗`).
    pub fn description(&self, materials: MaterialPreset) -> String {
        let shadows = if self.shadows {
            " with shadows (§5.1)"
        } else {
            ""
        };
        let mut text = match self.stage {
            Stage::Flat => "ρ, the reflectance".to_owned(),
            Stage::Incoming if self.indirect => format!("D + N (eq. 29){shadows}"),
            Stage::Incoming => format!("D, the incoming light (eq. 27){shadows}"),
            Stage::Direct | Stage::Shadows | Stage::Lab if self.indirect => {
                format!("ρ·(D + N) (eq. 30){shadows}")
            }
            Stage::Direct | Stage::Shadows | Stage::Lab => format!("ρ·D (eq. 28){shadows}"),
            Stage::Path => {
                let bounces = match self.max_bounces() {
                    0 => "no bounces: direct light only".to_owned(),
                    u32::MAX => "real indirect light, bounces until Russian roulette ends the \
                                 path"
                        .to_owned(),
                    1 => "real indirect light, 1 bounce".to_owned(),
                    n => format!("real indirect light, up to {n} bounces"),
                };
                format!("π × radiance: ρ·D{shadows} at every diffuse hit; {bounces}")
            }
        };
        // The preset named as the selector names it ("mirror tall block", …).
        let named = || {
            let label = materials.label();
            let mut chars = label.chars();
            chars.next().map_or_else(String::new, |first| {
                first.to_lowercase().chain(chars).collect::<String>()
            })
        };
        match (materials, self.stage.integrator()) {
            (MaterialPreset::None, Integrator::Lab | Integrator::Path) => {}
            (MaterialPreset::Rough, Integrator::Path) => {
                text.push_str("; rough metal tall block sampled (GGX)");
            }
            // The lab stages shade the rough metal as a surface whose ρ is its GGX reflection
            // toward the light's centre: a highlight, no reflected ray.
            (MaterialPreset::Rough, Integrator::Lab) => {
                text.push_str("; rough metal tall block: its GGX highlight from the light");
            }
            (MaterialPreset::Plastic, Integrator::Path) => {
                text.push_str("; glossy plastic tall block sampled (coating and base)");
            }
            // The plastic likewise: π·f toward the light's centre, its coating's highlight
            // over its base's diffuse colour.
            (MaterialPreset::Plastic, Integrator::Lab) => {
                text.push_str(
                    "; glossy plastic tall block: its coating's highlight from the light",
                );
            }
            (_, Integrator::Path) => text.push_str(&format!("; {} sampled", named())),
            (_, Integrator::Lab) => text.push_str(&format!(
                "; {} followed up to {} deep (Whitted)",
                named(),
                self.specular_depth
            )),
        }
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each switch set otherwise than its stage's figure, shadows before N, with its setting;
    /// none in the flat stage, whose figure no switch changes.
    #[test]
    fn the_switches_unlike_the_figure_are_named_in_order() {
        let mut lab = Shading::for_stage(Stage::Lab);
        assert!(lab.switches_unlike_figure().is_empty());
        lab.shadows = false;
        assert_eq!(lab.switches_unlike_figure(), [("shadows", false)]);
        lab.indirect = false;
        assert_eq!(
            lab.switches_unlike_figure(),
            [("shadows", false), ("N", false)]
        );
        let mut incoming = Shading::for_stage(Stage::Incoming);
        incoming.indirect = true;
        assert_eq!(incoming.switches_unlike_figure(), [("N", true)]);
        let mut flat = Shading::for_stage(Stage::Flat);
        flat.shadows = true;
        flat.indirect = true;
        assert!(flat.switches_unlike_figure().is_empty());
    }
}

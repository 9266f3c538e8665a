//! A guided walk through the lab: its figures in order, then the extensions raylab adds.
//!
//! Each [`Step`] says in raylab's own words what is computed and which equation does it, and
//! sets the settings that show it: the stage, its switches, the materials and the samples. The
//! user's camera and light (position, power, colour) are left as they are, so a student can
//! walk the steps from any view; only the light's radius is set, by the soft-shadows step (and
//! back to the lab's point by the others). The workbench shows the steps with Previous / Next.

use crate::shading::light::LightKind;
use crate::shading::material::{MaterialPreset, TexturePreset};
use crate::transport::integrator::{Shading, Stage};
use crate::transport::settings::Caustics;
use crate::transport::settings::RenderSettings;

/// One step of the walk.
#[derive(Clone, Copy, Debug)]
pub struct Step {
    /// A short title, with the lab's figure where there is one.
    pub title: &'static str,
    /// The equation the step computes, in the lab's numbering (`·` stands for its `∗`).
    pub equation: &'static str,
    /// What to look at, in a few sentences.
    pub text: &'static str,
    /// The settings the step shows.
    settings: StepSettings,
}

#[derive(Clone, Copy, Debug)]
struct StepSettings {
    stage: Stage,
    samples: u32,
    materials: MaterialPreset,
    light_radius: f32,
    caustics: Caustics,
}

impl Step {
    /// The step's settings applied to `settings`: the stage with its figure's switches, the
    /// materials, the sample target and the light's radius; the camera, the light's position,
    /// power and colour, the scene, N and everything else stay as the user set them.
    pub fn apply(&self, settings: &mut RenderSettings) {
        let s = &self.settings;
        let old = settings.shading;
        settings.shading = Shading {
            indirect_light: old.indirect_light,
            bounces: old.bounces,
            specular_depth: old.specular_depth,
            smooth: old.smooth,
            parallax_shadows: old.parallax_shadows,
            caustics: s.caustics,
            ..Shading::for_stage(s.stage)
        };
        settings.material_preset = s.materials;
        settings.texture_preset = TexturePreset::None;
        settings.samples_per_pixel = s.samples;
        settings.light.kind = if s.light_radius > 0.0 {
            LightKind::Sphere {
                radius: s.light_radius,
            }
        } else {
            LightKind::Point
        };
    }
}

/// Leaving the walk: puts back in `settings` what the steps set ([`Step::apply`]: the shading,
/// the materials and textures, the sample target, the light's size and shape) as `before`, the
/// settings when the walk started, had them. What the user changed meanwhile that the steps
/// never set (the camera, the light's position, power and colour, the scene) stays as it is now.
pub fn restore(before: &RenderSettings, settings: &mut RenderSettings) {
    settings.shading = before.shading;
    settings.material_preset = before.material_preset;
    settings.texture_preset = before.texture_preset;
    settings.samples_per_pixel = before.samples_per_pixel;
    settings.light.kind = before.light.kind;
}

/// The walk: the lab's figures 2, 3, 5, 6 and 7, then anti-aliasing, path tracing, soft shadows,
/// and mirror and glass.
pub const STEPS: [Step; 10] = [
    Step {
        title: "Flat colour (figure 2)",
        equation: "ρ, the reflectance of the first surface hit",
        text: "Each pixel's ray (eq. 24) finds the closest triangle it crosses (eqs. 7–12, \
               closest_intersection) and shows that surface's colour ρ. No light yet: this is \
               what the camera sees, and the check that the box and the camera are right.",
        settings: StepSettings {
            stage: Stage::Flat,
            samples: 1,
            materials: MaterialPreset::None,
            light_radius: 0.0,
            caustics: Caustics::Off,
        },
    },
    Step {
        title: "Incoming light (figure 3)",
        equation: "D = P·max(r̂·n̂, 0) / (4πr²) (eq. 27)",
        text: "The power per area arriving from the point light: P spread over a sphere of \
               radius r (4πr²), times the cosine between the surface normal and the direction \
               to the light. Surfaces near the light and facing it are bright; nothing blocks \
               the light yet.",
        settings: StepSettings {
            stage: Stage::Incoming,
            samples: 1,
            materials: MaterialPreset::None,
            light_radius: 0.0,
            caustics: Caustics::Off,
        },
    },
    Step {
        title: "Direct light (figure 5)",
        equation: "R = ρ·D (eq. 28)",
        text: "A diffuse surface reflects the fraction ρ of the light it receives, per colour \
               channel. The colours come back, lit by the light, but light still passes \
               through the blocks: the floor behind them is lit.",
        settings: StepSettings {
            stage: Stage::Direct,
            samples: 1,
            materials: MaterialPreset::None,
            light_radius: 0.0,
            caustics: Caustics::Off,
        },
    },
    Step {
        title: "Shadows (figure 6)",
        equation: "R = ρ·D, D = 0 where the shadow ray is blocked (§5.1)",
        text: "From each hit a shadow ray goes toward the light; if anything lies in between, \
               the point is in shadow and gets no direct light. Shadows are pitch black: \
               nothing else lights them.",
        settings: StepSettings {
            stage: Stage::Shadows,
            samples: 1,
            materials: MaterialPreset::None,
            light_radius: 0.0,
            caustics: Caustics::Off,
        },
    },
    Step {
        title: "Indirect light (figure 7)",
        equation: "R = ρ·(D + N) (eq. 30)",
        text: "Light also arrives after bouncing off other surfaces. The lab approximates all \
               of it by one constant N added everywhere: shadows are no longer black. This is \
               the lab's final image.",
        settings: StepSettings {
            stage: Stage::Lab,
            samples: 1,
            materials: MaterialPreset::None,
            light_radius: 0.0,
            caustics: Caustics::Off,
        },
    },
    Step {
        title: "Anti-aliasing",
        equation: "the mean of ρ·(D + N) over 16 points in each pixel",
        text: "One ray through each pixel's centre gives jagged edges. Averaging rays through \
               random points inside the pixel smooths them: the samples accumulate as you \
               watch.",
        settings: StepSettings {
            stage: Stage::Lab,
            samples: 16,
            materials: MaterialPreset::None,
            light_radius: 0.0,
            caustics: Caustics::Off,
        },
    },
    Step {
        title: "Path tracing: real indirect light",
        equation: "ρ·D at every bounce, Σ over paths, in place of N",
        text: "Instead of the constant N, each path bounces on in a random direction and adds \
               the direct light it finds at every surface. Colour bleeds from wall to wall and \
               corners darken, which N cannot show. The image starts noisy and converges.",
        settings: StepSettings {
            stage: Stage::Path,
            samples: 1024,
            materials: MaterialPreset::None,
            light_radius: 0.0,
            caustics: Caustics::Off,
        },
    },
    Step {
        title: "Soft shadows",
        equation: "D times the fraction of the light seen (eq. 27, §5.1)",
        text: "A real light has a size. Here it is a sphere of radius 0.1: each sample's shadow \
               ray goes to a random point of it, so points that see part of the light are \
               partly lit: the shadows' edges soften into penumbrae.",
        settings: StepSettings {
            stage: Stage::Lab,
            samples: 256,
            materials: MaterialPreset::None,
            light_radius: 0.1,
            caustics: Caustics::Off,
        },
    },
    Step {
        title: "Mirror and glass",
        equation: "mirror: the tint times what the reflected ray sees; glass: F and 1 − F (Fresnel)",
        text: "The tall block becomes a mirror and the short one glass. A ray that hits them \
               continues, reflected or refracted (Snell's law), and the pixel shows what it \
               finds, weighted by the Fresnel equations. Path traced, with real light.",
        settings: StepSettings {
            stage: Stage::Path,
            samples: 1024,
            materials: MaterialPreset::Both,
            light_radius: 0.0,
            caustics: Caustics::Off,
        },
    },
    Step {
        title: "Caustics (photon mapping)",
        equation: "L ≈ Σ f·Φ / (π r²): photons' power per area around the point, r shrinking",
        text: "Under the lab's point light the glass block throws a solid shadow in the path \
               stage: a path tracer never finds a point light through glass. Photon mapping \
               shoots photons from the light, keeps those that passed through mirror or glass \
               where they land on the diffuse floor and walls, and estimates the light there \
               from their density: the caustic appears, focused light in the glass's shadow. \
               Each pass shoots new photons and shrinks the gathering radius, so the image \
               converges. A global illumination technique (Jensen 1996).",
        settings: StepSettings {
            stage: Stage::Path,
            samples: 1024,
            materials: MaterialPreset::Glass,
            light_radius: 0.0,
            caustics: Caustics::Photons,
        },
    },
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::scene::cornell_box;
    use crate::transport::render::render;

    /// Each of the lab's steps renders exactly the stage it names, with its figure's switches,
    /// from the user's own camera and light, which the walk leaves alone.
    #[test]
    fn each_step_reproduces_its_stage_exactly() {
        let scene = cornell_box();
        let mut user = RenderSettings::default();
        user.camera = user.camera.with_resolution(48, 40);
        user.camera.position.x = 0.2;
        user.light.position.x = -0.3;
        user.light.power = 20.0;
        for (step, stage) in STEPS[..5].iter().zip(Stage::LAB) {
            let mut walked = user.clone();
            step.apply(&mut walked);
            let mut by_hand = user.clone();
            by_hand.shading = Shading::for_stage(stage);
            assert_eq!(walked, by_hand, "{}", step.title);
            assert_eq!(render(&scene, &walked), render(&scene, &by_hand));
            assert!(step.title.contains(&stage.figure().unwrap().to_string()));
        }
        for step in STEPS {
            let mut walked = user.clone();
            step.apply(&mut walked);
            assert_eq!(walked.camera, user.camera, "{}", step.title);
            assert_eq!(walked.light.position, user.light.position);
            assert_eq!(walked.light.power, user.light.power);
            walked.validate().unwrap();
        }
    }

    /// Leaving after any step gives back the settings the walk started from, with the camera
    /// and light position the user moved meanwhile.
    #[test]
    fn leaving_restores_what_the_steps_set() {
        let mut user = RenderSettings::default();
        user.shading = Shading::for_stage(Stage::Shadows);
        user.shading.specular_depth = 3;
        user.material_preset = MaterialPreset::Glass;
        user.texture_preset = TexturePreset::GridWalls;
        user.samples_per_pixel = 5;
        user.light.kind = LightKind::Quad { side: 0.2 };
        for step in STEPS {
            let mut walked = user.clone();
            step.apply(&mut walked);
            walked.camera.position.x = 0.4;
            walked.light.position.y = -0.2;
            restore(&user, &mut walked);
            let mut expected = user.clone();
            expected.camera.position.x = 0.4;
            expected.light.position.y = -0.2;
            assert_eq!(walked, expected, "{}", step.title);
        }
    }
}

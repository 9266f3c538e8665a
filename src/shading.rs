//! The lab's shading stages (figures 2, 3, 5, 6 and 7) as one function of a few switches.
//!
//! Every stage traces the same primary ray to its closest intersection; they differ only in
//! what they compute there. A [`Stage`] picks the quantity and presets the two switches, shadows
//! and the constant indirect term, which can then be flipped on their own, so any combination
//! renders (for instance figure 7 without shadows).

use std::fmt;
use std::str::FromStr;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::geometry::Ray;
use crate::light::{PointLight, direct_light, in_shadow, shadow_ray};
use crate::scene::Scene;

/// A step of the lab, named after what it shows.
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
}

impl Stage {
    pub const ALL: [Stage; 5] = [
        Stage::Flat,
        Stage::Incoming,
        Stage::Direct,
        Stage::Shadows,
        Stage::Lab,
    ];

    /// The name used on the command line and in settings files.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Flat => "flat",
            Stage::Incoming => "incoming",
            Stage::Direct => "direct",
            Stage::Shadows => "shadows",
            Stage::Lab => "lab",
        }
    }

    /// The lab figure this stage reproduces with its preset switches.
    pub fn figure(self) -> u32 {
        match self {
            Stage::Flat => 2,
            Stage::Incoming => 3,
            Stage::Direct => 5,
            Stage::Shadows => 6,
            Stage::Lab => 7,
        }
    }

    /// What this stage computes, in the lab's terms and equation numbers. `·` stands for the
    /// lab's element-wise product `∗` (a glyph the workbench's font lacks).
    pub fn equation(self) -> &'static str {
        match self {
            Stage::Flat => "ρ, the reflectance",
            Stage::Incoming => "D, the incoming light (eq. 27)",
            Stage::Direct => "ρ·D (eq. 28)",
            Stage::Shadows => "ρ·D with shadows (eq. 28, §5.1)",
            Stage::Lab => "ρ·(D + N) with shadows (eq. 30)",
        }
    }

    /// The shadows and indirect switches as the lab's figure has them.
    pub fn preset_switches(self) -> (bool, bool) {
        match self {
            Stage::Flat | Stage::Incoming | Stage::Direct => (false, false),
            Stage::Shadows => (true, false),
            Stage::Lab => (true, true),
        }
    }
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Stage {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Stage::ALL
            .into_iter()
            .find(|stage| stage.name() == s)
            .ok_or_else(|| {
                format!("unknown stage '{s}' (expected flat, incoming, direct, shadows or lab)")
            })
    }
}

/// What to compute at a hit: the stage and its switches.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Shading {
    pub stage: Stage,
    /// Cast shadow rays (section 5.1).
    pub shadows: bool,
    /// Add the constant indirect term N (section 5.2).
    pub indirect: bool,
    /// N, the constant indirect illumination, per colour channel (the lab's `indirectLight`).
    pub indirect_light: Vec3,
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
        }
    }

    /// N if the indirect switch is on, else 0.
    pub fn indirect_term(&self) -> Vec3 {
        if self.indirect {
            self.indirect_light
        } else {
            Vec3::ZERO
        }
    }
}

/// The value of a primary ray: black for a miss, else the stage's quantity at the closest hit.
///
/// * flat: `ρ`
/// * incoming: `D` (equation 27), plus `N` with indirect on (`T`, equation 29)
/// * direct, shadows, lab: `ρ ∗ (D + N)` (equation 30), with `N = 0` when indirect is off
///   (equation 28)
///
/// `D` is 0 at points the shadow ray finds blocked when shadows are on.
pub fn shade(scene: &Scene, light: &PointLight, shading: &Shading, ray: &Ray) -> Vec3 {
    let Some(hit) = scene.closest_intersection(ray, f32::INFINITY) else {
        return Vec3::ZERO;
    };
    let rho = scene.material_of(hit.triangle_index).reflectance;
    if shading.stage == Stage::Flat {
        return rho;
    }
    let normal = scene.triangles[hit.triangle_index].normal;
    let mut d = direct_light(light, hit.position, normal);
    // A shadow ray only matters where there is light to block.
    if shading.shadows && d != Vec3::ZERO && in_shadow(scene, light, hit.position, normal) {
        d = Vec3::ZERO;
    }
    let total = d + shading.indirect_term();
    match shading.stage {
        Stage::Incoming => total,
        _ => rho * total,
    }
}

/// How many rays [`shade_batch`] takes through each phase together.
pub const SHADE_BATCH: usize = 64;

/// [`shade`] for many rays at once, bit for bit the same values.
///
/// The work is done in phases over up to [`SHADE_BATCH`] rays — all closest hits, then the
/// light at every hit, then all shadow rays, then the sums — instead of ray by ray. Each phase is
/// a loop of independent queries, which the CPU overlaps; ray by ray, every pixel's long chain
/// of dependent divisions and square roots runs alone. On the Cornell box this halves the time
/// of a lab pass (see PERFORMANCE.md).
pub fn shade_batch(
    scene: &Scene,
    light: &PointLight,
    shading: &Shading,
    rays: &[Ray],
    out: &mut [Vec3],
) {
    debug_assert_eq!(rays.len(), out.len());
    for (rays, out) in rays.chunks(SHADE_BATCH).zip(out.chunks_mut(SHADE_BATCH)) {
        let mut hits = [None; SHADE_BATCH];
        for (hit, ray) in hits.iter_mut().zip(rays) {
            *hit = scene.closest_intersection(ray, f32::INFINITY);
        }
        // ρ and D (before shadows) per hit, and the shadow rays to cast.
        let mut rho_d = [(Vec3::ZERO, Vec3::ZERO); SHADE_BATCH];
        let mut shadows = [None; SHADE_BATCH];
        for i in 0..rays.len() {
            let Some(hit) = hits[i] else { continue };
            let rho = scene.material_of(hit.triangle_index).reflectance;
            if shading.stage == Stage::Flat {
                rho_d[i] = (rho, Vec3::ZERO);
                continue;
            }
            let normal = scene.triangles[hit.triangle_index].normal;
            let d = direct_light(light, hit.position, normal);
            if shading.shadows && d != Vec3::ZERO {
                shadows[i] = shadow_ray(light, hit.position, normal);
            }
            rho_d[i] = (rho, d);
        }
        for (shadow, (_, d)) in shadows.iter().zip(rho_d.iter_mut()) {
            if let Some((ray, t_max)) = shadow
                && scene.occluded(ray, *t_max)
            {
                *d = Vec3::ZERO;
            }
        }
        for (i, value) in out.iter_mut().enumerate() {
            let (rho, d) = rho_d[i];
            *value = match (hits[i], shading.stage) {
                (None, _) => Vec3::ZERO,
                (Some(_), Stage::Flat) => rho,
                (Some(_), Stage::Incoming) => d + shading.indirect_term(),
                (Some(_), _) => rho * (d + shading.indirect_term()),
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stages_parse_and_name_their_figures() {
        for stage in Stage::ALL {
            assert_eq!(stage.name().parse::<Stage>(), Ok(stage));
        }
        assert_eq!(
            Stage::ALL.map(Stage::figure),
            [2, 3, 5, 6, 7],
            "the lab's figures"
        );
        assert!("phong".parse::<Stage>().unwrap_err().contains("phong"));
        assert_eq!(Shading::default().stage, Stage::Lab);
        assert!(Shading::default().shadows && Shading::default().indirect);
        assert_eq!(Shading::default().indirect_term(), Vec3::splat(0.5));
    }

    #[test]
    fn the_batch_shades_exactly_like_shade() {
        let scene = crate::scene::cornell_box();
        let cam = crate::Camera::default_for(61, 47);
        let rays: Vec<Ray> = (0..47)
            .flat_map(|y| (0..61).map(move |x| (x, y)))
            .map(|(x, y)| cam.pixel_ray(x, y))
            .collect();
        let light = PointLight::default();
        for stage in Stage::ALL {
            for shadows in [false, true] {
                let mut shading = Shading::for_stage(stage);
                shading.shadows = shadows;
                let mut out = vec![Vec3::NAN; rays.len()];
                shade_batch(&scene, &light, &shading, &rays, &mut out);
                for (ray, got) in rays.iter().zip(&out) {
                    let want = shade(&scene, &light, &shading, ray);
                    assert_eq!(
                        got.to_array().map(f32::to_bits),
                        want.to_array().map(f32::to_bits)
                    );
                }
            }
        }
    }
}

//! The lab's stages and switches as what an image may be instead of the figure checked
//! against: a student's lab is most often at another figure (2, 3, 5, 6 or 7) or has a switch
//! the other way (no shadows yet, N not added), and checked with the defaults.
//!
//! A stage and its two switches ([`StageSwitches`]) compute a set of the lab's terms
//! ([`Terms`]: ρ, D, N, shadows); two that compute the same terms render the same figure, so
//! each set is rendered once ([`others`]), and what an image's set lacks or adds against the
//! one checked is said in the lab's words ([`StageSwitches::differences`]).

use serde::Serialize;

use crate::shading::material::MaterialPreset;
use crate::transport::integrator::Stage;
use crate::transport::settings::{RenderSettings, Shading};

/// A lab stage with its shadows and indirect switches: what a pass of the lab computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct StageSwitches {
    pub stage: Stage,
    pub shadows: bool,
    pub indirect: bool,
}

/// The lab's terms a stage and its switches put in a pixel: ρ (equation 28), D (equation 27),
/// N (section 5.2) and shadows (section 5.1). The flat stage shows ρ alone, whatever the
/// switches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Terms {
    pub rho: bool,
    pub d: bool,
    pub n: bool,
    pub shadows: bool,
}

impl StageSwitches {
    /// The stage and switches of `shading`.
    pub fn of(shading: &Shading) -> Self {
        Self {
            stage: shading.stage,
            shadows: shading.shadows,
            indirect: shading.indirect,
        }
    }

    /// The stage with the switches its figure uses.
    pub fn preset(stage: Stage) -> Self {
        let (shadows, indirect) = stage.preset_switches();
        Self {
            stage,
            shadows,
            indirect,
        }
    }

    pub fn terms(self) -> Terms {
        let lit = self.stage != Stage::Flat;
        let rho = match self.stage {
            Stage::Flat | Stage::Direct | Stage::Shadows | Stage::Lab => true,
            Stage::Incoming | Stage::Path => false,
        };
        Terms {
            rho,
            d: lit,
            n: lit && self.indirect,
            shadows: lit && self.shadows,
        }
    }

    /// The lab figure these compute exactly, with its own switches, if any.
    pub fn figure(self) -> Option<u32> {
        Stage::LAB
            .into_iter()
            .find(|s| Self::preset(*s).terms() == self.terms())
            .and_then(Stage::figure)
    }

    /// How a person names it: "figure 6", or the stage's figure with the switch that differs
    /// from it ("figure 7 without shadows", "figure 5 with N").
    pub fn name(self) -> String {
        if let Some(f) = self.figure() {
            return format!("figure {f}");
        }
        let mut with = Vec::new();
        let mut without = Vec::new();
        for (what, on) in self.shading(&Shading::default()).switches_unlike_figure() {
            if on {
                with.push(what);
            } else {
                without.push(what);
            }
        }
        let mut name = format!("figure {}", self.stage.figure().unwrap_or(0));
        if !with.is_empty() {
            name += &format!(" with {}", with.join(" and "));
        }
        if !without.is_empty() {
            name += &format!(" without {}", without.join(" or "));
        }
        name
    }

    /// What a pass computes with these, in the lab's terms ([`Shading::description`]).
    pub fn computes(self, materials: MaterialPreset) -> String {
        self.shading(&Shading::default()).description(materials)
    }

    /// `shading` with this stage and these switches.
    pub fn shading(self, shading: &Shading) -> Shading {
        Shading {
            stage: self.stage,
            shadows: self.shadows,
            indirect: self.indirect,
            ..*shading
        }
    }

    /// The command line's options that select them: `--stage shadows`, with a switch only
    /// where it differs from the stage's figure (`--stage lab --shadows off`; N on is the
    /// lab's N, 0.5).
    pub fn options(self) -> String {
        let preset = Self::preset(self.stage);
        let mut options = format!("--stage {}", self.stage);
        if self.shadows != preset.shadows {
            options += if self.shadows {
                " --shadows on"
            } else {
                " --shadows off"
            };
        }
        if self.indirect != preset.indirect {
            options += &if self.indirect {
                format!(" --indirect {}", Shading::LAB_INDIRECT_LIGHT.x)
            } else {
                " --indirect off".to_owned()
            };
        }
        options
    }

    /// What an image computed with `self` lacks or adds against `against`, as clauses
    /// ("the constant indirect term N is missing"), and for each what to do to get from
    /// `self` to `against`.
    pub fn differences(self, against: StageSwitches) -> (Vec<&'static str>, Vec<&'static str>) {
        let (mine, theirs) = (self.terms(), against.terms());
        let mut clauses = Vec::new();
        let mut fixes = Vec::new();
        let parts: [(bool, bool, [&str; 4]); 4] = [
            (
                mine.d,
                theirs.d,
                [
                    "the light D is missing: only the surfaces' colour ρ is drawn",
                    "compute the light D that reaches each point (equation 27)",
                    "the light D is added",
                    "draw the surfaces' colour ρ alone, with no light (figure 2)",
                ],
            ),
            (
                mine.rho,
                theirs.rho,
                [
                    "the surfaces' colour ρ is missing",
                    "multiply the light by the surface's colour ρ (equation 28)",
                    "the light is multiplied by the surfaces' colour ρ",
                    "draw the light alone, not multiplied by ρ (figure 3)",
                ],
            ),
            (
                mine.n,
                theirs.n,
                [
                    "the constant indirect term N is missing",
                    "add the constant indirect term N to D before multiplying by ρ: \
                     R = ρ·(D + N) (section 5.2, equation 30)",
                    "the constant indirect term N is added",
                    "leave the indirect term N out",
                ],
            ),
            (
                mine.shadows,
                theirs.shadows,
                [
                    "shadows are missing",
                    "cast a shadow ray from each point toward the light and set D = 0 where \
                     a surface closer than the light blocks it (section 5.1)",
                    "it has shadows",
                    "cast no shadow rays",
                ],
            ),
        ];
        for (has, wanted, [missing, add, added, drop]) in parts {
            match (has, wanted) {
                (false, true) => {
                    clauses.push(missing);
                    fixes.push(add);
                }
                (true, false) => {
                    clauses.push(added);
                    fixes.push(drop);
                }
                _ => {}
            }
        }
        (clauses, fixes)
    }
}

/// The stages and switches an image checked against `settings` is offered as, each computing
/// other terms than `settings` and than each other: the lab's figures 2, 3, 5, 6 and 7 with
/// their own switches, then the settings' stage with its shadows switch turned, and with its
/// indirect switch turned.
pub fn others(settings: &RenderSettings) -> Vec<StageSwitches> {
    let own = StageSwitches::of(&settings.shading);
    let turned = [
        StageSwitches {
            shadows: !own.shadows,
            ..own
        },
        StageSwitches {
            indirect: !own.indirect,
            ..own
        },
    ];
    let mut found: Vec<StageSwitches> = Vec::new();
    for candidate in Stage::LAB
        .into_iter()
        .map(StageSwitches::preset)
        .chain(turned)
    {
        let terms = candidate.terms();
        if terms != own.terms() && found.iter().all(|f| f.terms() != terms) {
            found.push(candidate);
        }
    }
    found
}

/// `settings` with `stage`'s stage and switches.
pub fn with_stage(settings: &RenderSettings, stage: StageSwitches) -> RenderSettings {
    RenderSettings {
        shading: stage.shading(&settings.shading),
        ..settings.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(stage: Stage, shadows: bool, indirect: bool) -> StageSwitches {
        StageSwitches {
            stage,
            shadows,
            indirect,
        }
    }

    #[test]
    fn names_follow_the_figures_and_the_switches() {
        assert_eq!(s(Stage::Shadows, true, false).name(), "figure 6");
        // The direct stage with shadows on computes figure 6's terms.
        assert_eq!(s(Stage::Direct, true, false).name(), "figure 6");
        assert_eq!(
            s(Stage::Lab, false, true).name(),
            "figure 7 without shadows"
        );
        assert_eq!(s(Stage::Incoming, false, true).name(), "figure 3 with N");
        assert_eq!(s(Stage::Flat, true, true).name(), "figure 2");
        let (clauses, _) = s(Stage::Shadows, true, false).differences(s(Stage::Lab, true, true));
        assert_eq!(clauses, ["the constant indirect term N is missing"]);
        let (clauses, _) = s(Stage::Lab, false, true).differences(s(Stage::Lab, true, true));
        assert_eq!(clauses, ["shadows are missing"]);
        assert_eq!(s(Stage::Shadows, true, false).options(), "--stage shadows");
        assert_eq!(
            s(Stage::Lab, false, true).options(),
            "--stage lab --shadows off"
        );
        assert_eq!(
            s(Stage::Direct, false, true).options(),
            "--stage direct --indirect 0.5"
        );
    }

    /// Figure 7's settings are offered figures 2, 3, 5 and 6, and figure 7 without shadows
    /// (without N it is figure 6, offered already).
    #[test]
    fn the_others_compute_other_terms_each() {
        let settings = RenderSettings::default();
        let names: Vec<String> = others(&settings).iter().map(|o| o.name()).collect();
        assert_eq!(
            names,
            [
                "figure 2",
                "figure 3",
                "figure 5",
                "figure 6",
                "figure 7 without shadows"
            ]
        );
    }
}

//! Display transforms: how linear image values become the 8-bit pixels on screen and in PNGs.
//!
//! Applied for display only: the film keeps linear values, EXR files keep them too (before
//! exposure and curve), and changing the transform never re-traces.

use std::fmt;
use std::str::FromStr;

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// The curve that maps an exposed linear value to a display value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DisplayTransform {
    /// The lab's display: each channel clamped to [0, 1], no gamma. The default.
    #[default]
    Lab,
    /// The standard sRGB encoding of the value clamped to [0, 1].
    Srgb,
    /// A filmic curve (highlights roll off instead of clipping), then sRGB.
    Filmic,
}

impl DisplayTransform {
    pub const ALL: [DisplayTransform; 3] = [
        DisplayTransform::Lab,
        DisplayTransform::Srgb,
        DisplayTransform::Filmic,
    ];

    pub fn name(self) -> &'static str {
        match self {
            DisplayTransform::Lab => "lab",
            DisplayTransform::Srgb => "srgb",
            DisplayTransform::Filmic => "filmic",
        }
    }
}

impl fmt::Display for DisplayTransform {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for DisplayTransform {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        DisplayTransform::ALL
            .into_iter()
            .find(|t| t.name() == s)
            .ok_or_else(|| format!("unknown display '{s}' (expected lab, srgb or filmic)"))
    }
}

/// A display transform and the exposure before it.
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct Display {
    pub transform: DisplayTransform,
    /// Exposure in stops: linear values are multiplied by 2^exposure before the curve.
    pub exposure: f32,
}

impl Display {
    /// The linear value after exposure: `linear · 2^exposure`.
    pub fn exposed(&self, linear: Vec3) -> Vec3 {
        linear * self.exposure.exp2()
    }
}

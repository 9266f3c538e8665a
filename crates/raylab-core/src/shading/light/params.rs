//! A light's parameters as `light_kinds!` lists them: their types (a size, a point, an angle),
//! their values and their bounds; what the settings, scene files, the command line and the
//! workbench know of a light's fields.

use glam::Vec3;

use crate::base::camera::{degrees, radians};
use crate::base::invalid::SettingsError;

/// What a light parameter is, which decides how it is written, shown, checked and edited.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamType {
    /// A length in scene units, the kind's size (`--light-size`): 0 is the point light, any
    /// other from `MIN_LIGHT_SIZE` to `MAX_LIGHT_SIZE` (`transport::settings`).
    Size,
    /// A point of the scene (x, y, z), within the scene's coordinates.
    Point,
    /// An angle: radians in memory and in the settings JSON, degrees in scene files, on the
    /// command line and in the workbench.
    Angle,
}

/// One parameter of a light kind, as `light_kinds!` lists it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Param {
    /// Its name in files and in `--light KIND:FIELD=V` (`radius`, `aim`, `cutoff`).
    pub name: &'static str,
    /// Its label in the workbench (`Light radius`, `Aim`, `Spot cutoff`).
    pub label: &'static str,
    /// What errors and Compare A/B call it (`light size`, `light aim`, `spot cutoff`).
    pub noun: &'static str,
    /// What it is, for the workbench's hover text and `--help`.
    pub what: &'static str,
    pub ty: ParamType,
    /// The values it may take (an angle's in degrees), beyond what its type requires.
    pub bounds: Bounds,
}

/// A parameter's value: a size or an angle (radians) as one number, or a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamValue {
    Number(f32),
    Point(Vec3),
}

impl ParamValue {
    /// The number, or `None` for a point.
    pub fn number(self) -> Option<f32> {
        match self {
            ParamValue::Number(x) => Some(x),
            ParamValue::Point(_) => None,
        }
    }

    /// The point, or `None` for a number.
    pub fn point(self) -> Option<Vec3> {
        match self {
            ParamValue::Point(p) => Some(p),
            ParamValue::Number(_) => None,
        }
    }
}

impl Param {
    /// The value as files other than the settings JSON, the command line and the workbench
    /// show it: an angle in degrees (exactly, see [`degrees`]), anything else as it is.
    pub fn shown(&self, value: f32) -> f64 {
        match self.ty {
            ParamType::Angle => degrees(value),
            ParamType::Size | ParamType::Point => f64::from(value),
        }
    }

    /// The inverse of [`Param::shown`]: an angle in degrees to radians.
    pub fn stored(&self, shown: f64) -> f32 {
        match self.ty {
            ParamType::Angle => radians(shown),
            ParamType::Size | ParamType::Point => shown as f32,
        }
    }

    /// A value as errors show it: an angle with its degree sign.
    pub fn display(&self, value: ParamValue) -> String {
        match (value, self.ty) {
            (ParamValue::Number(x), ParamType::Angle) => format!("{}°", degrees(x)),
            (ParamValue::Number(x), ParamType::Size | ParamType::Point) => format!("{x}"),
            (ParamValue::Point(p), _) => format!("({}, {}, {})", p.x, p.y, p.z),
        }
    }

    /// Checks `value` against the parameter's [`Bounds`] (its type's own rules are
    /// `RenderSettings::validate`'s).
    pub fn check_bounds(&self, value: ParamValue) -> Result<(), SettingsError> {
        match value {
            ParamValue::Number(x) if !self.bounds.holds(self.shown(x)) => Err(SettingsError {
                name: self.noun.into(),
                value: self.display(value),
                reason: self.bounds.reason,
            }),
            ParamValue::Number(_) | ParamValue::Point(_) => Ok(()),
        }
    }
}

/// The values a number may take, in the units it is shown in (degrees for an angle): from
/// `lo` to `hi`, each end included or not; `reason` says so in an error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub lo: f64,
    pub hi: f64,
    pub lo_open: bool,
    pub hi_open: bool,
    pub reason: &'static str,
}

impl Bounds {
    /// No bounds beyond the type's.
    pub const ANY: Bounds = Bounds {
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
        lo_open: false,
        hi_open: false,
        reason: "",
    };

    /// Above `lo` and below `hi`.
    pub const fn open(lo: f64, hi: f64, reason: &'static str) -> Bounds {
        Bounds {
            lo,
            hi,
            lo_open: true,
            hi_open: true,
            reason,
        }
    }

    /// From `lo` to `hi`, both included.
    pub const fn closed(lo: f64, hi: f64, reason: &'static str) -> Bounds {
        Bounds {
            lo,
            hi,
            lo_open: false,
            hi_open: false,
            reason,
        }
    }

    /// Whether `x` lies within (NaN never does, unless there are no bounds).
    pub fn holds(&self, x: f64) -> bool {
        if *self == Bounds::ANY {
            return true;
        }
        let above = if self.lo_open {
            x > self.lo
        } else {
            x >= self.lo
        };
        let below = if self.hi_open {
            x < self.hi
        } else {
            x <= self.hi
        };
        above && below
    }
}

/// The Rust type of each [`ParamType`], for `light_kinds!`'s variants: `Size` and `Angle` are
/// `f32`, `Point` is `Vec3`.
pub trait LightParam {
    type Value: Copy;
    const TYPE: ParamType;
    fn value(v: Self::Value) -> ParamValue;
    fn of_value(value: ParamValue) -> Option<Self::Value>;
    /// What the parameter adds to a light's size: its value for a size, else 0.
    #[inline(always)]
    fn size_of(_: Self::Value) -> f32 {
        0.0
    }
}

/// Markers naming the parameter types in `light_kinds!`.
pub mod ty {
    use super::*;

    pub struct Size;
    pub struct Point;
    pub struct Angle;

    impl LightParam for Size {
        type Value = f32;
        const TYPE: ParamType = ParamType::Size;
        fn value(v: f32) -> ParamValue {
            ParamValue::Number(v)
        }
        fn of_value(value: ParamValue) -> Option<f32> {
            value.number()
        }
        #[inline(always)]
        fn size_of(v: f32) -> f32 {
            v
        }
    }

    impl LightParam for Angle {
        type Value = f32;
        const TYPE: ParamType = ParamType::Angle;
        fn value(v: f32) -> ParamValue {
            ParamValue::Number(v)
        }
        fn of_value(value: ParamValue) -> Option<f32> {
            value.number()
        }
    }

    impl LightParam for Point {
        type Value = Vec3;
        const TYPE: ParamType = ParamType::Point;
        fn value(v: Vec3) -> ParamValue {
            ParamValue::Point(v)
        }
        fn of_value(value: ParamValue) -> Option<Vec3> {
            value.point()
        }
    }
}

/// The rules between a kind's parameters, for a kind whose parameters are a struct of their
/// own (`Spot(SpotCone)` in `light_kinds!`): what no single parameter's bounds can say (the
/// spot's beam within its cutoff, its aim away from the light). Both default to nothing.
pub trait KindRules {
    /// Checks the parameters together, for a light at `position`.
    fn check(&self, _position: Vec3) -> Result<(), SettingsError> {
        Ok(())
    }

    /// Brings the parameters back within their rules after the workbench edited one.
    fn tidy(&mut self) {}
}

//! The light kinds as one table (`light_kinds!`): each kind's variant, name, label, emitter
//! and parameters (type, default, bounds, label, name in errors, what it is). [`LightShape`],
//! [`LightKind`] and [`AnyLight`] are declared from it, and the settings JSON, scene files,
//! `--light`, the workbench's light panel and Compare A/B read, write, check and edit every
//! kind through what it writes ([`LightKind::params`], [`LightKind::values`],
//! [`LightKind::set`], [`LightKind::read`]).

use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

use super::params::{Bounds, KindRules, LightParam, Param, ParamType, ParamValue, ty};
use super::{DEFAULT_QUAD_SIDE, DEFAULT_SPHERE_RADIUS, Light, LightSample};
use super::{PointLight, QuadLight, SphereLight, SpotCone, SpotLight};
use crate::base::camera::radians;
use crate::base::geometry::Ray;
use crate::base::invalid::SettingsError;
use crate::base::named::named_enum;

/// Declares [`LightKind`], [`LightShape`] and [`AnyLight`] from one table. A row is
/// `Variant => "name", "Label", Emitter { field: Type = default, bounds, "Label", "noun",
/// "what it is"; … }`, `Type` one of [`ty`]'s (`Size`, `Point`, `Angle`); a kind whose
/// parameters are a struct of their own is `Variant(Struct) => …`, the struct implementing
/// [`KindRules`] (its `Default` is written from the table).
macro_rules! light_kinds {
    ($(
        $(#[$meta:meta])*
        $variant:ident $(($inner:ident))? => $name:literal, $label:literal, $emitter:ident {
            $( $field:ident: $ty:ident = $default:expr, $bounds:expr,
               $flabel:literal, $noun:literal, $what:literal; )*
        }
    )+) => {
        light_kinds!(@enum [] $( $(#[$meta])* $variant $(($inner))? {
            $($field: $ty = $default, $what),*
        } )+);

        /// The kind of light, by name: what `--light-shape`, the workbench's selector and the
        /// files' `shape` choose ([`LightKind::of_shape`] makes the kind with its defaults).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
        pub enum LightShape {
            $( $(#[$meta])* #[serde(rename = $name)] $variant, )+
        }

        named_enum!(LightShape as "light shape" { $( $variant => $name, $label; )+ });

        /// One of the lights, whichever its kind: enum dispatch, so a light is a plain `Copy`
        /// value (no allocation, no virtual call, `Send + Sync` for the render threads) and
        /// each call is a `match` the compiler can inline.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum AnyLight {
            $( $variant($emitter), )+
        }

        $(
            impl From<$emitter> for AnyLight {
                fn from(light: $emitter) -> Self {
                    AnyLight::$variant(light)
                }
            }
        )+

        /// Each call goes to the light inside.
        impl Light for AnyLight {
            #[inline]
            fn sample_li(&self, p: Vec3, u: Vec2) -> Option<LightSample> {
                match self { $( AnyLight::$variant(l) => l.sample_li(p, u), )+ }
            }

            #[inline]
            fn pdf_li(&self, p: Vec3, wi: Vec3) -> f32 {
                match self { $( AnyLight::$variant(l) => l.pdf_li(p, wi), )+ }
            }

            #[inline]
            fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
                match self { $( AnyLight::$variant(l) => l.intersect(ray, t_max), )+ }
            }

            #[inline]
            fn le(&self, ray_direction: Vec3) -> Vec3 {
                match self { $( AnyLight::$variant(l) => l.le(ray_direction), )+ }
            }

            #[inline]
            fn is_delta(&self) -> bool {
                match self { $( AnyLight::$variant(l) => l.is_delta(), )+ }
            }

            #[inline]
            fn power(&self) -> Vec3 {
                match self { $( AnyLight::$variant(l) => l.power(), )+ }
            }

            #[inline]
            fn sample_le(&self, u_point: Vec2, u_direction: Vec2) -> Option<Ray> {
                match self { $( AnyLight::$variant(l) => l.sample_le(u_point, u_direction), )+ }
            }
        }

        impl LightKind {
            /// The kind's name ([`LightShape`]).
            pub fn shape(&self) -> LightShape {
                match self {
                    $( light_kinds!(@any $variant $(($inner))?) => LightShape::$variant, )+
                }
            }

            /// The kind of this `shape` with its default parameters.
            pub fn of_shape(shape: LightShape) -> Self {
                match shape {
                    $( LightShape::$variant => light_kinds!(@new $variant $(($inner))? {
                        $($field: $default),*
                    }), )+
                }
            }

            /// The kind's parameters, in the table's order.
            pub fn params(&self) -> &'static [Param] {
                match self {
                    $( light_kinds!(@any $variant $(($inner))?) => &[ $( Param {
                        name: stringify!($field),
                        label: $flabel,
                        noun: $noun,
                        what: $what,
                        ty: <ty::$ty as LightParam>::TYPE,
                        bounds: $bounds,
                    }, )* ], )+
                }
            }

            /// An area light's size (its size parameter), 0 for a kind with none: read from
            /// the fields with no list made, as the lab stages ask it for every batch.
            #[inline]
            pub fn size(&self) -> f32 {
                match *self {
                    $( light_kinds!(@pat $variant $(($inner))? { $($field),* }) => {
                        0.0 $( + <ty::$ty as LightParam>::size_of($field) )*
                    } )+
                }
            }

            /// The kind's parameters' values, in the order of [`LightKind::params`].
            pub fn values(&self) -> Vec<ParamValue> {
                match *self {
                    $( light_kinds!(@pat $variant $(($inner))? { $($field),* }) => vec![
                        $( <ty::$ty as LightParam>::value($field), )*
                    ], )+
                }
            }

            /// Sets the parameter `name` to `value` (an angle in radians): an error if the
            /// kind has no such parameter or `value` is not of its type.
            pub fn set(&mut self, name: &str, value: ParamValue) -> Result<(), String> {
                match self {
                    $( light_kinds!(@pat $variant $(($inner))? { $($field),* }) => {
                        $(
                            if name == stringify!($field) {
                                return match <ty::$ty as LightParam>::of_value(value) {
                                    Some(v) => { *$field = v; Ok(()) }
                                    None => Err(wrong_type(stringify!($field))),
                                };
                            }
                        )*
                    } )+
                }
                Err(self.unknown_field(name))
            }

            /// The rules between the kind's parameters ([`KindRules::check`]), for a light at
            /// `position`.
            pub fn check_rules(&self, position: Vec3) -> Result<(), SettingsError> {
                $( light_kinds!(@check self, position, $variant $(($inner))?); )+
                Ok(())
            }

            /// Brings the parameters back within their rules ([`KindRules::tidy`]).
            pub fn tidy(&mut self) {
                $( light_kinds!(@tidy self, $variant $(($inner))?); )+
            }
        }
    };

    (@enum [$($done:tt)*]) => {
        /// What the light is, with the parameters of its kind (`light_kinds!`). Every kind
        /// sits at the light's `position` and emits the total power of the lab's omni light,
        /// `power · colour`, or for the spot the omni light's intensity `power · colour / (4π)`
        /// inside its cone.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum LightKind { $($done)* }
    };
    (@enum [$($done:tt)*] $(#[$m:meta])* $v:ident ($inner:ident) {
        $($f:ident: $t:ident = $d:expr, $w:literal),*
    } $($rest:tt)*) => {
        /// The defaults `light_kinds!` gives.
        impl Default for $inner {
            fn default() -> Self {
                $inner { $($f: $d),* }
            }
        }
        light_kinds!(@enum [$($done)* $(#[$m])* $v($inner),] $($rest)*);
    };
    (@enum [$($done:tt)*] $(#[$m:meta])* $v:ident {} $($rest:tt)*) => {
        light_kinds!(@enum [$($done)* $(#[$m])* $v,] $($rest)*);
    };
    (@enum [$($done:tt)*] $(#[$m:meta])* $v:ident {
        $($f:ident: $t:ident = $d:expr, $w:literal),+
    } $($rest:tt)*) => {
        light_kinds!(@enum [$($done)* $(#[$m])* $v {
            $( #[doc = $w] $f: <ty::$t as LightParam>::Value ),+
        },] $($rest)*);
    };

    (@any $v:ident ($inner:ident)) => { LightKind::$v(_) };
    (@any $v:ident) => { LightKind::$v { .. } };
    (@pat $v:ident ($inner:ident) { $($f:ident),* }) => { LightKind::$v($inner { $($f),* }) };
    (@pat $v:ident { $($f:ident),* }) => { LightKind::$v { $($f),* } };
    (@new $v:ident ($inner:ident) { $($f:ident: $d:expr),* }) => {
        LightKind::$v($inner { $($f: $d),* })
    };
    (@new $v:ident { $($f:ident: $d:expr),* }) => { LightKind::$v { $($f: $d),* } };
    (@check $s:ident, $p:ident, $v:ident ($inner:ident)) => {
        if let LightKind::$v(rules) = $s {
            KindRules::check(rules, $p)?;
        }
    };
    (@check $s:ident, $p:ident, $v:ident) => {};
    (@tidy $s:ident, $v:ident ($inner:ident)) => {
        if let LightKind::$v(rules) = $s {
            KindRules::tidy(rules);
        }
    };
    (@tidy $s:ident, $v:ident) => {};
}

const SPOT_CUTOFF: Bounds =
    Bounds::open(0.0, 90.0, "must be above 0° and below 90° (--spot-cutoff)");
const SPOT_BEAM: Bounds = Bounds::closed(
    0.0,
    90.0,
    "must be from 0° to the cutoff (--spot-beam, --spot-cutoff)",
);

light_kinds! {
    /// The lab's point light (section 5): hard shadows. The default.
    Point => "point", "Point (the lab)", PointLight {}
    /// A sphere about the position, emitting from its surface ([`SphereLight`]): soft shadows
    /// from every side; a radius of 0 is the point light.
    Sphere => "sphere", "Sphere", SphereLight {
        radius: Size = DEFAULT_SPHERE_RADIUS, Bounds::ANY, "Light radius", "light size",
            "the sphere's radius, in scene units (0 is the point light)";
    }
    /// A square centred on the position, facing the floor (+y) ([`QuadLight`]): a Cornell
    /// box's ceiling light; a side of 0 is the point light.
    Quad => "quad", "Square (quad)", QuadLight {
        side: Size = DEFAULT_QUAD_SIDE, Bounds::ANY, "Light side", "light size",
            "the square's side, in scene units (0 is the point light)";
    }
    /// The point light given a direction ([`SpotLight`]): a cone of light.
    Spot(SpotCone) => "spot", "Spot", SpotLight {
        aim: Point = Vec3::new(0.0, 1.0, -0.2), Bounds::ANY, "Aim", "light aim",
            "the point the spot is aimed at (its axis runs from the light to it)";
        cutoff: Angle = radians(25.0), SPOT_CUTOFF, "Spot cutoff", "spot cutoff",
            "the cutoff angle from the axis, in degrees: no light beyond it";
        beam: Angle = radians(15.0), SPOT_BEAM, "Spot beam", "spot beam",
            "the beam width in degrees: full intensity within it, falling linearly in the \
             angle to 0 at the cutoff";
    }
}

impl Default for LightShape {
    /// The table's first kind, the lab's point light.
    fn default() -> Self {
        LightShape::ALL[0]
    }
}

fn wrong_type(name: &str) -> String {
    format!("'{name}' is a point: give three numbers, x,y,z")
}

/// How the light's fields were not what its kind takes, for [`LightKind::read`].
#[derive(Clone, Debug, PartialEq)]
pub enum ReadError {
    /// A field the kind does not have (its name).
    Unknown(String),
    /// A field the kind needs and was not given.
    Missing(&'static str),
    /// A field of the wrong type: one number for a point, three for a number.
    WrongType(String, String),
}

/// A field's value as a file holds it: a number or an array of numbers.
#[derive(Clone, Debug, PartialEq)]
pub enum RawParam {
    Number(f64),
    Array(Vec<f64>),
}

impl LightKind {
    /// The kind named `name` with its default parameters; the error lists the kinds.
    pub fn of_name(name: &str) -> Result<LightKind, String> {
        name.parse::<LightShape>().map(LightKind::of_shape)
    }

    /// The kind's name in files and on the command line.
    pub fn name(&self) -> &'static str {
        self.shape().name()
    }

    /// The parameters with their values, in the table's order.
    pub fn params_and_values(&self) -> impl Iterator<Item = (&'static Param, ParamValue)> + use<> {
        self.params().iter().zip(self.values())
    }

    /// The kind's size parameter (a sphere's radius, a square's side), if it has one.
    pub fn size_param(&self) -> Option<&'static Param> {
        self.params().iter().find(|p| p.ty == ParamType::Size)
    }

    /// The kind `shape` of size `size`: [`LightKind::of_shape`] with its size parameter set to
    /// `size` (a kind without one keeps its defaults).
    pub fn sized(shape: LightShape, size: f32) -> Self {
        let mut kind = LightKind::of_shape(shape);
        if let Some(p) = kind.size_param() {
            // The parameter is the kind's own and a number: this cannot fail.
            let _ = kind.set(p.name, ParamValue::Number(size));
        }
        kind
    }

    fn unknown_field(&self, name: &str) -> String {
        match self.params().is_empty() {
            true => format!(
                "unknown field `{name}`: a {} light has no fields",
                self.name()
            ),
            false => format!(
                "unknown field `{name}` for a {} light (its fields: {})",
                self.name(),
                self.params()
                    .iter()
                    .map(|p| p.name)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }
    }

    /// The kind `shape` with the fields `given` as a file holds them (angles in degrees when
    /// `degrees`, else radians): each of the kind's fields must be given, and no other.
    pub fn read(
        shape: LightShape,
        given: &[(String, RawParam)],
        degrees: bool,
    ) -> Result<LightKind, ReadError> {
        let mut kind = LightKind::of_shape(shape);
        for (key, raw) in given {
            let Some(p) = kind.params().iter().find(|p| p.name == key) else {
                return Err(ReadError::Unknown(key.clone()));
            };
            let value = match (p.ty, raw) {
                (ParamType::Angle, RawParam::Number(x)) if degrees => {
                    ParamValue::Number(radians(*x))
                }
                (ParamType::Size | ParamType::Angle, RawParam::Number(x)) => {
                    ParamValue::Number(*x as f32)
                }
                (ParamType::Point, RawParam::Array(v)) if v.len() == 3 => {
                    ParamValue::Point(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32))
                }
                (ParamType::Point, _) => {
                    return Err(ReadError::WrongType(
                        key.clone(),
                        "an array of exactly 3 numbers".to_owned(),
                    ));
                }
                (ParamType::Size | ParamType::Angle, RawParam::Array(_)) => {
                    return Err(ReadError::WrongType(key.clone(), "a number".to_owned()));
                }
            };
            kind.set(p.name, value)
                .map_err(|_| ReadError::Unknown(key.clone()))?;
        }
        if let Some(p) = kind
            .params()
            .iter()
            .find(|p| !given.iter().any(|(k, _)| k == p.name))
        {
            return Err(ReadError::Missing(p.name));
        }
        Ok(kind)
    }

    /// Reads a light as `--light` gives it: its kind's name, then optionally `:` and
    /// `field=value` pairs separated by commas, a point's three coordinates separated by
    /// commas too, angles in degrees: `spot:aim=0,1,0,cutoff=30`, `sphere:radius=0.2`. Fields
    /// not given keep their defaults; each is checked against its bounds (the rules between
    /// them and the light's position are `RenderSettings::validate`'s). Errors are one line,
    /// naming the kind or field.
    pub fn parse(text: &str) -> Result<LightKind, String> {
        let (name, rest) = text.split_once(':').unwrap_or((text, ""));
        let mut kind = LightKind::of_name(name.trim())?;
        let mut pairs: Vec<(String, Vec<f64>)> = Vec::new();
        for token in rest.split(',').map(str::trim).filter(|t| !t.is_empty()) {
            let (field, number) = match token.split_once('=') {
                Some((field, number)) => (Some(field.trim()), number.trim()),
                None => (None, token),
            };
            let x: f64 = number
                .parse()
                .map_err(|_| format!("'{number}' in '{token}' is not a number"))?;
            match (field, pairs.last_mut()) {
                (Some(field), _) => pairs.push((field.to_owned(), vec![x])),
                (None, Some((_, numbers))) => numbers.push(x),
                (None, None) => return Err(format!("'{token}': give each value as field=value")),
            }
        }
        for (field, numbers) in pairs {
            let Some(p) = kind.params().iter().find(|p| p.name == field) else {
                return Err(kind.unknown_field(&field));
            };
            let value = match (p.ty, &numbers[..]) {
                (ParamType::Point, [x, y, z]) => {
                    ParamValue::Point(Vec3::new(*x as f32, *y as f32, *z as f32))
                }
                (ParamType::Size | ParamType::Angle, [x]) => ParamValue::Number(p.stored(*x)),
                (ParamType::Point, _) => {
                    return Err(format!("'{field}' is a point: give three numbers, x,y,z"));
                }
                (ParamType::Size | ParamType::Angle, _) => {
                    return Err(format!("'{field}' is one number, not {}", numbers.len()));
                }
            };
            kind.set(p.name, value)?;
        }
        for (p, value) in kind.params_and_values() {
            p.check_bounds(value).map_err(|e| e.to_string())?;
        }
        Ok(kind)
    }
}

impl<'de> Deserialize<'de> for RawParam {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = RawParam;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "a number or an array of 3 numbers")
            }
            fn visit_f64<E>(self, x: f64) -> Result<RawParam, E> {
                Ok(RawParam::Number(x))
            }
            fn visit_i64<E>(self, x: i64) -> Result<RawParam, E> {
                Ok(RawParam::Number(x as f64))
            }
            fn visit_u64<E>(self, x: u64) -> Result<RawParam, E> {
                Ok(RawParam::Number(x as f64))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<RawParam, A::Error> {
                let mut out = Vec::with_capacity(3);
                while let Some(x) = seq.next_element::<f64>()? {
                    out.push(x);
                }
                Ok(RawParam::Array(out))
            }
        }
        d.deserialize_any(Visitor)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A kind's parameters as a file holds them: angles in degrees.
    fn raw(kind: &LightKind) -> Vec<(String, RawParam)> {
        kind.params_and_values()
            .map(|(p, value)| {
                let raw = match value {
                    ParamValue::Number(x) => RawParam::Number(p.shown(x)),
                    ParamValue::Point(v) => RawParam::Array(v.to_array().map(f64::from).to_vec()),
                };
                (p.name.to_owned(), raw)
            })
            .collect()
    }

    /// Every kind of the table reads back what it wrote through `values`, `set` and `read`
    /// (each field required, no other taken), and is named as its shape.
    #[test]
    fn every_kind_reads_and_writes_its_parameters_through_the_table() {
        for shape in LightShape::ALL {
            let kind = LightKind::of_shape(shape);
            assert_eq!((kind.shape(), kind.name()), (shape, shape.name()));
            assert_eq!(LightKind::of_name(shape.name()), Ok(kind));
            assert_eq!(kind.params().len(), kind.values().len());
            let given = raw(&kind);
            assert_eq!(LightKind::read(shape, &given, true), Ok(kind), "{shape}");
            let mut again = kind;
            for (p, value) in kind.params_and_values() {
                again.set(p.name, value).unwrap();
            }
            assert_eq!(again, kind);
            for (i, p) in kind.params().iter().enumerate() {
                let mut less = given.clone();
                less.remove(i);
                assert_eq!(
                    LightKind::read(shape, &less, true),
                    Err(ReadError::Missing(p.name))
                );
            }
        }
        let aim = [("aim".to_owned(), RawParam::Array(vec![0.0, 1.0, 0.0]))];
        assert_eq!(
            LightKind::read(LightShape::Sphere, &aim, true),
            Err(ReadError::Unknown("aim".to_owned()))
        );
        let one = [("aim".to_owned(), RawParam::Number(1.0))];
        assert!(matches!(
            LightKind::read(LightShape::Spot, &one, true),
            Err(ReadError::WrongType(..))
        ));
        // Radians when not in degrees (the settings JSON, scene files of version 1).
        let spot = LightKind::of_shape(LightShape::Spot);
        let mut radians_given = raw(&spot);
        for (key, value) in &mut radians_given {
            if key == "cutoff" {
                *value = RawParam::Number(0.5);
            }
        }
        let LightKind::Spot(cone) =
            LightKind::read(LightShape::Spot, &radians_given, false).unwrap()
        else {
            panic!("not a spot");
        };
        assert_eq!(cone.cutoff, 0.5);
    }

    /// `--light-kind`'s text: the kind, then fields in degrees; bounds checked, errors named.
    #[test]
    fn a_light_kind_is_parsed_from_its_name_and_fields() {
        assert_eq!(
            LightKind::parse("spot:aim=0,1,0,cutoff=30"),
            Ok(LightKind::Spot(SpotCone {
                aim: Vec3::Y,
                cutoff: radians(30.0),
                ..SpotCone::default()
            }))
        );
        assert_eq!(
            LightKind::parse("sphere:radius=0.2"),
            Ok(LightKind::Sphere { radius: 0.2 })
        );
        assert_eq!(LightKind::parse("quad"), Ok(LightKind::Quad { side: 0.5 }));
        for (text, says) in [
            ("disc", "unknown light shape 'disc'"),
            (
                "spot:cutoff=90",
                "invalid spot cutoff 90°: must be above 0° and below 90°",
            ),
            ("point:radius=1", "a point light has no fields"),
            (
                "sphere:aim=0,1,0",
                "unknown field `aim` for a sphere light (its fields: radius)",
            ),
            ("spot:aim=1", "'aim' is a point"),
            ("spot:cutoff=1,2", "'cutoff' is one number"),
            ("spot:cutoff=x", "'x' in 'cutoff=x' is not a number"),
        ] {
            let e = LightKind::parse(text).unwrap_err();
            assert!(e.contains(says), "{text}: {e}");
        }
    }

    /// The size is the kind's `Size` parameter; `tidy` keeps the spot's beam within its
    /// cutoff and the cutoff above 0.
    #[test]
    fn sizes_and_the_rules_between_parameters() {
        assert_eq!(
            LightKind::sized(LightShape::Quad, 0.3),
            LightKind::Quad { side: 0.3 }
        );
        assert_eq!(LightKind::Quad { side: 0.3 }.size(), 0.3);
        let spot = LightKind::of_shape(LightShape::Spot);
        assert_eq!(LightKind::sized(LightShape::Spot, 0.3), spot);
        assert_eq!((spot.size(), spot.size_param()), (0.0, None));
        let mut wide = LightKind::Spot(SpotCone {
            cutoff: radians(10.0),
            beam: radians(20.0),
            ..SpotCone::default()
        });
        let aimed = Vec3::new(0.0, -0.5, -0.7);
        assert!(wide.check_rules(aimed).is_err());
        wide.tidy();
        let LightKind::Spot(cone) = wide else {
            panic!("not a spot");
        };
        assert_eq!(cone.beam, cone.cutoff);
        assert!(wide.check_rules(aimed).is_ok());
        let at_itself = LightKind::Spot(SpotCone {
            aim: aimed,
            ..SpotCone::default()
        });
        assert!(
            at_itself
                .check_rules(aimed)
                .unwrap_err()
                .to_string()
                .contains("light aim")
        );
    }
}

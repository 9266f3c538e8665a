//! Materials: how a surface scatters the light that reaches it.
//!
//! The lab models every surface as ideally diffuse with reflectance ρ (its figure 4, left) and
//! lists specular materials among its extensions. raylab's kinds, as pbrt splits them from the
//! shapes that carry them, are one table (`material_kinds!`): diffuse (the lab's, BRDF ρ/π),
//! mirror, glass (exact Fresnel reflection and refraction), a rough metal and a glossy
//! plastic, each with its parameters' names, defaults and ranges. The scene file, the settings
//! JSON, `--material` and the workbench's material editor all read and write a material
//! through that table; [`Material::bsdf`] is where a kind becomes the [`Bsdf`] it scatters by.
//!
//! Every quantity here is in raylab's image units, π × radiance (see [`crate::transport::integrator`]).
//! In those units a diffuse bounce sampled with pdf cos θ/π carries the weight ρ exactly:
//! (ρ/π)·cos θ / (cos θ/π) = ρ.
//!
//! Both integrators use the same functions: the lab stages follow every specular branch
//! (Whitted-style, [`Material::specular_branches`]); the path tracer picks one branch at random
//! with the same weights ([`Material::sample`]).

use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

use crate::base::invalid::SettingsError;
use crate::base::named::named_enum;
use crate::base::sampling::{Rng, cosine_hemisphere_by_rejection, hemisphere_around};
use crate::shading::bsdf::{Bsdf, RoughPlastic, ShadingFrame, snell_cos_t};
pub use crate::shading::bsdf::{fresnel_dielectric, reflect};
use crate::shading::relief::Relief;
use crate::shading::texture::Texture;
use std::sync::Arc;

/// Declares [`MaterialKind`] from one table: each kind's variant, its name (in files and on
/// the command line), its label (in the workbench) and its parameters, each with its type
/// (`f32`, or `Vec3` for a colour), its default, its range and what it is. Everything that
/// reads or writes a material's parameters (the scene file, the settings JSON, `--material`,
/// the workbench's material editor, [`MaterialKind::check`]) goes through what this writes:
/// [`MaterialKind::DEFAULTS`], [`MaterialKind::name`], [`MaterialKind::label`],
/// [`MaterialKind::fields`], [`MaterialKind::values`] and [`MaterialKind::set`].
macro_rules! material_kinds {
    ($(
        $(#[$meta:meta])*
        $variant:ident => $name:literal, $label:literal $({
            $(
                $(#[$fmeta:meta])*
                $field:ident: $ty:ty = $default:expr, [$lo:literal, $hi:literal], $what:literal;
            )*
        })?
    )+) => {
        /// How a surface scatters light: a kind and its parameters (`material_kinds!`).
        #[derive(Clone, Copy, Debug, PartialEq, Default)]
        pub enum MaterialKind {
            $(
                $(#[$meta])*
                $variant $({ $( $(#[$fmeta])* $field: $ty, )* })?,
            )+
        }

        impl MaterialKind {
            /// Every kind with its default parameters, in the order the workbench lists them.
            pub const DEFAULTS: &'static [MaterialKind] = &[
                $( MaterialKind::$variant $({ $( $field: $default, )* })?, )+
            ];

            /// The kind's name in files and on the command line: `diffuse`, `mirror`, …
            pub fn name(&self) -> &'static str {
                match self {
                    $( MaterialKind::$variant { .. } => $name, )+
                }
            }

            /// The kind's label in the workbench.
            pub fn label(&self) -> &'static str {
                match self {
                    $( MaterialKind::$variant { .. } => $label, )+
                }
            }

            /// The kind's parameters: name, range and what each is.
            pub fn fields(&self) -> &'static [Field] {
                match self {
                    $( MaterialKind::$variant { .. } => &[
                        $($( Field {
                            name: stringify!($field),
                            what: $what,
                            range: [$lo as f32, $hi as f32],
                            colour: <$ty as FieldType>::COLOUR,
                            reason: concat!("must be in [", stringify!($lo), ", ",
                                stringify!($hi), "]"),
                        }, )*)?
                    ], )+
                }
            }

            /// The kind's parameters' values, in the order of [`MaterialKind::fields`].
            pub fn values(&self) -> Vec<FieldValue> {
                match *self {
                    $( MaterialKind::$variant $({ $( $field, )* })? => vec![
                        $($( FieldType::value($field), )*)?
                    ], )+
                }
            }

            /// Sets the parameter `name` to `value`: an error if the kind has no such
            /// parameter or `value` is not of its type (a number, or a colour). The value's
            /// range is [`MaterialKind::check`]'s.
            pub fn set(&mut self, name: &str, value: FieldValue) -> Result<(), String> {
                match self {
                    $( MaterialKind::$variant $({ $( $field, )* })? => {
                        $($(
                            if name == stringify!($field) {
                                return match FieldType::of_value(value) {
                                    Some(v) => { *$field = v; Ok(()) }
                                    None => Err(wrong_type(stringify!($field), <$ty as FieldType>::COLOUR)),
                                };
                            }
                        )*)?
                    } )+
                }
                Err(self.unknown_field(name))
            }
        }
    };
}

material_kinds! {
    /// The lab's surface: light reflected equally in every direction, by ρ.
    #[default]
    Diffuse => "diffuse", "Diffuse"
    /// An ideal mirror: the reflected ray carries `tint` of what it sees.
    Mirror => "mirror", "Mirror" {
        tint: Vec3 = Vec3::splat(0.9), [0, 1], "tint: the share reflected per channel";
    }
    /// Clear glass: exact Fresnel reflection and refraction at index of refraction `ior`
    /// (outside is 1.0); refracted light is multiplied by `tint`.
    Glass => "glass", "Glass" {
        ior: f32 = 1.5, [1, 4], "index of refraction (outside 1)";
        tint: Vec3 = Vec3::ONE, [0, 1], "tint: the share refracted per channel";
    }
    /// A rough metal: microfacets of GGX roughness `alpha` (0 is a mirror, 1 very rough) that
    /// reflect `tint` of the light, with no Fresnel falloff ([`crate::shading::bsdf::Bsdf::RoughConductor`]).
    Rough => "rough", "Rough metal" {
        alpha: f32 = DEFAULT_ROUGHNESS, [0.01, 1], "GGX roughness α (0.01 nearly a mirror, 1 very rough)";
        tint: Vec3 = PRESET_ROUGH_TINT, [0, 1], "tint: the share reflected per channel";
    }
    /// A glossy plastic: the diffuse base of reflectance ρ (the material's `reflectance`)
    /// under a rough dielectric coating of GGX roughness `alpha`, indices `int_ior` inside
    /// and `ext_ior` outside, whose reflection is scaled by `specular`
    /// ([`crate::shading::bsdf::RoughPlastic`], Mitsuba 3's `roughplastic`).
    Plastic => "plastic", "Glossy plastic" {
        alpha: f32 = DEFAULT_PLASTIC_ROUGHNESS, [0.01, 1], "the coating's GGX roughness α";
        int_ior: f32 = 1.5, [1, 4], "index of refraction inside the coating";
        ext_ior: f32 = 1.0, [1, 4], "index of refraction outside";
        specular: Vec3 = Vec3::ONE, [0, 1], "specular reflectance: the coating's reflection per channel";
    }
}

/// A material parameter, as `material_kinds!` lists it: what the scene file, the settings
/// JSON, `--material` and the workbench's editor know of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Field {
    /// Its name in files and on the command line (`alpha`, `int_ior`, `tint`).
    pub name: &'static str,
    /// What it is, for the workbench and `--help`.
    pub what: &'static str,
    /// The values it may take, `[low, high]` (each channel's, for a colour).
    pub range: [f32; 2],
    /// Whether it is a colour (three channels) rather than one number.
    pub colour: bool,
    /// Why a value outside `range` is refused: "must be in [low, high]".
    pub reason: &'static str,
}

/// A parameter's value: one number, or a colour's three channels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FieldValue {
    Number(f32),
    Colour(Vec3),
}

impl FieldValue {
    /// The channels: a number's once, a colour's three.
    pub fn channels(self) -> Vec<f32> {
        match self {
            FieldValue::Number(x) => vec![x],
            FieldValue::Colour(c) => c.to_array().to_vec(),
        }
    }
}

impl std::fmt::Display for FieldValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FieldValue::Number(x) => write!(f, "{x}"),
            FieldValue::Colour(c) => write!(f, "[{}, {}, {}]", c.x, c.y, c.z),
        }
    }
}

/// The Rust types a material parameter may have: `f32` or `Vec3` (a colour).
pub trait FieldType: Copy {
    const COLOUR: bool;
    fn value(self) -> FieldValue;
    fn of_value(value: FieldValue) -> Option<Self>;
}

impl FieldType for f32 {
    const COLOUR: bool = false;
    fn value(self) -> FieldValue {
        FieldValue::Number(self)
    }
    fn of_value(value: FieldValue) -> Option<Self> {
        match value {
            FieldValue::Number(x) => Some(x),
            FieldValue::Colour(_) => None,
        }
    }
}

impl FieldType for Vec3 {
    const COLOUR: bool = true;
    fn value(self) -> FieldValue {
        FieldValue::Colour(self)
    }
    /// A colour, or one number for a grey (every channel the same).
    fn of_value(value: FieldValue) -> Option<Self> {
        match value {
            FieldValue::Number(x) => Some(Vec3::splat(x)),
            FieldValue::Colour(c) => Some(c),
        }
    }
}

fn wrong_type(name: &str, colour: bool) -> String {
    match colour {
        true => format!("'{name}' is a colour: give three numbers (or one for a grey)"),
        false => format!("'{name}' is one number, not a colour"),
    }
}

/// "a, b or c".
fn listed<'a>(names: impl IntoIterator<Item = &'a str>) -> String {
    let names: Vec<&str> = names.into_iter().collect();
    match names.split_last() {
        None => "none".to_owned(),
        Some((last, [])) => (*last).to_owned(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
    }
}

impl MaterialKind {
    /// The kind named `name` with its default parameters; the error lists the kinds.
    pub fn of_name(name: &str) -> Result<MaterialKind, String> {
        MaterialKind::DEFAULTS
            .iter()
            .find(|k| k.name() == name)
            .copied()
            .ok_or_else(|| {
                crate::base::named::unknown(
                    "material kind",
                    name,
                    MaterialKind::DEFAULTS.iter().map(|k| k.name()),
                )
            })
    }

    /// This kind's default parameters.
    pub fn defaults(&self) -> MaterialKind {
        MaterialKind::of_name(self.name()).unwrap_or_default()
    }

    /// The parameters with their values, in the table's order.
    pub fn fields_and_values(&self) -> impl Iterator<Item = (&'static Field, FieldValue)> + use<> {
        self.fields().iter().zip(self.values())
    }

    fn unknown_field(&self, name: &str) -> String {
        let fields = self.fields().iter().map(|f| f.name);
        match self.fields().is_empty() {
            true => format!(
                "unknown field `{name}`: a {} material has no fields",
                self.name()
            ),
            false => format!(
                "unknown field `{name}` for a {} material (its fields: {})",
                self.name(),
                listed(fields)
            ),
        }
    }

    /// Checks every parameter against its range (each channel of a colour), and that a
    /// plastic's two indices differ (equal, the coating would not reflect). The error names
    /// the parameter as `field` makes its path (`scene.models[0].material.alpha`).
    pub fn check(&self, field: impl Fn(&str) -> String) -> Result<(), SettingsError> {
        for (f, value) in self.fields_and_values() {
            let [lo, hi] = f.range;
            if !value.channels().iter().all(|x| (lo..=hi).contains(x)) {
                return Err(SettingsError {
                    name: field(f.name).into(),
                    value: value.to_string(),
                    reason: f.reason,
                });
            }
        }
        if let MaterialKind::Plastic {
            int_ior, ext_ior, ..
        } = *self
            && int_ior == ext_ior
        {
            return Err(SettingsError {
                name: field("int_ior").into(),
                value: format!("{int_ior}"),
                reason: "must differ from ext_ior (equal indices make no coating)",
            });
        }
        Ok(())
    }

    /// Reads a material as the command line gives it: its kind's name, then optionally `:`
    /// and `field=value` pairs separated by commas, a colour's three channels separated by
    /// commas too (or one number for a grey): `plastic:alpha=0.2,int_ior=1.5`,
    /// `mirror:tint=0.9,0.8,0.7`. Fields not given keep their defaults; every value is
    /// checked against its range. Errors are one line, naming the kind or field.
    pub fn parse(text: &str) -> Result<MaterialKind, String> {
        let (name, rest) = text.split_once(':').unwrap_or((text, ""));
        let mut kind = MaterialKind::of_name(name.trim())?;
        let mut pairs: Vec<(String, Vec<f32>)> = Vec::new();
        for token in rest.split(',').map(str::trim).filter(|t| !t.is_empty()) {
            let (field, number) = match token.split_once('=') {
                Some((field, number)) => (Some(field.trim()), number.trim()),
                None => (None, token),
            };
            let x: f32 = number
                .parse()
                .map_err(|_| format!("'{number}' in '{token}' is not a number"))?;
            match (field, pairs.last_mut()) {
                (Some(field), _) => pairs.push((field.to_owned(), vec![x])),
                (None, Some((_, channels))) => channels.push(x),
                (None, None) => return Err(format!("'{token}': give each value as field=value")),
            }
        }
        for (field, channels) in pairs {
            let value = match channels[..] {
                [x] => FieldValue::Number(x),
                [r, g, b] => FieldValue::Colour(Vec3::new(r, g, b)),
                _ => {
                    return Err(format!(
                        "'{field}' has {} numbers: give one, or a colour's three",
                        channels.len()
                    ));
                }
            };
            kind.set(&field, value)?;
        }
        kind.check(|f| format!("material {f}"))
            .map_err(|e| e.to_string())?;
        Ok(kind)
    }
}

/// As the scene file and the settings JSON hold it: `{ kind = "plastic", alpha = 0.1,
/// int_ior = 1.5, ext_ior = 1.0, specular = [1.0, 1.0, 1.0] }`, the kind's every field and
/// no other.
impl Serialize for MaterialKind {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap as _;
        let mut map = s.serialize_map(Some(1 + self.fields().len()))?;
        map.serialize_entry("kind", self.name())?;
        for (f, value) in self.fields_and_values() {
            match value {
                FieldValue::Number(x) => map.serialize_entry(f.name, &x)?,
                FieldValue::Colour(c) => map.serialize_entry(f.name, &c.to_array())?,
            }
        }
        map.end()
    }
}

/// One value of a material's table as read: a number or an array of numbers.
enum RawValue {
    Number(f32),
    Array(Vec<f32>),
}

impl<'de> Deserialize<'de> for RawValue {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = RawValue;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "a number or an array of 3 numbers")
            }
            fn visit_f64<E>(self, x: f64) -> Result<RawValue, E> {
                Ok(RawValue::Number(x as f32))
            }
            fn visit_i64<E>(self, x: i64) -> Result<RawValue, E> {
                Ok(RawValue::Number(x as f32))
            }
            fn visit_u64<E>(self, x: u64) -> Result<RawValue, E> {
                Ok(RawValue::Number(x as f32))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<RawValue, A::Error> {
                let mut out = Vec::with_capacity(3);
                while let Some(x) = seq.next_element::<f32>()? {
                    if out.len() == 3 {
                        return Err(serde::de::Error::custom(
                            "invalid length: more than 3 elements, expected an array of exactly 3 numbers",
                        ));
                    }
                    out.push(x);
                }
                Ok(RawValue::Array(out))
            }
        }
        d.deserialize_any(Visitor)
    }
}

impl<'de> Deserialize<'de> for MaterialKind {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = MaterialKind;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "a material: its kind and its fields")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<MaterialKind, A::Error> {
                use serde::de::Error as _;
                let mut name: Option<String> = None;
                let mut given: Vec<(String, RawValue)> = Vec::new();
                while let Some(key) = map.next_key::<String>()? {
                    if key == "kind" {
                        name = Some(map.next_value()?);
                    } else if given.iter().any(|(k, _)| *k == key) {
                        return Err(A::Error::custom(format_args!("duplicate field `{key}`")));
                    } else {
                        let value = map.next_value()?;
                        given.push((key, value));
                    }
                }
                let name = name.ok_or_else(|| A::Error::missing_field("kind"))?;
                let mut kind = MaterialKind::of_name(&name).map_err(A::Error::custom)?;
                for (key, raw) in &given {
                    let value = match raw {
                        RawValue::Number(x) => FieldValue::Number(*x),
                        RawValue::Array(c) if c.len() == 3 => {
                            FieldValue::Colour(Vec3::new(c[0], c[1], c[2]))
                        }
                        RawValue::Array(c) => {
                            return Err(A::Error::custom(format_args!(
                                "`{key}`: invalid length {}, expected an array of exactly 3 \
                                 numbers",
                                c.len()
                            )));
                        }
                    };
                    kind.set(key, value).map_err(A::Error::custom)?;
                }
                // Every field is written, so a file that leaves one out was edited by hand.
                if let Some(f) = kind
                    .fields()
                    .iter()
                    .find(|f| !given.iter().any(|(k, _)| k == f.name))
                {
                    return Err(A::Error::missing_field(f.name));
                }
                Ok(kind)
            }
        }
        d.deserialize_map(Visitor)
    }
}

/// A material: the lab's per-triangle `color` (its diffuse reflectance ρ) and its kind.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    pub name: String,
    /// ρ, the fraction of incoming light a diffuse surface reflects per colour channel (lab
    /// section 5). Kept for specular kinds too, so switching a preset off restores the lab's
    /// surface.
    pub reflectance: Vec3,
    pub kind: MaterialKind,
    /// A texture for ρ (diffuse surfaces only): where set, ρ at a hit is the texture's value at
    /// the hit's texture coordinates, not `reflectance`.
    #[serde(skip)]
    pub texture: Option<Texture>,
    /// A normal map and/or a height map ([`crate::shading::relief`]): where set, the shading normal
    /// and the texture coordinates at a hit are the relief's.
    #[serde(skip)]
    pub relief: Option<Arc<Relief>>,
}

/// A direction to continue along and the weight it carries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scatter {
    pub direction: Vec3,
    pub weight: Vec3,
}

impl Material {
    pub fn diffuse(name: impl Into<String>, reflectance: Vec3) -> Self {
        Self {
            name: name.into(),
            reflectance,
            kind: MaterialKind::Diffuse,
            texture: None,
            relief: None,
        }
    }

    /// ρ at a hit at `position` with unit `normal` and texture coordinates `uv` (asked for
    /// only by a texture that uses them): the texture's value where there is one, else the
    /// constant reflectance (exactly, for the lab's box).
    #[inline(always)]
    pub fn reflectance_at(
        &self,
        uv: impl FnOnce() -> glam::Vec2,
        position: Vec3,
        normal: Vec3,
    ) -> Vec3 {
        match &self.texture {
            None => self.reflectance,
            Some(texture) => texture.at(uv, position, normal),
        }
    }

    pub fn is_diffuse(&self) -> bool {
        matches!(self.kind, MaterialKind::Diffuse)
    }

    /// Whether the material scatters only into single directions (mirror, glass): such
    /// surfaces are followed, never lit directly by a point light.
    pub fn is_specular(&self) -> bool {
        matches!(
            self.kind,
            MaterialKind::Mirror { .. } | MaterialKind::Glass { .. }
        )
    }

    /// The specular branches at a hit, for Whitted-style tracing: up to two directions, each
    /// with its weight (a mirror: the reflection with its tint; glass: the reflection with
    /// Fresnel's F and the refraction with (1 − F)·tint, or only the reflection past the
    /// critical angle). Empty for a diffuse material.
    ///
    /// `direction` is the incoming ray's (unit) direction, `normal` the surface's geometric
    /// normal (either side).
    #[inline(always)]
    pub fn specular_branches(&self, direction: Vec3, normal: Vec3) -> Branches {
        let mut out = Branches::default();
        match self.kind {
            MaterialKind::Diffuse | MaterialKind::Rough { .. } | MaterialKind::Plastic { .. } => {}
            MaterialKind::Mirror { tint } => out.push(reflect(direction, normal), tint),
            MaterialKind::Glass { ior, tint } => {
                let g = GlassHit::new(direction, normal, ior);
                out.push(reflect(direction, normal), Vec3::splat(g.fresnel));
                if let Some(refracted) = g.refracted {
                    out.push(refracted, (1.0 - g.fresnel) * tint);
                }
            }
        }
        out
    }

    /// The BSDF of this material at a hit whose diffuse reflectance is `rho` (the texture's
    /// value there, or [`Material::reflectance`]): the one place a material says how it
    /// scatters ([`crate::shading::bsdf`]).
    #[inline(always)]
    pub fn bsdf(&self, rho: Vec3) -> Bsdf {
        match self.kind {
            MaterialKind::Diffuse => Bsdf::Lambertian { rho },
            MaterialKind::Mirror { tint } => Bsdf::Mirror { tint },
            MaterialKind::Glass { ior, tint } => Bsdf::Glass { ior, tint },
            MaterialKind::Rough { alpha, tint } => Bsdf::RoughConductor { alpha, tint },
            MaterialKind::Plastic {
                alpha,
                int_ior,
                ext_ior,
                specular,
            } => Bsdf::Plastic(RoughPlastic::new(alpha, int_ior, ext_ior, rho, specular)),
        }
    }

    /// Samples the direction a path continues along after hitting this material, with the
    /// weight of that sample (the BSDF times cos θ over the pdf, in π × radiance units), or
    /// `None` where the BSDF sends nothing on (a rough reflection below the surface).
    ///
    /// * diffuse: a cosine-weighted direction on the side the ray came from, weight ρ (drawn
    ///   by rejection: 2.5 numbers on average). The path tracer draws its diffuse bounces
    ///   sixteen at a time with the same functions, weighted by ρ at the hit (a texture's):
    ///   [`Bsdf::Lambertian`]'s sampling, specialised to lanes;
    /// * every other material: [`Bsdf::sample`] in the shading frame of `shading` about the
    ///   surface's `geometric` normal ([`ShadingFrame::new`]: the geometric normal decides
    ///   reflection and transmission), with one number for the choice of lobe and, where the
    ///   BSDF is not a delta (the rough metal), two for the direction. `shading` is the
    ///   geometric normal itself, or a relief's bent normal
    ///   ([`crate::transport::integrator::Tracer::specular_normal`]).
    #[inline(never)]
    pub fn sample(
        &self,
        direction: Vec3,
        shading: Vec3,
        geometric: Vec3,
        rng: &mut Rng,
    ) -> Option<Scatter> {
        let bsdf = self.bsdf(self.reflectance);
        if let Bsdf::Lambertian { rho } = bsdf {
            let local = cosine_hemisphere_by_rejection(rng, true);
            return Some(Scatter {
                direction: hemisphere_around(facing(geometric, direction), local),
                weight: rho,
            });
        }
        let uc = rng.next_f32();
        let u = if bsdf.is_delta() {
            Vec2::ZERO
        } else {
            Vec2::new(rng.next_f32(), rng.next_f32())
        };
        let frame = ShadingFrame::new(shading, geometric, -direction);
        frame
            .sample_world(&bsdf, -direction, uc, u)
            .map(|s| Scatter {
                direction: s.wi,
                weight: s.weight,
            })
    }
}

/// Up to two weighted directions (see [`Material::specular_branches`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Branches {
    len: usize,
    items: [(Vec3, Vec3); 2],
}

impl Branches {
    fn push(&mut self, direction: Vec3, weight: Vec3) {
        self.items[self.len] = (direction, weight);
        self.len += 1;
    }

    pub fn as_slice(&self) -> &[(Vec3, Vec3)] {
        &self.items[..self.len]
    }
}

/// The normal turned to face a ray coming along `direction` (surfaces are two-sided for
/// bounces).
#[inline(always)]
pub fn facing(normal: Vec3, direction: Vec3) -> Vec3 {
    if normal.dot(direction) > 0.0 {
        -normal
    } else {
        normal
    }
}

/// What happens where a ray meets glass.
struct GlassHit {
    fresnel: f32,
    /// The refracted direction, or `None` past the critical angle.
    refracted: Option<Vec3>,
}

impl GlassHit {
    /// `normal` points out of the glass (the geometric normal): a ray against it enters.
    #[inline(always)]
    fn new(direction: Vec3, normal: Vec3, ior: f32) -> Self {
        let entering = direction.dot(normal) < 0.0;
        let (n, eta) = if entering {
            (normal, ior)
        } else {
            (-normal, 1.0 / ior)
        };
        let cos_i = -direction.dot(n);
        let fresnel = fresnel_dielectric(cos_i, eta);
        let refracted = (fresnel < 1.0).then(|| {
            // Snell's law in vector form (pbrt's `Refract`), with the ratio of the indices
            // near/far = 1/eta.
            let cos_t = snell_cos_t(cos_i, eta);
            let cos_i = cos_i.clamp(0.0, 1.0);
            (direction / eta + (cos_i / eta - cos_t) * n).normalize()
        });
        Self { fresnel, refracted }
    }
}

/// Materials a scene can be given without editing it: the Cornell box's blocks turned mirror or
/// glass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MaterialPreset {
    /// The scene's own materials (the lab's diffuse box).
    #[default]
    None,
    /// The tall blue block becomes an ideal mirror reflecting 0.9 in every channel.
    Mirror,
    /// The short red block becomes clear glass: index of refraction 1.5, no tint.
    Glass,
    /// Both.
    Both,
    /// The tall blue block becomes a rough metal reflecting 0.9 in every channel, of roughness
    /// [`crate::RenderSettings::roughness`] (0.2 by default).
    Rough,
    /// The tall blue block becomes a glossy plastic: its own ρ under a rough dielectric
    /// coating (interior index 1.5, exterior 1, specular reflectance 1) of roughness
    /// [`crate::RenderSettings::roughness`] (0.1 when the preset is chosen).
    Plastic,
}

/// The material name of the Cornell box's tall block, which the mirror presets change.
pub const TALL_BLOCK: &str = "blue";
/// The material name of the Cornell box's short block, which the glass presets change.
pub const SHORT_BLOCK: &str = "red";

/// The mirror of the presets.
pub const PRESET_MIRROR: MaterialKind = MaterialKind::Mirror {
    tint: Vec3::splat(0.9),
};
/// The tint of the rough preset's metal.
pub const PRESET_ROUGH_TINT: Vec3 = Vec3::splat(0.9);
/// The rough preset's roughness unless the settings say otherwise.
pub const DEFAULT_ROUGHNESS: f32 = 0.2;
/// The smallest roughness α a rough metal may have (below it the microfacet distribution's
/// peak exceeds what `f32` evaluates well; a mirror is its own material).
pub const MIN_ROUGHNESS: f32 = 0.01;
/// The plastic preset's coating unless the settings say otherwise.
pub const DEFAULT_PLASTIC_ROUGHNESS: f32 = 0.1;
/// The plastic preset's coating, of roughness `alpha`, over the block's own ρ.
pub fn preset_plastic(alpha: f32) -> MaterialKind {
    MaterialKind::Plastic {
        alpha,
        int_ior: 1.5,
        ext_ior: 1.0,
        specular: Vec3::ONE,
    }
}
/// The glass of the presets.
pub const PRESET_GLASS: MaterialKind = MaterialKind::Glass {
    ior: 1.5,
    tint: Vec3::ONE,
};

/// The roughness α from which the rough preset's metal shows a bright front face in the lab's
/// box: the light hangs in front of the blocks, and microfacets this rough turn enough of it
/// toward the camera. The face brightens gradually: its mean display value is near the
/// mirror's black at α = 0.03, about 0.15 at 0.05 and 0.5 at the default 0.2
/// (`tests/extensions.rs` checks the notes on either side of 0.05–0.1).
pub const ROUGH_FRONT_BRIGHT_FROM: f32 = 0.075;

named_enum!(MaterialPreset as "material preset" {
    None => "none", "Diffuse (the lab)";
    Mirror => "mirror", "Mirror tall block";
    Glass => "glass", "Glass short block";
    Both => "both", "Mirror and glass";
    Rough => "rough", "Rough metal tall block";
    Plastic => "plastic", "Glossy plastic tall block";
});

impl MaterialPreset {
    /// The roughness α the preset starts with: the plastic's coating 0.1, the rough metal's
    /// (and the setting's otherwise) 0.2.
    pub fn default_roughness(self) -> f32 {
        match self {
            MaterialPreset::Plastic => DEFAULT_PLASTIC_ROUGHNESS,
            MaterialPreset::None
            | MaterialPreset::Mirror
            | MaterialPreset::Glass
            | MaterialPreset::Both
            | MaterialPreset::Rough => DEFAULT_ROUGHNESS,
        }
    }

    /// What the tall block's front face shows in the lab's box, and why, for the workbench's
    /// Materials row; `None` where it is not a reflector's (diffuse, glass) or where the lab's
    /// stages shade the rough metal by its highlight alone (`path` false). The face looks at
    /// the box's open front: a mirror, or a metal smoother than [`ROUGH_FRONT_BRIGHT_FROM`],
    /// reflects the void behind the camera; a rougher metal catches the light in front of it.
    pub fn front_face_note(self, path: bool, roughness: f32) -> Option<&'static str> {
        match self {
            MaterialPreset::Mirror | MaterialPreset::Both => Some(
                "The mirror's front face is black above what it shows of the floor and the short \
                 block: there it reflects the box's open front, the void behind the camera \
                 (physically right: the lab's box has no front wall)",
            ),
            MaterialPreset::Rough if path && roughness < ROUGH_FRONT_BRIGHT_FROM => Some(
                "The metal's front face is dark above what it shows of the floor and the short \
                 block: this smooth (α below 0.075), it reflects mostly the box's open front, the void \
                 behind the camera, as the mirror does (physically right: the lab's box has no \
                 front wall)",
            ),
            MaterialPreset::Rough if path => Some(
                "The metal's front face is bright, where the mirror's is black: the light hangs \
                 in front of the blocks, and the rough microfacets (α from 0.075) turn its \
                 light toward the camera; a smoother metal reflects the box's open front, the \
                 void behind the camera",
            ),
            MaterialPreset::Rough
            | MaterialPreset::None
            | MaterialPreset::Glass
            | MaterialPreset::Plastic => None,
        }
    }

    /// The materials with the preset applied: by name, the tall block's (`blue`) becomes the
    /// mirror (or the rough metal or the plastic of roughness `roughness`), the short block's (`red`) the
    /// glass. Scenes without those names are unchanged.
    pub fn apply(self, materials: &[Material], roughness: f32) -> Vec<Material> {
        let mirror = matches!(self, MaterialPreset::Mirror | MaterialPreset::Both);
        let glass = matches!(self, MaterialPreset::Glass | MaterialPreset::Both);
        let rough = self == MaterialPreset::Rough;
        let plastic = self == MaterialPreset::Plastic;
        materials
            .iter()
            .map(|m| {
                let mut m = m.clone();
                if mirror && m.name == TALL_BLOCK {
                    m.kind = PRESET_MIRROR;
                } else if rough && m.name == TALL_BLOCK {
                    m.kind = MaterialKind::Rough {
                        alpha: roughness,
                        tint: PRESET_ROUGH_TINT,
                    };
                } else if plastic && m.name == TALL_BLOCK {
                    m.kind = preset_plastic(roughness);
                } else if glass && m.name == SHORT_BLOCK {
                    m.kind = PRESET_GLASS;
                }
                m
            })
            .collect()
    }
}

/// Textures for the Cornell box's surfaces, beside the scene's own (a textured model keeps its
/// texture whatever the preset).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TexturePreset {
    /// No textures but the scene's own (the lab's box).
    #[default]
    None,
    /// The green floor becomes a checkerboard of its green and a light grey, squares 0.25 a
    /// side (8 across the floor).
    CheckerFloor,
    /// The room's four walls and ceiling get a grid of darker lines every 0.25.
    GridWalls,
    /// Both.
    Both,
    /// White fBm clouds drift over the cyan ceiling ([`clouds`]).
    Clouds,
    /// The back and side walls get a normal map of rounded bricks (generated in code,
    /// [`crate::shading::relief::bricks`]): relief under the point light, the walls still flat.
    BumpyWalls,
    /// The floor becomes the checkerboard's tiles with grout between them, carved by
    /// parallax occlusion mapping and lit by the matching normal map
    /// ([`crate::shading::relief::tile`]).
    ParallaxFloor,
}

/// The Cornell box's back and side walls (left, right, back), which the bumpy preset
/// normal-maps.
pub const SIDE_AND_BACK_WALLS: [&str; 3] = ["purple", "yellow", "white"];

/// The bumpy walls' bricks: one pattern (four courses of two bricks) every 0.5 scene units,
/// mortar 0.012 deep.
pub const BRICK_PERIOD: f32 = 0.5;
pub const BRICK_DEPTH: f32 = 0.012;
/// The parallax floor's tiles: one a checker square (0.25), grout 0.03 deep.
pub const TILE_DEPTH: f32 = 0.03;

/// The bumpy walls' relief, made once: a 256² normal map of [`crate::shading::relief::bricks`].
fn brick_relief() -> Arc<Relief> {
    static RELIEF: std::sync::OnceLock<Arc<Relief>> = std::sync::OnceLock::new();
    RELIEF
        .get_or_init(|| {
            let size = 256;
            let at = |i: u32| (i as f32 + 0.5) / size as f32;
            let heights = |i, j| crate::shading::relief::bricks(at(i), at(j));
            let image = crate::shading::relief::normal_map_of_heights(
                "bricks",
                size,
                BRICK_PERIOD,
                BRICK_DEPTH,
                &heights,
            );
            Arc::new(Relief {
                normal: Some(crate::shading::relief::NormalMap {
                    image: Arc::new(image),
                    strength: 1.0,
                }),
                height: None,
                uv_scale: 1.0 / BRICK_PERIOD,
            })
        })
        .clone()
}

/// The parallax floor's relief, made once: a 128² height map of [`crate::shading::relief::tile`],
/// [`TILE_DEPTH`] deep, and the normal map of the same heights.
fn tile_relief() -> Arc<Relief> {
    static RELIEF: std::sync::OnceLock<Arc<Relief>> = std::sync::OnceLock::new();
    RELIEF
        .get_or_init(|| {
            let size = 128;
            let period = 1.0 / PRESET_TEXTURE_SCALE;
            let at = |i: u32| (i as f32 + 0.5) / size as f32;
            let heights = |i, j| crate::shading::relief::tile(at(i), at(j));
            let normals = crate::shading::relief::normal_map_of_heights(
                "tiles", size, period, TILE_DEPTH, &heights,
            );
            let height = crate::shading::relief::height_image("tile heights", size, &heights);
            Arc::new(Relief {
                normal: Some(crate::shading::relief::NormalMap {
                    image: Arc::new(normals),
                    strength: 1.0,
                }),
                height: Some(crate::shading::relief::HeightMap::new(
                    Arc::new(height),
                    TILE_DEPTH,
                )),
                uv_scale: PRESET_TEXTURE_SCALE,
            })
        })
        .clone()
}

/// The Cornell box's floor material, which the checkerboard presets texture.
pub const FLOOR: &str = "green";
/// The Cornell box's walls and ceiling, which the grid presets texture.
pub const WALLS: [&str; 4] = ["purple", "yellow", "cyan", "white"];

/// Texture cells per unit of scene length in the presets: 0.25 a side.
pub const PRESET_TEXTURE_SCALE: f32 = 4.0;

named_enum!(TexturePreset as "texture preset" {
    None => "none", "None (the lab)";
    CheckerFloor => "checker-floor", "Checkerboard floor";
    GridWalls => "grid-walls", "Grid on the walls";
    Both => "both", "Checkerboard and grid";
    Clouds => "clouds", "Clouds on the ceiling";
    BumpyWalls => "bumpy-walls", "Bumpy brick walls (normal map)";
    ParallaxFloor => "parallax-floor", "Tiled floor with depth (parallax)";
});

/// The Cornell box's ceiling, which the clouds preset textures.
pub const CEILING: &str = "cyan";

/// The clouds preset: fBm of 7 octaves, about two cloud cells across the ceiling, over the
/// ceiling's own cyan.
pub fn clouds(sky: Vec3) -> Texture {
    Texture::Clouds {
        noise: crate::base::noise::Fbm {
            seed: 7,
            octaves: 7,
            ..crate::base::noise::Fbm::default()
        },
        scale: 1.5,
        sky,
        cloud: Vec3::splat(0.9),
        cover: 0.45,
    }
}

impl TexturePreset {
    /// The materials with this preset's textures (the box's surfaces are found by name).
    pub fn apply(self, materials: &[Material]) -> Vec<Material> {
        let checker = matches!(
            self,
            TexturePreset::CheckerFloor | TexturePreset::Both | TexturePreset::ParallaxFloor
        );
        let grid = matches!(self, TexturePreset::GridWalls | TexturePreset::Both);
        let bumpy = self == TexturePreset::BumpyWalls;
        let parallax = self == TexturePreset::ParallaxFloor;
        materials
            .iter()
            .map(|m| {
                let mut m = m.clone();
                if self == TexturePreset::Clouds && m.name == CEILING {
                    m.texture = Some(clouds(m.reflectance));
                }
                if bumpy && SIDE_AND_BACK_WALLS.contains(&m.name.as_str()) {
                    m.relief = Some(brick_relief());
                }
                if parallax && m.name == FLOOR {
                    m.relief = Some(tile_relief());
                }
                if checker && m.name == FLOOR {
                    m.texture = Some(Texture::Checker {
                        scale: PRESET_TEXTURE_SCALE,
                        colours: [m.reflectance, Vec3::splat(0.8)],
                    });
                } else if grid && WALLS.contains(&m.name.as_str()) {
                    m.texture = Some(Texture::Grid {
                        scale: PRESET_TEXTURE_SCALE,
                        line_width: 0.06,
                        background: m.reflectance,
                        line: 0.25 * m.reflectance,
                    });
                }
                m
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn glass() -> Material {
        Material {
            name: "glass".into(),
            reflectance: Vec3::ZERO,
            kind: PRESET_GLASS,
            texture: None,
            relief: None,
        }
    }

    /// The clouds preset textures the ceiling alone, over its own colour.
    #[test]
    fn the_clouds_preset_textures_only_the_ceiling() {
        let box_materials = crate::shapes::scene::cornell_box().materials;
        let clouded = TexturePreset::Clouds.apply(&box_materials);
        for (before, after) in box_materials.iter().zip(&clouded) {
            if before.name == CEILING {
                assert_eq!(after.texture, Some(clouds(before.reflectance)));
            } else {
                assert_eq!(after, before);
            }
        }
    }

    /// The angle of reflection equals the angle of incidence, exactly for a 45° ray on an axis
    /// plane: (1, −1, 0)/√2 on the floor (normal (0, −1, 0)) leaves as (1, 1, 0)/√2.
    #[test]
    fn mirror_reflection_angle_is_exact() {
        let d = Vec3::new(1.0, 1.0, 0.0).normalize(); // going down (y points down)
        let n = Vec3::new(0.0, -1.0, 0.0); // the floor faces up
        let r = reflect(d, n);
        assert_eq!(r, Vec3::new(d.x, -d.y, 0.0));
        // Any plane: the cosines with the normal are equal and opposite, the length is kept.
        let n = Vec3::new(0.3, -0.8, 0.52).normalize();
        let d = Vec3::new(0.6, 0.7, -0.2).normalize();
        let r = reflect(d, n);
        assert!((r.dot(n) + d.dot(n)).abs() < 1e-6);
        assert!((r.length() - 1.0).abs() < 1e-6);
        // r lies in the plane of d and n: (d × n) · r = 0.
        assert!(d.cross(n).dot(r).abs() < 1e-6);
        let mirror = Material {
            name: "m".into(),
            reflectance: Vec3::ZERO,
            kind: PRESET_MIRROR,
            texture: None,
            relief: None,
        };
        // Sampled through the BSDF, in the shading frame: the same direction up to the
        // rounding of the change of frame.
        let s = mirror.sample(d, n, n, &mut Rng::new(1)).unwrap();
        assert!(
            (s.direction - r).abs().max_element() < 1e-6,
            "{} {r}",
            s.direction
        );
        assert_eq!(s.weight, Vec3::splat(0.9));
    }

    /// At normal incidence the reflectance is ((n − 1)/(n + 1))²: 0.04 for n = 1.5, from
    /// either side.
    #[test]
    fn glass_at_normal_incidence_reflects_4_percent() {
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-7);
        assert!((fresnel_dielectric(1.0, 1.0 / 1.5) - 0.04).abs() < 1e-7);
        let n = Vec3::new(0.0, 0.0, -1.0);
        let b = glass().specular_branches(Vec3::Z, n);
        let [(r_dir, r_w), (t_dir, t_w)] = b.as_slice() else {
            panic!("two branches")
        };
        assert_eq!(*r_dir, -Vec3::Z);
        assert!((r_w.x - 0.04).abs() < 1e-7);
        assert!((*t_dir - Vec3::Z).length() < 1e-7, "straight through");
        assert!((t_w.x - 0.96).abs() < 1e-7);
    }

    /// Brewster's angle, tan θ = n: the p-polarised reflectance vanishes, so F is half the
    /// s-polarised one. At θ = atan 1.5 = 56.31°, cos θ_t = sin θ = 0.83205, and
    /// r_s = (cos θ − n cos θ_t)/(cos θ + n cos θ_t) = (0.55470 − 1.24808)/(0.55470 + 1.24808)
    /// = −0.38462, so F = r_s²/2 = 0.073964.
    #[test]
    fn fresnel_at_brewsters_angle_is_half_the_s_reflectance() {
        let theta = 1.5f32.atan();
        assert!((fresnel_dielectric(theta.cos(), 1.5) - 0.073964).abs() < 1e-5);
    }

    /// Inside glass of n = 1.5 the critical angle is asin(1/1.5) = 41.81°: past it everything
    /// is reflected, just below it some light leaves, bent to nearly 90°.
    #[test]
    fn total_internal_reflection_past_the_critical_angle() {
        let critical = (1.0f32 / 1.5).asin();
        let outward = Vec3::Y; // a ray inside going +y meets a face whose normal is +y
        let ray = |angle: f32| Vec3::new(angle.sin(), angle.cos(), 0.0);
        for angle in [critical + 0.01, 1.2, 1.5] {
            assert_eq!(fresnel_dielectric(angle.cos(), 1.0 / 1.5), 1.0);
            let b = glass().specular_branches(ray(angle), outward);
            assert_eq!(b.as_slice().len(), 1, "only the reflection");
            assert_eq!(b.as_slice()[0].1, Vec3::ONE);
        }
        let b = glass().specular_branches(ray(critical - 0.01), outward);
        assert_eq!(b.as_slice().len(), 2);
        let (t, _) = b.as_slice()[1];
        // Leaving the glass the ray bends away from the normal: sin θ_t = 1.5 sin θ_i.
        let sin_t = t.x;
        assert!((sin_t - 1.5 * (critical - 0.01).sin()).abs() < 1e-4, "{t}");
        assert!(t.y > 0.0);
    }

    /// Snell's law when entering: sin θ_t = sin θ_i / 1.5.
    #[test]
    fn refraction_obeys_snells_law() {
        let n = Vec3::new(0.0, -1.0, 0.0);
        for angle in [0.1f32, 0.5, 1.0, 1.4] {
            let d = Vec3::new(angle.sin(), angle.cos(), 0.0);
            let b = glass().specular_branches(d, n);
            let (t, _) = b.as_slice()[1];
            assert!((t.x - angle.sin() / 1.5).abs() < 1e-6, "{angle}: {t}");
            assert!(t.y > 0.0 && (t.length() - 1.0).abs() < 1e-6);
        }
    }

    /// A white furnace for the BSDFs: every sample's weight is the tint or 1, and the mean
    /// weight of many glass samples equals the Whitted branches' weights summed (with tint 1:
    /// exactly 1), so glass and mirror neither create nor lose light beyond their tint.
    #[test]
    fn specular_materials_conserve_energy_up_to_their_tint() {
        let mut rng = Rng::new(5);
        let n = Vec3::new(0.0, -1.0, 0.0);
        for angle in [0.0f32, 0.7, 1.3, 1.55] {
            let d = Vec3::new(angle.sin(), angle.cos(), 0.0);
            let branches = glass().specular_branches(d, n);
            let total: Vec3 = branches.as_slice().iter().map(|(_, w)| *w).sum();
            assert!((total - Vec3::ONE).abs().max_element() < 1e-6, "{total}");
            let samples = 20_000;
            let mut reflected = 0;
            for _ in 0..samples {
                let s = glass().sample(d, n, n, &mut rng).unwrap();
                assert_eq!(s.weight, Vec3::ONE);
                if s.direction.y < 0.0 {
                    reflected += 1;
                }
            }
            // The share reflected estimates F: binomial, 4 standard deviations.
            let f = branches.as_slice()[0].1.x;
            let share = reflected as f32 / samples as f32;
            let sd = (f * (1.0 - f) / samples as f32).sqrt();
            assert!(
                (share - f).abs() <= 4.0 * sd + 1e-6,
                "{angle}: {share} vs {f}"
            );
        }
        let tinted = Material {
            name: "g".into(),
            reflectance: Vec3::ZERO,
            kind: MaterialKind::Glass {
                ior: 1.5,
                tint: Vec3::new(0.5, 1.0, 0.25),
            },
            texture: None,
            relief: None,
        };
        let b = tinted.specular_branches(Vec3::Y, n);
        let total: Vec3 = b.as_slice().iter().map(|(_, w)| *w).sum();
        let expected = 0.04 + 0.96 * Vec3::new(0.5, 1.0, 0.25);
        assert!((total - expected).abs().max_element() < 1e-6);
    }

    #[test]
    fn diffuse_samples_leave_on_the_side_the_ray_came_from() {
        let m = Material::diffuse("white", Vec3::splat(0.75));
        let mut rng = Rng::new(9);
        let n = Vec3::new(0.0, 0.0, -1.0);
        for d in [Vec3::Z, -Vec3::Z] {
            for _ in 0..1000 {
                let s = m.sample(d, n, n, &mut rng).unwrap();
                assert!(s.direction.dot(d) < 0.0, "back towards the ray's side");
                assert!((s.direction.length() - 1.0).abs() < 1e-5);
                assert_eq!(s.weight, Vec3::splat(0.75));
            }
        }
    }

    /// The table describes each kind once: unique names, every default within its ranges,
    /// and `values`/`set` agreeing field by field with `fields`.
    #[test]
    fn the_kinds_table_is_consistent() {
        let names: Vec<&str> = MaterialKind::DEFAULTS.iter().map(|k| k.name()).collect();
        assert_eq!(names, ["diffuse", "mirror", "glass", "rough", "plastic"]);
        for kind in MaterialKind::DEFAULTS {
            assert_eq!(MaterialKind::of_name(kind.name()), Ok(*kind));
            kind.check(|f| f.to_owned()).unwrap();
            assert_eq!(kind.fields().len(), kind.values().len());
            let mut copy = *kind;
            for (field, value) in kind.fields_and_values() {
                assert_eq!(field.colour, matches!(value, FieldValue::Colour(_)));
                // Setting each field to its top of range changes that field alone.
                let top = match value {
                    FieldValue::Number(_) => FieldValue::Number(field.range[1]),
                    FieldValue::Colour(_) => FieldValue::Colour(Vec3::splat(field.range[1])),
                };
                copy.set(field.name, top).unwrap();
                let i = kind
                    .fields()
                    .iter()
                    .position(|f| f.name == field.name)
                    .unwrap();
                assert_eq!(copy.values()[i], top);
            }
        }
        assert_eq!(MaterialKind::of_name("plastic"), Ok(preset_plastic(0.1)));
        assert_eq!(MaterialKind::of_name("mirror"), Ok(PRESET_MIRROR));
        assert_eq!(MaterialKind::of_name("glass"), Ok(PRESET_GLASS));
    }

    /// Materials in the form the scene file and the settings JSON held before the table
    /// (serde's tagged enum) read as the same kinds, and every kind is written back to it.
    #[test]
    fn materials_read_and_write_the_earlier_format() {
        let old = [
            (r#"{"kind":"diffuse"}"#, MaterialKind::Diffuse),
            (r#"{"kind":"mirror","tint":[0.9,0.9,0.9]}"#, PRESET_MIRROR),
            (
                r#"{"kind":"glass","ior":1.5,"tint":[1.0,1.0,1.0]}"#,
                PRESET_GLASS,
            ),
            (
                r#"{"kind":"rough","alpha":0.2,"tint":[0.9,0.9,0.9]}"#,
                MaterialKind::Rough {
                    alpha: 0.2,
                    tint: Vec3::splat(0.9),
                },
            ),
            (
                r#"{"kind":"plastic","alpha":0.25,"int_ior":1.4,"ext_ior":1.0,"specular":[1.0,0.9,0.8]}"#,
                MaterialKind::Plastic {
                    alpha: 0.25,
                    int_ior: 1.4,
                    ext_ior: 1.0,
                    specular: Vec3::new(1.0, 0.9, 0.8),
                },
            ),
        ];
        for (text, kind) in old {
            assert_eq!(
                serde_json::from_str::<MaterialKind>(text).unwrap(),
                kind,
                "{text}"
            );
            assert_eq!(serde_json::to_string(&kind).unwrap(), text);
        }
        // The kind may come after its fields; integers are numbers.
        let k: MaterialKind =
            serde_json::from_str(r#"{"ior":2,"tint":[1,1,1],"kind":"glass"}"#).unwrap();
        assert_eq!(
            k,
            MaterialKind::Glass {
                ior: 2.0,
                tint: Vec3::ONE
            }
        );
        for (text, error) in [
            (
                r#"{"kind":"gold"}"#,
                "unknown material kind 'gold' (expected diffuse, mirror",
            ),
            (
                r#"{"kind":"mirror","tint":[1,1,1],"ior":1.5}"#,
                "unknown field `ior`",
            ),
            (r#"{"kind":"mirror"}"#, "missing field `tint`"),
            (r#"{"tint":[1,1,1]}"#, "missing field `kind`"),
            (r#"{"kind":"mirror","tint":[1,1]}"#, "invalid length 2"),
            (
                r#"{"kind":"mirror","tint":[1,1,1,1]}"#,
                "more than 3 elements",
            ),
            (
                r#"{"kind":"glass","ior":[1,1,1],"tint":[1,1,1]}"#,
                "'ior' is one number",
            ),
        ] {
            let e = serde_json::from_str::<MaterialKind>(text)
                .unwrap_err()
                .to_string();
            assert!(e.contains(error), "{text}: {e}");
        }
    }

    /// `--material`'s form: the kind, then fields by name; defaults for the rest; one-line
    /// errors naming the kind, the field or the range.
    #[test]
    fn a_material_parses_from_its_kind_and_fields() {
        assert_eq!(
            MaterialKind::parse("plastic:alpha=0.2,int_ior=1.6"),
            Ok(MaterialKind::Plastic {
                alpha: 0.2,
                int_ior: 1.6,
                ext_ior: 1.0,
                specular: Vec3::ONE
            })
        );
        assert_eq!(
            MaterialKind::parse("mirror:tint=0.9,0.8,0.7"),
            Ok(MaterialKind::Mirror {
                tint: Vec3::new(0.9, 0.8, 0.7)
            })
        );
        assert_eq!(
            MaterialKind::parse("rough:tint=0.5,alpha=0.3"),
            Ok(MaterialKind::Rough {
                alpha: 0.3,
                tint: Vec3::splat(0.5)
            })
        );
        assert_eq!(MaterialKind::parse("diffuse"), Ok(MaterialKind::Diffuse));
        assert_eq!(MaterialKind::parse("glass"), Ok(PRESET_GLASS));
        for (text, error) in [
            (
                "gold",
                "unknown material kind 'gold' (expected diffuse, mirror, glass, rough or plastic)",
            ),
            (
                "mirror:ior=1.5",
                "unknown field `ior` for a mirror material (its fields: tint)",
            ),
            (
                "diffuse:tint=1",
                "unknown field `tint`: a diffuse material has no fields",
            ),
            (
                "rough:alpha=2",
                "invalid material alpha 2: must be in [0.01, 1]",
            ),
            (
                "glass:tint=1,1.5,1",
                "invalid material tint [1, 1.5, 1]: must be in [0, 1]",
            ),
            (
                "plastic:int_ior=1",
                "invalid material int_ior 1: must differ from ext_ior",
            ),
            ("rough:alpha=x", "'x' in 'alpha=x' is not a number"),
            ("mirror:0.5", "'0.5': give each value as field=value"),
            ("mirror:tint=1,1", "'tint' has 2 numbers"),
            ("glass:ior=1,1,1", "'ior' is one number, not a colour"),
        ] {
            let e = MaterialKind::parse(text).unwrap_err();
            assert!(e.contains(error), "{text}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn presets_change_the_blocks_by_name() {
        let box_materials = crate::shapes::scene::cornell_box().materials;
        assert_eq!(
            MaterialPreset::None.apply(&box_materials, DEFAULT_ROUGHNESS),
            box_materials
        );
        let both = MaterialPreset::Both.apply(&box_materials, DEFAULT_ROUGHNESS);
        let kind = |name: &str| both.iter().find(|m| m.name == name).unwrap().kind;
        assert_eq!(kind("blue"), PRESET_MIRROR);
        assert_eq!(kind("red"), PRESET_GLASS);
        assert_eq!(kind("white"), MaterialKind::Diffuse);
        let mirror = MaterialPreset::Mirror.apply(&box_materials, DEFAULT_ROUGHNESS);
        assert_eq!(mirror.iter().filter(|m| !m.is_diffuse()).count(), 1);
        for p in MaterialPreset::ALL {
            assert_eq!(p.name().parse::<MaterialPreset>(), Ok(p));
        }
        assert!("gold".parse::<MaterialPreset>().is_err());
    }
}

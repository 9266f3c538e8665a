//! The options' values as clap reads them: numbers, points, colours, angles, pixels,
//! `--material`.

use glam::Vec3;
use raylab_core::shading::material::MaterialKind;
use raylab_core::shapes::scene::spec::{BoxPart, PartMaterial};
use raylab_core::transport::settings::{MAX_EXPOSURE, MAX_IMAGE_SIDE, MAX_SAMPLES};

/// The `--pixel` value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pixel(pub u32, pub u32);

/// The `--bounces` value: a cap, or unlimited.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounces(pub Option<u32>);

/// The `--indirect` value: a constant N, or off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Indirect {
    Off,
    Constant(f32),
}

pub(super) fn parse_finite(s: &str) -> Result<f32, String> {
    finite(s)
}

/// `--material`'s long help: the kinds and their fields as the kinds' table lists them.
pub(super) fn part_material_help() -> String {
    let kinds: Vec<String> = MaterialKind::DEFAULTS
        .iter()
        .map(|k| {
            let fields: Vec<String> = k
                .fields()
                .iter()
                .map(|f| {
                    let [lo, hi] = f.range;
                    format!("{} in [{lo}, {hi}]: {}", f.name, f.what)
                })
                .collect();
            match fields.is_empty() {
                true => format!("  {}: no fields", k.name()),
                false => format!("  {}: {}", k.name(), fields.join("; ")),
            }
        })
        .collect();
    format!(
        "A part of the box given a material of its own, over --material-preset: PART=KIND, \
         then optionally :FIELD=VALUE,… (a colour's three channels separated by commas too, or \
         one number for a grey); fields left out keep their defaults. Repeat for more parts. \
         PART: tall (the tall block), short, floor, left-wall, right-wall, back-wall, ceiling. \
         KIND and its fields:\n{}\nFor example --material tall=plastic:alpha=0.2,int_ior=1.5 \
         --material short=mirror:tint=0.9,0.8,0.7",
        kinds.join("\n")
    )
}

/// `--material PART=KIND[:FIELD=VALUE,…]`: the part by its name (`tall` and `short` for the
/// blocks), the material through its kind's table ([`MaterialKind::parse`]).
pub(super) fn parse_part_material(s: &str) -> Result<PartMaterial, String> {
    let Some((part, material)) = s.split_once('=') else {
        return Err(format!(
            "'{s}': give the part and its material as PART=KIND, e.g. tall=plastic:alpha=0.2"
        ));
    };
    let part = match part.trim() {
        "tall" => BoxPart::TallBlock,
        "short" => BoxPart::ShortBlock,
        other => other
            .parse::<BoxPart>()
            .map_err(|e| format!("{e}; or tall, short for the blocks"))?,
    };
    let kind = MaterialKind::parse(material)?;
    Ok(PartMaterial { part, kind })
}

/// An angle in degrees (`--yaw`, `--pitch`), read as an `f64`: the same number gives the same
/// radians as in a scene file (`camera::radians`).
pub(super) fn parse_degrees(s: &str) -> Result<f64, String> {
    finite(s)
}

/// A number that is finite as an `f32`.
pub(super) fn finite<T: std::str::FromStr + Into<f64> + Copy>(s: &str) -> Result<T, String> {
    let x: T = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))?;
    if (x.into() as f32).is_finite() {
        Ok(x)
    } else {
        Err(format!("{s} is not a finite number"))
    }
}

pub(super) fn parse_positive(s: &str) -> Result<f32, String> {
    let x = parse_finite(s)?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(format!("{s} must be > 0"))
    }
}

pub(super) fn parse_non_negative(s: &str) -> Result<f32, String> {
    let x = parse_finite(s)?;
    if x >= 0.0 {
        Ok(x)
    } else {
        Err(format!("{s} must be ≥ 0"))
    }
}

pub(super) fn parse_side(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(n) if (1..=MAX_IMAGE_SIDE).contains(&n) => Ok(n),
        _ => Err(format!(
            "{s} must be a whole number of pixels from 1 to {MAX_IMAGE_SIDE}"
        )),
    }
}

pub(super) fn parse_samples(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(n) if (1..=MAX_SAMPLES).contains(&n) => Ok(n),
        _ => Err(format!(
            "{s} must be a whole number from 1 to {MAX_SAMPLES}"
        )),
    }
}

pub(super) fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').collect();
    let [x, y, z] = parts[..] else {
        return Err(format!("'{s}' is not three numbers X,Y,Z"));
    };
    Ok(Vec3::new(
        parse_finite(x)?,
        parse_finite(y)?,
        parse_finite(z)?,
    ))
}

pub(super) fn parse_colour(s: &str) -> Result<Vec3, String> {
    let c = parse_vec3(s)?;
    if c.min_element() >= 0.0 {
        Ok(c)
    } else {
        Err(format!("{s}: each channel must be ≥ 0"))
    }
}

pub(super) fn parse_exposure(s: &str) -> Result<f32, String> {
    let x = parse_finite(s)?;
    if x.abs() <= MAX_EXPOSURE {
        Ok(x)
    } else {
        Err(format!(
            "{s} must be between -{MAX_EXPOSURE} and {MAX_EXPOSURE} stops"
        ))
    }
}

pub(super) fn parse_on_off(s: &str) -> Result<bool, String> {
    match s {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("'{s}' is neither on nor off")),
    }
}

pub(super) fn parse_pixel(s: &str) -> Result<Pixel, String> {
    let parts: Vec<&str> = s.split(',').collect();
    let bad = || format!("'{s}' is not a pixel X,Y (two whole numbers ≥ 0)");
    let [x, y] = parts[..] else {
        return Err(bad());
    };
    match (x.trim().parse::<u32>(), y.trim().parse::<u32>()) {
        (Ok(x), Ok(y)) => Ok(Pixel(x, y)),
        _ => Err(bad()),
    }
}

pub(super) fn parse_bounces(s: &str) -> Result<Bounces, String> {
    if s == "unlimited" {
        return Ok(Bounces(None));
    }
    match s.trim().parse::<u32>() {
        Ok(n) => Ok(Bounces(Some(n))),
        _ => Err(format!(
            "'{s}' is neither a whole number of bounces nor unlimited"
        )),
    }
}

pub(super) fn parse_indirect(s: &str) -> Result<Indirect, String> {
    if s == "off" {
        Ok(Indirect::Off)
    } else {
        parse_non_negative(s).map(Indirect::Constant)
    }
}

//! Which term is off: the student's quantity and the lab's evaluated at a
//! few thousand random valid inputs (hit points, normals, lights, cameras), as WeBWorK checks a
//! typed formula at random points. The answer: equal to the lab's (any algebraic rewrite), a
//! classic mistake of the catalogue, two inputs swapped, a constant factor (such as 4π), a
//! power of the distance, the sign, or (for `D`) a difference only where the cosine is
//! negative or in shadow.
//!
//! The lab's values are the renderer's own code: [`DirectLight::at`] for D,
//! [`shaded_value`] for R, [`Camera::primary_ray_rotated`] for d, [`shadow_ray`] for
//! the shadow ray's start; the mistakes' are [`check`]'s.
//!
//! [`check`]: crate::teaching::check
//! [`DirectLight::at`]: crate::shading::light::DirectLight::at

use std::fmt;

use glam::Vec3;

use super::compile::Equations;
use super::{INPUT_COMPONENTS, INPUTS, Quantity, Ty, offset};
use crate::base::camera::Camera;
use crate::base::sampling::Rng;
use crate::shading::light::{LightKind, LightSpec, shadow_ray};
use crate::teaching::check::mistakes::{Mistake, mistaken_direct};
use crate::transport::integrator::{Stage, shaded_value};

/// How many random inputs a quantity is judged at.
pub const SAMPLES: usize = 4096;

/// Relative difference within which two values are equal (rounding of an algebraic rewrite).
const EQUAL: f32 = 1e-4;

/// How the student's quantity compares with the lab's.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// Equal to the lab's at every input (an algebraic rewrite at most).
    Equal,
    /// Equal to a classic mistake's formula.
    Mistake(Mistake),
    /// Equal to the lab's with these two inputs swapped.
    Swapped(&'static str, &'static str),
    /// The lab's times this constant (−1: the sign).
    Factor(f32),
    /// The lab's times `factor · r^power`, r the distance to the light.
    DistancePower { power: f32, factor: f32 },
    /// Equal where the surface faces the light; not 0 where the cosine is negative.
    NegativeCosine,
    /// Equal out of shadow; not 0 in shadow.
    NotZeroInShadow,
    /// None of these: the inputs where it differs most, as text, and both values.
    Differs {
        at: String,
        yours: String,
        lab: String,
    },
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Verdict::Equal => write!(f, "equal to the lab's"),
            Verdict::Mistake(m) => {
                write!(f, "the classic mistake {}: {}. {}", m, m.what(), m.fix())
            }
            Verdict::Swapped(a, b) => {
                write!(
                    f,
                    "equal to the lab's with `{a}` and `{b}` swapped: swap them back"
                )
            }
            Verdict::Factor(k) if (*k + 1.0).abs() < 1e-3 => {
                write!(
                    f,
                    "the lab's with the opposite sign: check the order of a subtraction"
                )
            }
            Verdict::Factor(k) => {
                write!(f, "the lab's times a constant factor {}", factor_name(*k))
            }
            Verdict::DistancePower { power, factor } => {
                let falls = 2.0 - power;
                write!(
                    f,
                    "falls as 1/r^{} instead of 1/r² (the lab's times {}·r^{}): a power of the \
                     distance",
                    round(falls),
                    factor_name(*factor),
                    round(*power)
                )
            }
            Verdict::NegativeCosine => write!(
                f,
                "equal where the surface faces the light, but not 0 where the cosine is \
                 negative: clamp it, max(dot(…), 0)"
            ),
            Verdict::NotZeroInShadow => write!(
                f,
                "equal out of shadow, but not 0 in shadow: D includes the shadow, `shadowed ? \
                 vec3(0) : …`"
            ),
            Verdict::Differs { at, yours, lab } => {
                write!(
                    f,
                    "differs from the lab's: at {at}, yours is {yours} where the lab's is {lab}"
                )
            }
        }
    }
}

fn round(x: f32) -> String {
    let r = x.round();
    if (x - r).abs() < 0.01 {
        format!("{r}")
    } else {
        format!("{x:.2}")
    }
}

/// `k` by name where it is a constant of the lab (4π, π, their inverses), else its digits.
fn factor_name(k: f32) -> String {
    use std::f32::consts::PI;
    let named = [
        (4.0 * PI, "4π"),
        (1.0 / (4.0 * PI), "1/(4π)"),
        (PI, "π"),
        (1.0 / PI, "1/π"),
        (2.0, "2"),
        (0.5, "1/2"),
    ];
    named
        .iter()
        .find(|(v, _)| ((k - v) / v).abs() < 1e-3)
        .map_or_else(|| format!("{k}"), |(_, n)| (*n).to_owned())
}

/// One random input: every input component, and the lab's values at it.
struct Sample {
    inputs: Vec<f32>,
    /// r̂·n̂ and |r| (D's classification).
    cos: f32,
    r: f32,
    shadowed: bool,
    /// D's size facing the light, P/(4πr²): D is compared within [`EQUAL`] of it, so that
    /// where the cosine is near 0 the rounding of r̂ is not a difference.
    scale: f32,
}

/// Judges quantity `q` of `equations` against the lab's at [`SAMPLES`] random inputs, for
/// the lab's `stage` (R's formula depends on it). `None` when `q` is not written.
pub fn judge(equations: &Equations, q: Quantity, stage: Stage) -> Option<Verdict> {
    let tape = equations.tape(q)?;
    let mut rng = Rng::new(40);
    let samples: Vec<Sample> = (0..SAMPLES).map(|_| sample(&mut rng)).collect();
    let mut slots = Vec::new();
    let mut yours = |inputs: &[f32]| Vec3::from_array(tape.run_one(inputs, &mut slots));
    let student: Vec<Vec3> = samples.iter().map(|s| yours(&s.inputs)).collect();
    let lab: Vec<Vec3> = samples
        .iter()
        .map(|s| lab_value(q, stage, s, Mistake::None))
        .collect();
    if agree(q, &samples, &student, &lab) {
        return Some(Verdict::Equal);
    }
    for m in candidates(q, stage) {
        let theirs: Vec<Vec3> = samples.iter().map(|s| lab_value(q, stage, s, m)).collect();
        if agree(q, &samples, &student, &theirs) {
            return Some(Verdict::Mistake(m));
        }
    }
    // Two inputs of one type swapped.
    let usable: Vec<_> = INPUTS
        .iter()
        .filter(|i| i.available_in(q) && i.ty != Ty::Bool && i.from > Quantity::Direction)
        .collect();
    for (k, a) in usable.iter().enumerate() {
        for b in usable[k + 1..].iter().filter(|b| b.ty == a.ty) {
            let swapped: Vec<Vec3> = samples
                .iter()
                .map(|s| {
                    let mut inputs = s.inputs.clone();
                    for c in 0..a.ty.width() {
                        inputs.swap(usize::from(a.offset) + c, usize::from(b.offset) + c);
                    }
                    yours(&inputs)
                })
                .collect();
            if agree(q, &samples, &swapped, &lab) {
                return Some(Verdict::Swapped(a.name, b.name));
            }
        }
    }
    if q.ty() == Ty::Bool {
        return Some(differs(&samples, &student, &lab, q));
    }
    // Where the lab's is not 0 (for D: out of shadow, facing the light).
    let lit: Vec<usize> = (0..SAMPLES).filter(|&i| lab[i] != Vec3::ZERO).collect();
    let ratio = |i: usize| {
        let (s, l) = (student[i], lab[i]);
        let k = l.abs().max_position();
        s[k] / l[k]
    };
    let scales: Vec<f32> = samples
        .iter()
        .map(|s| if q == Quantity::Direct { s.scale } else { 0.0 })
        .collect();
    let equal_on = |set: &[usize], f: &dyn Fn(usize) -> Vec3| {
        set.iter().all(|&i| close(student[i], f(i), scales[i]))
    };
    // A factor or a power holds everywhere, the lab's zeros staying 0.
    let every: Vec<usize> = (0..SAMPLES).collect();
    if let Some(&first) = lit.first() {
        let k = ratio(first);
        if k.is_finite() && k != 0.0 && equal_on(&every, &|i| lab[i] * k) {
            return Some(Verdict::Factor(k));
        }
        if q == Quantity::Direct {
            // log(yours/lab) = log(factor) + power·log(r), fitted on two samples and checked on
            // all.
            if let Some(&second) = lit
                .iter()
                .find(|&&i| (samples[i].r / samples[first].r - 1.0).abs() > 0.2)
            {
                let (k1, k2) = (ratio(first), ratio(second));
                let power = (k2 / k1).ln() / (samples[second].r / samples[first].r).ln();
                let factor = k1 / samples[first].r.powf(power);
                if power.is_finite()
                    && factor.is_finite()
                    && equal_on(&every, &|i| lab[i] * (factor * samples[i].r.powf(power)))
                {
                    return Some(Verdict::DistancePower { power, factor });
                }
            }
            let facing: Vec<usize> = (0..SAMPLES)
                .filter(|&i| !samples[i].shadowed && samples[i].cos > 0.0)
                .collect();
            let unshadowed_equal = equal_on(&facing, &|i| lab[i]);
            if unshadowed_equal {
                let facing_away_zero = (0..SAMPLES)
                    .filter(|&i| !samples[i].shadowed && samples[i].cos <= 0.0)
                    .all(|i| student[i] == Vec3::ZERO);
                if !facing_away_zero {
                    return Some(Verdict::NegativeCosine);
                }
                return Some(Verdict::NotZeroInShadow);
            }
        }
    }
    Some(differs(&samples, &student, &lab, q))
}

/// The mistakes of the catalogue whose formula is this quantity's.
fn candidates(q: Quantity, stage: Stage) -> Vec<Mistake> {
    use Mistake::*;
    match q {
        Quantity::Direction => vec![PixelCorner, Eq24Typo, FocalHalf],
        Quantity::ShadowStart => vec![ShadowAcne],
        Quantity::Shadowed => vec![ShadowBeyondLight],
        Quantity::Direct => vec![No4Pi, InverseR, UnclampedCos, FlippedNormal],
        Quantity::Value if stage.reflects_light() => {
            vec![NoRho, IndirectOutsideRho, ShadowDropsIndirect]
        }
        Quantity::Value => vec![],
    }
}

/// Whether two lists of values agree everywhere (bools: exactly; `d`: as directions, the
/// ray normalises it; the rest within [`EQUAL`]).
fn agree(q: Quantity, samples: &[Sample], a: &[Vec3], b: &[Vec3]) -> bool {
    a.iter().zip(b).zip(samples).all(|((x, y), s)| match q {
        Quantity::Shadowed => (x.x != 0.0) == (y.x != 0.0),
        Quantity::Direction => close(x.normalize_or_zero(), y.normalize_or_zero(), 0.0),
        // Within a hundredth of the lab's offset: the rounding of a lifted point.
        Quantity::ShadowStart => (*x - *y).length() <= 1e-6,
        Quantity::Direct => close(*x, *y, s.scale),
        Quantity::Value => close(*x, *y, 0.0),
    })
}

/// Whether `a` and `b` are within [`EQUAL`] of the larger of them and `scale` (a NaN or an
/// infinity is close only to the same value).
fn close(a: Vec3, b: Vec3, scale: f32) -> bool {
    if a == b {
        return true;
    }
    if !a.is_finite() || !b.is_finite() {
        return false;
    }
    let scale = a.length().max(b.length()).max(scale);
    (a - b).length() <= EQUAL * scale
}

fn differs(samples: &[Sample], student: &[Vec3], lab: &[Vec3], q: Quantity) -> Verdict {
    let i = (0..samples.len())
        .max_by(|&i, &j| {
            let e = |k: usize| {
                let d = (student[k] - lab[k]).length();
                if d.is_nan() { f32::INFINITY } else { d }
            };
            e(i).total_cmp(&e(j))
        })
        .unwrap_or(0);
    let s = &samples[i].inputs;
    let names: &[&str] = match q {
        Quantity::Direction => &["x", "y", "W", "H"],
        Quantity::ShadowStart => &["position", "normal", "lightPos"],
        Quantity::Shadowed => &["shadowDistance", "shadowStart", "lightPos"],
        Quantity::Direct => &["position", "normal", "lightPos", "shadowed"],
        Quantity::Value => &["color", "D", "indirectLight", "shadowed"],
    };
    let at = names
        .iter()
        .map(|n| format!("{n} = {}", show(s, n)))
        .collect::<Vec<_>>()
        .join(", ");
    let value = |v: Vec3| match q.ty() {
        Ty::Bool => format!("{}", v.x != 0.0),
        _ => format!("({:.4}, {:.4}, {:.4})", v.x, v.y, v.z),
    };
    Verdict::Differs {
        at,
        yours: value(student[i]),
        lab: value(lab[i]),
    }
}

fn show(inputs: &[f32], name: &str) -> String {
    let Some(i) = super::input(name) else {
        return String::new();
    };
    let k = usize::from(i.offset);
    match i.ty {
        Ty::Vec3 => format!(
            "({:.3}, {:.3}, {:.3})",
            inputs[k],
            inputs[k + 1],
            inputs[k + 2]
        ),
        Ty::Bool => format!("{}", inputs[k] != 0.0),
        Ty::Number => format!("{:.3}", inputs[k]),
    }
}

fn vec_at(inputs: &[f32], name: &str) -> Vec3 {
    let k = offset(name);
    Vec3::new(inputs[k], inputs[k + 1], inputs[k + 2])
}

/// The lab's light at `inputs`: a point at `lightPos` with power per channel `lightColor`.
fn light_at(inputs: &[f32]) -> LightSpec {
    LightSpec {
        position: vec_at(inputs, "lightPos"),
        power: 1.0,
        colour: vec_at(inputs, "lightColor"),
        kind: LightKind::Point,
    }
}

/// The lab's camera at `inputs` (its axes are the sample's).
fn camera_at(inputs: &[f32], focal_scale: f32) -> (Camera, glam::Mat3) {
    let mut camera = Camera::default_for(inputs[offset("W")] as u32, inputs[offset("H")] as u32);
    camera.focal_length = inputs[offset("focalLength")] * focal_scale;
    camera.position = vec_at(inputs, "cameraPos");
    let rotation = glam::Mat3::from_cols(
        vec_at(inputs, "right"),
        vec_at(inputs, "down"),
        vec_at(inputs, "forward"),
    );
    (camera, rotation)
}

/// Quantity `q` at a sample as the lab computes it, or as `mistake` does.
fn lab_value(q: Quantity, stage: Stage, s: &Sample, mistake: Mistake) -> Vec3 {
    let i = &s.inputs;
    let number = |n: &str| i[offset(n)];
    let light = light_at(i);
    let (position, normal) = (vec_at(i, "position"), vec_at(i, "normal"));
    let truth = |b: bool| Vec3::splat(if b { 1.0 } else { 0.0 });
    match q {
        Quantity::Direction => {
            let (focal, corner, typo) = match mistake {
                Mistake::FocalHalf => (0.5, 0.5, false),
                Mistake::PixelCorner => (1.0, 0.0, false),
                Mistake::Eq24Typo => (1.0, 0.5, true),
                _ => (1.0, 0.5, false),
            };
            let (mut camera, rotation) = camera_at(i, focal);
            if typo {
                // y − W/2 where y − H/2 belongs.
                camera.height = camera.width;
            }
            camera
                .primary_ray_rotated(&rotation, number("x") + corner, number("y") + corner)
                .direction
        }
        Quantity::ShadowStart => match mistake {
            Mistake::ShadowAcne => position,
            _ => shadow_ray(&light, position, normal, None).map_or(position, |(ray, _)| {
                // The ray's origin is its start moved along by the offset it skips: the start
                // is the point lifted off the surface.
                ray.origin - ray.direction * crate::shading::light::SHADOW_OFFSET
            }),
        },
        Quantity::Shadowed => {
            let distance = number("shadowDistance");
            let to_light = (light.position - vec_at(i, "shadowStart")).length();
            truth(match mistake {
                Mistake::ShadowBeyondLight => distance < f32::INFINITY,
                _ => distance < to_light,
            })
        }
        Quantity::Direct => {
            let d = match mistake {
                Mistake::FlippedNormal => mistaken_direct(&light, mistake, position, -normal),
                _ => mistaken_direct(&light, mistake, position, normal),
            };
            if s.shadowed { Vec3::ZERO } else { d }
        }
        Quantity::Value => {
            let (rho, d, n) = (
                vec_at(i, "color"),
                vec_at(i, "D"),
                vec_at(i, "indirectLight"),
            );
            match mistake {
                Mistake::NoRho => shaded_value(Stage::Incoming, rho, d, false, n),
                Mistake::IndirectOutsideRho => rho * d + n,
                Mistake::ShadowDropsIndirect if s.shadowed => Vec3::ZERO,
                _ => shaded_value(stage, rho, d, false, n),
            }
        }
    }
}

/// A random valid input: a light and a hit 0.05 to 3.5 apart in the box's scale, a unit
/// normal facing anywhere, positive powers and reflectances, a camera turned anywhere and a
/// pixel in its image, a shadow distance before, beyond or without a surface.
fn sample(rng: &mut Rng) -> Sample {
    let mut inputs = vec![0.0f32; INPUT_COMPONENTS];
    let mut put = |name: &str, v: &[f32]| {
        let k = offset(name);
        inputs[k..k + v.len()].copy_from_slice(v);
    };
    let point = |rng: &mut Rng| {
        Vec3::new(
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
        )
    };
    let light = point(rng);
    let position = loop {
        let p = point(rng);
        if (light - p).length() > 0.05 {
            break p;
        }
    };
    let normal = loop {
        let n = point(rng);
        if n.length() > 0.1 && n.length() <= 1.0 {
            break n.normalize();
        }
    };
    let r = (light - position).length();
    let cos = (light - position).dot(normal) / r;
    let shadowed = rng.next_f32() < 0.3;
    let positive = |rng: &mut Rng, lo: f32, hi: f32| [0; 3].map(|_| rng.uniform(lo, hi));
    put("lightPos", &light.to_array());
    put("position", &position.to_array());
    put("normal", &normal.to_array());
    let power = Vec3::from_array(positive(rng, 1.0, 20.0));
    put("lightColor", &power.to_array());
    put("color", &positive(rng, 0.05, 1.0));
    put("indirectLight", &positive(rng, 0.05, 0.5));
    put("D", &positive(rng, 0.0, 2.0));
    put("distance", &[rng.uniform(0.1, 5.0)]);
    let start = position + normal * (if cos >= 0.0 { 1e-4 } else { -1e-4 });
    put("shadowStart", &start.to_array());
    let to_light = (light - start).length();
    let shadow_distance = match rng.next_u32() % 3 {
        0 => f32::INFINITY,
        1 => rng.uniform(0.0, to_light),
        _ => rng.uniform(to_light * 1.01, to_light * 3.0),
    };
    put("shadowDistance", &[shadow_distance]);
    put("shadowed", &[if shadowed { 1.0 } else { 0.0 }]);
    let (w, h) = (16 + rng.next_u32() % 500, 16 + rng.next_u32() % 500);
    put("W", &[w as f32]);
    put("H", &[h as f32]);
    put("focalLength", &[w as f32 * rng.uniform(0.5, 2.0)]);
    put("x", &[(rng.next_u32() % w) as f32]);
    put("y", &[(rng.next_u32() % h) as f32]);
    put("cameraPos", &point(rng).to_array());
    let rotation = glam::Mat3::from_rotation_y(rng.uniform(-3.0, 3.0))
        * glam::Mat3::from_rotation_x(rng.uniform(-1.0, 1.0));
    put("right", &rotation.x_axis.to_array());
    put("down", &rotation.y_axis.to_array());
    put("forward", &rotation.z_axis.to_array());
    Sample {
        inputs,
        cos,
        r,
        shadowed,
        scale: power.length() / (4.0 * std::f32::consts::PI * r * r),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::teaching::sandbox::compile;

    const R: &str = "vec3 r = lightPos - position;\n";

    fn verdict(text: &str, q: Quantity) -> Verdict {
        let equations = compile(text).unwrap_or_else(|e| panic!("{text}: {e:?}"));
        judge(&equations, q, Stage::Lab).unwrap()
    }

    fn d(body: &str) -> Verdict {
        verdict(&format!("{R}D = {body}"), Quantity::Direct)
    }

    /// The lab's quantities and algebraic rewrites of them (r·r for |r|², normalising before
    /// or after, C++ spellings) are equal to the lab's.
    #[test]
    fn rewrites_are_equal() {
        for body in [
            "shadowed ? vec3(0) : lightColor * max(dot(r / length(r), normal), 0.0) / (4 * pi * dot(r, r))",
            "shadowed ? vec3(0) : lightColor * max(dot(normalize(r), normal), 0.0f) / (4.f * M_PI * pow(length(r), 2))",
            "shadowed ? vec3(0) : max(dot(r, normal) / length(r), 0) * lightColor / (4 * pi * length(r) * length(r))",
            "!shadowed ? lightColor / (4 * pi) * std::max(glm::dot(normal, r), 0.0f) / (dot(r, r) * length(r)) : vec3(0.0)",
        ] {
            assert_eq!(d(body), Verdict::Equal, "{body}");
        }
        for (text, q) in [
            ("R = color * (D + indirectLight)", Quantity::Value),
            ("R = color * D + color * indirectLight", Quantity::Value),
            (
                "shadowed = shadowDistance < length(lightPos - shadowStart)",
                Quantity::Shadowed,
            ),
            (
                "shadowed = shadowDistance * shadowDistance < dot(lightPos - shadowStart, lightPos - shadowStart)",
                Quantity::Shadowed,
            ),
            (
                "d = right * (x + 0.5 - W / 2) + down * (y + 0.5 - H / 2) + forward * focalLength",
                Quantity::Direction,
            ),
            (
                "d = normalize(right * (x + 0.5 - W / 2) + down * (y + 0.5 - H / 2) + forward * focalLength)",
                Quantity::Direction,
            ),
            (
                "shadowStart = position + normal * (dot(lightPos - position, normal) < 0 ? -1e-4 : 1e-4)",
                Quantity::ShadowStart,
            ),
        ] {
            assert_eq!(verdict(text, q), Verdict::Equal, "{text}");
        }
    }

    /// Every formula mistake of the catalogue, typed, is named.
    #[test]
    fn the_catalogues_mistakes_are_named() {
        let cases: [(&str, Quantity, Mistake); 10] = [
            (
                "D = shadowed ? vec3(0) : lightColor * max(dot(normalize(r), normal), 0.0) / dot(r, r)",
                Quantity::Direct,
                Mistake::No4Pi,
            ),
            (
                "D = shadowed ? vec3(0) : lightColor * max(dot(normalize(r), normal), 0.0) / (4 * pi * length(r))",
                Quantity::Direct,
                Mistake::InverseR,
            ),
            (
                "D = shadowed ? vec3(0) : lightColor * dot(normalize(r), normal) / (4 * pi * dot(r, r))",
                Quantity::Direct,
                Mistake::UnclampedCos,
            ),
            (
                "D = shadowed ? vec3(0) : lightColor * max(dot(normalize(position - lightPos), normal), 0.0) / (4 * pi * dot(r, r))",
                Quantity::Direct,
                Mistake::FlippedNormal,
            ),
            ("R = D + indirectLight", Quantity::Value, Mistake::NoRho),
            (
                "R = color * D + indirectLight",
                Quantity::Value,
                Mistake::IndirectOutsideRho,
            ),
            (
                "R = shadowed ? vec3(0) : color * (D + indirectLight)",
                Quantity::Value,
                Mistake::ShadowDropsIndirect,
            ),
            (
                "shadowStart = position",
                Quantity::ShadowStart,
                Mistake::ShadowAcne,
            ),
            (
                "shadowed = shadowDistance < 1e30",
                Quantity::Shadowed,
                Mistake::ShadowBeyondLight,
            ),
            (
                "d = right * (x - W / 2) + down * (y - H / 2) + forward * focalLength",
                Quantity::Direction,
                Mistake::PixelCorner,
            ),
        ];
        for (text, q, m) in cases {
            let v = verdict(&format!("{R}{text}"), q);
            assert_eq!(v, Verdict::Mistake(m), "{text}");
            assert!(v.to_string().contains(m.name()), "{v}");
        }
    }

    /// Differences that are no mistake of the catalogue are described: a factor, the sign, a
    /// power of the distance, a negative cosine, the shadow forgotten, two inputs swapped.
    #[test]
    fn other_differences_are_described() {
        let lab = "lightColor * max(dot(normalize(r), normal), 0.0) / (4 * pi * dot(r, r))";
        assert_eq!(
            d(&format!("shadowed ? vec3(0) : 2 * {lab}")),
            Verdict::Factor(2.0)
        );
        let v = verdict("R = 4 * pi * color * (D + indirectLight)", Quantity::Value);
        assert!(v.to_string().contains("constant factor 4π"), "{v}");
        let v = d(&format!("shadowed ? vec3(0) : {lab} / (4 * pi)"));
        assert!(v.to_string().contains("constant factor 1/(4π)"), "{v}");
        let v = verdict("R = -color * (D + indirectLight)", Quantity::Value);
        assert!(v.to_string().contains("opposite sign"), "{v}");
        let v = d(&format!("shadowed ? vec3(0) : {lab} / length(r)"));
        assert!(
            matches!(v, Verdict::DistancePower { power, .. } if (power + 1.0).abs() < 1e-3),
            "{v:?}"
        );
        assert!(
            v.to_string().starts_with("falls as 1/r^3 instead of 1/r²"),
            "{v}"
        );
        let abs = "lightColor * abs(dot(normalize(r), normal)) / (4 * pi * dot(r, r))";
        assert_eq!(
            d(&format!("shadowed ? vec3(0) : {abs}")),
            Verdict::NegativeCosine
        );
        assert_eq!(d(lab), Verdict::NotZeroInShadow);
        assert_eq!(
            verdict("R = indirectLight * (D + color)", Quantity::Value),
            Verdict::Swapped("color", "indirectLight")
        );
        let v = verdict("R = color * color", Quantity::Value);
        assert!(matches!(v, Verdict::Differs { .. }), "{v:?}");
        assert!(
            v.to_string()
                .starts_with("differs from the lab's: at color = ("),
            "{v}"
        );
    }

    /// A quantity that comes out infinite or NaN is never equal to the lab's, nor a factor of
    /// it (an infinity is within any relative tolerance of anything).
    #[test]
    fn infinities_and_nans_are_not_equal() {
        for text in [
            "R = color * (D + indirectLight) / 0",
            "R = color * (D + indirectLight) * (0 / 0)",
            "R = vec3(1 / 0)",
        ] {
            let v = verdict(text, Quantity::Value);
            assert!(matches!(v, Verdict::Differs { .. }), "{text}: {v:?}");
        }
        let v = d("lightColor / (dot(normal, normal) - 1)");
        assert!(matches!(v, Verdict::Differs { .. }), "{v:?}");
    }
}

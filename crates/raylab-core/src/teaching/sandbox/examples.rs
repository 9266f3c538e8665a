//! Texts a student starts from: each quantity as the lab computes it, and each formula mistake
//! of the catalogue ([`Mistake`]) typed as a student makes it.

use super::Quantity;
use crate::teaching::check::mistakes::Mistake;
use crate::transport::settings::Shading;
use crate::transport::settings::Stage;

/// Quantity `q` as the lab computes it for `shading` (R by the stage; `shadowed` is section
/// 5.1's test whatever the switch, as [`super::judge`] compares it):
/// equation 24 at the pixel's centre, section 5.1's shadow test, equation 27 with the shadow,
/// equations 28–30. Equal to the lab's at every input; a text equal to it stands for the
/// lab's own quantity.
pub fn lab_text(q: Quantity, shading: &Shading) -> &'static str {
    match q {
        Quantity::Direction => {
            "// Equation 24 through the pixel's centre, turned by the camera's rotation\n\
             d = right * (x + 0.5 - W / 2) + down * (y + 0.5 - H / 2) + forward * focalLength"
        }
        Quantity::ShadowStart => {
            "// A little off the surface, on the light's side (section 5.1)\n\
             shadowStart = position + normal * (dot(lightPos - position, normal) < 0 ? -1e-4 : 1e-4)"
        }
        Quantity::Shadowed => {
            "// Blocked if a surface is closer than the light (section 5.1)\n\
             shadowed = shadowDistance < length(lightPos - shadowStart)"
        }
        Quantity::Direct => {
            "// Equation 27, shadow included\n\
             vec3 r = lightPos - position; // from the surface to the light\n\
             D = shadowed ? vec3(0) : lightColor * max(dot(normalize(r), normal), 0.0) / (4 * pi * dot(r, r))"
        }
        Quantity::Value => match shading.stage {
            Stage::Flat => "// Figure 2: the colour alone\nR = color",
            Stage::Incoming => "// Figure 3: the light arriving\nR = D + indirectLight",
            Stage::Direct | Stage::Shadows | Stage::Lab | Stage::Path => {
                "// Equations 28 and 30\nR = color * (D + indirectLight)"
            }
        },
    }
}

/// Mistake `m` typed: the quantity it is in and its text, for the formula mistakes of the
/// catalogue and the pixel's corner.
pub fn mistake_text(m: Mistake) -> Option<(Quantity, &'static str)> {
    Some(match m {
        Mistake::No4Pi => (
            Quantity::Direct,
            "vec3 r = lightPos - position;\n\
             D = shadowed ? vec3(0) : lightColor * max(dot(normalize(r), normal), 0.0) / dot(r, r)",
        ),
        Mistake::InverseR => (
            Quantity::Direct,
            "vec3 r = lightPos - position;\n\
             D = shadowed ? vec3(0) : lightColor * max(dot(normalize(r), normal), 0.0) / (4 * pi * length(r))",
        ),
        Mistake::UnclampedCos => (
            Quantity::Direct,
            "vec3 r = lightPos - position;\n\
             D = shadowed ? vec3(0) : lightColor * dot(normalize(r), normal) / (4 * pi * dot(r, r))",
        ),
        Mistake::FlippedNormal => (
            Quantity::Direct,
            "vec3 r = lightPos - position;\n\
             vec3 n = -normal;\n\
             D = shadowed ? vec3(0) : lightColor * max(dot(normalize(r), n), 0.0) / (4 * pi * dot(r, r))",
        ),
        Mistake::NoRho => (Quantity::Value, "R = D + indirectLight"),
        Mistake::IndirectOutsideRho => (Quantity::Value, "R = color * D + indirectLight"),
        Mistake::ShadowAcne => (Quantity::ShadowStart, "shadowStart = position"),
        Mistake::ShadowBeyondLight => (Quantity::Shadowed, "shadowed = shadowDistance < 1e30"),
        Mistake::ShadowDropsIndirect => (
            Quantity::Value,
            "R = shadowed ? vec3(0) : color * (D + indirectLight)",
        ),
        Mistake::PixelCorner => (
            Quantity::Direction,
            "d = right * (x - W / 2) + down * (y - H / 2) + forward * focalLength",
        ),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::super::{Verdict, carried::compile_one, judge};
    use super::*;

    /// The lab's texts are judged equal to the lab's, and each mistake's text names its
    /// mistake, for every lab stage.
    #[test]
    fn the_lab_is_equal_and_each_mistake_named() {
        for stage in Stage::LAB {
            let shading = Shading::for_stage(stage);
            for q in Quantity::ALL {
                let e = compile_one(q, lab_text(q, &shading)).unwrap();
                assert_eq!(
                    judge(&e, q, stage),
                    Some(Verdict::Equal),
                    "{stage} {}",
                    q.name()
                );
            }
        }
        let mut typed = 0;
        for m in Mistake::catalogue() {
            if let Some((q, text)) = mistake_text(m) {
                let e = compile_one(q, text).unwrap();
                assert_eq!(judge(&e, q, Stage::Lab), Some(Verdict::Mistake(m)), "{m}");
                typed += 1;
            }
        }
        assert_eq!(typed, 10);
    }
}

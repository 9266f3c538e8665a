//! The pixel inspector: what it reports is what the renderer computed (its R is the rendered
//! pixel bit for bit, its D the lab's equation 27 at the hit), its lines carry the lab's
//! numbers, and `raylab inspect` prints them.

mod common;

use std::f32::consts::PI;

use common::{assert_pixels_trace_alone, every_pixel, settings, vec3_bits};
use glam::Vec3;
use raylab_core::shading::light::direct_light;
use raylab_core::shading::material::TexturePreset;
use raylab_core::shapes::scene::{Scene, SceneChoice, cornell_box};
use raylab_core::teaching::inspect::{InspectError, Inspection, ShadedHit, inspect_pixel};
use raylab_core::transport::render::render;
use raylab_core::{MaterialPreset, RenderSettings, Stage};

fn inspect(scene: &Scene, s: &RenderSettings, x: u32, y: u32) -> Inspection {
    inspect_pixel(scene, s, x, y).expect("a pixel of the image")
}

/// Every pixel of a small image: the inspector's R is the rendered pixel (one sample per
/// pixel) and `trace_pixel`'s value, bit for bit.
fn assert_every_pixel_matches(scene: &Scene, s: &RenderSettings, what: &str) {
    let image = render(scene, s);
    assert_pixels_trace_alone(scene, s, &image, 0, every_pixel(s), what);
    for (x, y) in every_pixel(s) {
        let i = inspect(scene, s, x, y);
        assert_eq!(
            vec3_bits(i.r),
            vec3_bits(image.get(x, y)),
            "{what}: pixel ({x}, {y})"
        );
    }
}

/// The inspector's numbers at a diffuse hit are the tracer's: D is equation 27 at the hit
/// with the normal it was computed with, and the parts printed (P, r̂·n̂, 4πr²) give that D
/// bit for bit.
fn assert_terms_are_equation_27(s: &RenderSettings, hit: &ShadedHit) {
    let t = &hit.terms;
    let Some(d) = t.d else {
        assert_eq!(
            s.shading.stage,
            Stage::Flat,
            "only the flat stage computes no D"
        );
        return;
    };
    let parts = t.power.unwrap() * t.cos_theta.unwrap().max(0.0) / t.four_pi_r2.unwrap();
    if t.relief_shadowed {
        assert_eq!(d, Vec3::ZERO, "the relief hides the light");
    } else if !t.light_behind_surface {
        assert_eq!(
            vec3_bits(d),
            vec3_bits(direct_light(&s.light, hit.position, hit.normal))
        );
        assert_eq!(vec3_bits(parts), vec3_bits(d), "the parts printed make D");
    }
    assert_eq!(
        t.four_pi_r2.unwrap(),
        4.0 * PI * t.light_distance_squared.unwrap()
    );
    if t.shadow_blocked {
        let b = t
            .blocker
            .as_ref()
            .expect("a blocked shadow ray names its blocker");
        let ray = t.shadow_ray.unwrap();
        assert!(b.distance >= 0.0 && b.distance < ray.length, "{b:?}");
    } else {
        assert!(t.blocker.is_none());
    }
}

/// Every stage, every material preset, textures and relief, a spherical light and a lens: R is the
/// rendered pixel, bit for bit, at every pixel of a 12 × 12 image, and every diffuse hit's D
/// is equation 27 there.
#[test]
fn r_is_the_rendered_pixel_in_every_configuration() {
    let scene = cornell_box();
    for stage in Stage::ALL {
        for preset in MaterialPreset::ALL {
            for texture in [
                TexturePreset::None,
                TexturePreset::Both,
                TexturePreset::BumpyWalls,
                TexturePreset::ParallaxFloor,
            ] {
                for (radius, aperture) in [(0.0, 0.0), (0.15, 0.0), (0.0, 0.08), (0.15, 0.08)] {
                    let mut s = settings(stage, 12);
                    s.material_preset = preset;
                    s.texture_preset = texture;
                    s.light.kind = raylab_core::shading::light::LightKind::Sphere { radius };
                    s.camera.aperture = aperture;
                    s.seed = 7;
                    let what = format!("{stage} {preset} {texture} r={radius} a={aperture}");
                    assert_every_pixel_matches(&scene, &s, &what);
                    for (x, y) in [(6, 6), (3, 10), (9, 9)] {
                        for hit in &inspect(&scene, &s, x, y).shaded {
                            assert_terms_are_equation_27(&s, hit);
                        }
                    }
                }
            }
        }
    }
}

/// Parallax self-shadowing explained: under a light low over the far right corner, pixel
/// (31, 96) of the 128² parallax floor is grout in a tile's shadow. Equation 27's value is
/// printed (P·cos/4πr² > 0), then why D is 0; R is the rendered pixel, ρ·N. With
/// self-shadowing off the same pixel is lit.
#[test]
fn the_inspector_says_when_the_relief_hides_the_light() {
    let scene = cornell_box();
    let mut s = common::parallax_floor_under_a_low_light();
    let i = inspect(&scene, &s, 31, 96);
    let t = &i.shaded[0].terms;
    assert!(t.relief_shadowed && !t.light_behind_surface, "{t:?}");
    assert_eq!(t.d, Some(Vec3::ZERO));
    assert!(t.cos_theta.unwrap() > 0.5, "{t:?}");
    let text = i.to_text();
    assert!(text.contains("parallax self-shadowing"), "{text}");
    assert!(text.contains("= 0.293 W per unit area"), "{text}");
    assert_eq!(vec3_bits(i.r), vec3_bits(render(&scene, &s).get(31, 96)));
    assert_eq!(i.r, i.shaded[0].terms.rho.unwrap() * 0.5);
    s.shading.parallax_shadows = false;
    let lit = inspect(&scene, &s, 31, 96);
    assert!(!lit.shaded[0].terms.relief_shadowed);
    assert!(lit.r.max_element() > i.r.max_element());
}

/// Smooth shading on and off, on a model with vertex normals and on the textured teapot (whose
/// texture comes from its file), in every stage.
#[test]
fn r_is_the_rendered_pixel_with_smooth_models() {
    for choice in [SceneChoice::Bunny, SceneChoice::TexturedTeapot] {
        let scene = choice.load().unwrap();
        for stage in Stage::ALL {
            for smooth in [true, false] {
                let mut s = settings(stage, 16);
                s.shading.smooth = smooth;
                let what = format!("{choice} {stage} smooth={smooth}");
                assert_every_pixel_matches(&scene, &s, &what);
                // A pixel of the model, where the smooth normal differs from the triangle's.
                let model = find(&scene, &s, |i| {
                    i.triangle.is_some_and(|t| t >= 30) && i.back_facing == Some(false)
                })
                .expect("a pixel of the model");
                check(&scene, &s, &model);
                if stage != Stage::Path {
                    assert_eq!(model.shading_normal.is_some(), smooth, "{what}");
                }
            }
        }
    }
}

/// The first pixel (scanning the image) for which `pick` holds.
fn find(
    scene: &Scene,
    s: &RenderSettings,
    pick: impl Fn(&Inspection) -> bool,
) -> Option<Inspection> {
    every_pixel(s)
        .map(|(x, y)| inspect(scene, s, x, y))
        .find(|i| pick(i))
}

/// Checks one inspected pixel: R as rendered, D as equation 27, the JSON keys present.
fn check(scene: &Scene, s: &RenderSettings, i: &Inspection) {
    let [x, y] = i.pixel;
    let image = render(scene, s);
    assert_pixels_trace_alone(scene, s, &image, 0, [(x, y)], "the inspected pixel");
    assert_eq!(vec3_bits(i.r), vec3_bits(image.get(x, y)), "{:?}", i.pixel);
    if let Some(first) = i.shaded.first() {
        assert_terms_are_equation_27(s, first);
        assert_eq!(i.terms, first.terms);
    }
    let json = serde_json::to_value(i).unwrap();
    for key in [
        "pixel",
        "origin",
        "direction",
        "triangle",
        "t",
        "u",
        "v",
        "position",
        "normal",
        "rho",
        "light_distance",
        "cos_theta",
        "D",
        "shadow_blocked",
        "blocker",
        "N",
        "R",
    ] {
        assert!(json.get(key).is_some(), "key {key} missing: {json}");
    }
    assert_eq!(json["pixel"], serde_json::json!([x, y]));
    assert!(i.to_text().lines().count() >= 3);
}

/// In every stage: a lit pixel, a shadowed one (stages with shadows), one that sees nothing,
/// and one that sees the back of a wall. Each is the rendered pixel, and its numbers are the
/// tracer's.
#[test]
fn lit_shadowed_empty_and_back_facing_pixels_in_every_stage() {
    let scene = cornell_box();
    for stage in Stage::ALL {
        let s = settings(stage, 32);
        let lit = find(&scene, &s, |i| {
            i.terms.d.is_some_and(|d| d.x > 0.0) && !i.terms.shadow_blocked
        });
        if stage == Stage::Flat {
            assert!(lit.is_none(), "the flat stage computes no light");
            let flat = inspect(&scene, &s, 16, 16);
            assert_eq!(Some(flat.r), flat.terms.rho);
            check(&scene, &s, &flat);
        } else {
            let lit = lit.expect("a lit pixel");
            check(&scene, &s, &lit);
            assert!(lit.terms.blocker.is_none());
            assert!(lit.r.max_element() > 0.0);
        }
        if s.shading.shadows {
            let shadowed = find(&scene, &s, |i| i.terms.shadow_blocked)
                .unwrap_or_else(|| panic!("{stage}: a shadowed pixel"));
            check(&scene, &s, &shadowed);
            let blocker = shadowed.terms.blocker.as_ref().unwrap();
            // What blocks it is something else, between the point and the light.
            assert_ne!(Some(blocker.triangle), shadowed.triangle);
            let text = shadowed.to_text();
            assert!(text.contains(&format!("blocked by triangle {}", blocker.triangle)));
            if stage != Stage::Path {
                // ρ·(0 + N): the shadowed pixel keeps only the indirect term.
                let rho = shadowed.terms.rho.unwrap();
                assert_eq!(
                    vec3_bits(shadowed.r),
                    vec3_bits(rho * (Vec3::ZERO + shadowed.n))
                );
            }
        }

        // Looking out of the box's open front: nothing is hit, R = 0.
        let mut out = s.clone();
        out.camera.yaw = PI;
        let empty = inspect(&scene, &out, 16, 16);
        check(&scene, &out, &empty);
        assert_eq!((empty.triangle, empty.t, empty.r), (None, None, Vec3::ZERO));
        assert!(empty.shaded.is_empty() && empty.terms.d.is_none());
        let json = serde_json::to_value(&empty).unwrap();
        assert!(json["triangle"].is_null() && json["D"].is_null());
        assert!(empty.to_text().contains("the ray leaves the box"));

        // Behind the back wall (z = 1) looking in: the wall's back. Its normal faces into the
        // box, toward the light, so the lab's one-sided surfaces light it (r̂·n̂ > 0); the path
        // tracer's are two-sided: the normal is turned to face the ray, away from the light,
        // and D = 0.
        let mut behind = s.clone();
        behind.camera.position = Vec3::new(0.0, 0.0, 1.5);
        behind.camera.yaw = PI;
        let back = inspect(&scene, &behind, 16, 16);
        check(&scene, &behind, &back);
        assert_eq!(back.back_facing, Some(true));
        assert_eq!(back.normal, Some(Vec3::new(0.0, 0.0, -1.0)));
        assert!(back.to_text().contains("the ray meets its back"));
        match stage {
            Stage::Flat => assert_eq!(back.terms.d, None),
            Stage::Path => {
                assert_eq!(back.shading_normal, Some(Vec3::new(0.0, 0.0, 1.0)));
                assert_eq!(back.terms.d, Some(Vec3::ZERO));
                assert!(back.terms.cos_theta.unwrap() < 0.0);
            }
            Stage::Incoming | Stage::Direct | Stage::Shadows | Stage::Lab => {
                assert_eq!(back.shading_normal, None);
                assert!(back.terms.cos_theta.unwrap() > 0.0);
                assert!(back.terms.d.unwrap().x > 0.0);
            }
        }
    }
}

/// The mirror preset: a pixel that sees the tall block sees what its reflection reaches. The
/// chain says so (a reflection of weight 0.9, the tint), the terms are those of the diffuse
/// hit the reflection reaches, and R = 0.9 × that hit's value.
#[test]
fn a_mirror_pixel_reports_its_chain_and_the_hit_it_reaches() {
    let scene = cornell_box();
    for stage in Stage::LAB {
        let mut s = settings(stage, 32);
        s.material_preset = MaterialPreset::Mirror;
        let mirror = find(&scene, &s, |i| {
            i.kind == Some("mirror") && !i.shaded.is_empty()
        })
        .expect("a mirror pixel whose reflection hits something");
        check(&scene, &s, &mirror);
        assert_eq!(mirror.surface.as_deref(), Some("blue"));
        assert_eq!(mirror.specular_chain.len(), 1);
        let step = &mirror.specular_chain[0];
        assert_eq!(
            (step.branch, step.weight, step.depth),
            ("reflection", Vec3::splat(0.9), 0)
        );
        let reached = &mirror.shaded[0];
        assert_eq!(reached.depth, 1);
        assert_ne!(Some(reached.triangle), mirror.triangle);
        assert_eq!(
            vec3_bits(mirror.r),
            vec3_bits(Vec3::splat(0.9) * reached.value)
        );
        let text = mirror.to_text();
        assert!(
            text.contains("mirror") && text.contains("reflection"),
            "{text}"
        );
    }
}

/// Glass at depth 1: the reflection (F) and the refraction (1 − F) are both followed, and the
/// pixel is the sum of what the branches add.
#[test]
fn a_glass_pixel_sums_its_branches() {
    let scene = cornell_box();
    let mut s = settings(Stage::Lab, 32);
    s.material_preset = MaterialPreset::Glass;
    let glass = find(&scene, &s, |i| i.kind == Some("glass")).expect("a glass pixel");
    check(&scene, &s, &glass);
    let first: Vec<_> = glass
        .specular_chain
        .iter()
        .filter(|step| step.depth == 0)
        .collect();
    assert_eq!(first.len(), 2, "{first:?}");
    assert_eq!(first[0].branch, "reflection");
    assert_eq!(first[1].branch, "refraction");
    // F + (1 − F) = 1 (clear glass), up to the rounding of 1 − F.
    assert!(
        (first[0].weight + first[1].weight - Vec3::ONE)
            .abs()
            .max_element()
            < 1e-6
    );
    let sum = glass
        .shaded
        .iter()
        .fold(Vec3::ZERO, |sum, hit| sum + hit.contribution);
    assert!(
        (sum - glass.r).abs().max_element() < 1e-6,
        "{sum} {}",
        glass.r
    );
}

/// The path stage records every vertex: β starts at 1, each diffuse vertex adds β·ρ·D, and
/// the sum of what they add is R.
#[test]
fn path_vertices_add_up_to_r() {
    let scene = cornell_box();
    let mut s = settings(Stage::Path, 16);
    s.seed = 11;
    let mut long_paths = 0;
    for (x, y) in [(8, 8), (3, 12), (12, 4), (8, 14)] {
        let i = inspect(&scene, &s, x, y);
        check(&scene, &s, &i);
        assert_eq!(i.bounces[0].beta, Vec3::ONE);
        long_paths += usize::from(i.bounces.len() > 2);
        let sum = i
            .bounces
            .iter()
            .fold(Vec3::ZERO, |sum, v| sum + v.light_added);
        assert_eq!(
            vec3_bits(sum),
            vec3_bits(i.r),
            "the vertices' light is added in order"
        );
        for pair in i.bounces.windows(2) {
            assert_eq!(pair[0].beta_after, Some(pair[1].beta));
        }
        assert!(i.bounces.last().unwrap().ends.is_some());
    }
    assert!(long_paths > 0);
    // With no bounces, the path stage is the shadows stage and says so.
    s.shading.bounces = Some(0);
    let i = inspect(&scene, &s, 8, 8);
    assert_eq!(i.bounces.len(), 1);
    assert!(
        i.bounces[0]
            .ends
            .as_deref()
            .unwrap()
            .contains("direct light only")
    );
    let shadows = inspect(&scene, &settings(Stage::Shadows, 16), 8, 8);
    assert_eq!(vec3_bits(i.r), vec3_bits(shadows.r));
}

/// Figure 7 at 32 × 32 (the library's example): the centre pixel (16, 16) looks through
/// image point (16.5, 16.5), d = (0.5, 0.5, 32) from s = (0, 0, −3.001), and meets the white
/// back wall z = 1 after 4.001/32 = 0.12503 of d: at p = (0.062516, 0.062516, 1).
///
/// With the light at (0, −0.5, −0.7): r = light − p = (−0.062516, −0.562516, −1.7),
/// r² = 0.003908 + 0.316424 + 2.89 = 3.210332, |r| = 1.791740; the wall's normal is
/// (0, 0, −1), so r̂·n̂ = 1.7/1.791740 = 0.948798;
/// D = 14 × 0.948798 / (4π × 3.210332) = 13.283178 / 40.342222 = 0.329262.
/// Nothing lies between, and R = ρ·(D + N) = 0.75 × (0.329262 + 0.5) = 0.621947.
#[test]
fn figure_7s_centre_pixel_by_hand() {
    let scene = cornell_box();
    let s = settings(Stage::Lab, 32);
    let i = inspect(&scene, &s, 16, 16);
    assert_eq!(i.surface.as_deref(), Some("white"));
    let close = |a: f32, b: f32| (a - b).abs() < 2e-5;
    assert!(close(
        i.t.unwrap(),
        4.001 * (0.5f32 * 0.5 * 2.0 + 32.0 * 32.0).sqrt() / 32.0
    ));
    assert!(close(i.terms.light_distance.unwrap(), 1.791_74));
    assert!(close(i.terms.cos_theta.unwrap(), 0.948798));
    assert!((i.terms.four_pi_r2.unwrap() - 40.342_22).abs() < 1e-4);
    assert!(close(i.terms.d.unwrap().x, 0.329262));
    assert!(!i.terms.shadow_blocked);
    assert!(close(i.r.x, 0.621947) && i.r.x == i.r.z);
    let lines = i.lines();
    let line = |equation: &str, text: &str| {
        lines
            .iter()
            .any(|l| l.equation == equation && l.text.contains(text))
    };
    assert!(line("eq. 24", "R·(0.5, 0.5, 32)"), "{lines:#?}");
    assert!(
        line("eq. 27", "|r| = 1.792 units, r̂·n̂ = 0.949"),
        "{lines:#?}"
    );
    assert!(
        line(
            "eq. 27",
            "D = P·max(r̂·n̂, 0)/(4πr²) = 14 W × 0.949 / (4π × 3.21 units² = 40.342 units²) \
             = 0.329 W per unit area"
        ),
        "{lines:#?}"
    );
    assert!(line("§5.1", "nothing in the way"), "{lines:#?}");
    assert!(
        line("eq. 30", "R = ρ·(D + N) = 0.75 · (0.329 + 0.5) = 0.622"),
        "{lines:#?}"
    );
    assert!(i.to_text().contains("eq. 30"));
}

/// A pixel outside the image, or settings that can't be rendered, are errors, not panics.
#[test]
fn bad_pixels_and_settings_are_errors() {
    let scene = cornell_box();
    let s = settings(Stage::Lab, 8);
    for (x, y) in [(8, 0), (0, 8), (u32::MAX, 3)] {
        let e = inspect_pixel(&scene, &s, x, y).unwrap_err();
        assert!(matches!(e, InspectError::OutsideImage { .. }));
        assert!(e.to_string().contains(&format!("pixel ({x}, {y})")), "{e}");
    }
    let mut nan = s.clone();
    nan.camera.position.x = f32::NAN;
    assert!(matches!(
        inspect_pixel(&scene, &nan, 0, 0),
        Err(InspectError::Settings(_))
    ));
}

use super::lines::colour;
use super::recording::{Event, Recording};
use super::*;
use crate::shading::light::{DirectLight, direct_light};
use crate::shapes::scene::cornell_box;
use crate::transport::display::Display;

#[test]
fn numbers_are_printed_short() {
    assert_eq!(num(14.0), "14");
    assert_eq!(num(2.74), "2.74");
    assert_eq!(num(0.906_183), "0.906");
    assert_eq!(num(0.368_454), "0.368");
    assert_eq!(num(0.078_6), "0.0786");
    assert_eq!(num(-0.5), "-0.5");
    assert_eq!(num(-0.0), "0");
    assert_eq!(num(40.342_22), "40.342");
    assert_eq!(num(9.4e-4), "9.40e-4");
    assert_eq!(num(f32::NAN), "NaN");
    assert_eq!(colour(Vec3::splat(0.5)), "0.5");
    assert_eq!(colour(Vec3::new(0.75, 0.15, 0.15)), "(0.75, 0.15, 0.15)");
}

/// The display's lines: R's 8 bits through the display in force (×255 and rounded for the
/// lab's; the sRGB curve's own), and with several samples, that R is sample 0's beside the
/// value on screen with its 8 bits.
#[test]
fn the_display_lines_give_the_8_bits_shown() {
    let scene = cornell_box();
    let mut settings = RenderSettings::default();
    settings.camera = settings.camera.with_resolution(64, 64);
    let inspection = inspect_pixel(&scene, &settings, 20, 50).unwrap();
    let r = inspection.r;
    let lab = |v: f32| crate::transport::display::to_display_u8(v);
    let lines = inspection.display_lines(&settings.display, None);
    assert_eq!(lines.len(), 1);
    assert_eq!(lines[0].equation, "on screen");
    let bits = format!("({}, {}, {})", lab(r.x), lab(r.y), lab(r.z));
    assert!(
        lines[0]
            .text
            .contains(&format!("shown as {bits} in 8 bits")),
        "{}",
        lines[0].text
    );
    let srgb = Display {
        transform: crate::transport::display::DisplayTransform::Srgb,
        exposure: 0.0,
    };
    let shown = ShownPixel {
        value: Vec3::new(0.25, 0.5, 0.75),
        samples: 16,
        denoised: false,
    };
    let lines = inspection.display_lines(&srgb, Some(shown));
    assert_eq!(lines.len(), 2);
    assert!(lines[0].text.starts_with("R above is sample 0's alone"));
    let [a, b, c] = srgb.encode(shown.value);
    assert_eq!((a, b, c), (137, 188, 225));
    assert_eq!(
        lines[1].text,
        "the pixel shown is the mean of its 16 samples (each through another point of the \
         pixel): (0.25, 0.5, 0.75), shown as (137, 188, 225) in 8 bits"
    );
    let denoised = ShownPixel {
        denoised: true,
        ..shown
    };
    let lines = inspection.display_lines(&srgb, Some(denoised));
    assert!(lines[1].text.contains("the denoised image's value"));
}

/// The parts of D at the lab's floor centre (0, 1, 0), by hand as in the integrator's
/// test: r = (0, −1.5, −0.7), r² = 2.74, r̂·n̂ = 1.5/√2.74 = 0.906183,
/// 4πr² = 34.431856, D = 14 × 0.906183 / 34.431856 = 0.368454, and the tracer's D exactly.
#[test]
fn the_parts_of_d_at_the_floor_centre() {
    let light = LightSpec::default();
    let (p, n) = (Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, -1.0, 0.0));
    let parts = DirectLight::at(&light, p, n);
    assert_eq!(parts.to_light, Vec3::new(0.0, -1.5, -0.7));
    assert!((parts.r2 - 2.74).abs() < 1e-6);
    assert!((parts.cos - 0.906_183).abs() < 1e-6);
    assert!((parts.four_pi_r2 - 34.431_856).abs() < 1e-4);
    assert!((parts.d.x - 0.368_454).abs() < 1e-6);
    assert_eq!(parts.d, direct_light(&light, p, n));
    // A light on the surface: the lab's guard, straight above at the least distance.
    let on = DirectLight::at(&light, light.position, n);
    assert_eq!(on.distance(), crate::shading::light::MIN_LIGHT_DISTANCE);
    assert_eq!(on.d, direct_light(&light, light.position, n));
}

/// The recorder sees the integrator's steps in order: one closest hit for the camera ray,
/// then its terms.
#[test]
fn the_recording_follows_the_integrator() {
    let scene = cornell_box();
    let mut s = RenderSettings::default();
    s.camera = s.camera.with_resolution(16, 16);
    let tracer = Tracer::new(&scene, &s);
    let (ray, rng, point, lens) = camera_sample_0(&tracer, &s, 8, 12);
    assert_eq!((point, lens), ([8.5, 12.5], None));
    let mut recording = Recording::default();
    let mut out = [Vec3::ZERO];
    tracer.trace_recorded(&[ray], &mut [rng], &mut out, &mut recording);
    let kinds: Vec<_> = recording
        .events
        .iter()
        .map(|e| match e {
            Event::Hit { .. } => "hit",
            Event::Specular { .. } => "specular",
            Event::Shaded { .. } => "shaded",
            Event::Scattered { .. } => "scattered",
            Event::Vertex(_) => "vertex",
        })
        .collect();
    assert_eq!(kinds, ["hit", "shaded"]);
    let Event::Shaded { value, weight, .. } = &recording.events[1] else {
        unreachable!()
    };
    assert_eq!((*value, *weight), (out[0], Vec3::ONE));
}

/// At the plastic tall block in the lab stage the inspector shows f's two parts: π·f_s
/// (the coating's highlight) and π·f_d (the base) sum to the ρ the pixel was shaded
/// with, R is the rendered pixel bit for bit, and where the light's highlight falls on the
/// block's visible faces the coating adds at least a quarter of the base's red.
#[test]
fn the_inspector_shows_the_plastics_two_parts() {
    let scene = crate::shapes::scene::cornell_box();
    let mut s = RenderSettings::default();
    s.camera = s.camera.with_resolution(48, 48);
    s.material_preset = crate::shading::material::MaterialPreset::Plastic;
    s.roughness = 0.1;
    let (mut on_block, mut highlight) = (0, 0);
    for y in 0..48 {
        for x in 0..48 {
            let i = inspect_pixel(&scene, &s, x, y).unwrap();
            let rendered = crate::transport::render::trace_pixel(&scene, &s, x, y, 0);
            assert_eq!(
                i.r.to_array().map(f32::to_bits),
                rendered.to_array().map(f32::to_bits)
            );
            let Some(g) = i.terms.glossy else { continue };
            assert_eq!(i.surface.as_deref(), Some("blue"));
            on_block += 1;
            let rho = i.terms.rho.unwrap();
            let sum = g.specular + g.diffuse;
            assert!(
                (sum - rho).abs().max_element() <= 1e-5 * rho.max_element(),
                "{g:?} {rho}"
            );
            // The coating is white, the base the block's blue.
            assert_eq!(g.specular.x, g.specular.z);
            assert!(g.diffuse.z >= 4.0 * g.diffuse.x);
            if g.specular.x > 0.25 * g.diffuse.x {
                highlight += 1;
                let text: Vec<String> = i.lines().into_iter().map(|l| l.text).collect();
                assert!(text.iter().any(|l| l.contains("π·f_s + π·f_d")), "{text:?}");
            }
        }
    }
    assert!(on_block > 20 && highlight > 0, "{on_block} {highlight}");
}

/// Under the quad light every vertex runs the single path's steps, and the inspector shows each
/// vertex's light sample with the BSDF's value, both densities and the MIS weight; R is
/// still the rendered pixel bit for bit. The weight is the power heuristic of the two
/// densities shown, p_L²/(p_L² + p_B²), computed here in f64 (within 1e-6: f32 rounding
/// of the same formula); the balance heuristic p_L/(p_L + p_B), or no weight (1), differ
/// from it wherever p_B > 0, so some vertices must have both densities well apart from 0
/// and from each other's extremes (a weight in (0.05, 0.95)).
#[test]
fn a_path_vertex_under_an_area_light_shows_its_mis_weight() {
    let scene = crate::shapes::scene::cornell_box();
    let mut s = RenderSettings::default();
    s.camera = s.camera.with_resolution(32, 32);
    s.shading = crate::transport::integrator::Shading::for_stage(Stage::Path);
    s.light.position = Vec3::new(0.0, -0.98, 0.0);
    // A square of side 1.5: large enough that, at vertices near it, BSDF samples find it
    // as readily as light samples do (at a side of 0.5 no weight of these pixels was within (0.05, 0.95)).
    s.light.kind = LightKind::Quad { side: 1.5 };
    s.material_preset = crate::shading::material::MaterialPreset::Rough;
    let (mut seen, mut shared) = (0, 0);
    // Every fourth pixel each way: the vertices of a few paths may all be far from or
    // near the light.
    for (x, y) in (0..64).map(|k| (1 + 4 * (k % 8), 1 + 4 * (k / 8))) {
        let i = inspect_pixel(&scene, &s, x, y).unwrap();
        let rendered = crate::transport::render::trace_pixel(&scene, &s, x, y, 0);
        assert_eq!(
            i.r.to_array().map(f32::to_bits),
            rendered.to_array().map(f32::to_bits)
        );
        // Every vertex below the light samples it (the ceiling, above it, cannot).
        for v in i.bounces.iter().filter(|v| v.position.y > -0.98) {
            let l = v.light_sample.expect("a vertex below the light samples it");
            assert!(l.pdf_light > 0.0, "{l:?}");
            let (p_l, p_b) = (f64::from(l.pdf_light), f64::from(l.pdf_bsdf));
            let power = p_l * p_l / (p_l * p_l + p_b * p_b);
            assert!(
                (f64::from(l.mis_weight) - power).abs() < 1e-6,
                "{l:?}: the power heuristic is {power}"
            );
            seen += 1;
            shared += usize::from((0.05..0.95).contains(&power));
        }
        let text: Vec<String> = i.lines().into_iter().map(|l| l.text).collect();
        // A vertex that sampled the light shows its weight (a path may see only the
        // ceiling, above the light, and end on the light's back).
        if i.bounces.iter().any(|v| v.light_sample.is_some()) {
            assert!(text.iter().any(|l| l.contains("MIS weight")), "{text:?}");
        }
    }
    assert!(seen > 0);
    assert!(
        shared > 0,
        "no vertex where the two strategies share the light"
    );
}

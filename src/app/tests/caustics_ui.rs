//! Caustics by photon mapping in the window: the switch is the path stage's, and turning it
//! on lights the shadow behind the glass block with the light the glass focuses into it.

use raylab_core::transport::settings::Caustics;
use raylab_core::transport::view::{ShadowState, View, ViewValues, render_view};

use super::*;

fn disabled(h: &Harness<'_, WorkbenchApp>, role: Role, label: &str) -> bool {
    h.get_by_role_and_label(role, label)
        .accesskit_node()
        .is_disabled()
}

#[test]
fn caustics_by_photons_light_the_shadow_behind_the_glass_block() {
    let mut h = harness(small_state());
    // The lab's stages gather no photons: the switch and the count are disabled there.
    assert!(disabled(&h, Role::CheckBox, "Caustics: photons"));
    assert!(disabled(&h, Role::Slider, "Photons per pass"));
    choose(&mut h, "Stage", "Path tracing (real light)");
    choose(&mut h, "Materials", "Glass short block");
    set_target(&mut h, 4);
    assert!(!disabled(&h, Role::CheckBox, "Caustics: photons"));
    assert!(disabled(&h, Role::Slider, "Photons per pass"));
    settle(&mut h);
    let off = shown(&h);
    assert_eq!(off.settings.shading.caustics, Caustics::Off);

    h.get_by_role_and_label(Role::CheckBox, "Caustics: photons")
        .click();
    h.run_steps(2);
    assert!(!disabled(&h, Role::Slider, "Photons per pass"));
    h.get_by_role_and_label(Role::Slider, "Photons per pass")
        .set_value_accesskit(20_000.0);
    settle(&mut h);
    let on = shown(&h);
    assert_eq!(on.settings.shading.caustics, Caustics::Photons);
    assert_eq!(on.settings.shading.photons, 20_000);
    assert!(
        h.query_by_label_contains("caustics by photon mapping")
            .is_some()
    );
    // What the library renders, bit for bit.
    assert_eq!(*on.image, render(&cornell_box(), &on.settings));

    // The blocks' shadow (the shadow view's blocked pixels) gains the light the glass focuses
    // into it. The path tracer draws the same numbers with and without photons, so on − off is
    // the photons' light alone: no pixel of the shadow is darker (beyond rounding), and the
    // shadow as a whole, and some of its pixels clearly, are brighter.
    let states = match render_view(&cornell_box(), &off.settings, View::Shadow, &|| false)
        .unwrap()
        .values
    {
        ViewValues::Shadow(states) => states,
        other => panic!("{other:?}"),
    };
    let luminance = |v: Vec3| (v.x + v.y + v.z) / 3.0;
    let (mut gained, mut brighter, mut darkest) = (0.0, 0, 0.0f32);
    for (i, (a, b)) in off.image.pixels.iter().zip(&on.image.pixels).enumerate() {
        if states[i] == ShadowState::Blocked {
            let d = luminance(*b) - luminance(*a);
            gained += d;
            brighter += usize::from(d > 0.05);
            darkest = darkest.min(d);
        }
    }
    // Measured at this size and 4 samples: 1.33 gained over 616 pixels, 7 brighter by 0.05.
    assert!(
        darkest > -1e-5,
        "a shadow pixel {darkest} darker with photons"
    );
    assert!(
        gained > 1.0 && brighter >= 5,
        "{gained} gained, {brighter} brighter"
    );
    settle(&mut h);
}

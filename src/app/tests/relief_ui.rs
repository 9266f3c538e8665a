//! Parallax self-shadowing in the window: its switch shows with the parallax floor, is on by
//! default, and turning it off relights the grout the tiles' edges shadow.

use super::*;

#[test]
fn the_parallax_floors_self_shadowing_can_be_switched_off() {
    let mut state = small_state();
    // A light low over the floor's far right corner: the tiles' shadows fall toward the
    // camera (with the lab's light they fall behind the tiles, out of sight).
    state.settings.light.position = Vec3::new(0.9, 0.7, 0.9);
    let mut h = harness(state);
    assert!(
        h.query_by_label("Parallax self-shadowing").is_none(),
        "no switch without a height map"
    );
    choose(&mut h, "Textures", "Tiled floor with depth (parallax)");
    settle(&mut h);
    let shadowed = shown(&h);
    assert!(shadowed.settings.shading.parallax_shadows);
    assert!(
        h.query_by_label_contains("parallax-mapped floor, self-shadowed")
            .is_some()
    );
    h.get_by_role_and_label(Role::CheckBox, "Parallax self-shadowing")
        .click();
    settle(&mut h);
    let lit = shown(&h);
    assert!(!lit.settings.shading.parallax_shadows);
    // What the library renders, bit for bit, each way; off, some pixels brighter, none darker.
    let scene = cornell_box();
    assert_eq!(*shadowed.image, render(&scene, &shadowed.settings));
    assert_eq!(*lit.image, render(&scene, &lit.settings));
    let mut brighter = 0;
    for (a, b) in shadowed.image.pixels.iter().zip(&lit.image.pixels) {
        assert!(b.cmpge(*a).all(), "{a} → {b}");
        brighter += usize::from(b != a);
    }
    assert!(brighter >= 5, "{brighter} pixels relit");
}

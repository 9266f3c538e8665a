//! The pool in the window: chosen in the Scene selector, its waves set with their sliders,
//! rendered as the library renders the same water.

use super::*;

#[test]
fn the_pools_waves_have_their_sliders() {
    let mut h = harness(tiny_state());
    assert!(
        h.query_by_label("Wave amplitude").is_none(),
        "no water, no slider"
    );
    choose(&mut h, "Scene", "Pool of water (waves)");
    settle(&mut h);
    h.get_by_role_and_label(Role::Slider, "Wave amplitude")
        .set_value_accesskit(0.02);
    h.get_by_role_and_label(Role::Slider, "Water time (s)")
        .set_value_accesskit(3.0);
    settle(&mut h);
    let s = settings(&h);
    let water = s.scene.spec().water.expect("the pool has water");
    assert_eq!((water.waves, water.time), (0.02, 3.0));
    let frame = shown(&h);
    assert_eq!(frame.settings, s);
    assert_eq!(*frame.image, render(&s.scene.load().unwrap(), &s));
}

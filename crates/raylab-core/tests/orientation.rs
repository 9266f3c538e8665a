//! The default render is the lab's view: purple left, yellow right, green floor, cyan ceiling,
//! the red short block right of centre and the blue tall block left of it.

use raylab_core::shapes::scene::cornell_box;
use raylab_core::transport::render::render;
use raylab_core::{RenderSettings, Shading, Stage};

/// The flat stage (figure 2) at 512 × 512, as names of the reflectance at each pixel.
fn flat_names() -> impl Fn(u32, u32) -> String {
    let scene = cornell_box();
    let mut settings = RenderSettings::default();
    settings.shading = Shading::for_stage(Stage::Flat);
    let image = render(&scene, &settings);
    move |x, y| {
        let p = image.get(x, y);
        let m = scene.materials.iter().find(|m| m.reflectance == p);
        m.map_or("black".to_owned(), |m| m.name.clone())
    }
}

#[test]
fn walls_floor_ceiling_and_blocks_are_where_the_lab_shows_them() {
    let colour_at = flat_names();
    // 512×512, default camera. Mid-height of the left and right edges: the side walls.
    assert_eq!(colour_at(2, 256), "purple");
    assert_eq!(colour_at(509, 256), "yellow");
    // Middle of the bottom and top rows: floor and ceiling.
    assert_eq!(colour_at(256, 509), "green");
    assert_eq!(colour_at(256, 2), "cyan");
    // The centre of the image: the white back wall.
    assert_eq!(colour_at(256, 200), "white");
    // Lower right of centre: the short red block; left of centre: the tall blue block.
    assert_eq!(colour_at(330, 380), "red");
    assert_eq!(colour_at(180, 300), "blue");
}

#[test]
fn the_flat_stage_shows_only_the_seven_reflectances() {
    let scene = cornell_box();
    let mut settings = RenderSettings::default();
    settings.camera = settings.camera.with_resolution(128, 128);
    settings.shading = Shading::for_stage(Stage::Flat);
    let image = render(&scene, &settings);
    let mut seen = std::collections::BTreeSet::new();
    for p in &image.pixels {
        let m = scene.materials.iter().find(|m| m.reflectance == *p);
        let m = m.unwrap_or_else(|| panic!("{p} is not one of the seven reflectances"));
        seen.insert(m.name.clone());
    }
    assert_eq!(seen.len(), 7, "{seen:?}");
}

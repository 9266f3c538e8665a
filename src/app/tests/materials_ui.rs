//! The material editor: a part of the box given any kind from the kind's table, its
//! parameters edited by rows made from that table, and the image rendered again with them.

use raylab_core::shading::material::{FieldValue, MaterialKind};
use raylab_core::shapes::scene::spec::{BoxPart, PartMaterial};

use super::*;

fn open_editor(h: &mut Harness<'_, WorkbenchApp>) {
    h.get_by_label("Material editor").click();
    h.run_steps(2);
}

/// The tall block's kind in the settings the window traces.
fn tall_kind(h: &Harness<'_, WorkbenchApp>) -> Option<MaterialKind> {
    settings(h)
        .part_materials
        .iter()
        .find(|p| p.part == BoxPart::TallBlock)
        .map(|p| p.kind)
}

#[test]
fn the_material_editor_makes_the_tall_block_plastic_and_renders_it() {
    let mut h = harness(small_state());
    let diffuse = shown(&h);
    open_editor(&mut h);
    // The tall block is chosen first; the kind selector lists every kind of the table.
    choose(&mut h, "Material kind", "Glossy plastic");
    settle(&mut h);
    let plastic = MaterialKind::of_name("plastic").unwrap();
    assert_eq!(tall_kind(&h), Some(plastic));
    // A row per parameter, from the table: the coating's roughness as a slider.
    h.get_by_role_and_label(Role::Slider, "alpha")
        .set_value_accesskit(0.3);
    settle(&mut h);
    let MaterialKind::Plastic { alpha, int_ior, .. } = tall_kind(&h).unwrap() else {
        panic!("still plastic")
    };
    assert_eq!((alpha, int_ior), (0.3, 1.5));
    // Rendered again with the edited material, as the library renders it, and no longer the
    // diffuse box.
    let after = shown(&h);
    assert_eq!(after.settings.part_materials, settings(&h).part_materials);
    assert_eq!(*after.image, render(&cornell_box(), &after.settings));
    assert_ne!(*after.image, *diffuse.image);
    // A colour parameter is three values, each labelled by its field and channel.
    h.get_by_role_and_label(Role::SpinButton, "specular g")
        .set_value_accesskit(0.5);
    settle(&mut h);
    let MaterialKind::Plastic { specular, .. } = tall_kind(&h).unwrap() else {
        panic!("still plastic")
    };
    assert_eq!(specular, Vec3::new(1.0, 0.5, 1.0));
    // "Reset material" gives the block back to the scene: the lab's image again.
    h.get_by_label("Reset material").click();
    settle(&mut h);
    assert!(settings(&h).part_materials.is_empty());
    assert_eq!(*shown(&h).image, *diffuse.image);
}

/// Every kind of the table gets a row for each of its parameters, with no code for any kind:
/// a slider per number, three values per colour.
#[test]
fn every_kind_shows_a_row_per_parameter() {
    let mut h = harness(small_state());
    open_editor(&mut h);
    choose(&mut h, "Material of", "Short block");
    // The short block is diffuse: the other kinds first, then back to diffuse.
    let kinds = MaterialKind::DEFAULTS.iter().cycle().skip(1);
    for kind in kinds.take(MaterialKind::DEFAULTS.len()) {
        choose(&mut h, "Material kind", kind.label());
        let part = settings(&h).part_materials;
        assert_eq!(
            part,
            vec![PartMaterial {
                part: BoxPart::ShortBlock,
                kind: *kind
            }]
        );
        for (field, value) in kind.fields_and_values() {
            match value {
                FieldValue::Number(x) => {
                    let node = h.get_by_role_and_label(Role::Slider, field.name);
                    let shown = node.accesskit_node().numeric_value().unwrap();
                    assert_eq!(shown, f64::from(x), "{}: {}", kind.name(), field.name);
                }
                FieldValue::Colour(c) => {
                    for (channel, x) in ["r", "g", "b"].iter().zip(c.to_array()) {
                        let label = format!("{} {channel}", field.name);
                        let node = h.get_by_role_and_label(Role::SpinButton, &label);
                        let shown = node.accesskit_node().numeric_value().unwrap();
                        assert_eq!(shown, f64::from(x), "{}: {label}", kind.name());
                    }
                }
            }
        }
    }
    settle(&mut h);
}

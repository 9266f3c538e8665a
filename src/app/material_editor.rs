//! The material editor: a part of the box (or a scene file's model) given any
//! [`MaterialKind`], its parameters edited through the kind's table ([`MaterialKind::fields`]):
//! a slider for a number, three for a colour, made from each field's name and range. No code
//! here names a kind, so a new kind shows up with its parameters as it is added.

use eframe::egui;
use raylab_core::shading::material::{FieldValue, MaterialKind};
use raylab_core::shapes::scene::SceneChoice;
use raylab_core::shapes::scene::cornell_box;
use raylab_core::shapes::scene::spec::{BoxPart, PartMaterial};
use raylab_core::{MaterialPreset, RenderSettings};

/// What the editor changes: a part of the box, or the `i`th model of a scene file's scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Target {
    Part(BoxPart),
    Model(usize),
}

impl Default for Target {
    fn default() -> Self {
        Target::Part(BoxPart::TallBlock)
    }
}

/// The kind a part has before the editor: the box's own (diffuse) or the preset's.
fn preset_kind(preset: MaterialPreset, roughness: f32, part: BoxPart) -> MaterialKind {
    let materials = preset.apply(&cornell_box().materials, roughness);
    materials
        .iter()
        .find(|m| m.name == part.material())
        .map_or(MaterialKind::Diffuse, |m| m.kind)
}

/// The kind `target` has in `settings` (`None` for a model the scene no longer has).
fn kind_of(settings: &RenderSettings, target: Target) -> Option<MaterialKind> {
    match target {
        Target::Part(part) => Some(
            settings
                .part_materials
                .iter()
                .find(|p| p.part == part)
                .map_or_else(
                    || preset_kind(settings.material_preset, settings.roughness, part),
                    |p| p.kind,
                ),
        ),
        Target::Model(i) => match &settings.scene {
            SceneChoice::Custom(spec) => spec.models.get(i).map(|m| m.kind),
            _ => None,
        },
    }
}

/// Gives `target` the kind `kind` in `settings`.
fn set_kind(settings: &mut RenderSettings, target: Target, kind: MaterialKind) {
    match target {
        Target::Part(part) => match settings.part_materials.iter_mut().find(|p| p.part == part) {
            Some(p) => p.kind = kind,
            None => settings.part_materials.push(PartMaterial { part, kind }),
        },
        Target::Model(i) => {
            if let SceneChoice::Custom(spec) = &mut settings.scene
                && let Some(m) = spec.models.get_mut(i)
            {
                m.kind = kind;
            }
        }
    }
}

/// The label of a target in the "Material of" selector.
fn target_label(settings: &RenderSettings, target: Target) -> String {
    match target {
        Target::Part(BoxPart::TallBlock) => "Tall block".to_owned(),
        Target::Part(BoxPart::ShortBlock) => "Short block".to_owned(),
        Target::Part(part) => part.name().replace('-', " "),
        Target::Model(i) => match &settings.scene {
            SceneChoice::Custom(spec) => match spec.models.get(i) {
                Some(m) => format!("Model {}: {}", i + 1, m.name()),
                None => format!("Model {}", i + 1),
            },
            _ => format!("Model {}", i + 1),
        },
    }
}

/// Every target the scene has: the box's parts, then a scene file's models.
fn targets(settings: &RenderSettings) -> Vec<Target> {
    let models = match &settings.scene {
        SceneChoice::Custom(spec) => spec.models.len(),
        _ => 0,
    };
    let blocks_first = [BoxPart::TallBlock, BoxPart::ShortBlock];
    let rest = BoxPart::ALL.into_iter().filter(|p| !p.is_block());
    blocks_first
        .into_iter()
        .chain(rest)
        .map(Target::Part)
        .chain((0..models).map(Target::Model))
        .collect()
}

/// The editor: the surface, its kind and a row per parameter. Any change lands in
/// `settings`, which the workbench renders again.
pub fn material_editor_ui(ui: &mut egui::Ui, settings: &mut RenderSettings) {
    let id = ui.make_persistent_id("material editor target");
    let all = targets(settings);
    let mut target: Target = ui.data(|d| d.get_temp(id)).unwrap_or_default();
    if !all.contains(&target) {
        target = Target::default();
    }
    egui::ComboBox::new("material surface", "Material of")
        .selected_text(target_label(settings, target))
        .show_ui(ui, |ui| {
            for &t in &all {
                ui.selectable_value(&mut target, t, target_label(settings, t));
            }
        })
        .response
        .on_hover_text("The surface whose material the rows below edit");
    ui.data_mut(|d| d.insert_temp(id, target));
    let Some(mut kind) = kind_of(settings, target) else {
        return;
    };
    let before = kind;
    ui.horizontal(|ui| {
        egui::ComboBox::new("material kind", "Material kind")
            .selected_text(kind.label())
            .show_ui(ui, |ui| {
                for k in MaterialKind::DEFAULTS {
                    let chosen = k.name() == kind.name();
                    if ui.selectable_label(chosen, k.label()).clicked() && !chosen {
                        kind = *k;
                    }
                }
            });
        if let Target::Part(part) = target
            && settings.part_materials.iter().any(|p| p.part == part)
            && ui
                .button("Reset material")
                .on_hover_text("Back to the scene's and the preset's material")
                .clicked()
        {
            settings.part_materials.retain(|p| p.part != part);
        }
    });
    for (field, value) in kind.fields_and_values() {
        let [lo, hi] = field.range;
        let edited = match value {
            FieldValue::Number(mut x) => {
                let slider = egui::Slider::new(&mut x, lo..=hi).text(field.name);
                let changed = ui.add(slider).on_hover_text(field.what).changed();
                changed.then_some(FieldValue::Number(x))
            }
            FieldValue::Colour(c) => {
                let mut channels = c.to_array();
                let mut changed = false;
                ui.horizontal(|ui| {
                    for (channel, x) in ["r", "g", "b"].iter().zip(&mut channels) {
                        let label = ui.label(format!("{} {channel}", field.name));
                        let drag = egui::DragValue::new(x).range(lo..=hi).speed(0.005);
                        changed |= ui
                            .add(drag)
                            .labelled_by(label.id)
                            .on_hover_text(field.what)
                            .changed();
                    }
                });
                changed.then_some(FieldValue::Colour(glam::Vec3::from_array(channels)))
            }
        };
        if let Some(value) = edited {
            // The value is of the field's own type and within its range: `set` cannot refuse it.
            let _ = kind.set(field.name, value);
        }
    }
    if kind != before {
        set_kind(settings, target, kind);
    }
}

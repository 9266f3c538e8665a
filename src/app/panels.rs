//! The side panel: grouped, labelled controls that edit the one [`RenderSettings`] value in
//! place, and return [`Command`]s for actions (reset, save, …) that the app handles in one place.
//!
//! Every control has a label; AccessKit exposes it, which is what screen readers and the tests
//! find them by.

use eframe::egui;
use raylab_core::base::camera;
use raylab_core::base::named::NamedEnum;
use raylab_core::shading::light::{LightKind, LightShape, ParamType, ParamValue};
use raylab_core::shading::material::MIN_ROUGHNESS;
use raylab_core::shading::material::TexturePreset;
use raylab_core::shapes::scene::SceneChoice;
use raylab_core::transport::display::Display;
use raylab_core::transport::integrator::MAX_SPECULAR_DEPTH;
use raylab_core::transport::settings::{Caustics, MAX_PHOTONS};
use raylab_core::transport::view::{Legend, View};
use raylab_core::{Camera, LightSpec, MaterialPreset, RenderSettings, Stage};

use super::Command;
use super::persistence::WorkbenchState;
use super::stats::Stats;

/// Square resolutions offered as presets; any width × height can be typed too.
pub const RESOLUTION_PRESETS: [u32; 5] = [128, 256, 512, 768, 1024];
/// The largest side the panel offers (the library allows more, from the command line).
pub const MAX_SIDE_UI: u32 = 4096;
/// The largest sample target the panel offers.
pub const MAX_SAMPLES_UI: u32 = 4096;
/// The most path-tracing bounces the panel's slider offers (or unlimited).
pub const MAX_BOUNCES_UI: u32 = 64;
/// The largest lens aperture radius the slider offers, in scene units.
pub const MAX_APERTURE_UI: f32 = 0.3;
/// The largest light radius the slider offers, in scene units.
pub const MAX_LIGHT_RADIUS_UI: f32 = 0.5;
/// The largest angle a light's angle slider offers (the spot's cutoff), in degrees: the
/// settings allow up to, not including, 90°.
pub const MAX_SPOT_CUTOFF_UI: f64 = 89.0;
/// The exposure slider's range either way, in stops.
pub const MAX_EXPOSURE_UI: f32 = 10.0;
/// The most render threads the panel offers.
pub const MAX_THREADS_UI: usize = 64;

/// What a point dragged on a control moves, on its rail or its number alike (egui's own rail
/// follows the pointer: on a 100-point rail Yaw's 360° would be 3.6° a point). Holding Shift
/// moves a tenth of it ([`FINE_DRAG`]), as in Blender.
/// Yaw and pitch, in degrees a point.
pub const DEGREES_PER_POINT: f64 = 0.5;
/// Camera and light coordinates, in scene units a point (the box, 2 units wide, in 400 points).
pub const UNITS_PER_POINT: f64 = 0.005;
/// The focal length, as a factor a point: `f · exp(points · this)`, 0.5 % a point.
pub const FOCAL_PER_POINT: f64 = 0.005;
/// The light's power, in watts a point.
pub const WATTS_PER_POINT: f64 = 0.1;
/// Shift divides a drag's movement by this (egui's number fields do the same).
pub const FINE_DRAG: f64 = 10.0;
/// A press on a rail that moves less than this, in points, is a click: the value goes where it
/// was clicked, as a slider's does.
const CLICK_POINTS: f32 = 3.0;

/// A selector of one of `T`'s values by their labels ([`NamedEnum::label`]), showing
/// `current`: its response (for its own tooltip) and the value clicked, if any. `hover` gives
/// each value's tooltip.
fn choice<T: NamedEnum>(
    ui: &mut egui::Ui,
    id: &str,
    label: &str,
    current: T,
    hover: Option<fn(T) -> &'static str>,
) -> (egui::Response, Option<T>) {
    let mut clicked = None;
    let response = egui::ComboBox::new(id, label)
        .selected_text(current.label())
        .show_ui(ui, |ui| {
            for &value in T::ALL {
                let mut item = ui.selectable_label(value == current, value.label());
                if let Some(hover) = hover {
                    item = item.on_hover_text(hover(value));
                }
                if item.clicked() {
                    clicked = Some(value);
                }
            }
        })
        .response;
    (response, clicked)
}

/// [`choice`] setting `value` to the value clicked.
fn choice_ui<T: NamedEnum>(
    ui: &mut egui::Ui,
    id: &str,
    label: &str,
    value: &mut T,
    hover: Option<fn(T) -> &'static str>,
) -> egui::Response {
    let (response, clicked) = choice(ui, id, label, *value, hover);
    if let Some(v) = clicked {
        *value = v;
    }
    response
}

/// The whole side panel.
pub fn controls_ui(
    ui: &mut egui::Ui,
    state: &mut WorkbenchState,
    stats: &Stats,
    loading: Option<&SceneChoice>,
    mut compare: Option<&mut super::compare::Compare>,
    check: Option<&mut super::check::StudentCheck>,
    equations: &mut super::equations::YourEquations,
) -> Vec<Command> {
    let mut commands = Vec::new();
    // What is shown comes first: which figure (or stage), the stage selector and what it
    // computes, in a block of fixed height so nothing below moves as the text changes.
    stage_ui(ui, &state.settings, &mut commands);
    ui.separator();
    ui.horizontal_wrapped(|ui| {
        if ui
            .button("Save screenshot")
            .on_hover_text(
                "Ctrl+S: the render at full resolution, as PNG carrying its settings (and a .json of them), \
                 into the folder under Screenshot",
            )
            .clicked()
        {
            commands.push(Command::SaveScreenshot);
        }
        if ui.button("Reset to lab defaults").clicked() {
            commands.push(Command::ResetToLabDefaults);
        }
        if ui.button("Help").on_hover_text("F1").clicked() {
            commands.push(Command::ToggleHelp);
        }
    });
    // The key figures stay in view however far the panel is scrolled.
    stats.key_figures_ui(ui);
    ui.separator();
    egui::ScrollArea::vertical().show(ui, |ui| {
        ui.horizontal(|ui| {
            let mut inspect = state.inspect_mode;
            if ui
                .checkbox(&mut inspect, "Inspect pixels")
                .on_hover_text(
                    "I: a click on the image pins a pixel; the panel on the right shows, line by \
                     line, the lab's equations that give it its value",
                )
                .changed()
            {
                commands.push(Command::ToggleInspector);
            }
        });
        egui::CollapsingHeader::new("Lab walk-through")
            .default_open(state.walk_step.is_some())
            .show(ui, |ui| walkthrough_ui(ui, state.walk_step, &mut commands));
        // Near the top: while checking, the diagnosis is what the student reads.
        egui::CollapsingHeader::new("Check my image")
            .default_open(false)
            .open(check.is_some().then_some(true))
            .show(ui, |ui| {
                super::check::check_ui(ui, check, &state.settings, &mut commands)
            });
        egui::CollapsingHeader::new("Your equations")
            .default_open(false)
            .show(ui, |ui| {
                super::equations::equations_ui(ui, equations, &state.settings)
            });
        egui::CollapsingHeader::new("Scene")
            .default_open(true)
            .show(ui, |ui| {
                scene_ui(
                    ui,
                    &mut state.settings.scene,
                    &mut state.obj_path,
                    loading,
                    &mut commands,
                )
            });
        egui::CollapsingHeader::new("Camera")
            .default_open(true)
            .show(ui, |ui| {
                camera_ui(ui, &mut state.settings.camera, &mut commands);
                lens_ui(ui, &mut state.settings.camera, &mut state.focus_mode);
            });
        egui::CollapsingHeader::new("Light")
            .default_open(true)
            .show(ui, |ui| light_ui(ui, &mut state.settings.light));
        egui::CollapsingHeader::new("Map")
            .default_open(true)
            .show(ui, |ui| map_ui(ui, &state.settings));
        egui::CollapsingHeader::new("Shading")
            .default_open(true)
            .show(ui, |ui| {
                shading_ui(
                    ui,
                    &mut state.settings,
                    &mut state.limited_bounces,
                    stats.legend.as_ref(),
                )
            });
        egui::CollapsingHeader::new("Image")
            .default_open(true)
            .show(ui, |ui| {
                image_ui(ui, &mut state.settings, &mut state.render_threads)
            });
        egui::CollapsingHeader::new("Display")
            .default_open(true)
            .show(ui, |ui| {
                display_ui(ui, &mut state.settings.display);
                denoise_ui(ui, &mut state.denoise, &state.settings);
            });
        egui::CollapsingHeader::new("Compare A/B")
            .default_open(true)
            .show(ui, |ui| {
                let compare = compare.as_deref_mut();
                super::compare::compare_ui(ui, compare, &state.settings, &mut commands)
            });
        egui::CollapsingHeader::new("Stats")
            .default_open(true)
            .show(ui, |ui| {
                stats.stats_ui(ui);
                if let Some(compare) = compare.as_deref() {
                    compare.stats_ui(ui, stats);
                }
            });
        egui::CollapsingHeader::new("Screenshot")
            .default_open(true)
            .show(ui, |ui| screenshot_ui(ui, &mut state.screenshot_folder));
    });
    commands
}

/// Rows of text the "Computes" block keeps room for; a longer text scrolls within it.
const COMPUTES_ROWS: f32 = 3.0;

/// The top of the side panel: the figure shown (or the stage, when the settings are not a lab
/// figure's), the stage selector with the figures' numbers, and what the settings compute.
fn stage_ui(ui: &mut egui::Ui, settings: &RenderSettings, commands: &mut Vec<Command>) {
    let heading = figure_heading(settings);
    ui.add(egui::Label::new(egui::RichText::new(&heading).strong()).truncate())
        .on_hover_text(&heading);
    // A stage chosen is a command: it also sets the stage's switches.
    let stage = settings.shading.stage;
    let (_, chosen) = choice(ui, "stage", "Stage", stage, Some(Stage::equation));
    if let Some(stage) = chosen {
        commands.push(Command::SetStage(stage));
    }
    // What the settings compute, as they are now: the one text the library keeps true. Its
    // block has one height whatever the text's length, so the controls below stay in place
    // (the walk-through's buttons among them) as the stage changes.
    let row = ui.text_style_height(&egui::TextStyle::Body) + ui.spacing().item_spacing.y;
    egui::ScrollArea::vertical()
        .id_salt("computes")
        .max_height(COMPUTES_ROWS * row)
        .auto_shrink([false, false])
        .show(ui, |ui| {
            ui.horizontal_wrapped(|ui| {
                ui.weak("Computes");
                ui.label(settings.description());
            });
        });
}

/// How `settings` differ from the lab figure of their stage, in a few words each: its switches
/// as the lab has them, N the lab's, on the lab's box with its materials, the shaded view and
/// the point light through a pinhole. The camera, the light's place and power and the samples
/// may be the user's: they change the view, not what is computed.
fn figure_differences(settings: &RenderSettings) -> Vec<String> {
    let s = &settings.shading;
    let mut differs: Vec<String> = s
        .switches_unlike_figure()
        .into_iter()
        .map(|(what, on)| format!("{what} {}", if on { "on" } else { "off" }))
        .collect();
    if s.stage != Stage::Flat {
        // N on as the figure has it, but not the lab's N.
        let (_, figure_n) = s.stage.preset_switches();
        if s.indirect && figure_n && s.indirect_light != raylab_core::Shading::LAB_INDIRECT_LIGHT {
            differs.push("another N".to_owned());
        }
        // Any light but the lab's point: an area light, or another kind by its name.
        if settings.light.is_area() {
            differs.push("an area light".to_owned());
        } else if settings.light.kind.size_param().is_none()
            && !settings.light.kind.params().is_empty()
        {
            differs.push(format!("a {} light", settings.light.kind.name()));
        }
    }
    if settings.scene != SceneChoice::Cornell {
        differs.push(format!("the {} scene", settings.scene.label()));
    }
    if settings.material_preset != MaterialPreset::None {
        differs.push(settings.material_preset.label().to_lowercase());
    }
    for p in &settings.part_materials {
        differs.push(format!(
            "a {} {}",
            p.kind.name(),
            p.part.name().replace('-', " ")
        ));
    }
    if settings.texture_preset != TexturePreset::None {
        differs.push("textures".to_owned());
    }
    if settings.view != View::Shaded {
        differs.push(format!("the {} view", settings.view.label().to_lowercase()));
    }
    if settings.camera.aperture > 0.0 {
        differs.push("depth of field".to_owned());
    }
    differs
}

/// One line naming what is shown: "Figure 7: ρ·(D + N) with shadows (eq. 30)" for a lab
/// figure ([`figure_differences`] finds none); otherwise the stage, and how it differs from its figure, without
/// claiming one.
pub fn figure_heading(settings: &RenderSettings) -> String {
    let stage = settings.shading.stage;
    let Some(figure) = stage.figure() else {
        return "Path tracing: beyond the lab's figures".to_owned();
    };
    let differs = figure_differences(settings);
    if differs.is_empty() {
        format!("Figure {figure}: {}", stage.equation())
    } else {
        let name = stage.label();
        let name = name.split(" (").next().unwrap_or(name);
        format!("{name} stage, not figure {figure}: {}", differs.join(", "))
    }
}

/// The pool's waves, when the scene has water: their amplitude and the time they are seen at.
/// A change makes another scene (its water's normal map is made again, off this thread).
fn water_ui(ui: &mut egui::Ui, scene: &mut SceneChoice) {
    let mut spec = scene.spec();
    let Some(water) = &mut spec.water else {
        return;
    };
    let before = *water;
    ui.add(
        egui::Slider::new(
            &mut water.waves,
            0.0..=raylab_core::shapes::scene::water::MAX_WAVES,
        )
        .text("Wave amplitude")
        .logarithmic(true)
        .smallest_positive(1e-4),
    )
    .on_hover_text(
        "How high the fractal waves are, in scene units: they tilt the water's normal (a normal \
         map), so reflections and refraction ripple; 0 is still water",
    );
    ui.add(egui::Slider::new(&mut water.time, 0.0..=60.0).text("Water time (s)"))
        .on_hover_text("The waves at this time: each octave of the wave field drifts its own way");
    if *water != before {
        *scene = SceneChoice::from_spec(spec);
    }
}

/// The scene: the lab's box or a model standing in it, a scene file's or any OBJ file; and the
/// File row, which opens scene files, screenshots and models and saves scene files.
pub fn scene_ui(
    ui: &mut egui::Ui,
    scene: &mut SceneChoice,
    file_path: &mut String,
    loading: Option<&SceneChoice>,
    commands: &mut Vec<Command>,
) {
    ui.horizontal(|ui| {
        egui::ComboBox::new("scene", "Scene")
            .selected_text(scene.label())
            .show_ui(ui, |ui| {
                for choice in SceneChoice::BUILT_IN {
                    let label = choice.label();
                    if ui.selectable_label(*scene == choice, label).clicked() {
                        if *scene != choice {
                            // The built-in scenes come from no file: a path left in the File
                            // field would name another scene's.
                            file_path.clear();
                        }
                        *scene = choice;
                    }
                }
            });
        if let Some(choice) = loading {
            // In the selector's row, so nothing below moves while a scene loads (the status
            // line says what is loading).
            ui.spinner().on_hover_text(format!("Loading {choice}..."));
            if ui
                .button("Cancel")
                .on_hover_text("Stop loading; the scene on screen stays")
                .clicked()
            {
                commands.push(Command::CancelLoading);
            }
        }
    });
    water_ui(ui, scene);
    ui.horizontal(|ui| {
        let label = ui.label("File");
        let field = ui
            .add(egui::TextEdit::singleline(file_path).desired_width(200.0))
            .labelled_by(label.id)
            .on_hover_text(
                "A scene file (.toml), a screenshot (.png, or its .json) or an OBJ model \
                 (Enter opens it). Files dropped on the window open too.",
            );
        if field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)) {
            commands.push(Command::OpenTyped);
        }
    });
    ui.horizontal_wrapped(|ui| {
        if ui
            .button("Open")
            .on_hover_text("Open the file typed above")
            .clicked()
        {
            commands.push(Command::OpenTyped);
        }
        if ui
            .button("Save scene")
            .on_hover_text(
                "Save the scene, camera, light and every setting to the .toml file typed above",
            )
            .clicked()
        {
            commands.push(Command::SaveSceneTyped);
        }
        if ui.button("Open…").on_hover_text("Ctrl+O").clicked() {
            commands.push(Command::ShowOpenDialog);
        }
        if ui
            .button("Save scene as…")
            .on_hover_text("Ctrl+Shift+S")
            .clicked()
        {
            commands.push(Command::ShowSaveSceneDialog);
        }
        if ui
            .button("Open settings from screenshot…")
            .on_hover_text("A screenshot's PNG (or .json) restores the render it shows")
            .clicked()
        {
            commands.push(Command::ShowScreenshotDialog);
        }
    });
}

pub fn camera_ui(ui: &mut egui::Ui, camera: &mut Camera, commands: &mut Vec<Command>) {
    position_slider(ui, &mut camera.position.x, -2.0..=2.0, "Camera x");
    position_slider(ui, &mut camera.position.y, -2.0..=2.0, "Camera y");
    position_slider(ui, &mut camera.position.z, -6.0..=2.0, "Camera z");
    degrees_slider(ui, &mut camera.yaw, -180.0..=180.0, "Yaw");
    degrees_slider(ui, &mut camera.pitch, -89.0..=89.0, "Pitch");
    let w = camera.width as f32;
    let before = f64::from(camera.focal_length);
    let response = ui.add(
        egui::Slider::new(&mut camera.focal_length, 0.1 * w..=10.0 * w)
            .custom_parser(typed_number("Focal length", 0.1 * w, 10.0 * w))
            .logarithmic(true)
            .max_decimals(1)
            .suffix(" px")
            .drag_value_speed(before * FOCAL_PER_POINT)
            .text("Focal length"),
    );
    if let Some(points) = rail_drag(ui, &response) {
        let f = before * (points * FOCAL_PER_POINT).exp();
        camera.focal_length = f.clamp(0.1 * f64::from(w), 10.0 * f64::from(w)) as f32;
    }
    ui.label(format!(
        "Field of view: {:.1}° horizontal, {:.1}° vertical",
        camera.horizontal_fov_degrees(),
        camera.vertical_fov_degrees()
    ));
    ui.horizontal_wrapped(|ui| {
        if ui.button("Look at the box centre").clicked() {
            commands.push(Command::LookAtBoxCentre);
        }
        if ui.button("Reset camera").clicked() {
            commands.push(Command::ResetCamera);
        }
    });
}

/// A slider over a coordinate. The keys may move a point past the slider's ends: the value is
/// kept as it is, not clamped back.
fn position_slider(
    ui: &mut egui::Ui,
    value: &mut f32,
    range: std::ops::RangeInclusive<f32>,
    label: &str,
) {
    let before = f64::from(*value);
    let response = ui.add(
        egui::Slider::new(value, range.clone())
            .custom_parser(typed_number(label, *range.start(), *range.end()))
            .clamping(egui::SliderClamping::Edits)
            .custom_formatter(|v, _| fixed(v, 2))
            .drag_value_speed(UNITS_PER_POINT)
            .text(label),
    );
    if let Some(points) = rail_drag(ui, &response) {
        let (lo, hi) = (f64::from(*range.start()), f64::from(*range.end()));
        *value = (before + points * UNITS_PER_POINT).clamp(lo.min(before), hi.max(before)) as f32;
    }
}

/// The points a slider's rail was dragged this frame (a tenth with Shift: [`FINE_DRAG`]),
/// while its drag goes on and on the frame it ends, or `None` when the rail is not dragged (or
/// the press was a click, which leaves the value where egui put it). The caller sets the value
/// from its value before the frame: the rail then moves its value by a fixed amount a point
/// ([`DEGREES_PER_POINT`] …) from where it was, not to where the pointer is on the rail.
fn rail_drag(ui: &egui::Ui, response: &egui::Response) -> Option<f64> {
    // While the number beside the rail has the focus, the response is the number's.
    let held = !response.has_focus() && ui.ctx().is_being_dragged(response.id);
    let moved_id = response.id.with("rail drag");
    let moved: Option<f32> = ui.data(|d| d.get_temp(moved_id));
    if !held && moved.is_none() {
        return None;
    }
    let (delta, shift) = ui.input(|i| (i.pointer.delta().x, i.modifiers.shift_only()));
    // The press's own frame moves nothing: its delta may be the pointer's jump onto the rail.
    let delta = if moved.is_some() { delta } else { 0.0 };
    let total = moved.unwrap_or(0.0) + delta.abs();
    if held {
        ui.data_mut(|d| d.insert_temp(moved_id, total));
    } else {
        ui.data_mut(|d| d.remove::<f32>(moved_id));
        if total < CLICK_POINTS {
            return None;
        }
    }
    let scale = if shift { 1.0 / FINE_DRAG } else { 1.0 };
    Some(f64::from(delta) * scale)
}

/// What the newest text typed into a number field came to, for the status line.
#[derive(Clone, Debug, PartialEq)]
pub enum Typed {
    /// The field named `field` got a text it could not use as it stands: not a number, or one
    /// outside its range (then clamped). `message` says which.
    Problem { field: String, message: String },
    /// The field named `field` got a number in its range: a message about it is stale.
    Fine { field: String },
}

thread_local! {
    /// The newest [`Typed`], until the app takes it.
    static TYPED: std::cell::RefCell<Option<Typed>> = const { std::cell::RefCell::new(None) };
}

fn report_typed(typed: Typed) {
    TYPED.with(|t| *t.borrow_mut() = Some(typed));
}

/// The parser of every number field. egui's own turns `NaN` into the field's maximum (NaN
/// compares false with both ends of the range); here a text that is not a finite number —
/// `NaN`, `inf`, `abc` — parses to nothing, so the value stays as it was, and [`take_typed`]
/// says so. A number outside `lo..=hi` is clamped by the field as before, and [`take_typed`]
/// says so too; a number in range reports the field fine, so a message about it goes.
///
/// egui parses the text at every keystroke: the last report is the text as it stands. A text
/// that is empty or only a sign or point (the start of a number being typed) reports nothing.
pub fn typed_number<'a, T: Into<f64> + Copy>(
    name: &'a str,
    lo: T,
    hi: T,
) -> impl Fn(&str) -> Option<f64> + 'a {
    let (lo, hi) = (lo.into(), hi.into());
    move |text: &str| {
        let number = text
            .trim()
            .trim_end_matches(['°', ' '])
            .trim_end_matches(" px")
            .trim_end_matches(" W")
            .trim_end_matches(" EV");
        let number = number.trim();
        let v = match number.parse::<f64>() {
            Ok(v) if v.is_finite() => v,
            parsed => {
                if !number.chars().all(|c| matches!(c, '-' | '+' | '.')) {
                    let what = if parsed.is_ok() {
                        "not a finite number"
                    } else {
                        "not a number"
                    };
                    report_typed(Typed::Problem {
                        field: name.to_owned(),
                        message: format!("{name}: \"{number}\" is {what}, so the value was kept"),
                    });
                }
                return None;
            }
        };
        if v < lo || v > hi {
            let to = v.clamp(lo, hi);
            let message = format!(
                "{name}: {number} is outside {} to {}, so it was set to {}",
                fixed(lo, 2).trim_end_matches(".00"),
                fixed(hi, 2).trim_end_matches(".00"),
                fixed(to, 2).trim_end_matches(".00")
            );
            report_typed(Typed::Problem {
                field: name.to_owned(),
                message,
            });
        } else {
            report_typed(Typed::Fine {
                field: name.to_owned(),
            });
        }
        Some(v)
    }
}

/// The newest [`Typed`] report of a number field, once.
pub fn take_typed() -> Option<Typed> {
    TYPED.with(|t| t.borrow_mut().take())
}

/// `v` with `decimals` decimals, never "-0.00": a value that rounds to zero shows as zero
/// whatever its sign.
pub fn fixed(v: f64, decimals: usize) -> String {
    let text = format!("{v:.decimals$}");
    match text.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_owned(),
        _ => text,
    }
}

/// A slider in degrees over an angle stored in radians; the value changes only when the
/// slider does, so no rounding creeps in from converting back and forth.
fn degrees_slider(
    ui: &mut egui::Ui,
    radians: &mut f32,
    range: std::ops::RangeInclusive<f32>,
    label: &str,
) {
    // In f64 and through `camera::radians`: a typed angle becomes the radians the same number
    // gives on the command line and in a scene file.
    let before = raylab_core::base::camera::degrees(*radians);
    let mut degrees = before;
    let response = ui.add(
        egui::Slider::new(
            &mut degrees,
            f64::from(*range.start())..=f64::from(*range.end()),
        )
        .custom_parser(typed_number(label, *range.start(), *range.end()))
        .suffix("°")
        .custom_formatter(|v, _| fixed(v, 1))
        .drag_value_speed(DEGREES_PER_POINT)
        .text(label),
    );
    if let Some(points) = rail_drag(ui, &response) {
        let (lo, hi) = (f64::from(*range.start()), f64::from(*range.end()));
        degrees = (before + points * DEGREES_PER_POINT).clamp(lo, hi);
    }
    if degrees != before {
        *radians = raylab_core::base::camera::radians(degrees);
    }
}

/// The thin lens: aperture and focus (depth of field).
pub fn lens_ui(ui: &mut egui::Ui, camera: &mut Camera, focus_mode: &mut bool) {
    ui.add(
        egui::Slider::new(&mut camera.aperture, 0.0..=MAX_APERTURE_UI)
            .custom_parser(typed_number("Aperture", 0.0, MAX_APERTURE_UI))
            .clamping(egui::SliderClamping::Edits)
            .max_decimals(3)
            .text("Aperture"),
    )
    .on_hover_text(
        "Radius of the lens, in scene units (the box is 2 wide): 0 is the lab's pinhole, \
         everything sharp; larger blurs what is off the focus distance",
    );
    ui.add_enabled(
        camera.aperture > 0.0,
        egui::Slider::new(&mut camera.focus_distance, 0.1..=10.0)
            .custom_parser(typed_number("Focus distance", 0.1, 10.0))
            .logarithmic(true)
            .clamping(egui::SliderClamping::Edits)
            .max_decimals(3)
            .text("Focus distance"),
    )
    .on_hover_text("Distance along the view direction to the plane that is sharp")
    .on_disabled_hover_text("Set an aperture above 0 for depth of field");
    ui.checkbox(focus_mode, "Click to focus")
        .on_hover_text("A click on the image sets the focus distance to that pixel's depth");
}

pub fn light_ui(ui: &mut egui::Ui, light: &mut LightSpec) {
    position_slider(ui, &mut light.position.x, -1.0..=1.0, "Light x");
    position_slider(ui, &mut light.position.y, -1.0..=1.0, "Light y");
    position_slider(ui, &mut light.position.z, -1.0..=1.0, "Light z");
    let before = f64::from(light.power);
    let response = ui
        .add(
            egui::Slider::new(&mut light.power, 0.0..=100.0)
                .custom_parser(typed_number("Light power", 0.0, 100.0))
                .suffix(" W")
                .drag_value_speed(WATTS_PER_POINT)
                .text("Light power"),
        )
        .on_hover_text("The total power P; each channel gets P times the colour");
    if let Some(points) = rail_drag(ui, &response) {
        light.power = (before + points * WATTS_PER_POINT).clamp(0.0, 100.0) as f32;
    }
    ui.horizontal(|ui| {
        let mut rgb = light.colour.to_array();
        let label = ui.label("Light colour");
        let response = egui::color_picker::color_edit_button_rgb(ui, &mut rgb)
            .labelled_by(label.id)
            .on_hover_text("The light's colour (the lab's is white, 1, 1, 1)");
        if response.changed() {
            light.colour = glam::Vec3::from_array(rgb);
        }
        if light.colour != glam::Vec3::ONE && ui.small_button("White").clicked() {
            light.colour = glam::Vec3::ONE;
        }
    });
    let mut shape = light.kind.shape();
    choice_ui(ui, "light_shape", "Light shape", &mut shape, None).on_hover_text(
        "The lab's point light, an area light of the same power (a sphere, or a square facing \
         the floor), or a spot (the point light's intensity inside a cone). The lab's stages \
         keep equation 27 from its centre and soften the shadows; the path stage sees the real \
         light, with multiple importance sampling",
    );
    if shape != light.kind.shape() {
        // An area light keeps its size from one shape to the other.
        let size = light.kind.size();
        light.kind = match LightKind::of_shape(shape).size_param() {
            Some(_) if size > 0.0 => LightKind::sized(shape, size),
            Some(_) | None => LightKind::of_shape(shape),
        };
    }
    light_params_ui(ui, &mut light.kind);
}

/// The light kind's parameters (`light_kinds!`), each by its type: a size as a slider in scene
/// units, a point as three coordinate sliders, an angle as a slider in degrees; then the
/// kind's own rules ([`LightKind::tidy`]: the spot's beam never wider than its cutoff). The
/// point light, of no parameters, shows the first sized kind's size at 0 (the sphere's radius):
/// a size above 0 makes it that light, the one it always meant.
fn light_params_ui(ui: &mut egui::Ui, kind: &mut LightKind) {
    let first_sized = LightShape::ALL
        .iter()
        .map(|&s| LightKind::sized(s, 0.0))
        .find(|k| k.size_param().is_some());
    let mut edited = match (kind.params().is_empty(), first_sized) {
        (true, Some(sized)) => sized,
        (true, None) | (false, _) => *kind,
    };
    for (p, value) in edited.params_and_values() {
        let value = match value {
            ParamValue::Number(mut x) => {
                let (degrees, shown) = match p.ty {
                    ParamType::Angle => (true, camera::degrees(x)),
                    ParamType::Size | ParamType::Point => (false, f64::from(x)),
                };
                let mut edit = shown;
                let max = match degrees {
                    true => p.bounds.hi.min(MAX_SPOT_CUTOFF_UI),
                    false => f64::from(MAX_LIGHT_RADIUS_UI),
                };
                let slider = egui::Slider::new(&mut edit, 0.0..=max)
                    .custom_parser(typed_number(p.label, 0.0, max as f32))
                    .text(p.label);
                let slider = match degrees {
                    true => slider
                        .clamping(egui::SliderClamping::Always)
                        .max_decimals(1)
                        .suffix("°"),
                    false => slider.clamping(egui::SliderClamping::Edits).max_decimals(3),
                };
                ui.add(slider).on_hover_text(p.what);
                if edit != shown {
                    x = p.stored(edit);
                }
                ParamValue::Number(x)
            }
            ParamValue::Point(v) => {
                let mut xyz = v.to_array();
                for (axis, c) in ["x", "y", "z"].into_iter().zip(&mut xyz) {
                    position_slider(ui, c, -1.0..=1.0, &format!("{} {axis}", p.label));
                }
                ParamValue::Point(glam::Vec3::from_array(xyz))
            }
        };
        // The parameter is the kind's own, of the value's type: this cannot fail.
        let _ = edited.set(p.name, value);
    }
    edited.tidy();
    if edited != *kind && !(kind.params().is_empty() && edited.size() == 0.0) {
        *kind = edited;
    }
}

/// The lab walk-through: the current step's explanation and equation, Previous / Next.
pub fn walkthrough_ui(ui: &mut egui::Ui, step: Option<usize>, commands: &mut Vec<Command>) {
    use raylab_core::teaching::walkthrough::STEPS;
    let Some(n) = step.filter(|&n| n < STEPS.len()) else {
        ui.label(
            "Step through the lab's figures 2, 3, 5, 6 and 7, then the extensions, each with \
             what it computes. Your camera and light stay as they are.",
        );
        if ui.button("Start the walk-through").clicked() {
            commands.push(Command::WalkTo(Some(0)));
        }
        return;
    };
    let s = &STEPS[n];
    // The buttons first, so they stay in place whatever the length of the step's text below.
    ui.horizontal(|ui| {
        if ui
            .add_enabled(n > 0, egui::Button::new("Previous"))
            .clicked()
        {
            commands.push(Command::WalkTo(Some(n - 1)));
        }
        if ui
            .add_enabled(n + 1 < STEPS.len(), egui::Button::new("Next"))
            .clicked()
        {
            commands.push(Command::WalkTo(Some(n + 1)));
        }
        if ui.button("Leave").clicked() {
            commands.push(Command::WalkTo(None));
        }
    });
    ui.strong(format!("Step {} of {}: {}", n + 1, STEPS.len(), s.title));
    ui.label(egui::RichText::new(s.equation).monospace());
    ui.label(s.text);
}

/// The map's size in points.
const MAP_SIZE: f32 = 180.0;

/// A top view of the box: the camera with its field of view, and the light. x runs right and z
/// (the camera's forward at yaw 0) up, as seen from above; the box is the square |x|, |z| ≤ 1.
pub fn map_ui(ui: &mut egui::Ui, settings: &RenderSettings) {
    let camera = &settings.camera;
    let light = settings.light.position;
    // Fit the box, the camera and the light, with a margin, keeping the scale equal.
    let (mut lo, mut hi) = (egui::vec2(-1.0, -1.0), egui::vec2(1.0, 1.0));
    for p in [camera.position, light] {
        if p.is_finite() {
            lo = lo.min(egui::vec2(p.x, p.z));
            hi = hi.max(egui::vec2(p.x, p.z));
        }
    }
    let centre = (lo + hi) / 2.0;
    let extent = (hi - lo).max_elem().min(50.0) + 0.6;
    let (response, painter) =
        ui.allocate_painter(egui::vec2(MAP_SIZE, MAP_SIZE), egui::Sense::hover());
    let rect = response.rect;
    let scale = MAP_SIZE / extent;
    let to_screen = |x: f32, z: f32| {
        rect.center() + egui::vec2((x - centre.x) * scale, -(z - centre.y) * scale)
    };
    let visuals = ui.visuals();
    painter.rect_filled(rect, 2.0, visuals.extreme_bg_color);
    let wall = egui::Stroke::new(1.5, visuals.text_color());
    let corners =
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, z)| to_screen(x, z));
    // The box's front (z = −1) is open: three walls.
    painter.line_segment([corners[1], corners[2]], wall);
    painter.line_segment([corners[2], corners[3]], wall);
    painter.line_segment([corners[3], corners[0]], wall);
    painter.line_segment(
        [corners[0], corners[1]],
        egui::Stroke::new(1.0, visuals.weak_text_color()),
    );
    // The camera: its position and the edges of its horizontal field of view.
    let eye = to_screen(camera.position.x, camera.position.z);
    let half = (camera.width as f32 / 2.0 / camera.focal_length).atan();
    let reach = 1.0;
    for a in [camera.yaw - half, camera.yaw + half] {
        let (s, c) = a.sin_cos();
        let end = to_screen(camera.position.x + reach * s, camera.position.z + reach * c);
        painter.line_segment(
            [eye, end],
            egui::Stroke::new(1.0, egui::Color32::LIGHT_BLUE),
        );
    }
    painter.circle_filled(eye, 4.0, egui::Color32::LIGHT_BLUE);
    painter.circle(
        to_screen(light.x, light.z),
        5.0,
        egui::Color32::from_rgb(255, 220, 60),
        egui::Stroke::new(1.0, egui::Color32::from_gray(30)),
    );
    response.on_hover_text(format!(
        "Top view: x to the right, z up. Camera at ({:.2}, {:.2}, {:.2}), yaw {:.0}°; light at ({:.2}, \
         {:.2}, {:.2}). The box's open front is the faint side.",
        camera.position.x,
        camera.position.y,
        camera.position.z,
        camera.yaw.to_degrees(),
        light.x,
        light.y,
        light.z
    ));
}

/// How the image is shown: changing it never re-traces.
pub fn display_ui(ui: &mut egui::Ui, display: &mut Display) {
    choice_ui(
        ui,
        "display",
        "Display transform",
        &mut display.transform,
        None,
    )
    .on_hover_text(
        "How linear values become screen pixels (and PNG screenshots). Lab: clamped to \
             [0, 1], no gamma, the lab's figures. sRGB: the standard encoding. Filmic: \
             highlights roll off instead of clipping.",
    );
    ui.add(
        egui::Slider::new(&mut display.exposure, -MAX_EXPOSURE_UI..=MAX_EXPOSURE_UI)
            .custom_parser(typed_number("Exposure", -MAX_EXPOSURE_UI, MAX_EXPOSURE_UI))
            .clamping(egui::SliderClamping::Edits)
            .max_decimals(2)
            .suffix(" EV")
            .text("Exposure"),
    )
    .on_hover_text("Stops: +1 doubles every value before the display curve");
}

/// The "Denoise" switch: on, noisy images are shown denoised. Offered for every image, said
/// to do nothing where nothing is noisy (the lab's stages with a point light and a pinhole).
fn denoise_ui(ui: &mut egui::Ui, denoise: &mut bool, settings: &RenderSettings) {
    let response = ui
        .checkbox(denoise, "Denoise")
        .on_hover_text(super::stats::DENOISE_HOVER);
    if !settings.is_stochastic() {
        response.on_hover_text(
            "Nothing to denoise here: this image has no noise (no path tracing, soft shadows \
             or depth of field)",
        );
    }
}

/// The view selector and, for a debug view, its legend: what the colours mean and their range.
fn view_ui(ui: &mut egui::Ui, view: &mut View, legend: Option<&Legend>) {
    choice_ui(ui, "view", "View", view, Some(View::description)).on_hover_text("What the image shows: the stage's shaded image, or a debug view traced from the same camera");
    if *view == View::Shaded {
        return;
    }
    egui::Frame::group(ui.style()).show(ui, |ui| match legend {
        Some(legend) => {
            ui.strong(&legend.title);
            for line in &legend.lines {
                ui.label(line);
            }
        }
        None => {
            ui.weak(view.description());
        }
    });
}

/// What each materials preset does, for its hover text.
fn material_hover(preset: MaterialPreset) -> &'static str {
    match preset {
        MaterialPreset::None => "Every surface diffuse, as in the lab",
        MaterialPreset::Mirror => "The tall blue block becomes an ideal mirror reflecting 90 %",
        MaterialPreset::Glass => {
            "The short red block becomes clear glass (index of refraction 1.5)"
        }
        MaterialPreset::Both => "The tall block a mirror, the short block glass",
        MaterialPreset::Rough => {
            "The tall blue block becomes a rough metal reflecting 90 % (GGX microfacets of \
             roughness α): a highlight under the light, blurred reflections in the path stage"
        }
        MaterialPreset::Plastic => {
            "The tall blue block becomes a glossy plastic: its blue base under a clear coating \
             (index 1.5, GGX roughness α): a white highlight under the light over the blue"
        }
    }
}

/// The stage, its switches, the path tracer's bounces and the materials. `limited_bounces` is
/// the bounce count the "Bounces" slider remembers while "Unlimited bounces" is ticked.
pub fn shading_ui(
    ui: &mut egui::Ui,
    settings: &mut RenderSettings,
    limited_bounces: &mut u32,
    legend: Option<&Legend>,
) {
    let path = settings.shading.stage == Stage::Path;
    view_ui(ui, &mut settings.view, legend);
    let roughness = &mut settings.roughness;
    let materials = &mut settings.material_preset;
    ui.horizontal_wrapped(|ui| {
        let before = *materials;
        choice_ui(
            ui,
            "materials",
            "Materials",
            materials,
            Some(material_hover),
        );
        if *materials != before {
            // Each preset starts at its own roughness (the plastic's coating 0.1).
            *roughness = materials.default_roughness();
        }
        if let Some(hint) = materials.front_face_note(path, *roughness) {
            ui.weak(hint);
        }
    });
    if matches!(*materials, MaterialPreset::Rough | MaterialPreset::Plastic) {
        ui.add(
            egui::Slider::new(roughness, MIN_ROUGHNESS..=1.0)
                .logarithmic(true)
                .text("Roughness α"),
        )
        .on_hover_text(
            "The rough metal's or the plastic coating's GGX roughness α: small is nearly a \
             mirror, 1 spreads the reflection over the whole hemisphere",
        );
    }
    egui::CollapsingHeader::new("Material editor")
        .default_open(!settings.part_materials.is_empty())
        .show(ui, |ui| {
            super::material_editor::material_editor_ui(ui, settings)
        });
    let materials_changed =
        settings.material_preset != MaterialPreset::None || !settings.part_materials.is_empty();
    let textures = &mut settings.texture_preset;
    let shading = &mut settings.shading;
    choice_ui(ui, "textures", "Textures", textures, None).on_hover_text(
        "Textures for the box: ρ read from a checkerboard or a grid at each hit (a textured \
             model keeps its own)",
    );
    ui.checkbox(&mut shading.smooth, "Smooth shading")
        .on_hover_text(
            "Light models with their vertex normals interpolated across each triangle; the box is \
         flat either way (the lab's look). Off: every triangle flat (faceted).",
        );
    if *textures == TexturePreset::ParallaxFloor {
        ui.checkbox(&mut shading.parallax_shadows, "Parallax self-shadowing")
            .on_hover_text(
                "Where the height map carves the floor, its own relief hides the light from the \
                 points behind it: a tile's edge shadows the grout beside it. Off: the carved \
                 floor is lit as if nothing stood in the way.",
            );
    }
    // The flat stage shows ρ alone: no light is computed, so neither switch changes anything.
    let flat = shading.stage == Stage::Flat;
    let flat_why = "The flat stage shows the reflectance ρ alone: it computes no light, so \
                    this changes nothing (choose another stage)";
    ui.add_enabled(!flat, egui::Checkbox::new(&mut shading.shadows, "Shadows"))
        .on_hover_text("Cast a shadow ray from each hit to the light (section 5.1)")
        .on_disabled_hover_text(flat_why);
    let indirect_hover = if path {
        "Follow bounces of real indirect light; off: direct light only"
    } else {
        "Add the lab's constant indirect light N (section 5.2)"
    };
    ui.add_enabled(
        !flat,
        egui::Checkbox::new(&mut shading.indirect, "Indirect light"),
    )
    .on_hover_text(indirect_hover)
    .on_disabled_hover_text(flat_why);
    let mut n = shading.indirect_light.x;
    let response = ui
        .add_enabled(
            shading.indirect && !path && !flat,
            egui::Slider::new(&mut n, 0.0..=1.0)
                .custom_parser(typed_number("Indirect N", 0.0, 1.0))
                .text("Indirect N"),
        )
        .on_hover_text("The lab's constant indirect light N, added to D at every hit")
        .on_disabled_hover_text(if path {
            "Not used by the path tracer: it computes the real indirect light instead, by \
             following bounces"
        } else if flat {
            flat_why
        } else {
            "Tick \"Indirect light\" to add N"
        });
    if response.changed() {
        shading.indirect_light = glam::Vec3::splat(n);
    }

    // The path tracer's bounces.
    let bounces_enabled = path && shading.indirect;
    let bounces_off_why = if path {
        "\"Indirect light\" is off: the path tracer computes direct light only"
    } else {
        "Used by the path tracing stage"
    };
    let mut unlimited = shading.bounces.is_none();
    let response = ui
        .add_enabled(
            bounces_enabled,
            egui::Checkbox::new(&mut unlimited, "Unlimited bounces"),
        )
        .on_hover_text("Paths bounce until Russian roulette ends them (unbiased)")
        .on_disabled_hover_text(bounces_off_why);
    if response.changed() {
        shading.bounces = if unlimited {
            // Remember the count for when the box is unticked again.
            *limited_bounces = shading.bounces.unwrap_or(*limited_bounces);
            None
        } else {
            Some(*limited_bounces)
        };
    }
    let mut bounces = shading.bounces.unwrap_or(*limited_bounces);
    let response = ui
        .add_enabled(
            bounces_enabled && shading.bounces.is_some(),
            egui::Slider::new(&mut bounces, 0..=MAX_BOUNCES_UI)
                .custom_parser(typed_number("Bounces", 0, MAX_BOUNCES_UI))
                .clamping(egui::SliderClamping::Edits)
                .text("Bounces"),
        )
        .on_hover_text("The most diffuse bounces a path makes: 0 is direct light only")
        .on_disabled_hover_text(if bounces_enabled {
            "Untick \"Unlimited bounces\" to cap the bounces"
        } else {
            bounces_off_why
        });
    if response.changed() {
        shading.bounces = Some(bounces);
        *limited_bounces = bounces;
    }

    // The lab stages follow mirror and glass Whitted-style.
    let whitted = !path && materials_changed;
    ui.add_enabled(
        whitted,
        egui::Slider::new(&mut shading.specular_depth, 0..=MAX_SPECULAR_DEPTH)
            .custom_parser(typed_number("Specular depth", 0, MAX_SPECULAR_DEPTH))
            .clamping(egui::SliderClamping::Edits)
            .text("Specular depth"),
    )
    .on_hover_text(
        "How many mirror and glass hits in a row are followed (Whitted-style) before a ray \
         is given up as black",
    )
    .on_disabled_hover_text(if path {
        "The path tracer follows mirror and glass along its paths instead"
    } else {
        "Choose a mirror or glass under Materials: only those are followed"
    });

    // Caustics by photon mapping: the path stage only.
    let caustics_off_why = "Used by the path tracing stage: the lab's stages follow mirror \
                            and glass Whitted-style and gather no photons";
    let mut photons_on = shading.caustics == Caustics::Photons;
    if ui
        .add_enabled(
            path,
            egui::Checkbox::new(&mut photons_on, "Caustics: photons"),
        )
        .on_hover_text(
            "Shoot a caustic photon map each pass (light through mirror and glass onto \
             diffuse surfaces) and gather it at each diffuse hit of a path: the caustic \
             of the lab's point light, which a path tracer never finds",
        )
        .on_disabled_hover_text(caustics_off_why)
        .changed()
    {
        shading.caustics = if photons_on {
            Caustics::Photons
        } else {
            Caustics::Off
        };
    }
    ui.add_enabled(
        path && photons_on,
        egui::Slider::new(&mut shading.photons, 1_000..=MAX_PHOTONS)
            .logarithmic(true)
            .custom_parser(typed_number("Photons per pass", 1, MAX_PHOTONS))
            .clamping(egui::SliderClamping::Edits)
            .text("Photons per pass"),
    )
    .on_hover_text("Photons shot from the light each pass; the gather radius shrinks pass by pass")
    .on_disabled_hover_text(if path {
        "Tick \"Caustics: photons\" to shoot photons"
    } else {
        caustics_off_why
    });
}

pub fn image_ui(ui: &mut egui::Ui, settings: &mut RenderSettings, threads: &mut usize) {
    let camera = &mut settings.camera;
    let (mut width, mut height) = (camera.width, camera.height);
    let current = format!("{width} × {height}");
    egui::ComboBox::new("resolution", "Resolution")
        .selected_text(current)
        .show_ui(ui, |ui| {
            for side in RESOLUTION_PRESETS {
                let selected = width == side && height == side;
                if ui
                    .selectable_label(selected, format!("{side} × {side}"))
                    .clicked()
                {
                    (width, height) = (side, side);
                }
            }
        });
    ui.horizontal(|ui| {
        let w = ui.label("Width");
        ui.add(
            egui::DragValue::new(&mut width)
                .range(1..=MAX_SIDE_UI)
                .custom_parser(typed_number("Width", 1, MAX_SIDE_UI)),
        )
        .labelled_by(w.id);
        let h = ui.label("Height");
        ui.add(
            egui::DragValue::new(&mut height)
                .range(1..=MAX_SIDE_UI)
                .custom_parser(typed_number("Height", 1, MAX_SIDE_UI)),
        )
        .labelled_by(h.id);
    });
    if (width, height) != (camera.width, camera.height) {
        // Keep the field of view: the focal length follows the width.
        *camera = camera.with_resolution(width, height);
    }
    ui.add(
        egui::Slider::new(&mut settings.samples_per_pixel, 1..=MAX_SAMPLES_UI)
            .custom_parser(typed_number("Sample target", 1, MAX_SAMPLES_UI))
            .logarithmic(true)
            .text("Sample target"),
    )
    .on_hover_text("Samples per pixel to accumulate: 1 is the lab's image, more anti-alias it");
    ui.add(
        egui::Slider::new(threads, 1..=MAX_THREADS_UI)
            .custom_parser(typed_number("Render threads", 1, MAX_THREADS_UI as u32))
            .text("Render threads"),
    );
}

pub fn screenshot_ui(ui: &mut egui::Ui, folder: &mut std::path::PathBuf) {
    let mut text = folder.to_string_lossy().into_owned();
    ui.horizontal(|ui| {
        let label = ui.label("Screenshot folder");
        let response = ui
            .add(egui::TextEdit::singleline(&mut text).desired_width(f32::INFINITY))
            .labelled_by(label.id)
            .on_hover_text("Screenshots are saved here as raylab-YYYYMMDD-HHMMSS.png");
        if response.changed() {
            *folder = std::path::PathBuf::from(&text);
        }
    });
}

//! The render on screen: one texture, scaled to fit the central panel with its aspect kept.
//!
//! Frames arrive as 8-bit RGBA (the lab's display transform is applied on the render thread) and
//! replace the texture's pixels in place. A small image shown two or more times its size uses
//! nearest filtering, so a coarse preview shows honest pixels rather than a blur.

use std::sync::Arc;

use eframe::egui;
use raylab_core::RenderSettings;
use raylab_core::shading::light::LightKind;

/// Magnification from which pixels are shown as blocks (nearest filtering).
const NEAREST_FROM_SCALE: f32 = 2.0;

/// What the pointer did on the image this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ViewportInput {
    /// Drag on the image, in points.
    pub drag_delta: egui::Vec2,
    /// Wheel or touchpad scroll over the image, in points (positive: away from the user).
    pub scroll_y: f32,
    /// The image was clicked or a drag started on it.
    pub pressed: bool,
    /// Where the image was clicked (not dragged), as a fraction of its width and height from
    /// its top-left corner.
    pub clicked_at: Option<egui::Vec2>,
    /// Where the pointer is over the image (or dragging from it), as such a fraction.
    pub pointer_at: Option<egui::Vec2>,
    /// A drag started this frame on the light's marker.
    pub drag_started_on_marker: bool,
    /// A drag started this frame on a spot light's aim (and not on the light's marker).
    pub drag_started_on_aim: bool,
    /// A drag on the image is going on.
    pub dragging: bool,
    /// Compare A/B: the drag is the divider's, not the camera's or the light's.
    pub on_divider: bool,
    /// Shift is held: the drag and the wheel move a tenth as far (fine control).
    pub fine: bool,
}

/// The light's marker radius, in points; a drag starting this close to it moves the light.
pub const MARKER_RADIUS: f32 = 7.0;
const MARKER_GRAB_RADIUS: f32 = 12.0;

/// A spot light's cone where the camera sees it, as fractions of the image's width and height:
/// the point it is aimed at (a handle: dragged, it turns the spot) and points of the circle its
/// cutoff makes about the aim.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SpotMarker {
    pub aim: Option<egui::Vec2>,
    pub rim: Vec<egui::Vec2>,
}

#[derive(Default)]
pub struct Viewport {
    texture: Option<egui::TextureHandle>,
    pixels: Option<Arc<egui::ColorImage>>,
    options: egui::TextureOptions,
    /// Where the image was drawn last, in points.
    shown_rect: Option<egui::Rect>,
    /// The inspector's pinned pixel, as a fraction of the image (set by the app each frame):
    /// outlined on the image.
    pub pinned: Option<egui::Rect>,
}

impl Viewport {
    /// Replaces the shown image. The same pixels again (a frame that only brings new figures,
    /// such as the passes between two denoised images) are not uploaded again: the texture
    /// upload and its drawing are a software renderer's largest cost of a frame.
    pub fn set_image(&mut self, ctx: &egui::Context, width: u32, height: u32, rgba: &[u8]) {
        let size = [width as usize, height as usize];
        if self.texture.is_some()
            && self
                .pixels
                .as_ref()
                .is_some_and(|p| p.size == size && p.as_raw() == rgba)
        {
            return;
        }
        let image = Arc::new(egui::ColorImage::from_rgba_unmultiplied(
            [width as usize, height as usize],
            rgba,
        ));
        match &mut self.texture {
            Some(texture) => texture.set(Arc::clone(&image), self.options),
            None => {
                self.texture =
                    Some(ctx.load_texture("raylab-render", Arc::clone(&image), self.options));
            }
        }
        self.pixels = Some(image);
    }

    /// The shown image's pixels as uploaded (8-bit RGBA after the display transform).
    #[cfg(test)]
    pub fn rgba(&self) -> Option<Vec<u8>> {
        self.pixels
            .as_ref()
            .map(|p| p.pixels.iter().flat_map(|c| c.to_array()).collect())
    }

    /// Where the image was drawn last, in points.
    pub fn shown_rect(&self) -> Option<egui::Rect> {
        self.shown_rect
    }

    /// The shown image's size in pixels.
    #[cfg(test)]
    pub fn image_size(&self) -> Option<[usize; 2]> {
        self.pixels.as_ref().map(|p| p.size)
    }

    /// Draws the image fitted into the available space, and the light's marker at `marker` (a
    /// fraction of the image's width and height) when it is on the image, with a spot light's
    /// cone (`spot`); reports pointer input on it.
    pub fn viewport_ui(
        &mut self,
        ui: &mut egui::Ui,
        marker: Option<egui::Vec2>,
        spot: Option<&SpotMarker>,
        mut overlay: Option<&mut dyn Overlay>,
    ) -> ViewportInput {
        let available = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(available, egui::Sense::click_and_drag());
        let (Some(texture), Some(pixels)) = (&mut self.texture, &self.pixels) else {
            ui.put(available, egui::Label::new("Rendering..."));
            return ViewportInput::default();
        };
        let size = egui::vec2(pixels.size[0] as f32, pixels.size[1] as f32);
        let rect = fit_rect(available, size);
        self.shown_rect = Some(rect);

        // Pick the filter for the scale it is shown at; re-upload only when that changes.
        let wanted = filter_for(rect, ui.ctx().pixels_per_point(), pixels.size[0]);
        if wanted != self.options {
            self.options = wanted;
            texture.set(Arc::clone(pixels), wanted);
        }

        // While comparing or checking, the wipe (or the difference) stands in for the image.
        if let Some(overlay) = overlay.as_deref_mut() {
            overlay.paint(ui, rect, texture.id());
        } else {
            let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
            ui.painter()
                .image(texture.id(), rect, uv, egui::Color32::WHITE);
        }

        let to_fraction = |p: egui::Pos2| (p - rect.min) / rect.size();
        let marker_pos = marker
            .filter(|m| (0.0..=1.0).contains(&m.x) && (0.0..=1.0).contains(&m.y))
            .map(|m| rect.min + m * rect.size());
        let aim_pos = spot.and_then(|s| s.aim).map(|m| rect.min + m * rect.size());
        if let Some(spot) = spot {
            let at = |m: &egui::Vec2| rect.min + *m * rect.size();
            draw_spot_cone(
                ui.painter(),
                marker.map(|m| at(&m)),
                aim_pos,
                &spot.rim.iter().map(at).collect::<Vec<_>>(),
            );
        }
        if let Some(pos) = marker_pos {
            draw_light_marker(ui.painter(), pos);
        }
        if let Some(pinned) = self.pinned {
            // The pixel's own square (at least a few points wide), in two contrasting strokes.
            let min = rect.min + pinned.min.to_vec2() * rect.size();
            let size = (pinned.size() * rect.size()).max(egui::vec2(5.0, 5.0));
            let square =
                egui::Rect::from_center_size(min + pinned.size() * rect.size() / 2.0, size);
            let painter = ui.painter();
            painter.rect_stroke(
                square.expand(1.0),
                0.0,
                egui::Stroke::new(1.0, egui::Color32::BLACK),
                egui::StrokeKind::Outside,
            );
            painter.rect_stroke(
                square,
                0.0,
                egui::Stroke::new(1.0, egui::Color32::WHITE),
                egui::StrokeKind::Outside,
            );
        }
        // Where the button went down, not where the pointer is when the move counts as a
        // drag (a few points further on).
        let press = ui.input(|i| i.pointer.press_origin());
        let drag_started_on_marker = response.drag_started()
            && marker_pos
                .zip(press)
                .is_some_and(|(m, p)| m.distance(p) <= MARKER_GRAB_RADIUS);
        let drag_started_on_aim = response.drag_started()
            && !drag_started_on_marker
            && aim_pos
                .zip(press)
                .is_some_and(|(m, p)| m.distance(p) <= MARKER_GRAB_RADIUS);
        let on_divider =
            overlay.is_some_and(|o| o.divider_input(ui, &response, rect, drag_started_on_marker));
        let pointer_at = response
            .interact_pointer_pos()
            .or_else(|| response.hover_pos())
            .map(to_fraction);

        let fine = ui.input(|i| i.modifiers.shift_only());
        // egui turns a wheel's scroll sideways while Shift is held (on every platform but
        // macOS, whose wheel does it itself): with Shift either way is the wheel.
        let scroll_y = match (response.hovered(), fine) {
            (false, _) => 0.0,
            (true, false) => ui.input(|i| i.smooth_scroll_delta.y),
            (true, true) => ui.input(|i| i.smooth_scroll_delta.y + i.smooth_scroll_delta.x),
        };
        ViewportInput {
            drag_delta: if response.dragged() {
                response.drag_delta()
            } else {
                egui::Vec2::ZERO
            },
            scroll_y,
            pressed: response.clicked() || response.drag_started(),
            clicked_at: response
                .clicked()
                .then(|| response.interact_pointer_pos())
                .flatten()
                .filter(|p| rect.contains(*p))
                .map(to_fraction),
            pointer_at,
            drag_started_on_marker,
            drag_started_on_aim,
            dragging: response.dragged(),
            on_divider,
            fine,
        }
    }
}

/// What stands in for the live image: the A/B wipe, or a student's image against the exact
/// figure. Implemented where each is defined (the viewport knows neither).
pub trait Overlay {
    /// Draws into `rect`, the live image's rect; `live` is the live image's texture.
    fn paint(&mut self, ui: &egui::Ui, rect: egui::Rect, live: egui::TextureId);

    /// Pointer input for its divider; returns whether the divider has the drag (then the
    /// camera must not turn).
    fn divider_input(
        &mut self,
        ui: &egui::Ui,
        response: &egui::Response,
        rect: egui::Rect,
        on_marker: bool,
    ) -> bool;
}

/// A spot light's cone: its rim (the circle its cutoff makes about the aim), four lines from
/// the light to it, and the aim's handle, a ring, in the marker's yellow over a dark rim.
fn draw_spot_cone(
    painter: &egui::Painter,
    light: Option<egui::Pos2>,
    aim: Option<egui::Pos2>,
    rim: &[egui::Pos2],
) {
    let dark = egui::Stroke::new(3.0, egui::Color32::from_gray(30));
    let yellow = egui::Stroke::new(1.5, egui::Color32::from_rgb(255, 210, 40));
    for stroke in [dark, yellow] {
        if rim.len() > 2 {
            painter.add(egui::Shape::closed_line(rim.to_vec(), stroke));
        }
        if let Some(light) = light {
            let quarter = (rim.len() / 4).max(1);
            for point in rim.iter().step_by(quarter) {
                painter.line_segment([light, *point], stroke);
            }
        }
        if let Some(aim) = aim {
            painter.circle_stroke(aim, MARKER_RADIUS * 0.7, stroke);
        }
    }
}

/// The light where the camera sees it: a small sun, yellow with a dark rim so it shows on light
/// and dark walls alike.
fn draw_light_marker(painter: &egui::Painter, pos: egui::Pos2) {
    let rim = egui::Stroke::new(1.5, egui::Color32::from_gray(30));
    for k in 0..8 {
        let a = k as f32 * std::f32::consts::FRAC_PI_4;
        let d = egui::vec2(a.cos(), a.sin());
        painter.line_segment(
            [
                pos + d * (MARKER_RADIUS + 2.0),
                pos + d * (MARKER_RADIUS + 5.0),
            ],
            egui::Stroke::new(2.0, egui::Color32::from_rgb(255, 210, 40)),
        );
    }
    painter.circle(
        pos,
        MARKER_RADIUS,
        egui::Color32::from_rgb(255, 220, 60),
        rim,
    );
}

/// The texture filter for an image `width` pixels wide shown in `rect`: nearest from
/// [`NEAREST_FROM_SCALE`] times magnification on (honest pixels), linear below.
pub fn filter_for(rect: egui::Rect, pixels_per_point: f32, width: usize) -> egui::TextureOptions {
    let scale = rect.width() * pixels_per_point / (width as f32).max(1.0);
    if scale >= NEAREST_FROM_SCALE {
        egui::TextureOptions::NEAREST
    } else {
        egui::TextureOptions::LINEAR
    }
}

/// The largest rect of `image`'s aspect that fits in `available`, centred.
pub fn fit_rect(available: egui::Rect, image: egui::Vec2) -> egui::Rect {
    if image.x <= 0.0 || image.y <= 0.0 || available.width() <= 0.0 || available.height() <= 0.0 {
        return egui::Rect::from_center_size(available.center(), egui::Vec2::ZERO);
    }
    let scale = (available.width() / image.x).min(available.height() / image.y);
    egui::Rect::from_center_size(available.center(), image * scale)
}

/// Where the light appears in the image, as a fraction of its width and height, or `None` when
/// it is behind the camera (the viewport also hides it off the image).
pub fn light_marker(settings: &RenderSettings) -> Option<egui::Vec2> {
    let camera = &settings.camera;
    let (px, py, _) = camera.project(settings.light.position)?;
    Some(egui::vec2(
        px / camera.width as f32,
        py / camera.height as f32,
    ))
}

/// A spot light's cone where the camera sees it ([`SpotMarker`]): its aim, and 24
/// points of the circle of the cutoff's radius about the aim, square to the spot's axis (each
/// left out when behind the camera); `None` for the other lights.
pub fn spot_marker(settings: &RenderSettings) -> Option<SpotMarker> {
    let LightKind::Spot(cone) = settings.light.kind else {
        return None;
    };
    let camera = &settings.camera;
    let fraction = |p| {
        let (px, py, _) = camera.project(p)?;
        Some(egui::vec2(
            px / camera.width as f32,
            py / camera.height as f32,
        ))
    };
    let to_aim = cone.aim - settings.light.position;
    let axis = to_aim.normalize_or_zero();
    let radius = to_aim.length() * cone.cutoff.tan();
    let (t1, t2) = raylab_core::base::sampling::orthonormal_basis(axis);
    let rim = (0..24)
        .filter_map(|k| {
            let a = k as f32 * std::f32::consts::TAU / 24.0;
            fraction(cone.aim + radius * (a.cos() * t1 + a.sin() * t2))
        })
        .collect();
    Some(SpotMarker {
        aim: fraction(cone.aim),
        rim,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_keeps_the_aspect_and_centres() {
        let area = egui::Rect::from_min_size(egui::pos2(10.0, 20.0), egui::vec2(800.0, 400.0));
        let r = fit_rect(area, egui::vec2(512.0, 512.0));
        assert_eq!(r.size(), egui::vec2(400.0, 400.0));
        assert_eq!(r.center(), area.center());
        let r = fit_rect(area, egui::vec2(1024.0, 256.0));
        assert_eq!(r.size(), egui::vec2(800.0, 200.0));
        assert_eq!(fit_rect(area, egui::Vec2::ZERO).size(), egui::Vec2::ZERO);
    }

    /// The same pixels again are not uploaded (the texture holds them already: egui is given
    /// no texture change); other pixels, or another size, are.
    #[test]
    fn the_same_pixels_are_not_uploaded_again() {
        let ctx = egui::Context::default();
        // Each delta taken is cleared (as a renderer would apply it): egui asserts that none
        // is dropped unhandled. Whatever the context made for itself (its fonts' atlas) first.
        let take = || {
            let mut delta = ctx.tex_manager().write().take_delta();
            let uploads = delta.set.len();
            delta.clear();
            uploads
        };
        take();
        let mut viewport = Viewport::default();
        // Opaque, as every converted frame is (the comparison is with egui's premultiplied
        // pixels, which are the same bytes only where alpha is 255).
        let grey = [128u8, 128, 128, 255].repeat(4 * 4);
        let uploads = |viewport: &mut Viewport, w: u32, h: u32, rgba: &[u8]| {
            viewport.set_image(&ctx, w, h, rgba);
            take()
        };
        assert_eq!(uploads(&mut viewport, 4, 4, &grey), 1);
        assert_eq!(uploads(&mut viewport, 4, 4, &grey), 0);
        let mut lighter = grey.clone();
        lighter[0] = 129;
        assert_eq!(uploads(&mut viewport, 4, 4, &lighter), 1);
        assert_eq!(viewport.rgba(), Some(lighter.clone()));
        assert_eq!(uploads(&mut viewport, 8, 2, &lighter), 1);
        assert_eq!(viewport.image_size(), Some([8, 2]));
    }
}

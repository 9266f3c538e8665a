//! The numbers shown under "Stats": pass time, UI frame time, ray throughput, samples and the
//! time from a change to its first image on screen.

use eframe::egui;

#[derive(Clone, Debug, Default)]
pub struct Stats {
    /// The last full-resolution pass: time in ms and size.
    pub full_pass: Option<(f64, u32, u32)>,
    /// Primary rays per second of the last full-resolution pass, in millions.
    pub mrays_per_s: Option<f64>,
    /// The UI's own work in the last frame, in ms.
    pub ui_frame_ms: f64,
    /// The whole last frame as eframe measured it (UI, tessellation, painting), in ms.
    pub frame_cpu_ms: Option<f64>,
    /// Full-resolution samples in the shown image, and the target.
    pub samples: u32,
    pub target: u32,
    /// Whether the shown image is the coarse preview.
    pub is_preview: bool,
    /// From the last change to its first image on screen: ms and UI frames.
    pub change_to_image: Option<(f64, u32)>,
    pub threads: usize,
}

impl Stats {
    /// Whether more passes are on their way.
    pub fn rendering(&self) -> bool {
        self.is_preview || self.samples < self.target
    }

    /// One line for the status bar, so the timing stays in view when the panel is scrolled.
    pub fn summary(&self) -> String {
        let pass = self.full_pass.map_or_else(
            || "pass -".to_owned(),
            |(ms, _, _)| format!("pass {ms:.1} ms"),
        );
        let samples = if self.is_preview {
            "preview".to_owned()
        } else {
            format!("{}/{} spp", self.samples, self.target)
        };
        let frame = self.frame_cpu_ms.unwrap_or(self.ui_frame_ms);
        format!("{pass} · UI {frame:.1} ms · {samples}")
    }

    pub fn stats_ui(&self, ui: &mut egui::Ui) {
        match self.full_pass {
            Some((ms, w, h)) => ui.label(format!("Last full pass: {ms:.1} ms ({w} × {h})")),
            None => ui.label("Last full pass: -"),
        };
        let frame = self.frame_cpu_ms.unwrap_or(self.ui_frame_ms);
        ui.label(format!("UI frame: {frame:.1} ms"))
            .on_hover_text(format!(
                "CPU time of the last UI frame (the app's own part: {:.1} ms)",
                self.ui_frame_ms
            ));
        match self.mrays_per_s {
            Some(m) => ui.label(format!("{m:.2} Mrays/s on {} threads", self.threads)),
            None => ui.label("Mrays/s: -"),
        }
        .on_hover_text("Primary (camera) rays per second in the last full pass");
        if let Some((ms, frames)) = self.change_to_image {
            let s = if frames == 1 { "" } else { "s" };
            ui.label(format!(
                "Change to first image: {ms:.0} ms, {frames} frame{s}"
            ));
        }
        let text = if self.is_preview {
            format!("Preview (1/8), target {} samples", self.target)
        } else {
            format!("Samples: {} / {}", self.samples, self.target)
        };
        ui.label(&text);
        let fraction = if self.target == 0 {
            0.0
        } else {
            self.samples as f32 / self.target as f32
        };
        // No animation once done: an animated bar would keep the app repainting.
        ui.add(
            egui::ProgressBar::new(fraction)
                .show_percentage()
                .animate(self.rendering()),
        )
        .on_hover_text("Progress toward the sample target");
    }
}

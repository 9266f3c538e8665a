//! The numbers shown under "Stats": pass time, UI frame time, ray throughput, samples, the
//! estimated remaining noise and the time from a change to its first image on screen.

use eframe::egui;
use raylab_core::transport::film::{CLEAN_RELATIVE_ERROR, NoiseEstimate};

/// What the noise figures mean, for their hover text.
const NOISE_HOVER: &str = "How far the image may still be from the converged one: each pixel's \
    standard error, estimated from the spread of its samples, as an RMS over the image relative \
    to the image's RMS brightness. Grain stops showing at about 1 %. The error shrinks as \
    1/√samples: four times the samples halve it, which is how the time to 1 % is estimated.";

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
    /// The estimated remaining noise of the shown image (from 2 samples on).
    pub noise: Option<NoiseEstimate>,
    /// From the change to the shown frame's pass, in ms: what its samples took.
    pub elapsed_ms: f64,
    /// What the shown debug view's colours mean (none for the shaded image).
    pub legend: Option<raylab_core::transport::view::Legend>,
    /// When the shown image is denoised: the samples it was denoised from and the time it
    /// took, in ms.
    pub denoised: Option<(u32, f64)>,
    /// The shown denoised image's estimated error, relative as the noise is (from 2 samples
    /// on).
    pub denoised_error: Option<f64>,
    /// Whether anything in the render is random ([`raylab_core::RenderSettings::is_stochastic`]):
    /// otherwise each pass is exact, and its samples differ only in where they fall in the pixel.
    pub stochastic: bool,
}

/// What the denoised image's error means, for its hover text.
const DENOISED_ERROR_HOVER: &str = "How far the denoised image on screen may be from the \
    converged one, as an RMS over the image relative to its brightness: estimated from the raw \
    image, its noise and a second filtering (Stein's unbiased risk estimate), so the blur the \
    filter adds counts as well as the noise it leaves.";

/// What a render with nothing random shows instead of a noise figure.
const EXACT_HOVER: &str = "Nothing in this render is random (no path tracing, soft shadows or \
    depth of field): one sample is the exact image, and more samples only move each ray within \
    its pixel, which smooths the edges (anti-aliasing). There is no noise to estimate.";

/// What the denoiser does, for the stats line and the switch.
pub const DENOISE_HOVER: &str = "An edge-avoiding filter guided by each pixel's albedo, normal, \
    depth and noise: the light is smoothed, the surfaces' detail is kept. What it shows is an \
    estimate; the accumulated image (inspector, EXR) is never changed. Off shows the raw image.";

/// A fraction as a percentage with about two significant digits: "0.42 %", "12.5 %".
pub fn percent(fraction: f64) -> String {
    let p = fraction * 100.0;
    let decimals = if p == 0.0 || p >= 10.0 {
        1
    } else {
        // Two significant digits below 10 %, at most 4 decimals.
        (1 - p.log10().floor() as i32).clamp(1, 4) as usize
    };
    format!("{p:.decimals$} %")
}

/// A duration for a person: "under 1 s", "40 s", "3 min", "2.5 h".
pub fn duration(seconds: f64) -> String {
    if seconds < 1.0 {
        "under 1 s".to_owned()
    } else if seconds < 90.0 {
        format!("{seconds:.0} s")
    } else if seconds < 90.0 * 60.0 {
        format!("{:.0} min", seconds / 60.0)
    } else {
        format!("{:.1} h", seconds / 3600.0)
    }
}

/// Where the noise stands against [`CLEAN_RELATIVE_ERROR`] (1 %), and what it takes to get
/// there: the samples so far, the target, and the time they took.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ToClean {
    /// At or below 1 %.
    Clean,
    /// 1 % is reached before the target, in about this many seconds.
    In(f64),
    /// 1 % needs about this many samples, more than the target.
    Needs(f64),
}

impl Stats {
    /// The way to a clean image, once there is a noise estimate.
    pub fn to_clean(&self) -> Option<ToClean> {
        let noise = self.noise.filter(|_| !self.is_preview && self.stochastic)?;
        if noise.relative_rms_error <= CLEAN_RELATIVE_ERROR {
            return Some(ToClean::Clean);
        }
        let needed = noise.samples_to_reach(self.samples, CLEAN_RELATIVE_ERROR);
        if needed > f64::from(self.target) {
            return Some(ToClean::Needs(needed));
        }
        let elapsed = self.elapsed_ms / 1e3;
        Some(ToClean::In(
            noise.seconds_to_reach(CLEAN_RELATIVE_ERROR, elapsed),
        ))
    }

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
        if !self.stochastic && !self.is_preview && self.legend.is_none() {
            return format!(
                "{pass} · UI {frame:.1} ms · {samples} · {}",
                self.exactness()
            );
        }
        // The figure is the image on screen's: the denoised one's own error when it is shown.
        if self.denoised.is_some() && !self.is_preview {
            let error = self
                .denoised_error
                .map_or_else(String::new, |e| format!(": error ±{}", percent(e)));
            return format!("{pass} · UI {frame:.1} ms · {samples} · denoised{error}");
        }
        let Some((noise, to_clean)) = self.noise.zip(self.to_clean()) else {
            return format!("{pass} · UI {frame:.1} ms · {samples}");
        };
        let to_clean = match to_clean {
            ToClean::Clean => "clean".to_owned(),
            ToClean::In(s) => format!("1 % in {}", duration(s)),
            ToClean::Needs(n) => format!("1 % at ~{n:.0} spp"),
        };
        format!(
            "{pass} · UI {frame:.1} ms · {samples} · noise ±{}, {to_clean}",
            percent(noise.relative_rms_error)
        )
    }

    /// What a render with nothing random is instead of noisy: exact with one sample, and with
    /// more, anti-aliased.
    fn exactness(&self) -> &'static str {
        if self.samples <= 1 {
            "exact"
        } else {
            "exact, anti-aliased"
        }
    }

    /// The figures a user watches, in two lines pinned above the scrolled panel: the pass time,
    /// the samples and the progress toward the target.
    pub fn key_figures_ui(&self, ui: &mut egui::Ui) {
        let pass = self
            .full_pass
            .map_or_else(|| "-".to_owned(), |(ms, _, _)| format!("{ms:.1} ms"));
        let samples = if self.is_preview {
            "preview".to_owned()
        } else {
            format!("{} / {} samples", self.samples, self.target)
        };
        ui.label(format!("Pass {pass} · {samples}"))
            .on_hover_text("The last full-resolution pass, and the samples averaged so far");
        ui.add(
            egui::ProgressBar::new(self.progress())
                .desired_height(6.0)
                .animate(false),
        );
    }

    /// The share of the sample target reached.
    pub fn progress(&self) -> f32 {
        if self.target == 0 {
            0.0
        } else {
            self.samples as f32 / self.target as f32
        }
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
        if !self.stochastic && !self.is_preview && self.legend.is_none() {
            let text = if self.samples <= 1 {
                "Exact: nothing is random, no noise"
            } else {
                "Exact, anti-aliased: nothing is random, no noise"
            };
            ui.label(text).on_hover_text(EXACT_HOVER);
        }
        if let Some((samples, ms)) = self.denoised {
            ui.label(format!("Denoised from {samples} samples in {ms:.1} ms"))
                .on_hover_text(DENOISE_HOVER);
            if let Some(error) = self.denoised_error {
                ui.label(format!(
                    "Denoised image's error: about ±{} (RMS over the image)",
                    percent(error)
                ))
                .on_hover_text(DENOISED_ERROR_HOVER);
            }
        }
        if let Some((noise, to_clean)) = self.noise.zip(self.to_clean()) {
            let of = if self.denoised.is_some() {
                "Noise of the raw image (not shown)"
            } else {
                "Noise"
            };
            ui.label(format!(
                "{of}: ±{} (RMS over the image)",
                percent(noise.relative_rms_error)
            ))
            .on_hover_text(NOISE_HOVER);
            let text = match to_clean {
                ToClean::Clean => "Below 1 %: clean to the eye".to_owned(),
                ToClean::In(s) if self.rendering() => {
                    format!("1 % (clean) in about {}", duration(s))
                }
                // Rounding: at the target, with the error a hair above 1 %.
                ToClean::In(_) => "About 1 %: clean to the eye".to_owned(),
                ToClean::Needs(n) => format!(
                    "1 % (clean) needs about {n:.0} samples: raise the sample target (now {})",
                    self.target
                ),
            };
            ui.label(text).on_hover_text(NOISE_HOVER);
        }
        let fraction = self.progress();
        // No animation once done: an animated bar would keep the app repainting.
        ui.add(
            egui::ProgressBar::new(fraction)
                .show_percentage()
                .animate(self.rendering()),
        )
        .on_hover_text("Progress toward the sample target");
    }
}

impl Stats {
    /// One line a UI frame for scripts (`RAYLAB_LOG_FRAMES`), its fields in a fixed order;
    /// `since_start_ms` is the time since the window opened.
    pub fn frame_log_line(&self, since_start_ms: f64) -> String {
        let (change_ms, change_frames) = self.change_to_image.unwrap_or((f64::NAN, 0));
        format!(
            "raylab-frame ui_ms={:.2} frame_cpu_ms={:.2} samples={} target={} preview={} \
             t_ms={:.1} change_to_image_ms={:.1} change_frames={} full_pass_ms={:.1} \
             denoised={}",
            self.ui_frame_ms,
            self.frame_cpu_ms.unwrap_or(f64::NAN),
            self.samples,
            self.target,
            self.is_preview,
            since_start_ms,
            change_ms,
            change_frames,
            self.full_pass.map_or(f64::NAN, |(ms, _, _)| ms),
            self.denoised.map_or(0, |(samples, _)| samples),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentages_keep_about_two_significant_digits() {
        assert_eq!(percent(0.0042), "0.42 %");
        assert_eq!(percent(0.125), "12.5 %");
        assert_eq!(percent(0.042), "4.2 %");
        assert_eq!(percent(0.000_042), "0.0042 %");
        assert_eq!(percent(0.0), "0.0 %");
        assert_eq!(percent(1.0), "100.0 %");
    }

    #[test]
    fn the_summary_shows_the_noise_once_there_is_one() {
        let mut stats = Stats {
            samples: 1,
            target: 8,
            stochastic: true,
            ..Stats::default()
        };
        assert!(!stats.summary().contains("noise"));
        stats.samples = 2;
        // 4 % after 2 samples in 0.5 s: 1 % needs 2 · 4² = 32 samples, above the target.
        stats.noise = Some(NoiseEstimate {
            relative_error_of_mean: 0.0042,
            share_of_pixels_above_1_percent: 0.5,
            relative_rms_error: 0.04,
        });
        stats.elapsed_ms = 600.0;
        let near = |a: f64, b: f64| (a - b).abs() < 1e-9;
        assert!(
            matches!(stats.to_clean(), Some(ToClean::Needs(n)) if near(n, 32.0)),
            "{:?}",
            stats.to_clean()
        );
        assert!(
            stats
                .summary()
                .ends_with("2/8 spp · noise ±4.0 %, 1 % at ~32 spp"),
            "{}",
            stats.summary()
        );
        // With a target of 64: 0.6 s · (4² − 1) = 9 s more.
        stats.target = 64;
        assert!(
            matches!(stats.to_clean(), Some(ToClean::In(s)) if near(s, 9.0)),
            "{:?}",
            stats.to_clean()
        );
        assert!(
            stats.summary().ends_with("noise ±4.0 %, 1 % in 9 s"),
            "{}",
            stats.summary()
        );
        stats.noise = stats.noise.map(|n| NoiseEstimate {
            relative_rms_error: 0.009,
            ..n
        });
        assert!(stats.summary().ends_with("noise ±0.90 %, clean"));
    }

    /// With the denoised image on screen, the figure is its own estimated error, not the raw
    /// image's noise (nor the time to make the raw image clean).
    #[test]
    fn a_denoised_image_shows_its_own_error() {
        let mut stats = Stats {
            samples: 64,
            target: 1024,
            stochastic: true,
            noise: Some(NoiseEstimate {
                relative_error_of_mean: 0.001,
                share_of_pixels_above_1_percent: 0.9,
                relative_rms_error: 0.049,
            }),
            elapsed_ms: 8000.0,
            denoised: Some((64, 12.0)),
            denoised_error: Some(0.0042),
            ..Stats::default()
        };
        let summary = stats.summary();
        assert!(
            summary.ends_with("64/1024 spp · denoised: error ±0.42 %"),
            "{summary}"
        );
        assert!(
            !summary.contains("4.9") && !summary.contains("1 %"),
            "{summary}"
        );
        // The denoiser off: the raw image's noise again.
        stats.denoised = None;
        stats.denoised_error = None;
        let summary = stats.summary();
        assert!(summary.contains("noise ±4.9 %, 1 % at"), "{summary}");
    }

    /// A render with nothing random (the lab's stages with a point light and a pinhole) has no
    /// noise figure, whatever spread its anti-aliasing samples have: it is exact.
    #[test]
    fn a_render_with_nothing_random_is_exact_not_noisy() {
        let mut stats = Stats {
            samples: 16,
            target: 16,
            stochastic: false,
            noise: Some(NoiseEstimate {
                relative_error_of_mean: 0.0002,
                share_of_pixels_above_1_percent: 0.05,
                relative_rms_error: 0.0083,
            }),
            ..Stats::default()
        };
        let summary = stats.summary();
        assert!(
            summary.ends_with("16/16 spp · exact, anti-aliased"),
            "{summary}"
        );
        assert!(
            !summary.contains("noise") && !summary.contains('±'),
            "{summary}"
        );
        assert_eq!(stats.to_clean(), None);
        stats.samples = 1;
        stats.target = 1;
        stats.noise = None;
        assert!(
            stats.summary().ends_with("1/1 spp · exact"),
            "{}",
            stats.summary()
        );
    }
}

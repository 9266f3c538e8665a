//! The status line at the bottom of the window: a message of a kind, which goes by itself once
//! its cause no longer holds ([`Cause`]), beside the stats' summary.

use eframe::egui;
use raylab_core::transport::progressive::WorkerError;

use super::WorkbenchApp;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StatusKind {
    Info,
    Notice,
    Error,
}

/// The status line at the bottom of the window.
#[derive(Clone, Debug)]
pub struct Status {
    pub text: String,
    pub kind: StatusKind,
    /// For an error whose condition can go away: what to check, so the message goes when the
    /// condition does.
    pub cause: Option<Cause>,
    /// More than fits on the line, offered by a "Copy details" button: for a render that
    /// panicked, its settings as JSON, to reproduce it with `raylab render --settings FILE`.
    pub details: Option<String>,
}

/// A condition a message reports, checked every frame ([`WorkbenchApp::clear_fixed_error`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Cause {
    /// Compare A/B is on (what to do while comparing): taken down when comparing stops.
    Comparing,
    /// Check my image is on (reading the image, what to set while checking): taken down when
    /// the check stops.
    Checking,
    /// The text typed into the number field of this name could not be used as it stood:
    /// taken down when a good number is typed there ([`super::panels::Typed`]).
    TypedNumber(String),
    /// The settings could not be rendered.
    InvalidSettings,
    /// The screenshot folder did not exist.
    MissingFolder(std::path::PathBuf),
    /// The camera sees nothing (a notice, taken down by the next render that sees something).
    CameraSeesNothing,
    /// A render job panicked. Taken down by the first frame of a job submitted after the error
    /// reached the screen (a generation above `submitted`, the newest then): a change made once
    /// the user could read it. Frames of jobs already on their way then don't hide it at once.
    RenderFailed { submitted: u64 },
}

impl WorkbenchApp {
    pub(super) fn set_status(&mut self, kind: StatusKind, text: impl Into<String>) {
        self.status = Some(Status {
            text: text.into(),
            kind,
            cause: None,
            details: None,
        });
    }

    /// A message that goes away by itself once `cause` no longer holds.
    pub(super) fn set_status_while(
        &mut self,
        kind: StatusKind,
        cause: Cause,
        text: impl Into<String>,
    ) {
        self.status = Some(Status {
            text: text.into(),
            kind,
            cause: Some(cause),
            details: None,
        });
    }

    /// An error that goes away by itself once `cause` no longer holds.
    pub(super) fn set_error(&mut self, cause: Cause, text: impl Into<String>) {
        self.status = Some(Status {
            text: text.into(),
            kind: StatusKind::Error,
            cause: Some(cause),
            details: None,
        });
    }

    /// A problem a render thread reported (`prefix` says whose: "" for the live image, "A: "
    /// for the frozen side), with the failed job's settings to copy. The live image's panic
    /// goes once a later change renders ([`Cause::RenderFailed`]); A is never re-rendered, so
    /// its error stays until another message replaces it.
    pub(super) fn show_worker_error(
        &mut self,
        prefix: &str,
        error: WorkerError,
        cause: Option<Cause>,
    ) {
        self.status = Some(Status {
            text: format!("{prefix}{}", error.message),
            kind: StatusKind::Error,
            details: error.settings_json(),
            cause: cause.filter(|_| error.settings.is_some()),
        });
    }

    /// Takes down a message whose condition is fixed: a stale red line would send the user
    /// looking for a problem that is gone, and stale advice would ask for the impossible.
    pub(super) fn clear_fixed_error(&mut self) {
        let fixed = match self.status.as_ref().and_then(|s| s.cause.as_ref()) {
            Some(Cause::InvalidSettings) => self.state.settings.validate().is_ok(),
            Some(Cause::Comparing) => self.compare.is_none(),
            Some(Cause::Checking) => self.check.is_none(),
            Some(Cause::TypedNumber(_)) => false,
            Some(Cause::MissingFolder(_)) => self.state.screenshot_folder.is_dir(),
            Some(Cause::CameraSeesNothing | Cause::RenderFailed { .. }) => false,
            None => false,
        };
        if fixed {
            self.status = None;
        }
    }

    /// The bottom bar: the status on the left, the stats' summary on the right. The summary
    /// takes its width (at most half the bar), the status what is left; each is one line, cut
    /// with "…" when longer and whole in its tooltip, so neither is ever drawn over the other.
    pub(super) fn status_ui(&self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                let room = egui::vec2(ui.available_width() / 2.0, ui.available_height());
                ui.allocate_ui_with_layout(room, *ui.layout(), |ui| {
                    ui.add(egui::Label::new(self.stats.summary()).truncate());
                });
                ui.with_layout(egui::Layout::left_to_right(egui::Align::Center), |ui| {
                    self.status_line_ui(ui);
                });
            });
        });
    }

    /// The status message, one line (see [`Self::status_ui`]).
    pub(super) fn status_line_ui(&self, ui: &mut egui::Ui) {
        let Some(status) = &self.status else {
            ui.add(egui::Label::new("Ready. F1 lists the keys.").truncate());
            return;
        };
        let color = match status.kind {
            StatusKind::Info => ui.visuals().text_color(),
            StatusKind::Notice => ui.visuals().warn_fg_color,
            StatusKind::Error => ui.visuals().error_fg_color,
        };
        if let Some(details) = &status.details
            && ui
                .small_button("Copy details")
                .on_hover_text(
                    "Copy the settings of the render that failed, as JSON: \
                     `raylab render --settings FILE` reproduces it",
                )
                .clicked()
        {
            ui.ctx().copy_text(details.clone());
        }
        // A label cut short shows its whole text when hovered.
        ui.add(egui::Label::new(egui::RichText::new(&status.text).color(color)).truncate());
    }
}

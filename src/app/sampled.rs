//! The sample targets: the path stage's, and the one the lab stages get when an effect that
//! averages random points (soft shadows, depth of field) is turned on.

use raylab_core::{RenderSettings, Stage};

use super::WorkbenchApp;
use super::status::StatusKind;

/// The least sample target the path stage gets when chosen: a path-traced image is noisy
/// until about this many samples are averaged.
pub const PATH_SAMPLE_TARGET: u32 = 1024;

/// The least sample target the lab stages get when soft shadows or depth of field are turned
/// on: both are averages over random points (of the light, of the lens), grainy at the 16
/// samples that anti-alias the lab's image.
pub const SOFT_SAMPLE_TARGET: u32 = 256;

/// The lab stages' effects that average random points, and so need many samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Sampled {
    /// Shadows from an area light: each sample's shadow ray goes to a random point of it.
    soft_shadows: bool,
    /// A lens of some aperture: each sample's ray leaves from a random point of it.
    depth_of_field: bool,
}

impl Sampled {
    /// Those `settings` use. The path stage samples everything anyway, at its own target
    /// ([`PATH_SAMPLE_TARGET`]); the flat stage computes no light.
    pub(super) fn of(settings: &RenderSettings) -> Self {
        let stage = settings.shading.stage;
        if stage == Stage::Path {
            return Self::default();
        }
        Self {
            soft_shadows: stage != Stage::Flat
                && settings.shading.shadows
                && settings.light.is_area(),
            depth_of_field: settings.camera.aperture > 0.0,
        }
    }

    /// What the user calls them, those of `self` that are on.
    fn name(self) -> Option<&'static str> {
        match (self.soft_shadows, self.depth_of_field) {
            (true, true) => Some("Soft shadows and depth of field"),
            (true, false) => Some("Soft shadows"),
            (false, true) => Some("Depth of field"),
            (false, false) => None,
        }
    }
}

impl WorkbenchApp {
    /// Soft shadows or depth of field just turned on in a lab stage: they average random points
    /// of the light or the lens, grainy at the lab's 16 samples, so the sample target is raised
    /// to [`SOFT_SAMPLE_TARGET`] as the path stage raises its own, and the status line says so.
    /// Only on the change: a target the user lowers afterwards stays as set.
    pub(super) fn refine_sampled_effects(&mut self) {
        let now = Sampled::of(&self.state.settings);
        let turned_on = Sampled {
            soft_shadows: now.soft_shadows && !self.sampled.soft_shadows,
            depth_of_field: now.depth_of_field && !self.sampled.depth_of_field,
        };
        self.sampled = now;
        let settings = &mut self.state.settings;
        let Some(what) = turned_on.name() else {
            return;
        };
        if settings.samples_per_pixel >= SOFT_SAMPLE_TARGET {
            return;
        }
        let from = settings.samples_per_pixel;
        settings.samples_per_pixel = SOFT_SAMPLE_TARGET;
        self.set_status(
            StatusKind::Info,
            format!(
                "{what}: refining to {SOFT_SAMPLE_TARGET} samples (the target was {from}), so \
                 the grain of random points averages out (noise: see Stats)"
            ),
        );
    }
}

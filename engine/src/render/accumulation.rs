//! Progressive accumulation: how many samples the view holds, and the one flag that restarts it. Systems that
//! change what the image shows (geometry, placements, materials) call [`Accumulation::restart`]; the frame also
//! restarts when the camera or an image-affecting setting changed, and clears the flag.

use super::settings::RenderSettings;
use crate::camera::CameraView;
use bevy_ecs::prelude::Resource;

#[derive(Resource)]
pub struct Accumulation {
    /// Samples per pixel accumulated since the last restart.
    pub samples: u32,
    /// Counts restarts: identifies this accumulation, so that an image denoised from it off the GPU is shown
    /// only while it lasts.
    pub epoch: u64,
    restart: bool,
    last_settings: Option<RenderSettings>,
    last_camera: Option<CameraView>,
    /// Stop tracing once this many samples per pixel have accumulated (the viewer idles on a converged image);
    /// the display transform still runs.
    pub sample_limit: Option<u32>,
    /// Whether each frame also runs the display transform (the viewer); headless renders tone-map once.
    pub display_each_frame: bool,
    /// Accumulate the denoisers' inputs (the moments and the first-hit AOVs) even while no denoiser is on, so
    /// that switching one on mid-accumulation works (interactive use; the default). Headless renders that never
    /// denoise nor write AOVs turn this off: the trace pass then runs a kernel without them, 3-9% faster on the
    /// H200 (docs/BENCHMARKS.md), and the AOV targets stay as they were.
    pub keep_denoiser_inputs: bool,
}

impl Default for Accumulation {
    fn default() -> Self {
        Self {
            samples: 0,
            epoch: 0,
            restart: true,
            last_settings: None,
            last_camera: None,
            sample_limit: None,
            display_each_frame: false,
            keep_denoiser_inputs: true,
        }
    }
}

impl Accumulation {
    /// Whether this frame's trace records the denoisers' inputs: a denoiser is on, or they are kept for one.
    pub fn records_denoiser_inputs(&self, settings: &RenderSettings) -> bool {
        settings.denoise || self.keep_denoiser_inputs
    }

    /// The image changed: the next frame starts a new accumulation.
    pub fn restart(&mut self) {
        self.restart = true;
    }

    /// Whether this frame starts a new accumulation (a restart was asked for, or the camera or an
    /// image-affecting setting changed since the last frame); remembers this frame's camera and settings.
    pub fn begin_frame(&mut self, settings: &RenderSettings, camera: &CameraView) -> bool {
        let settings_changed = self
            .last_settings
            .as_ref()
            .is_none_or(|s| s.changes_image(settings));
        let restart = self.restart || settings_changed || self.last_camera != Some(*camera);
        if self.last_settings.as_ref() != Some(settings) {
            self.last_settings = Some(settings.clone());
        }
        self.last_camera = Some(*camera);
        self.restart = false;
        if restart {
            self.samples = 0;
            self.epoch += 1;
        }
        restart
    }

    /// The sample limit is reached: only the display transform needs to run.
    pub fn converged(&self) -> bool {
        self.sample_limit.is_some_and(|limit| self.samples >= limit)
    }
}

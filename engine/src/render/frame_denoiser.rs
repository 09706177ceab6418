//! A denoiser outside the renderer that the real-time path hands each frame's history to, in place of the
//! a-trous filter: Open Image Denoise per frame. The `oidn` module implements [`ExternalDenoise`] and installs
//! it ([`FrameDenoiser::install`]); the renderer only calls it (it never imports `oidn`, which depends on it).
//! When it fails, the frame falls back to the a-trous filter, a warning says why, and it is not asked again.

use super::settings::RenderSettings;
use super::view::DenoiserSources;
use crate::gpu::GpuContext;
use bevy_ecs::prelude::Resource;

/// What a denoise of one frame did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameDenoiseReport {
    /// The device that ran it ("CUDA NVIDIA H200").
    pub device: String,
    /// It read the history in GPU memory it shares with wgpu (no host copies).
    pub shared_memory: bool,
    /// Wall milliseconds of the denoise once the frame before it finished on the GPU (inputs, filter, output;
    /// with host copies where not shared).
    pub ms: f64,
}

/// A denoiser the real-time frame can hand its history to.
pub trait ExternalDenoise: Send {
    /// Whether it denoises frames under `settings` on this device (it is fast enough here, or asked to run
    /// anyway). May open the device the first time.
    fn wanted(&mut self, ctx: &GpuContext, settings: &RenderSettings) -> bool;

    /// `sources` (the colour history in the accumulation's layout) denoised into `shown` (the display's layout:
    /// `HostDenoised::image_buffer`). Every command submitted before the call has finished before it reads.
    fn denoise(
        &mut self,
        ctx: &GpuContext,
        sources: &DenoiserSources,
        shown: &wgpu::Buffer,
        settings: &RenderSettings,
    ) -> Result<FrameDenoiseReport, String>;
}

/// The installed denoiser, if any, and what it last did.
#[derive(Resource, Default)]
pub struct FrameDenoiser {
    /// Behind a lock only so that the resource is `Sync`; the frame has it mutably.
    denoiser: Option<std::sync::Mutex<Box<dyn ExternalDenoise>>>,
    /// It failed once: why (it is not asked again).
    pub failed: Option<String>,
    /// The last real-time frame it denoised.
    pub last: Option<FrameDenoiseReport>,
}

impl FrameDenoiser {
    pub fn install(denoiser: Box<dyn ExternalDenoise>) -> Self {
        Self {
            denoiser: Some(std::sync::Mutex::new(denoiser)),
            ..Default::default()
        }
    }

    /// Whether this frame goes to the external denoiser: it is installed and has not failed, the settings ask
    /// for a denoised real-time image from OIDN, and it wants to run here.
    pub fn runs(&mut self, ctx: &GpuContext, settings: &RenderSettings) -> bool {
        let asked = settings.realtime.spatial
            && settings.denoiser == super::settings::DenoiserKind::Oidn
            && settings.realtime.oidn != super::settings::FrameOidn::Off;
        if !asked || self.failed.is_some() {
            return false;
        }
        self.denoiser.as_mut().is_some_and(|d| {
            d.get_mut()
                .unwrap_or_else(|p| p.into_inner())
                .wanted(ctx, settings)
        })
    }

    /// Denoises `sources` into `shown`; false (with a warning, and never again) when it failed.
    pub fn denoise(
        &mut self,
        ctx: &GpuContext,
        sources: &DenoiserSources,
        shown: &wgpu::Buffer,
        settings: &RenderSettings,
    ) -> bool {
        let Some(d) = self.denoiser.as_mut() else {
            return false;
        };
        let d = d.get_mut().unwrap_or_else(|p| p.into_inner());
        match d.denoise(ctx, sources, shown, settings) {
            Ok(report) => {
                self.last = Some(report);
                true
            }
            Err(e) => {
                tracing::warn!("{e}; the real-time path uses its a-trous filter instead");
                self.failed = Some(e);
                self.last = None;
                false
            }
        }
    }
}

//! OIDN per frame in the real-time path (`RealtimeSettings::oidn`): the renderer hands each frame's colour
//! history to [`OidnPerFrame`] (through `render::frame_denoiser`) in place of its a-trous filter, and shows
//! what it writes. With [`FrameOidn::Shared`] it runs only where OIDN's GPU device reads the history in GPU
//! memory it shares with wgpu (5-13 ms per 1440p frame on the H200 by quality, docs/BENCHMARKS.md); with
//! [`FrameOidn::Always`] also through host copies (OIDN's CPU device: far from real time, but the same image).
//! Unlike the viewer's still-image denoise ([`super::viewer`]) it blocks the frame: the frame's image is its
//! output.

use super::device::{AdapterIdentity, DeviceRequest};
use super::{AuxMode, DenoiseOptions, Oidn, OidnError};
use crate::gpu::GpuContext;
use crate::render::RenderSettings;
use crate::render::frame_denoiser::{ExternalDenoise, FrameDenoiseReport};
use crate::render::settings::FrameOidn;
use crate::render::view::DenoiserSources;
use std::time::Instant;

/// The real-time path's OIDN: its own device (the viewer's still-image worker keeps another), opened at the
/// first frame that asks for it.
#[derive(Default)]
pub struct OidnPerFrame {
    oidn: Option<Result<Oidn, OidnError>>,
    /// Denoising in shared GPU memory failed once: host copies from then on (`Always`) or not at all.
    shared_failed: bool,
}

impl OidnPerFrame {
    /// What a frame is denoised with: the settings' quality, HDR radiance, and the history's albedo and normal
    /// trusted as they are (averages of one camera ray per pixel per frame: no path noise to prefilter).
    pub fn options(settings: &RenderSettings) -> DenoiseOptions {
        DenoiseOptions {
            quality: settings.realtime.oidn_quality,
            hdr: true,
            aux: AuxMode::Clean,
        }
    }

    /// OIDN's GPU device reads wgpu's memory here (opens the device the first time on a GPU adapter it has a
    /// backend for; never on CPU adapters).
    fn shares_memory(&mut self, ctx: &GpuContext) -> bool {
        if self.shared_failed || AdapterIdentity::from_wgpu(&ctx.info).gpu_kind().is_none() {
            return false;
        }
        open(&mut self.oidn, ctx).is_ok_and(|o| o.shares_memory_with(ctx))
    }
}

/// The device matching `ctx`'s adapter, opened into `oidn` the first time.
fn open<'o>(
    oidn: &'o mut Option<Result<Oidn, OidnError>>,
    ctx: &GpuContext,
) -> Result<&'o mut Oidn, OidnError> {
    let request = DeviceRequest::MatchAdapter(AdapterIdentity::from_wgpu(&ctx.info));
    match oidn.get_or_insert_with(|| Oidn::new(&request)) {
        Ok(o) => Ok(o),
        Err(e) => Err(e.clone()),
    }
}

impl ExternalDenoise for OidnPerFrame {
    fn wanted(&mut self, ctx: &GpuContext, settings: &RenderSettings) -> bool {
        match settings.realtime.oidn {
            FrameOidn::Off => false,
            FrameOidn::Shared => self.shares_memory(ctx),
            FrameOidn::Always => true,
        }
    }

    fn denoise(
        &mut self,
        ctx: &GpuContext,
        sources: &DenoiserSources,
        shown: &wgpu::Buffer,
        settings: &RenderSettings,
    ) -> Result<FrameDenoiseReport, String> {
        let options = Self::options(settings);
        // The frame so far first, so that the time below is the denoise's alone.
        ctx.wait_idle();
        let start = Instant::now();
        let oidn = open(&mut self.oidn, ctx).map_err(|e| e.to_string())?;
        let through_host = settings.realtime.oidn == FrameOidn::Always;
        let into = super::shared::denoise_sources_into(
            oidn,
            ctx,
            &mut self.shared_failed,
            (sources, shown),
            &options,
            through_host,
        )
        .ok_or("Open Image Denoise cannot read the GPU's memory here")?;
        into.result.map_err(|e| e.to_string())?;
        Ok(FrameDenoiseReport {
            device: oidn.device_description(),
            shared_memory: into.shared_memory,
            ms: start.elapsed().as_secs_f64() * 1e3,
        })
    }
}

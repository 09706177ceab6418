//! The display's passes: the accumulation's (denoised or not) into the view's `rgba8`, and a still's hand-over
//! from the last real-time image to the accumulation. Both frame paths and the queries end here.

use super::passes::denoise::{DenoiseInputs, Denoiser};
use super::passes::handover::{HandoverBuffers, HandoverParams};
use super::passes::tonemap::{TonemapInput, TonemapParams, TonemapPass};
use super::realtime::{Realtime, RealtimeImage, RealtimeTargets, Shown};
use super::settings::RenderSettings;
use super::stats::{FrameStats, TONEMAP_PAIR};
use super::view::ViewTargets;
use crate::gpu::GpuContext;

/// What every display pass reads: the view, the settings, the tone mapper and the denoiser, with the frame's
/// timestamp pairs.
pub struct Display<'a> {
    pub ctx: &'a GpuContext,
    pub view: &'a ViewTargets,
    pub settings: &'a RenderSettings,
    pub tonemap: &'a TonemapPass,
    pub denoiser: &'a Denoiser,
    pub stats: &'a FrameStats,
}

impl<'a> Display<'a> {
    /// The accumulation's display transform; during a still's hand-over (`handover` < 1 after a real-time
    /// frame), mixed with the last real-time image first. `host`: an image denoised off the GPU to show instead
    /// of svgf's. True when svgf ran.
    pub fn encode_accumulation(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        realtime: &mut Realtime,
        handover: Option<f32>,
        host: Option<&wgpu::Buffer>,
    ) -> bool {
        let mixing = handover.is_some_and(|w| w < 1.0)
            && realtime.targets.is_some()
            && realtime.state.shown != Shown::Accumulation;
        if !mixing {
            if handover.is_some() {
                realtime.state.shown = Shown::Accumulation;
            }
            return self.encode(encoder, host);
        }
        let weight = handover.unwrap_or(1.0);
        realtime.state.shown = Shown::Handover;
        let settings = self.settings;
        let denoise = settings.shows_denoised() && host.is_none();
        let accumulated = match host {
            Some(image) if settings.shows_denoised() => image,
            _ if denoise => self.encode_denoise(encoder),
            _ => &self.view.accum,
        };
        let (Some(passes), Some(targets)) = (realtime.passes.as_ref(), realtime.targets.as_ref())
        else {
            return self.encode(encoder, host);
        };
        passes.handover.encode(
            self.ctx,
            encoder,
            &HandoverBuffers {
                realtime: realtime_image(realtime, targets),
                accumulated,
                output: &targets.handover,
            },
            &HandoverParams {
                width: self.view.width,
                height: self.view.height,
                weight,
                _pad: 0,
            },
        );
        self.tonemap.encode(
            self.ctx,
            encoder,
            self.view,
            TonemapInput::Denoised(&targets.handover),
            &tonemap_params(self.view, settings),
            self.stats.pass_writes(TONEMAP_PAIR),
        );
        denoise
    }

    /// The denoiser pass over the view, timed by the frame's denoise pair; returns its output.
    pub fn encode_denoise(&self, encoder: &mut wgpu::CommandEncoder) -> &'a wgpu::Buffer {
        let output = self.denoiser.encode(
            self.ctx,
            encoder,
            &DenoiseInputs::of(self.view),
            &self.settings.denoise_params,
            self.stats.denoise_writes(),
        );
        if let Some(t) = &self.stats.denoise_timestamps {
            t.resolve(encoder, 1);
        }
        output
    }

    /// The display transform into the view's `rgba8`, denoising first when the settings ask for it (`host`, an
    /// image denoised off the GPU for this accumulation, stands in for svgf's); true when svgf ran.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, host: Option<&wgpu::Buffer>) -> bool {
        let shows_denoised = self.settings.shows_denoised();
        let (input, denoise) = match host {
            Some(image) if shows_denoised => (TonemapInput::Denoised(image), false),
            _ if shows_denoised => (TonemapInput::Denoised(self.encode_denoise(encoder)), true),
            _ => (TonemapInput::Accumulation, false),
        };
        self.tonemap.encode(
            self.ctx,
            encoder,
            self.view,
            input,
            &tonemap_params(self.view, self.settings),
            self.stats.pass_writes(TONEMAP_PAIR),
        );
        denoise
    }
}

/// The last real-time frame's displayed radiance (in the accumulation's layout): the external denoiser's
/// output, the spatial filter's, or the history itself, as that frame recorded.
pub fn realtime_image<'t>(
    realtime: &'t Realtime,
    targets: &'t RealtimeTargets,
) -> &'t wgpu::Buffer {
    let history = &targets.history.accum;
    match realtime.state.image {
        RealtimeImage::External => realtime.external_image.as_ref().unwrap_or(history),
        RealtimeImage::Spatial => realtime
            .spatial_filter
            .as_ref()
            .and_then(Denoiser::output)
            .unwrap_or(history),
        RealtimeImage::History => history,
    }
}

pub fn tonemap_params(view: &ViewTargets, settings: &RenderSettings) -> TonemapParams {
    TonemapParams {
        width: view.width,
        height: view.height,
        tonemapper: settings.tonemapper as u32,
        view: settings.view as u32,
        exposure_scale: 2f32.powf(settings.exposure),
        depth_scale: settings.depth_view_scale,
        _pad: [0; 2],
    }
}

//! The display's passes: the accumulation's (denoised or not) into the view's `rgba8`, and a still's hand-over
//! from the last real-time image to the accumulation. Both frame paths and the queries end here.

use super::passes::denoise::{DenoiseInputs, Denoiser};
use super::passes::handover::{HandoverBuffers, HandoverParams};
use super::passes::tonemap::{TonemapInput, TonemapParams, TonemapPass};
use super::realtime::{Realtime, RealtimeTargets, Shown};
use super::settings::RenderSettings;
use super::stats::{FrameStats, TONEMAP_PAIR};
use super::view::ViewTargets;
use crate::gpu::GpuContext;

/// The accumulation's display transform; during a still's hand-over (`handover` < 1 after a real-time
/// frame), mixed with the last real-time image first. `host`: an image denoised off the GPU to show instead
/// of svgf's. True when svgf ran.
#[allow(clippy::too_many_arguments)]
pub fn encode_accumulation_display(
    ctx: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    view: &ViewTargets,
    settings: &RenderSettings,
    tonemap: &TonemapPass,
    denoiser: &Denoiser,
    stats: &FrameStats,
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
        return encode_display(ctx, encoder, view, settings, tonemap, denoiser, stats, host);
    }
    let weight = handover.unwrap_or(1.0);
    realtime.state.shown = Shown::Handover;
    let denoise = settings.shows_denoised() && host.is_none();
    let accumulated = match host {
        Some(image) if settings.shows_denoised() => image,
        _ if denoise => encode_denoise(ctx, encoder, view, settings, denoiser, stats),
        _ => &view.accum,
    };
    let (Some(passes), Some(targets)) = (realtime.passes.as_ref(), realtime.targets.as_ref())
    else {
        return encode_display(ctx, encoder, view, settings, tonemap, denoiser, stats, host);
    };
    passes.handover.encode(
        ctx,
        encoder,
        &HandoverBuffers {
            realtime: realtime_image(targets, realtime.spatial_filter.as_ref(), settings),
            accumulated,
            output: &targets.handover,
        },
        &HandoverParams {
            width: view.width,
            height: view.height,
            weight,
            _pad: 0,
        },
    );
    tonemap.encode(
        ctx,
        encoder,
        view,
        TonemapInput::Denoised(&targets.handover),
        &tonemap_params(view, settings),
        stats.pass_writes(TONEMAP_PAIR),
    );
    denoise
}

/// The last real-time frame's displayed radiance (in the accumulation's layout): the spatial filter's output,
/// or the history itself when the filter is off.
pub fn realtime_image<'t>(
    targets: &'t RealtimeTargets,
    spatial_filter: Option<&'t Denoiser>,
    settings: &RenderSettings,
) -> &'t wgpu::Buffer {
    if settings.realtime.spatial {
        spatial_filter
            .and_then(Denoiser::output)
            .unwrap_or(&targets.history.accum)
    } else {
        &targets.history.accum
    }
}

/// The denoiser pass over the view, timed by the frame's denoise pair; returns its output.
pub fn encode_denoise<'d>(
    ctx: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    view: &ViewTargets,
    settings: &RenderSettings,
    denoiser: &'d Denoiser,
    stats: &FrameStats,
) -> &'d wgpu::Buffer {
    let output = denoiser.encode(
        ctx,
        encoder,
        &DenoiseInputs::of(view),
        &settings.denoise_params,
        stats.denoise_writes(),
    );
    if let Some(t) = &stats.denoise_timestamps {
        t.resolve(encoder, 1);
    }
    output
}

/// The display transform into the view's `rgba8`, denoising first when the settings ask for it (`host`, an
/// image denoised off the GPU for this accumulation, stands in for svgf's); true when svgf ran.
#[allow(clippy::too_many_arguments)]
pub fn encode_display(
    ctx: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    view: &ViewTargets,
    settings: &RenderSettings,
    tonemap: &TonemapPass,
    denoiser: &Denoiser,
    stats: &FrameStats,
    host: Option<&wgpu::Buffer>,
) -> bool {
    let (input, denoise) = match host {
        Some(image) if settings.shows_denoised() => (TonemapInput::Denoised(image), false),
        _ if settings.shows_denoised() => (
            TonemapInput::Denoised(encode_denoise(
                ctx, encoder, view, settings, denoiser, stats,
            )),
            true,
        ),
        _ => (TonemapInput::Accumulation, false),
    };
    tonemap.encode(
        ctx,
        encoder,
        view,
        input,
        &tonemap_params(view, settings),
        stats.pass_writes(TONEMAP_PAIR),
    );
    denoise
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

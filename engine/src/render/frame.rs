//! The frame: every GPU pass of one frame, in order, in one submission.
//!
//! 1. deform + refit: recorded by the deform plugin earlier in the frame ([`DeformCommands`]);
//! 2. trace: `spp_per_frame` samples per pixel into the view's accumulation (skipped once converged);
//! 3. denoise: when the display shows the denoised image;
//! 4. tonemap: when the display runs each frame (the viewer).
//!
//! Accumulation restarts here, before the trace, when anything that changes the image happened.

use super::accumulation::Accumulation;
use super::gpu_scene::GpuScene;
use super::layout::{FRAME_HIT_AOV, FRAME_MOMENTS, FRAME_NEE, GpuFrame};
use super::passes::denoise::{DenoiseInputs, Denoiser};
use super::passes::tonemap::{TonemapInput, TonemapParams, TonemapPass};
use super::passes::trace::TracePass;
use super::scene_bindings::SceneBindings;
use super::settings::{AovView, LightSampler, RenderSettings};
use super::stats::{FrameStats, TONEMAP_PAIR, TRACE_PAIR};
use super::view::ViewTargets;
use crate::camera::CameraView;
use crate::gpu::GpuContext;
use bevy_ecs::prelude::*;

/// GPU work other plugins recorded for this frame, submitted before the trace in the frame's submission (the
/// deform plugin's skin and refit passes, which the trace must see).
#[derive(Resource, Default)]
pub struct DeformCommands(pub Vec<wgpu::CommandBuffer>);

/// Encodes and submits the frame's passes.
#[allow(clippy::too_many_arguments)]
pub fn render_frame(
    ctx: Res<GpuContext>,
    settings: Res<RenderSettings>,
    camera: Res<CameraView>,
    scene: Res<GpuScene>,
    mut bindings: ResMut<SceneBindings>,
    mut view: ResMut<ViewTargets>,
    mut accumulation: ResMut<Accumulation>,
    mut trace: ResMut<TracePass>,
    tonemap: Res<TonemapPass>,
    mut denoiser: ResMut<Denoiser>,
    mut stats: ResMut<FrameStats>,
    mut deform: ResMut<DeformCommands>,
) {
    if view.resize(&ctx, settings.width, settings.height) {
        denoiser.release();
    }
    if accumulation.begin_frame(&settings, &camera) {
        view.clear(&ctx);
    }
    let deform = std::mem::take(&mut deform.0);
    if accumulation.converged() && deform.is_empty() {
        if accumulation.display_each_frame {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            encode_display(
                &ctx,
                &mut encoder,
                &view,
                &settings,
                &tonemap,
                &denoiser,
                &stats,
            );
            ctx.queue.submit([encoder.finish()]);
        }
        return;
    }
    let spp = settings.spp_per_frame;
    write_frame_constants(
        &ctx,
        &view,
        &scene,
        &settings,
        &camera,
        FrameConstants {
            sample_base: accumulation.samples,
            spp,
            max_depth: settings.max_depth,
            keep_denoiser_inputs: accumulation.keep_denoiser_inputs,
        },
    );
    trace.prepare(&ctx, &view);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    trace.encode(
        &mut encoder,
        bindings.group(&ctx, &scene),
        &view,
        stats.pass_writes(TRACE_PAIR),
    );
    accumulation.samples += spp;
    let display = accumulation.display_each_frame;
    let denoised = display
        && encode_display(
            &ctx,
            &mut encoder,
            &view,
            &settings,
            &tonemap,
            &denoiser,
            &stats,
        );
    if let Some(t) = &stats.timestamps {
        t.resolve(&mut encoder, if display { 2 } else { 1 });
    }
    stats.denoised_last_frame = denoised;
    stats.frames += 1;
    stats.encode_async(&mut encoder, &view.ray_counter, denoised);
    ctx.queue
        .submit(deform.into_iter().chain([encoder.finish()]));
    stats.after_submit();
    if stats.time_passes {
        stats.last_pass_times = stats.read_pass_times(&ctx);
    }
}

/// Whether the display shows the denoised image (colour view with the denoiser on).
pub fn shows_denoised(settings: &RenderSettings) -> bool {
    settings.denoise && settings.view == AovView::Color
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

/// The display transform into the view's `rgba8`, denoising first when the settings ask for it; true when it
/// denoised.
pub fn encode_display(
    ctx: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    view: &ViewTargets,
    settings: &RenderSettings,
    tonemap: &TonemapPass,
    denoiser: &Denoiser,
    stats: &FrameStats,
) -> bool {
    let denoise = shows_denoised(settings);
    let input = if denoise {
        TonemapInput::Denoised(encode_denoise(
            ctx, encoder, view, settings, denoiser, stats,
        ))
    } else {
        TonemapInput::Accumulation
    };
    let params = TonemapParams {
        width: view.width,
        height: view.height,
        tonemapper: settings.tonemapper as u32,
        view: settings.view as u32,
        exposure_scale: 2f32.powf(settings.exposure),
        depth_scale: settings.depth_view_scale,
        _pad: [0; 2],
    };
    tonemap.encode(
        ctx,
        encoder,
        view,
        input,
        &params,
        stats.pass_writes(TONEMAP_PAIR),
    );
    denoise
}

/// What varies between dispatches of the same view.
pub struct FrameConstants {
    /// Samples per pixel already accumulated (the sample index base of the random streams).
    pub sample_base: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub keep_denoiser_inputs: bool,
}

/// Writes the view's per-dispatch constants (`shaders/view.wgsl` `Frame`).
pub fn write_frame_constants(
    ctx: &GpuContext,
    view: &ViewTargets,
    scene: &GpuScene,
    settings: &RenderSettings,
    camera: &CameraView,
    c: FrameConstants,
) {
    let frame = GpuFrame {
        world_from_camera: camera.world_from_camera.to_cols_array_2d(),
        tan_half_fov: (camera.yfov * 0.5).tan(),
        lens_radius: settings.lens.aperture_radius.max(0.0),
        focus_distance: settings.lens.focus_distance.max(1e-6),
        light_count: scene.lights.count,
        width: view.width,
        height: view.height,
        sample_base: c.sample_base,
        spp: c.spp,
        max_depth: c.max_depth,
        seed: settings.seed,
        rr_depth: if settings.russian_roulette {
            settings.rr_depth
        } else {
            u32::MAX
        },
        // The primary-hit AOV is written by the first dispatch of an accumulation.
        flags: if settings.nee { FRAME_NEE } else { 0 }
            | if view.hit_aov && c.sample_base == 0 {
                FRAME_HIT_AOV
            } else {
                0
            }
            | if settings.denoise || c.keep_denoiser_inputs {
                FRAME_MOMENTS
            } else {
                0
            },
        infinite_light_first: scene.lights.infinite_first,
        infinite_light_count: scene.lights.infinite_count,
        tree_light_count: match settings.light_sampler {
            LightSampler::Tree => scene.lights.tree_count,
            LightSampler::Power => 0,
        },
        _pad: 0,
    };
    ctx.queue
        .write_buffer(&view.frame, 0, bytemuck::bytes_of(&frame));
}

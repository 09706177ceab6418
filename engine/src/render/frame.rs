//! The frame: every GPU pass of one frame, in order, in one submission.
//!
//! Accumulation (the default, and any still):
//! 1. deform + refit: recorded by the deform plugin earlier in the frame ([`DeformCommands`]);
//! 2. trace: `spp_per_frame` samples per pixel into the view's accumulation (skipped once converged); the
//!    wavefront pass instead where `RenderSettings::integrator` asks for it (or `Auto` timed it faster:
//!    [`IntegratorChoice`]) and only radiance is recorded;
//! 3. denoise: when the display shows the denoised image;
//! 4. tonemap: when the display runs each frame (the viewer).
//!
//! Accumulation restarts here, before the trace, when anything that changes the image happened.
//!
//! The real-time path (`RenderMode::Realtime`, while anything moves; [`encode_realtime_frame`]):
//! 1. deform + refit, as above;
//! 2. gbuffer: one jittered camera ray per pixel, what it hit and where that was last frame;
//! 3. restir_di: light candidates, temporal and spatial reuse, direct light at the first hit;
//! 4. gradient: last frame's gradient samples shaded again, filtered (A-SVGF);
//! 5. realtime_trace: one path per pixel from the G-buffer hit;
//! 6. temporal: history reprojected, shortened by the gradients, the new sample blended in;
//! 7. denoise: the a-trous filter over the history, with its temporal variance; or, where OIDN runs per frame
//!    ([`FrameDenoiser`]), the frame so far is submitted, OIDN denoises the history, and the rest follows in
//!    a second submission;
//! 8. tonemap.
//!
//! Once nothing moves, the still accumulates as above and the display hands over from the last real-time image
//! to the accumulation (`display::Display::encode_accumulation`).

use super::accumulation::Accumulation;
use super::display::{Display, tonemap_params};
use super::frame_constants::{FrameConstants, write_frame_constants};
use super::frame_denoiser::FrameDenoiser;
use super::gpu_scene::{GpuScene, SceneWrites};
use super::host_denoised::HostDenoised;
use super::integrator_choice::{IntegratorChoice, Workload};
use super::layout::{LIGHT_DIRECTIONAL, LIGHT_ENVIRONMENT, LIGHT_SUN};
use super::material_lobes::{KernelNeeds, MaterialNeeds};
use super::passes::denoise::{DenoiseInputs, Denoiser};
use super::passes::gradient::FILTERED;
use super::passes::tonemap::{TonemapInput, TonemapPass};
use super::passes::trace::TracePass;
use super::passes::wavefront::{WavefrontPass, WavefrontSlot};
use super::realtime::{
    Realtime, RealtimeImage, RealtimePasses, SceneGroups, Shown, runs as realtime_runs,
};
use super::scene_bindings::SceneBindings;
use super::settings::{Integrator, RenderSettings};
use super::stats::*;
use super::view::ViewTargets;
use crate::camera::CameraView;
use crate::gpu::GpuContext;
use crate::scene::SceneAssets;
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
    assets: Res<SceneAssets>,
    mut scene: ResMut<GpuScene>,
    mut bindings: ResMut<SceneBindings>,
    mut view: ResMut<ViewTargets>,
    mut accumulation: ResMut<Accumulation>,
    (mut trace, mut wavefront, mut choice): (
        ResMut<TracePass>,
        ResMut<WavefrontSlot>,
        ResMut<IntegratorChoice>,
    ),
    tonemap: Res<TonemapPass>,
    mut denoiser: ResMut<Denoiser>,
    mut stats: ResMut<FrameStats>,
    mut deform: ResMut<DeformCommands>,
    mut realtime: ResMut<Realtime>,
    host_denoised: Res<HostDenoised>,
    mut frame_denoiser: ResMut<FrameDenoiser>,
) {
    if view.resize(&ctx, settings.width, settings.height) {
        denoiser.release();
        realtime.release_targets();
    }
    let changed = accumulation.begin_frame(&settings, &camera);
    let deform = std::mem::take(&mut deform.0);
    if realtime_runs(&settings) {
        // Anything moved (or the hand-over is off): a real-time frame; a still accumulates below.
        if changed || !settings.realtime.handover {
            if scene.motion.is_none() {
                scene.enable_motion(&ctx, &assets.0);
            }
            // The real-time kernels traverse the BVH2: no wide top level is built while they run.
            scene.want_wide_top_level(&ctx, false);
            encode_realtime_frame(
                &ctx,
                &settings,
                &camera,
                &mut scene,
                &mut bindings,
                &view,
                (&mut realtime, &mut frame_denoiser),
                &tonemap,
                &mut stats,
                deform,
            );
            return;
        }
    } else if changed {
        realtime.state.skipped_frame();
    }
    if let Some(motion) = scene.motion.as_mut() {
        // Nothing moved this frame (or the real-time path is off): no previous positions to keep.
        motion.write_mesh_motion(&ctx);
    }
    if changed || accumulation.samples == 0 {
        // A new accumulation (after real-time frames the view still holds an older still's).
        view.clear(&ctx);
    }
    // OIDN's image of this accumulation, once one was handed over, replaces svgf's on the display.
    let host = host_denoised.current(&settings, &view, &accumulation);
    // A converged still with nothing deformed traces nothing; the viewer still displays it each frame.
    let traces = !accumulation.converged() || !deform.is_empty();
    if !traces && !accumulation.display_each_frame {
        return;
    }
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    if traces {
        let spp = settings.spp_per_frame;
        let frame = write_frame_constants(
            &ctx,
            &view,
            &scene,
            &settings,
            &camera,
            FrameConstants {
                sample_base: accumulation.samples,
                spp,
                max_depth: settings.max_depth,
            },
        );
        let needs = kernel_needs(&ctx, &scene);
        let aovs = accumulation.records_denoiser_inputs(&settings);
        let workload = Workload {
            width: view.width,
            height: view.height,
            spp_per_frame: spp,
            max_depth: settings.max_depth,
            needs,
        };
        // The wavefront form records radiance only, and its state must fit the adapter's bindings.
        let waves_fit = WavefrontPass::fits(&ctx, view.pixels());
        if !waves_fit
            && settings.integrator == Integrator::Wavefront
            && choice.first_too_large(view.width, view.height)
        {
            tracing::warn!(
                "{}x{} is too large for the wavefront integrator's path state on this adapter (48 bytes a \
                 pixel in one binding); the megakernel traces it",
                view.width,
                view.height
            );
        }
        let waves_possible = !aovs && !view.hit_aov && waves_fit;
        let mut in_waves =
            choice.form(settings.integrator, workload, waves_possible) == Integrator::Wavefront;
        if settings.integrator == Integrator::Auto
            && choice.decision().map(|d| d.chosen) == Some(Integrator::Megakernel)
        {
            // Auto settled on the megakernel: the waves' path state is memory nothing uses.
            wavefront.0 = None;
        }
        // The waves traverse the wide top level, built beside the BVH2 while they trace.
        let wide_top_level = scene.want_wide_top_level(&ctx, in_waves && ctx.wide_top_level);
        if in_waves {
            let layout = &bindings.layout;
            let pass = wavefront
                .0
                .get_or_insert_with(|| WavefrontPass::new(&ctx, layout));
            let wave_needs = KernelNeeds {
                wide_top_level,
                ..needs
            };
            // Where the GPU's memory holds no wave's path state (the pass has said so), the megakernel traces.
            in_waves = pass.prepare(&ctx, &view, wave_needs, spp, choice.rays_sorted());
        }
        if !in_waves {
            trace.prepare(&ctx, &view, needs, aovs);
        }
        let deformed = deformed_on_gpu(&deform, &scene);
        let group = bindings.group(&ctx, &mut scene, &mut encoder, deformed);
        let timestamps = stats.pass_writes(TRACE_PAIR);
        match wavefront.0.as_ref().filter(|_| in_waves) {
            Some(pass) => pass.encode(
                &mut encoder,
                group,
                &view,
                (spp, settings.max_depth),
                choice.rays_sorted(),
                timestamps,
            ),
            None => trace.encode(&mut encoder, group, &view, frame.sample_lanes, timestamps),
        }
        accumulation.samples += spp;
    }
    let handover = realtime_runs(&settings).then(|| handover_weight(&settings, &accumulation));
    let display = accumulation.display_each_frame;
    if !display && handover.is_some() {
        // Nothing is displayed, so nothing is mixed: what a still shows is its accumulation.
        realtime.state.shown = Shown::Accumulation;
    }
    let denoised = display
        && Display {
            ctx: &ctx,
            view: &view,
            settings: &settings,
            tonemap: &tonemap,
            denoiser: &denoiser,
            stats: &stats,
        }
        .encode_accumulation(&mut encoder, &mut realtime, handover, host.as_ref());
    if !traces {
        ctx.queue.submit([encoder.finish()]);
        return;
    }
    if let Some(t) = &stats.timestamps {
        t.resolve(&mut encoder, if display { 2 } else { 1 });
    }
    stats.denoised_last_frame = denoised;
    stats.realtime_last_frame = false;
    stats.frames += 1;
    stats.encode_async(&mut encoder, &view.ray_counter, denoised);
    ctx.queue
        .submit(deform.into_iter().chain([encoder.finish()]));
    stats.after_submit();
    if stats.time_passes || choice.timing() {
        stats.last_pass_times = stats.read_pass_times(&ctx);
    }
    if choice.timing() {
        // A frame of Auto's trial: its trace time (blocking, for the trial's few frames only).
        choice.record(stats.last_pass_times.map(|t| t.trace_ms));
    }
}

/// The scene buffers the GPU deformer's command buffers of this frame write (skinned positions, refit BLAS
/// nodes, and the wide trees refit with them where the scene has any): CPU adapters copy them into the
/// kernels' textures after those commands.
fn deformed_on_gpu(deform: &[wgpu::CommandBuffer], scene: &GpuScene) -> SceneWrites {
    if deform.is_empty() {
        SceneWrites::NONE
    } else if scene.has_wide_deformed() {
        SceneWrites::VERTEX_POOL | SceneWrites::BLAS_NODES | SceneWrites::WIDE_NODES
    } else {
        SceneWrites::VERTEX_POOL | SceneWrites::BLAS_NODES
    }
}

/// What the path-tracing kernels are compiled for this frame: the materials' needs and, where the adapter
/// compiles for the scene's shape ([`GpuContext::scene_shape_kernels`]), the top level's one leaf, the BLAS
/// layouts of its leaves, whether the environment maps sample their cells uniformly and the light kinds
/// next-event estimation can pick.
fn kernel_needs(ctx: &GpuContext, scene: &GpuScene) -> KernelNeeds {
    let materials = MaterialNeeds::of(&scene.material_data);
    if !ctx.scene_shape_kernels {
        return KernelNeeds {
            materials,
            ..Default::default()
        };
    }
    KernelNeeds {
        materials,
        sole_instance: scene.sole_instance,
        blas_layouts: scene.blas_layouts,
        environment_cells_uniform: scene.lights.environment_cells_uniform(),
        next_event_light_kinds: Some(scene.lights.next_event_kinds),
        // Only the waves' kernels traverse the wide top level: set where they are prepared.
        wide_top_level: None,
    }
}

/// A still's hand-over: the accumulation's weight in the displayed image (1: the accumulation alone).
fn handover_weight(settings: &RenderSettings, accumulation: &Accumulation) -> f32 {
    let spp = settings.realtime.handover_spp;
    if spp == 0 {
        return 1.0;
    }
    (accumulation.samples as f32 / spp as f32).min(1.0)
}

/// The real-time path's frame: the passes in the order of the module documentation, one submission.
#[allow(clippy::too_many_arguments)]
pub fn encode_realtime_frame(
    ctx: &GpuContext,
    settings: &RenderSettings,
    camera: &CameraView,
    scene: &mut GpuScene,
    bindings: &mut SceneBindings,
    view: &ViewTargets,
    (realtime, frame_denoiser): (&mut Realtime, &mut FrameDenoiser),
    tonemap: &TonemapPass,
    stats: &mut FrameStats,
    mut deform: Vec<wgpu::CommandBuffer>,
) {
    // ReSTIR DI runs when some light is at a finite distance. A scene lit only from infinity (sky, sun,
    // directional lights) keeps next-event estimation at the first hit: on the H200's sky-lit crowd ReSTIR
    // costs 3x the frame time (20.0 against 6.7 ms at 720p) for a worse image (settled relMSE 0.0159 against
    // 0.0144, FLIP 0.050 against 0.035; docs/BENCHMARKS.md, "The drift's cause").
    let lights = scene
        .lights
        .uploaded
        .iter()
        .any(|l| !matches!(l.kind, LIGHT_DIRECTIONAL | LIGHT_ENVIRONMENT | LIGHT_SUN));
    realtime.targets_for(ctx, view.width, view.height);
    let Realtime {
        passes,
        targets,
        spatial_filter,
        external_image,
        state,
    } = realtime;
    let targets = targets.as_mut().expect("made by targets_for");
    let spatial_filter = spatial_filter.as_ref().expect("made by targets_for");
    let passes = passes.get_or_insert_with(|| RealtimePasses::new(ctx, &bindings.layout));
    let motion = scene
        .motion
        .as_mut()
        .expect("the real-time path's scene motion is enabled before its frame");
    let plan = state.begin_frame(
        settings,
        camera,
        (view.width, view.height),
        lights,
        motion.lights_remapped,
        targets.strata,
    );
    if plan.restir {
        targets.ensure_restir(ctx);
    }
    if !state.edited_materials.is_empty() {
        targets.write_edited_materials(ctx, &state.edited_materials);
    }
    motion.write_mesh_motion(ctx);
    let motion_group = passes.motion_group(ctx, motion);
    write_frame_constants(
        ctx,
        view,
        scene,
        settings,
        camera,
        FrameConstants {
            sample_base: state.frame_index,
            spp: 1,
            max_depth: settings.max_depth,
        },
    );
    ctx.queue
        .write_buffer(&targets.uniform, 0, bytemuck::bytes_of(&plan.uniform));
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    let deformed = deformed_on_gpu(&deform, scene);
    let scene_group = bindings.group(ctx, scene, &mut encoder, deformed).clone();
    let groups = SceneGroups {
        scene: &scene_group,
        motion: &motion_group,
    };
    let targets = &*targets;
    encoder.clear_buffer(&view.ray_counter, 0, None);
    passes.gbuffer.encode(
        ctx,
        &mut encoder,
        &groups,
        view,
        targets,
        stats.realtime_writes(GBUFFER_PAIR),
    );
    if plan.restir {
        let ts = stats.realtime_writes(RESTIR_PAIR);
        passes
            .restir
            .encode(ctx, &mut encoder, &groups, view, targets, ts);
    } else {
        stats.time_skipped(&mut encoder, RESTIR_PAIR);
    }
    if plan.gradients {
        let ts = stats.realtime_writes(GRADIENT_PAIR);
        passes
            .gradient
            .encode(ctx, &mut encoder, &groups, view, targets, ts);
    } else {
        // No gradients this frame: the temporal pass reads none.
        encoder.clear_buffer(&targets.gradients[FILTERED], 0, None);
        stats.time_skipped(&mut encoder, GRADIENT_PAIR);
    }
    passes.trace.encode(
        ctx,
        kernel_needs(ctx, scene),
        &mut encoder,
        &groups,
        view,
        targets,
        stats.realtime_writes(REALTIME_TRACE_PAIR),
    );
    passes.temporal.encode(
        ctx,
        &mut encoder,
        view,
        targets,
        stats.realtime_writes(TEMPORAL_PAIR),
    );
    let h = &targets.history;
    let history = DenoiseInputs {
        accum: &h.accum,
        albedo_depth: &h.albedo_depth,
        normal_hits: &h.normal_hits,
        moments: &h.moments,
        width: view.width,
        height: view.height,
    };
    let mut shown = if plan.spatial {
        RealtimeImage::Spatial
    } else {
        RealtimeImage::History
    };
    if plan.spatial && frame_denoiser.runs(ctx, settings) {
        // The denoiser reads the history once this much has run: submit it, then record the rest anew.
        let first = std::mem::replace(
            &mut encoder,
            ctx.device.create_command_encoder(&Default::default()),
        );
        ctx.queue.submit(
            std::mem::take(&mut deform)
                .into_iter()
                .chain([first.finish()]),
        );
        let output = external_image.get_or_insert_with(|| {
            super::host_denoised::HostDenoised::image_buffer_sized(ctx, view.accum.size())
        });
        if frame_denoiser.denoise(ctx, &h.denoiser_sources(view), output, settings) {
            shown = RealtimeImage::External;
        }
    }
    let image = match shown {
        RealtimeImage::Spatial => spatial_filter.encode(
            ctx,
            &mut encoder,
            &history,
            &settings.denoise_params,
            stats.realtime_writes(SPATIAL_PAIR),
        ),
        RealtimeImage::External => {
            stats.time_skipped(&mut encoder, SPATIAL_PAIR);
            external_image.as_ref().expect("written above")
        }
        RealtimeImage::History => {
            stats.time_skipped(&mut encoder, SPATIAL_PAIR);
            &h.accum
        }
    };
    tonemap.encode(
        ctx,
        &mut encoder,
        view,
        TonemapInput::Denoised(image),
        &tonemap_params(view, settings),
        stats.pass_writes(TONEMAP_PAIR),
    );
    stats.resolve_realtime(&mut encoder);
    if let Some(t) = &stats.timestamps {
        // The accumulation trace's pair is not written on real-time frames; the tone mapper's is.
        t.resolve(&mut encoder, 2);
    }
    stats.denoised_last_frame = false;
    stats.realtime_last_frame = true;
    stats.frames += 1;
    stats.encode_async(&mut encoder, &view.ray_counter, false);
    ctx.queue
        .submit(deform.into_iter().chain([encoder.finish()]));
    stats.after_submit();
    if stats.time_passes {
        stats.last_pass_times = stats.read_pass_times(ctx);
    }
    state.end_frame(camera, &plan, shown);
}

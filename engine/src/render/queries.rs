//! GPU work run outside the frame, on demand: one denoise of the current accumulation, one display transform,
//! the ray-casting benchmark. Each records its pass, submits and reads the result back (blocking).

use super::accumulation::Accumulation;
use super::display::Display;
use super::frame_constants::{FrameConstants, write_frame_constants};
use super::gpu_scene::GpuScene;
use super::host_denoised::HostDenoised;
use super::passes::OnFirstUse;
use super::passes::denoise::Denoiser;
use super::passes::denoiser_planes::{DenoiserPlanesPass, DenoiserSources};
use super::passes::raycast::{RaycastPass, TraversalWork};
use super::passes::tonemap::TonemapPass;
use super::scene_bindings::SceneBindings;
use super::settings::RenderSettings;
use super::stats::{FrameStats, RayCastTiming, TRACE_PAIR};
use super::view::{ViewTargets, mean_rgb};
use crate::camera::CameraView;
use crate::gpu::GpuContext;
use bevy_ecs::prelude::World;

/// Denoises the current accumulation with the settings' `denoise_params` (whatever `RenderSettings::denoise`
/// says) and reads it back: linear RGB per pixel, row-major from the top-left.
pub fn denoised_radiance(world: &World) -> Vec<[f32; 3]> {
    let display = display_passes(world);
    let ctx = display.ctx;
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    let output = display.encode_denoise(&mut encoder);
    ctx.queue.submit([encoder.finish()]);
    mean_rgb(&ctx.read_buffer(output, output.size()))
}

/// Writes the accumulation's current means (scattered radiance, first-hit albedo and normal, sanitised, as
/// packed float3 planes) into `planes` (colour, albedo, normal) and waits for the GPU: the images Open Image Denoise's GPU
/// device reads in place from memory it shares with wgpu.
pub fn write_denoiser_inputs(
    ctx: &GpuContext,
    sources: &DenoiserSources,
    planes: [&wgpu::Buffer; 3],
) {
    // The pipelines and layouts come from the device's cache; only the small parameter buffer is new.
    let pass = DenoiserPlanesPass::new(ctx);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    pass.encode_pack(ctx, &mut encoder, sources, planes);
    ctx.queue.submit([encoder.finish()]);
    ctx.wait_idle();
}

/// Writes a denoiser's packed float3 `output` plus the unscattered radiance of `sources` where it was split off
/// into `shown` in the accumulation's layout (sample count 1, what the display shows from `HostDenoised`),
/// non-finite and kept pixels (`oidn::inputs::PixelSplit`) from the `color` plane it was given, and waits for the
/// GPU.
pub fn write_denoised_output(
    ctx: &GpuContext,
    sources: &DenoiserSources,
    planes: [&wgpu::Buffer; 2],
    shown: &wgpu::Buffer,
) {
    let pass = DenoiserPlanesPass::new(ctx);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    pass.encode_unpack(ctx, &mut encoder, sources, planes, shown);
    ctx.queue.submit([encoder.finish()]);
    ctx.wait_idle();
}

/// The display passes over the world's view, settings and passes.
fn display_passes(world: &World) -> Display<'_> {
    Display {
        ctx: world.resource::<GpuContext>(),
        view: world.resource::<ViewTargets>(),
        settings: world.resource::<RenderSettings>(),
        tonemap: world.resource::<TonemapPass>(),
        denoiser: world.resource::<Denoiser>(),
        stats: world.resource::<FrameStats>(),
    }
}

/// The image denoised on the host that the display shows for the current accumulation, if any.
fn host_denoised(world: &World) -> Option<wgpu::Buffer> {
    world.resource::<HostDenoised>().current(
        world.resource::<RenderSettings>(),
        world.resource::<ViewTargets>(),
        world.resource::<Accumulation>(),
    )
}

/// Tone-maps the current accumulation (denoised if the settings say so: OIDN's image when one was handed
/// over for it, else svgf's) and reads the sRGB RGBA8 image back.
pub fn display_rgba8(world: &World) -> Vec<u8> {
    let display = display_passes(world);
    let (ctx, view) = (display.ctx, display.view);
    let host = host_denoised(world);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    display.encode(&mut encoder, host.as_ref());
    ctx.queue.submit([encoder.finish()]);
    view.read_rgba8(ctx)
}

/// Casts one camera ray per pixel centre and, with `diffuse_bounce`, one cosine-distributed ray from each hit,
/// without shading, through the current scene and camera. Blocks for the result; `None` without timestamp
/// queries. Leaves the accumulation untouched.
pub fn cast_rays(world: &World, diffuse_bounce: bool) -> Option<RayCastTiming> {
    let stats = world.resource::<FrameStats>();
    stats.timestamps.as_ref()?;
    let ctx = world.resource::<GpuContext>();
    submit_raycast(world, diffuse_bounce, false);
    let gpu_ms = stats.timestamps.as_ref()?.read_ms(ctx)[0];
    Some(RayCastTiming {
        gpu_ms,
        rays: world.resource::<ViewTargets>().read_ray_count(ctx),
    })
}

/// The rays of [`cast_rays`] once more, counting their traversal work (nodes fetched by kind, triangles tested)
/// instead of timing it, with the number of rays cast. Blocks for the result.
pub fn count_traversal_work(world: &World, diffuse_bounce: bool) -> (TraversalWork, u64) {
    let ctx = world.resource::<GpuContext>();
    let pass = submit_raycast(world, diffuse_bounce, true);
    (
        pass.read_work(ctx),
        world.resource::<ViewTargets>().read_ray_count(ctx),
    )
}

/// Records and submits the ray-casting pass over the view: the counting kernel with `count_work`, else the
/// timed one (its timestamps resolved).
fn submit_raycast(world: &World, diffuse_bounce: bool, count_work: bool) -> &RaycastPass {
    let ctx = world.resource::<GpuContext>();
    let stats = world.resource::<FrameStats>();
    let pass = raycast_pass(world, diffuse_bounce);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    let scene = world
        .resource::<SceneBindings>()
        .fresh(ctx, world.resource::<GpuScene>());
    let timestamps = if count_work {
        None
    } else {
        stats.pass_writes(TRACE_PAIR)
    };
    let view = world.resource::<ViewTargets>();
    pass.encode(ctx, &mut encoder, &scene, view, count_work, timestamps);
    if let (false, Some(t)) = (count_work, &stats.timestamps) {
        t.resolve(&mut encoder, 1);
    }
    ctx.queue.submit([encoder.finish()]);
    pass
}

/// The ray-casting pass (made on first use), its frame constants written for `diffuse_bounce`.
fn raycast_pass(world: &World, diffuse_bounce: bool) -> &RaycastPass {
    let ctx = world.resource::<GpuContext>();
    let scene = world.resource::<GpuScene>();
    let view = world.resource::<ViewTargets>();
    let bindings = world.resource::<SceneBindings>();
    write_frame_constants(
        ctx,
        view,
        scene,
        world.resource::<RenderSettings>(),
        world.resource::<CameraView>(),
        FrameConstants {
            sample_base: world.resource::<Accumulation>().samples,
            spp: 1,
            max_depth: u32::from(diffuse_bounce),
        },
    );
    world
        .resource::<OnFirstUse<RaycastPass>>()
        .get_or_init(|| RaycastPass::new(ctx, &bindings.layout))
}

/// The linear radiance the display shows: the last real-time image, the hand-over's mix, or the accumulation
/// (denoised when the settings say so, by OIDN when its image was handed over). Row-major from the top-left.
pub fn displayed_radiance(world: &World) -> Vec<[f32; 3]> {
    use super::realtime::{Realtime, Shown, runs};
    let ctx = world.resource::<GpuContext>();
    let settings = world.resource::<RenderSettings>();
    let realtime = world.resource::<Realtime>();
    let buffer = match (&realtime.targets, realtime.state.shown, runs(settings)) {
        (Some(t), Shown::Realtime, true) => super::display::realtime_image(realtime, t),
        (Some(t), Shown::Handover, true) => &t.handover,
        _ => {
            if let Some(image) = host_denoised(world) {
                return mean_rgb(&ctx.read_buffer(&image, image.size()));
            }
            return if settings.denoise {
                denoised_radiance(world)
            } else {
                world.resource::<ViewTargets>().read_radiance(ctx)
            };
        }
    };
    mean_rgb(&ctx.read_buffer(buffer, buffer.size()))
}

/// The real-time path's colour history after the last real-time frame: mean radiance and history length per
/// pixel (empty before the first real-time frame).
pub fn realtime_history(world: &World) -> Vec<([f32; 3], f32)> {
    let ctx = world.resource::<GpuContext>();
    let Some(targets) = &world.resource::<super::realtime::Realtime>().targets else {
        return Vec::new();
    };
    let bytes = ctx.read_buffer(&targets.history.accum, targets.history.accum.size());
    bytemuck::cast_slice::<u8, [f32; 4]>(&bytes)
        .iter()
        .take(targets.pixels() as usize)
        .map(|p| {
            let n = p[3].max(1.0);
            ([p[0] / n, p[1] / n, p[2] / n], p[3])
        })
        .collect()
}

/// The real-time G-buffer of the last real-time frame (empty before the first).
pub fn realtime_gbuffer(world: &World) -> Vec<super::layout::GpuSurface> {
    let ctx = world.resource::<GpuContext>();
    let Some(targets) = &world.resource::<super::realtime::Realtime>().targets else {
        return Vec::new();
    };
    let bytes = ctx.read_buffer(&targets.gbuffer, targets.gbuffer.size());
    bytemuck::cast_slice::<u8, super::layout::GpuSurface>(&bytes)
        .iter()
        .take(targets.pixels() as usize)
        .copied()
        .collect()
}

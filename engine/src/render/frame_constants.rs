//! The per-dispatch constants of a view (`shaders/view.wgsl` `Frame`), written before each trace.

use super::gpu_scene::GpuScene;
use super::layout::{FRAME_HIT_AOV, FRAME_NEE, GpuFrame};
use super::passes::trace::sample_lanes;
use super::settings::{LightSampler, RenderSettings};
use super::view::ViewTargets;
use crate::camera::CameraView;
use crate::gpu::GpuContext;

/// What varies between dispatches of the same view.
pub struct FrameConstants {
    /// Samples per pixel already accumulated (the sample index base of the random streams).
    pub sample_base: u32,
    pub spp: u32,
    pub max_depth: u32,
}

/// Writes the view's per-dispatch constants (`shaders/view.wgsl` `Frame`) and returns them (the trace pass
/// dispatches by their `sample_lanes`).
pub fn write_frame_constants(
    ctx: &GpuContext,
    view: &ViewTargets,
    scene: &GpuScene,
    settings: &RenderSettings,
    camera: &CameraView,
    c: FrameConstants,
) -> GpuFrame {
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
            },
        infinite_light_first: scene.lights.infinite_first,
        infinite_light_count: scene.lights.infinite_count,
        tree_light_count: match settings.light_sampler {
            LightSampler::Tree => scene.lights.tree_count,
            LightSampler::Power => 0,
        },
        sample_lanes: sample_lanes(ctx, view.pixels(), c.spp),
    };
    ctx.queue
        .write_buffer(&view.frame, 0, bytemuck::bytes_of(&frame));
    frame
}

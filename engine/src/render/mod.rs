//! The render plugin: the scene's GPU buffers, the view's targets, the GPU passes and the frame that runs them.
//!
//! - [`gpu_scene`]: the scene packed into storage buffers (meshes, BLASes, materials, textures, instances,
//!   lights); [`scene_bindings`]: group 0 over them; [`environment`]: the environment setting as lights.
//! - [`view`]: the view's targets (accumulation, AOVs, display image); [`accumulation`]: its sample count and
//!   restart flag; [`host_denoised`]: an image denoised on the host (OIDN) for the display to show;
//!   [`frame_denoiser`]: the denoiser outside the renderer that a real-time frame may hand its history to;
//!   [`realtime`]: the real-time path's targets and state (G-buffers, histories, reservoirs).
//! - [`passes`]: one struct per GPU pass beside its WGSL kernel; [`shaders`]: the WGSL library they compose.
//! - [`frame`]: the frame's passes in order, in one submission; [`systems`]: what runs before it (refit on the
//!   CPU backend, the top-level BVH, material edits, the light list); [`queries`]: GPU work run on demand;
//!   [`picking`].
//! - [`integrator_choice`]: which form of the path integrator traces a frame; [`stats`]: GPU pass times;
//!   [`layout`]: the structs and constants Rust shares with WGSL; [`settings`].

pub mod accumulation;
pub mod display;
pub mod environment;
pub mod frame;
pub mod frame_constants;
pub mod frame_denoiser;
pub mod gpu_scene;
pub mod host_denoised;
pub mod integrator_choice;
pub mod layout;
pub mod material_lobes;
pub mod passes;
pub mod picking;
pub mod queries;
pub mod realtime;
pub mod realtime_targets;
pub mod scene_bindings;
pub mod scene_texels;
pub mod settings;
pub mod shaders;
pub mod stats;
pub mod systems;
pub mod view;

pub use accumulation::Accumulation;
pub use gpu_scene::{GpuMemory, GpuScene, InstanceInput, UploadError};
pub use host_denoised::HostDenoised;
pub use passes::denoise::{DenoiseParams, Denoiser};
pub use settings::{
    AovView, DenoiserKind, Environment, FrameOidn, Integrator, LightSampler, RealtimeSettings,
    RenderMode, RenderSettings, RestirSettings, ThinLens, Tonemapper,
};
pub use stats::{FrameStats, GpuFrameStats, PassTimes, RayCastTiming};
pub use view::{Aovs, PrimaryHit, ViewTargets};

use crate::FrameSet;
use crate::animation::{DeformedElsewhere, DeformedMeshes, MeshPoses};
use crate::bvh::refit::BvhStats;
use crate::gpu::GpuContext;
use bevy_app::{App, Plugin, Update};
use bevy_ecs::prelude::*;
use passes::OnFirstUse;
use passes::pick::PickPass;
use passes::raycast::RaycastPass;
use passes::tonemap::TonemapPass;
use passes::trace::TracePass;
use scene_bindings::SceneBindings;
use systems::{GeometryChanged, InstanceMap};

/// Builds the scene's BVHs and uploads it, makes the view's targets and the passes, and inserts them as
/// resources; returns notes for the user (textures downscaled to fit, ...). Errors when the scene exceeds the
/// adapter's limits. `binding_limit` overrides the adapter's storage binding limit (tests of the over-limit path).
pub fn insert_resources(
    world: &mut World,
    ctx: &GpuContext,
    scene: &crate::scene::SceneAsset,
    settings: &RenderSettings,
    binding_limit: Option<u64>,
) -> Result<Vec<String>, UploadError> {
    let (mut gpu_scene, mut notes) = GpuScene::new(
        ctx,
        scene,
        settings.bvh_quality,
        settings.deformable_bvh_quality(ctx.info.device_type),
        settings.static_bvh,
        settings.merge_static.then_some(settings.merged_bvh_quality),
        binding_limit,
    )?;
    let baked = environment::bake(&settings.environment, gpu_scene.binding_limit)
        .map_err(UploadError::Environment)?;
    notes.extend(baked.notes.iter().cloned());
    gpu_scene.set_environment(ctx, Some(&baked));
    world.insert_resource(systems::UploadedEnvironment(settings.environment.clone()));
    let bindings = SceneBindings::new(ctx);
    world.insert_resource(TracePass::new(ctx, &bindings.layout));
    world.insert_resource(passes::wavefront::WavefrontSlot::default());
    world.insert_resource(integrator_choice::IntegratorChoice::for_adapter(ctx));
    world.insert_resource(TonemapPass::new(ctx));
    world.insert_resource(Denoiser::new(ctx));
    world.insert_resource(OnFirstUse::<PickPass>::default());
    world.insert_resource(OnFirstUse::<RaycastPass>::default());
    world.insert_resource(ViewTargets::new(ctx, settings.width, settings.height));
    world.insert_resource(FrameStats::new(ctx));
    // A new scene: nothing the real-time path kept applies.
    world.insert_resource(realtime::Realtime::default());
    world.insert_resource(realtime::scene_motion::MotionObjects::default());
    world.insert_resource(bindings);
    world.insert_resource(gpu_scene);
    Ok(notes)
}

/// Needs [`GpuContext`], [`RenderSettings`], [`crate::camera::CameraView`] and the resources of
/// [`insert_resources`].
pub struct RenderPlugin;

impl Plugin for RenderPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<BvhStats>()
            .init_resource::<DeformedMeshes>()
            .init_resource::<MeshPoses>()
            .init_resource::<DeformedElsewhere>()
            .init_resource::<Accumulation>()
            .init_resource::<HostDenoised>()
            .init_resource::<frame_denoiser::FrameDenoiser>()
            .init_resource::<GeometryChanged>()
            .init_resource::<InstanceMap>()
            .init_resource::<frame::DeformCommands>()
            .add_systems(
                Update,
                (
                    realtime::scene_motion::sync_scene_motion.in_set(FrameSet::Deform),
                    (
                        systems::refit_deformed,
                        systems::update_instances,
                        realtime::scene_motion::update_scene_motion,
                    )
                        .chain()
                        .in_set(FrameSet::Bvh),
                    (
                        systems::upload_materials,
                        systems::upload_variant,
                        systems::update_lights,
                    )
                        .chain()
                        .in_set(FrameSet::Upload),
                    frame::render_frame.in_set(FrameSet::Render),
                ),
            );
    }
}

//! The render plugin: GPU scene buffers, the top-level BVH each frame, and the path tracer.

pub mod denoise;
pub mod layout;
pub mod path_tracer;
pub mod scene_buffers;
pub mod settings;
pub mod shaders;

pub use denoise::{DenoiseParams, Denoiser};
pub use path_tracer::{Aovs, PassTimes, PathTracer, RayCastTiming};
pub use scene_buffers::{GpuMemory, GpuScene, InstanceInput, UploadError};
pub use settings::{AovView, Environment, RenderSettings, Tonemapper};

use crate::FrameSet;
use crate::animation::DeformedMeshes;
use crate::bvh::MeshBvh;
use crate::bvh::refit::BvhStats;
use crate::camera::CameraView;
use crate::gpu::GpuContext;
use crate::scene::{GlobalTransform, MeshInstance, SceneAssets, SkinnedMesh};
use bevy_app::{App, Plugin, Update};
use bevy_ecs::prelude::*;

/// The renderer's GPU state, one resource so systems borrow it together.
#[derive(Resource)]
pub struct Renderer {
    pub scene: GpuScene,
    pub tracer: PathTracer,
    /// Instances as last uploaded: a change restarts accumulation.
    last_instances: Vec<InstanceInput>,
    last_settings: Option<RenderSettings>,
    last_camera: Option<CameraView>,
    /// Set by systems that changed geometry (deformation) this frame.
    pub geometry_changed: bool,
    /// Whether each frame also runs the display transform (the viewer); headless renders tone-map once.
    pub tonemap_each_frame: bool,
    /// GPU pass times of the last frame when `time_passes` is set (blocks the CPU each frame).
    pub time_passes: bool,
    pub last_pass_times: Option<PassTimes>,
    pub frames: u64,
}

impl Renderer {
    /// Builds BVHs and uploads the scene; errors when it exceeds the adapter's limits.
    pub fn new(
        ctx: &GpuContext,
        scene: &crate::scene::SceneAsset,
        settings: &RenderSettings,
        binding_limit: Option<u64>,
    ) -> Result<(Self, Vec<String>), UploadError> {
        let (gpu_scene, notes) = GpuScene::new(
            ctx,
            scene,
            settings.bvh_quality,
            settings.static_bvh,
            binding_limit,
        )?;
        let tracer = PathTracer::new(ctx, settings.width, settings.height);
        Ok((
            Self {
                scene: gpu_scene,
                tracer,
                last_instances: Vec::new(),
                last_settings: None,
                last_camera: None,
                geometry_changed: false,
                tonemap_each_frame: false,
                time_passes: false,
                last_pass_times: None,
                frames: 0,
            },
            notes,
        ))
    }
}

/// Collects mesh instances; rebuilds the TLAS and re-uploads instances when any placement changed.
pub fn update_instances(
    ctx: Res<GpuContext>,
    assets: Res<SceneAssets>,
    mut renderer: ResMut<Renderer>,
    instances: Query<(&GlobalTransform, &MeshInstance, Option<&SkinnedMesh>)>,
) {
    // Skinned vertices are already in world space (the joint matrices place them).
    let mut inputs: Vec<InstanceInput> = instances
        .iter()
        .map(|(g, m, skinned)| InstanceInput {
            world: if skinned.is_some() {
                glam::Mat4::IDENTITY
            } else {
                g.0
            },
            mesh: m.mesh as u32,
        })
        .collect();
    // Query order is not stable across archetype changes; sort for a deterministic TLAS.
    inputs.sort_by(|a, b| {
        a.mesh.cmp(&b.mesh).then_with(|| {
            a.world
                .to_cols_array()
                .partial_cmp(&b.world.to_cols_array())
                .unwrap_or(std::cmp::Ordering::Equal)
        })
    });
    if inputs == renderer.last_instances && !renderer.geometry_changed {
        return;
    }
    let renderer = &mut *renderer;
    if let Err(e) = renderer.scene.update_instances(&ctx, &assets.0, &inputs) {
        tracing::error!("top-level BVH: {e}");
    }
    renderer.last_instances = inputs;
    renderer.tracer.reset(&ctx);
}

/// Uploads this frame's deformed meshes (only their vertex ranges), refits their BLAS, and rebuilds the
/// worst ones past the SAH-ratio threshold (at most `max_rebuilds_per_frame`). Any change sets
/// `geometry_changed`: the TLAS is rebuilt with the new root bounds and accumulation restarts.
pub fn refit_deformed(
    ctx: Res<GpuContext>,
    assets: Res<SceneAssets>,
    settings: Res<RenderSettings>,
    deformed: Res<DeformedMeshes>,
    mut stats: ResMut<BvhStats>,
    mut renderer: ResMut<Renderer>,
) {
    let scene = &assets.0;
    let renderer = &mut *renderer;
    stats.ensure_len(scene.meshes.len());
    let start = std::time::Instant::now();
    for (m, ratio) in renderer.scene.apply_deformations(&ctx, &deformed) {
        stats.sah_ratio[m] = ratio;
        stats.refits += 1;
        renderer.geometry_changed = true;
    }
    stats.last_refit_seconds = start.elapsed().as_secs_f64();
    let start = std::time::Instant::now();
    for m in stats.due() {
        match renderer
            .scene
            .rebuild_mesh(&ctx, scene, m, settings.bvh_quality)
        {
            Ok(()) => {
                stats.sah_ratio[m] = renderer.scene.mesh_slots[m]
                    .blas
                    .binary()
                    .map_or(1.0, MeshBvh::sah_ratio);
                stats.mesh_rebuilds[m] += 1;
                stats.rebuilds += 1;
                renderer.geometry_changed = true;
            }
            Err(e) => {
                tracing::error!(
                    "mesh `{}`: BVH rebuild: {e}; keeping the refit tree",
                    scene.meshes[m].name
                );
                stats.sah_ratio[m] = 1.0;
            }
        }
    }
    stats.last_rebuild_seconds = start.elapsed().as_secs_f64();
}

/// Traces this frame's samples, restarting accumulation when the camera or settings changed.
pub fn render_frame(
    ctx: Res<GpuContext>,
    settings: Res<RenderSettings>,
    camera: Res<CameraView>,
    mut renderer: ResMut<Renderer>,
) {
    let renderer = &mut *renderer;
    renderer
        .tracer
        .resize(&ctx, settings.width, settings.height);
    let settings_changed = renderer
        .last_settings
        .as_ref()
        .is_none_or(|s| s.changes_image(&settings));
    if settings_changed || renderer.last_camera != Some(*camera) || renderer.geometry_changed {
        renderer.tracer.reset(&ctx);
    }
    renderer.last_settings = Some(settings.clone());
    renderer.last_camera = Some(*camera);
    renderer.geometry_changed = false;
    renderer.tracer.dispatch(
        &ctx,
        &renderer.scene,
        &settings,
        &camera,
        settings.spp_per_frame,
        renderer.tonemap_each_frame,
    );
    renderer.frames += 1;
    if renderer.time_passes {
        renderer.last_pass_times = renderer.tracer.read_pass_times(&ctx);
    }
}

/// Needs [`GpuContext`], [`Renderer`], [`RenderSettings`] and [`CameraView`] resources.
pub struct RenderPlugin;

impl Plugin for RenderPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<BvhStats>()
            .init_resource::<DeformedMeshes>()
            .add_systems(
                Update,
                (
                    (refit_deformed, update_instances)
                        .chain()
                        .in_set(FrameSet::Bvh),
                    render_frame.in_set(FrameSet::Render),
                ),
            );
    }
}

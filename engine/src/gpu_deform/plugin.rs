//! The deform plugin: which backend deforms each mesh ([`DeformBackend`], switchable at run time), and the GPU
//! backend's frame: its skin and refit passes recorded for the frame's submission (`render::frame` runs them
//! before the trace), their pass times, and the bounds the top-level BVH needs.

use super::{DeformBackend, GpuDeformer};
use crate::FrameSet;
use crate::animation::{DeformedElsewhere, MeshPoses};
use crate::bvh::refit::BvhStats;
use crate::gpu::GpuContext;
use crate::render::RenderSettings;
use crate::render::frame::{DeformCommands, render_frame};
use crate::render::gpu_scene::GpuScene;
use crate::render::stats::FrameStats;
use crate::render::systems::{GeometryChanged, refit_deformed, update_instances};
use crate::scene::{SceneAsset, SceneAssets};
use bevy_app::{App, Plugin, Update};
use bevy_ecs::prelude::*;

/// GPU deformation state: the deformer when the GPU deforms, and the backend in use.
#[derive(Resource)]
pub struct GpuDeformation {
    pub deformer: Option<GpuDeformer>,
    /// The backend `RenderSettings::deform` resolved to on this adapter.
    pub backend: DeformBackend,
    /// What the settings asked for when the backend was last chosen.
    requested: DeformBackend,
}

impl GpuDeformation {
    /// Chooses the backend `settings.deform` asks for on this adapter; returns a note when the GPU cannot take
    /// the scene's deformable meshes and the CPU keeps them.
    pub fn new(
        ctx: &GpuContext,
        scene: &SceneAsset,
        gpu_scene: &mut GpuScene,
        wanted: DeformBackend,
    ) -> (Self, Option<String>) {
        let mut state = Self {
            deformer: None,
            backend: DeformBackend::Cpu,
            requested: DeformBackend::Cpu,
        };
        let note = state.select(ctx, scene, gpu_scene, wanted);
        (state, note)
    }

    fn select(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        gpu_scene: &mut GpuScene,
        wanted: DeformBackend,
    ) -> Option<String> {
        let wanted = wanted.resolve(ctx.info.device_type);
        self.requested = wanted;
        if let Some(old) = self.deformer.take() {
            // The CPU tree of each mesh is current again only after the CPU deforms it; until then the top
            // level uses the trees' boxes.
            for (m, owned) in old.owned().into_iter().enumerate() {
                if owned {
                    gpu_scene.mesh_slots[m].deformed_bounds = None;
                }
            }
        }
        self.backend = DeformBackend::Cpu;
        gpu_scene.memory.deform = 0;
        if wanted != DeformBackend::Gpu {
            return None;
        }
        match GpuDeformer::new(ctx, scene, gpu_scene) {
            Ok(deformer) => {
                gpu_scene.memory.deform = deformer.as_ref().map_or(0, |d| d.gpu_bytes);
                self.deformer = deformer;
                self.backend = DeformBackend::Gpu;
                None
            }
            Err(note) => Some(note),
        }
    }
}

/// Inserts the deformation state for `settings` (after `render::insert_resources`); returns a note for the
/// user when the GPU cannot deform the scene.
pub fn insert_resources(
    world: &mut World,
    ctx: &GpuContext,
    scene: &SceneAsset,
    settings: &RenderSettings,
) -> Option<String> {
    let mut gpu_scene = world.resource_mut::<GpuScene>();
    let (state, note) = GpuDeformation::new(ctx, scene, &mut gpu_scene, settings.deform);
    world.insert_resource(state);
    note
}

/// Follows `RenderSettings::deform` (also when the viewer changes it): creates or drops the GPU deformer and
/// tells the CPU deformer which meshes it must skip. Runs before the poses, so a switch re-deforms every mesh in
/// the same frame.
pub fn sync_deform_backend(
    ctx: Res<GpuContext>,
    assets: Res<SceneAssets>,
    settings: Res<RenderSettings>,
    mut state: ResMut<GpuDeformation>,
    mut gpu_scene: ResMut<GpuScene>,
    mut elsewhere: ResMut<DeformedElsewhere>,
    mut poses: ResMut<MeshPoses>,
) {
    let wanted = settings.deform.resolve(ctx.info.device_type);
    if wanted != state.requested {
        if let Some(note) = state.select(&ctx, &assets.0, &mut gpu_scene, wanted) {
            tracing::warn!("{note}");
        }
        poses.invalidate();
    }
    let owned = state
        .deformer
        .as_ref()
        .map_or_else(Vec::new, GpuDeformer::owned);
    if elsewhere.0 != owned {
        elsewhere.0 = owned;
    }
}

/// The GPU backend's frame: arrived SAH costs, finished rebuilds, this frame's poses, and the deform + refit
/// passes, queued for the frame's submission.
#[allow(clippy::too_many_arguments)]
pub fn deform_on_gpu(
    ctx: Res<GpuContext>,
    assets: Res<SceneAssets>,
    poses: Res<MeshPoses>,
    mut stats: ResMut<BvhStats>,
    mut state: ResMut<GpuDeformation>,
    mut gpu_scene: ResMut<GpuScene>,
    mut geometry: ResMut<GeometryChanged>,
    mut commands: ResMut<DeformCommands>,
) {
    let Some(deformer) = state.deformer.as_mut() else {
        return;
    };
    let frame = deformer.frame(&ctx, &assets.0, &mut gpu_scene, &poses, &mut stats);
    geometry.0 |= frame.geometry_changed;
    commands.0.extend(frame.commands);
    stats.last_upload_seconds += frame.upload_seconds;
    stats.last_rebuild_seconds += frame.rebuild_seconds;
}

/// With pass timing on, adds the deform passes' GPU times to the frame's (blocking, as the frame's own).
pub fn read_deform_pass_times(
    ctx: Res<GpuContext>,
    state: Res<GpuDeformation>,
    mut stats: ResMut<FrameStats>,
) {
    if !stats.time_passes {
        return;
    }
    let Some(times) = state
        .deformer
        .as_ref()
        .and_then(|d| d.read_pass_times(&ctx))
    else {
        return;
    };
    if let Some(t) = stats.last_pass_times.as_mut() {
        (t.skin_ms, t.refit_ms) = (times.skin_ms, times.refit_ms);
    }
}

/// Needs the resources of `render::insert_resources` and [`insert_resources`], and the [`crate::render::RenderPlugin`].
pub struct DeformPlugin;

impl Plugin for DeformPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(
            Update,
            (
                sync_deform_backend
                    .in_set(FrameSet::Deform)
                    .before(crate::animation::pose_meshes),
                deform_on_gpu
                    .in_set(FrameSet::Bvh)
                    .after(refit_deformed)
                    .before(update_instances),
                read_deform_pass_times
                    .in_set(FrameSet::Render)
                    .after(render_frame),
            ),
        );
    }
}

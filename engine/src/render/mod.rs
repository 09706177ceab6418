//! The render plugin: GPU scene buffers, the top-level BVH each frame, and the path tracer.

pub mod denoise;
pub mod display;
pub mod layout;
pub mod path_tracer;
pub mod pick;
pub mod scene_buffers;
pub mod settings;
pub mod shaders;

pub use denoise::{DenoiseParams, Denoiser};
pub use path_tracer::{Aovs, GpuFrameStats, PassTimes, PathTracer, PrimaryHit, RayCastTiming};
pub use scene_buffers::{GpuMemory, GpuScene, InstanceInput, UploadError};
pub use settings::{AovView, DenoiserKind, Environment, RenderSettings, Tonemapper};

use crate::FrameSet;
use crate::animation::{DeformedElsewhere, DeformedMeshes, MeshPoses};
use crate::bvh::MeshBvh;
use crate::bvh::refit::BvhStats;
use crate::camera::CameraView;
use crate::gpu::GpuContext;
use crate::gpu_deform::{DeformBackend, GpuDeformer};
use crate::scene::{GlobalTransform, Materials, MeshInstance, SceneAssets, SkinnedMesh};
use bevy_app::{App, Plugin, Update};
use bevy_ecs::prelude::*;

/// The renderer's GPU state, one resource so systems borrow it together.
#[derive(Resource)]
pub struct Renderer {
    pub scene: GpuScene,
    pub tracer: PathTracer,
    /// Instances as last uploaded: a change restarts accumulation.
    last_instances: Vec<InstanceInput>,
    /// The entity behind each GPU instance (TLAS leaf order), to map primary hits back to scene nodes.
    pub instance_entities: Vec<Entity>,
    last_settings: Option<RenderSettings>,
    last_camera: Option<CameraView>,
    /// Set by systems that changed geometry (deformation) this frame.
    pub geometry_changed: bool,
    /// Set by systems that changed what the image shows without moving geometry (material edits).
    pub restart_accumulation: bool,
    /// Stop tracing once this many samples per pixel have accumulated (the viewer idles on a converged image);
    /// the display transform still runs.
    pub sample_limit: Option<u32>,
    /// Whether each frame also runs the display transform (the viewer); headless renders tone-map once.
    pub tonemap_each_frame: bool,
    /// GPU pass times of the last frame when `time_passes` is set (blocks the CPU each frame).
    pub time_passes: bool,
    pub last_pass_times: Option<PassTimes>,
    pub frames: u64,
    /// GPU skinning, morphing and refit ([`crate::gpu_deform`]) when the deform backend is the GPU.
    pub deformer: Option<GpuDeformer>,
    /// The backend `RenderSettings::deform` resolved to on this adapter, and what it asked for.
    pub deform_backend: DeformBackend,
    deform_requested: DeformBackend,
    /// Command buffers submitted together with the next trace (the GPU deform passes).
    pending_commands: Vec<wgpu::CommandBuffer>,
}

impl Renderer {
    /// Builds BVHs and uploads the scene; errors when it exceeds the adapter's limits.
    pub fn new(
        ctx: &GpuContext,
        scene: &crate::scene::SceneAsset,
        settings: &RenderSettings,
        binding_limit: Option<u64>,
    ) -> Result<(Self, Vec<String>), UploadError> {
        let (gpu_scene, mut notes) = GpuScene::new(
            ctx,
            scene,
            settings.bvh_quality,
            settings.static_bvh,
            binding_limit,
        )?;
        let tracer = PathTracer::new(ctx, settings.width, settings.height);
        let mut renderer = Self {
            scene: gpu_scene,
            tracer,
            last_instances: Vec::new(),
            instance_entities: Vec::new(),
            last_settings: None,
            last_camera: None,
            geometry_changed: false,
            restart_accumulation: false,
            sample_limit: None,
            tonemap_each_frame: false,
            time_passes: false,
            last_pass_times: None,
            frames: 0,
            deformer: None,
            deform_backend: DeformBackend::Cpu,
            deform_requested: DeformBackend::Cpu,
            pending_commands: Vec::new(),
        };
        notes.extend(renderer.select_deform_backend(ctx, scene, settings.deform));
        Ok((renderer, notes))
    }

    /// Starts or stops GPU deformation for `wanted` (resolved for this adapter); returns a note when the
    /// GPU cannot take the scene's deformable meshes and the CPU keeps them.
    fn select_deform_backend(
        &mut self,
        ctx: &GpuContext,
        scene: &crate::scene::SceneAsset,
        wanted: DeformBackend,
    ) -> Option<String> {
        let wanted = wanted.resolve(ctx.info.device_type);
        self.deform_requested = wanted;
        if let Some(old) = self.deformer.take() {
            // The CPU tree of each mesh is current again only after the CPU deforms it; until then the
            // top level uses the trees' boxes.
            for (m, owned) in old.owned().into_iter().enumerate() {
                if owned {
                    self.scene.mesh_slots[m].deformed_bounds = None;
                }
            }
        }
        self.deform_backend = DeformBackend::Cpu;
        self.scene.memory.deform = 0;
        if wanted != DeformBackend::Gpu {
            return None;
        }
        match GpuDeformer::new(ctx, scene, &self.scene) {
            Ok(deformer) => {
                self.scene.memory.deform = deformer.as_ref().map_or(0, |d| d.gpu_bytes);
                self.deformer = deformer;
                self.deform_backend = DeformBackend::Gpu;
                None
            }
            Err(note) => Some(note),
        }
    }
}

/// Follows `RenderSettings::deform` (also when the viewer changes it): creates or drops the GPU deformer
/// and tells the CPU deformer which meshes it must skip. Runs before the poses, so a switch re-deforms
/// every mesh in the same frame.
pub fn sync_deform_backend(
    ctx: Res<GpuContext>,
    assets: Res<SceneAssets>,
    settings: Res<RenderSettings>,
    mut renderer: ResMut<Renderer>,
    mut elsewhere: ResMut<DeformedElsewhere>,
    mut poses: ResMut<MeshPoses>,
) {
    let wanted = settings.deform.resolve(ctx.info.device_type);
    if wanted != renderer.deform_requested {
        if let Some(note) = renderer.select_deform_backend(&ctx, &assets.0, wanted) {
            tracing::warn!("{note}");
        }
        poses.invalidate();
    }
    let owned = renderer
        .deformer
        .as_ref()
        .map_or_else(Vec::new, GpuDeformer::owned);
    if elsewhere.0 != owned {
        elsewhere.0 = owned;
    }
}

/// The GPU backend's frame: arrived SAH costs, finished rebuilds, this frame's poses, and the deform +
/// refit passes, queued for the trace's submission.
pub fn deform_on_gpu(
    ctx: Res<GpuContext>,
    assets: Res<SceneAssets>,
    settings: Res<RenderSettings>,
    poses: Res<MeshPoses>,
    mut stats: ResMut<BvhStats>,
    mut renderer: ResMut<Renderer>,
) {
    let renderer = &mut *renderer;
    let Some(deformer) = renderer.deformer.as_mut() else {
        return;
    };
    let frame = deformer.frame(
        &ctx,
        &assets.0,
        &mut renderer.scene,
        &poses,
        &mut stats,
        settings.bvh_quality,
    );
    renderer.geometry_changed |= frame.geometry_changed;
    renderer.pending_commands.extend(frame.commands);
    stats.last_upload_seconds += frame.upload_seconds;
    stats.last_rebuild_seconds += frame.rebuild_seconds;
}

/// Collects mesh instances; rebuilds the TLAS and re-uploads instances when any placement changed.
pub fn update_instances(
    ctx: Res<GpuContext>,
    assets: Res<SceneAssets>,
    mut renderer: ResMut<Renderer>,
    mut stats: ResMut<BvhStats>,
    instances: Query<(
        Entity,
        &GlobalTransform,
        &MeshInstance,
        Option<&SkinnedMesh>,
    )>,
) {
    let start = std::time::Instant::now();
    stats.last_tlas_seconds = 0.0;
    // Skinned vertices are already in world space (the joint matrices place them).
    let mut placed: Vec<(InstanceInput, Entity)> = instances
        .iter()
        .map(|(e, g, m, skinned)| {
            let world = if skinned.is_some() {
                glam::Mat4::IDENTITY
            } else {
                g.0
            };
            let input = InstanceInput {
                world,
                mesh: m.mesh as u32,
            };
            (input, e)
        })
        .collect();
    // Query order is not stable across archetype changes; sort for a deterministic TLAS.
    placed.sort_by(|(a, _), (b, _)| {
        a.mesh.cmp(&b.mesh).then_with(|| {
            a.world
                .to_cols_array()
                .partial_cmp(&b.world.to_cols_array())
                .unwrap_or(std::cmp::Ordering::Equal)
        })
    });
    let (inputs, entities): (Vec<InstanceInput>, Vec<Entity>) = placed.into_iter().unzip();
    if inputs == renderer.last_instances && !renderer.geometry_changed {
        return;
    }
    let renderer = &mut *renderer;
    if let Err(e) = renderer.scene.update_instances(&ctx, &assets.0, &inputs) {
        tracing::error!("top-level BVH: {e}");
    }
    renderer.instance_entities = renderer
        .scene
        .instance_order
        .iter()
        .map(|&i| entities[i as usize])
        .collect();
    renderer.last_instances = inputs;
    renderer.tracer.reset(&ctx);
    stats.last_tlas_seconds = start.elapsed().as_secs_f64();
}

/// Uploads this frame's deformed meshes (only their vertex ranges), refits their BLAS, and rebuilds the
/// worst ones past the SAH-ratio threshold (at most `max_rebuilds_per_frame`). Any change sets
/// `geometry_changed`: the TLAS is rebuilt with the new root bounds and accumulation restarts.
pub fn refit_deformed(
    ctx: Res<GpuContext>,
    assets: Res<SceneAssets>,
    settings: Res<RenderSettings>,
    deformed: Res<DeformedMeshes>,
    elsewhere: Res<DeformedElsewhere>,
    mut stats: ResMut<BvhStats>,
    mut renderer: ResMut<Renderer>,
) {
    let scene = &assets.0;
    let renderer = &mut *renderer;
    stats.ensure_len(scene.meshes.len());
    let start = std::time::Instant::now();
    let (ratios, upload_seconds) = if deformed.changed.is_empty() {
        (Vec::new(), 0.0)
    } else {
        renderer
            .scene
            .apply_deformations(&ctx, scene, &deformed, stats.policy)
    };
    for (m, ratio) in ratios {
        stats.sah_ratio[m] = ratio;
        stats.refits += 1;
        renderer.geometry_changed = true;
    }
    stats.last_upload_seconds = upload_seconds;
    stats.last_refit_seconds = start.elapsed().as_secs_f64() - upload_seconds;
    let start = std::time::Instant::now();
    // Meshes the GPU deforms are rebuilt by the GPU deformer, from their GPU positions.
    let cpu_owned = |m: usize| !elsewhere.0.get(m).copied().unwrap_or(false);
    for m in stats.due(cpu_owned) {
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

/// Traces this frame's samples, restarting accumulation when the camera, settings, geometry or materials
/// changed; once `sample_limit` samples have accumulated only the display transform runs.
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
    if settings_changed
        || renderer.last_camera != Some(*camera)
        || renderer.geometry_changed
        || renderer.restart_accumulation
    {
        renderer.tracer.reset(&ctx);
    }
    renderer.last_settings = Some(settings.clone());
    renderer.last_camera = Some(*camera);
    renderer.geometry_changed = false;
    renderer.restart_accumulation = false;
    if renderer
        .sample_limit
        .is_some_and(|limit| renderer.tracer.samples >= limit)
        && renderer.pending_commands.is_empty()
    {
        if renderer.tonemap_each_frame {
            renderer.tracer.tonemap(&ctx, &settings);
        }
        return;
    }
    renderer.tracer.dispatch(
        &ctx,
        &renderer.scene,
        &settings,
        &camera,
        settings.spp_per_frame,
        renderer.tonemap_each_frame,
        std::mem::take(&mut renderer.pending_commands),
    );
    renderer.frames += 1;
    if renderer.time_passes {
        renderer.last_pass_times = renderer.tracer.read_pass_times(&ctx).map(|mut t| {
            if let Some(d) = renderer
                .deformer
                .as_ref()
                .and_then(|d| d.read_pass_times(&ctx))
            {
                (t.skin_ms, t.refit_ms) = (d.skin_ms, d.refit_ms);
            }
            t
        });
    }
}

/// Uploads edited materials (only those that differ from the GPU's copy) and restarts accumulation.
pub fn upload_materials(
    ctx: Res<GpuContext>,
    assets: Res<SceneAssets>,
    materials: Res<Materials>,
    mut renderer: ResMut<Renderer>,
) {
    if !materials.is_changed() {
        return;
    }
    if renderer
        .scene
        .update_materials(&ctx, &assets.0, &materials.0)
        > 0
    {
        renderer.restart_accumulation = true;
    }
}

/// Needs [`GpuContext`], [`Renderer`], [`RenderSettings`] and [`CameraView`] resources.
pub struct RenderPlugin;

impl Plugin for RenderPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<BvhStats>()
            .init_resource::<DeformedMeshes>()
            .init_resource::<MeshPoses>()
            .init_resource::<DeformedElsewhere>()
            .add_systems(
                Update,
                (
                    sync_deform_backend
                        .in_set(FrameSet::Deform)
                        .before(crate::animation::pose_meshes),
                    (refit_deformed, deform_on_gpu, update_instances)
                        .chain()
                        .in_set(FrameSet::Bvh),
                    upload_materials.in_set(FrameSet::Upload),
                    render_frame.in_set(FrameSet::Render),
                ),
            );
    }
}

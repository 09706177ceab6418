//! raykin: an ECS engine that plays animated glTF scenes and path-traces them with wgpu compute kernels.
//!
//! Data flows one way: assets ([`scene`]) -> ECS components -> GPU buffers ([`render`]) -> image.
//! `docs/ARCHITECTURE.md` maps the plugins, the frame schedule and the GPU data layout.

pub mod animation;
pub mod bvh;
pub mod camera;
pub mod editor;
pub mod environment;
pub mod frame_timing;
pub mod gpu;
pub mod gpu_deform;
pub mod headless;
pub mod image_io;
pub mod motion;
pub mod oidn;
pub mod panic_guard;
pub mod record;
pub mod render;
pub mod scene;

use bevy_ecs::schedule::SystemSet;

/// The frame schedule: every system of every plugin runs in one of these sets, in this order, in `Update`.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FrameSet {
    /// Animation players advance and write node transforms and morph weights.
    Animate,
    /// Global transforms from the hierarchy.
    Transform,
    /// Skinning and morphing of deformable meshes.
    Deform,
    /// BVH refit (or rebuild) of changed meshes, then the top-level structure.
    Bvh,
    /// Upload of what changed to the GPU.
    Upload,
    /// Path tracing, accumulation, tone mapping.
    Render,
}

/// Adds the frame schedule's sets in order.
pub fn configure_frame_schedule(app: &mut bevy_app::App) {
    use bevy_ecs::schedule::IntoScheduleConfigs;
    app.configure_sets(
        bevy_app::Update,
        (
            FrameSet::Animate,
            FrameSet::Transform,
            FrameSet::Deform,
            FrameSet::Bvh,
            FrameSet::Upload,
            FrameSet::Render,
        )
            .chain(),
    );
}

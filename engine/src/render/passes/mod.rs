//! The GPU passes. Each is a struct beside its WGSL kernel that holds its bind-group layouts and pipeline, built
//! once, and records its work with `encode`; bind groups over the view's targets are remade only when those
//! targets change. Passes never call each other: `render::frame` orders them within a frame's submission.

pub mod deform;
pub mod denoise;
pub mod denoiser_planes;
pub mod display;
pub mod gbuffer;
pub mod gradient;
pub mod handover;
pub mod pick;
pub mod raycast;
pub mod realtime_trace;
pub mod refit;
pub mod restir_di;
pub mod temporal;
pub mod tonemap;
pub mod trace;
pub mod wavefront;

use crate::render::shaders::{ShaderModule, compose};

/// Every kernel, composed with its library modules: what the naga test validates.
pub fn all_kernels() -> Vec<(&'static str, String)> {
    [
        &trace::KERNEL,
        &wavefront::KERNEL,
        &tonemap::KERNEL,
        &denoise::KERNEL,
        &pick::KERNEL,
        &raycast::KERNEL,
        &display::KERNEL,
        &deform::KERNEL,
        &refit::KERNEL,
        &gbuffer::KERNEL,
        &restir_di::KERNEL,
        &realtime_trace::KERNEL,
        &gradient::KERNEL,
        &temporal::KERNEL,
        &handover::KERNEL,
        &denoiser_planes::PACK_KERNEL,
        &denoiser_planes::UNPACK_KERNEL,
    ]
    .into_iter()
    .map(|k: &ShaderModule| (k.name, compose(k)))
    .collect()
}

/// A pass built the first time it is used (picking, the ray-casting benchmark): its pipeline compiles the whole
/// traversal, which a session that never clicks should not pay for at start-up.
#[derive(bevy_ecs::prelude::Resource)]
pub struct OnFirstUse<T: Send + Sync + 'static>(std::sync::OnceLock<T>);

impl<T: Send + Sync + 'static> Default for OnFirstUse<T> {
    fn default() -> Self {
        Self(std::sync::OnceLock::new())
    }
}

impl<T: Send + Sync + 'static> OnFirstUse<T> {
    pub fn get_or_init(&self, make: impl FnOnce() -> T) -> &T {
        self.0.get_or_init(make)
    }
}

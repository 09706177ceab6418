//! What a render looks like: size, sampling, environment, display transform.

use bevy_ecs::prelude::Resource;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Environment {
    /// Uniform radiance from every direction.
    Constant([f32; 3]),
    /// White at and below the horizon, blue at the zenith.
    Sky,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Tonemapper {
    #[default]
    AcesFitted = 0,
    Reinhard = 1,
    Clamp = 2,
}

/// Which buffer the display transform shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum AovView {
    #[default]
    Color = 0,
    Albedo = 1,
    Normal = 2,
    Depth = 3,
}

/// Which denoiser `RenderSettings::denoise` turns on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum DenoiserKind {
    /// Intel Open Image Denoise on the host ([`crate::oidn`]); where it cannot run, svgf is used instead.
    #[default]
    Oidn,
    /// The GPU a-trous filter ([`super::denoise`]).
    Svgf,
}

#[derive(Resource, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel traced each frame.
    pub spp_per_frame: u32,
    /// Surface interactions after the camera ray.
    pub max_depth: u32,
    pub environment: Environment,
    /// Exposure in stops (display only; EXR output is never exposed).
    pub exposure: f32,
    pub tonemapper: Tonemapper,
    pub view: AovView,
    /// Depth view: brightness exp(-depth * scale).
    pub depth_view_scale: f32,
    pub seed: u32,
    pub russian_roulette: bool,
    /// First path depth at which Russian roulette may end a path.
    pub rr_depth: u32,
    /// Next-event estimation on emissive triangles (with MIS).
    pub nee: bool,
    pub bvh_quality: crate::bvh::BvhQuality,
    /// Show the denoised image (display-side: turning it on or off keeps the accumulated samples).
    #[serde(default)]
    pub denoise: bool,
    #[serde(default)]
    pub denoise_params: super::denoise::DenoiseParams,
    #[serde(default)]
    pub denoiser: DenoiserKind,
    /// OIDN's quality and AOV treatment.
    #[serde(default)]
    pub oidn: crate::oidn::DenoiseOptions,
    /// BVH layout of static meshes (deformable meshes always refit a BVH2).
    pub static_bvh: crate::bvh::StaticLayout,
    /// Where deformable meshes are skinned, morphed and refit (`Auto`: GPU on real GPUs).
    pub deform: crate::gpu_deform::DeformBackend,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 640,
            height: 360,
            spp_per_frame: 1,
            max_depth: 6,
            environment: Environment::Sky,
            exposure: 0.0,
            tonemapper: Tonemapper::AcesFitted,
            view: AovView::Color,
            depth_view_scale: 0.1,
            seed: 0,
            russian_roulette: true,
            rr_depth: 3,
            nee: true,
            bvh_quality: crate::bvh::BvhQuality::Medium,
            denoise: false,
            denoise_params: Default::default(),
            denoiser: DenoiserKind::default(),
            oidn: Default::default(),
            static_bvh: crate::bvh::StaticLayout::Wide,
            deform: crate::gpu_deform::DeformBackend::Auto,
        }
    }
}

impl RenderSettings {
    /// True when changing from `self` to `other` invalidates accumulated samples (display-only settings do not).
    pub fn changes_image(&self, other: &Self) -> bool {
        let image_part = |s: &Self| Self {
            exposure: 0.0,
            tonemapper: Tonemapper::default(),
            view: AovView::default(),
            depth_view_scale: 0.0,
            spp_per_frame: 1,
            denoise: false,
            denoise_params: Default::default(),
            denoiser: DenoiserKind::default(),
            oidn: Default::default(),
            ..s.clone()
        };
        image_part(self) != image_part(other)
    }
}

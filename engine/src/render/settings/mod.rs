//! What a render looks like: size, sampling, environment, display transform.

use bevy_ecs::prelude::Resource;
use serde::{Deserialize, Serialize};

mod denoise;
mod realtime;

pub use denoise::{AuxMode, DenoiseOptions, DenoiseParams, DenoiserKind, Quality};
pub use realtime::{FrameOidn, RealtimeSettings, RenderMode, RestirSettings};

/// What rays leaving the scene see. Every kind is a light the light sampler picks (importance-sampled,
/// with MIS against BSDF sampling): `crate::environment` turns it into a map (and a sun).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Environment {
    /// Uniform radiance from every direction.
    Constant([f32; 3]),
    /// A gradient from white-blue at and below the horizon to blue at the zenith.
    Sky,
    /// An HDR equirectangular map (`.hdr` / `.exr`).
    Map(crate::environment::MapSettings),
    /// The Preetham sky with the sun as a disc light.
    SunSky(crate::environment::SunSkySettings),
}

/// How next-event estimation picks a light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum LightSampler {
    /// In proportion to power (pbrt-v4 `PowerLightSampler`).
    Power,
    /// The lights at finite distance by a light tree's spatial importance (pbrt-v4 `BVHLightSampler`), the
    /// lights at infinity by power.
    #[default]
    Tree,
}

/// How the trace pass runs the path integrator (`shaders/integrator/path.wgsl`). Both trace the same paths with
/// the same random numbers: the choice changes the speed, never the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
pub enum Integrator {
    /// The faster of the two on this GPU, scene and image size, timed on the first frames of each workload;
    /// the megakernel on CPU adapters (`render::integrator_choice`).
    #[default]
    Auto,
    /// One kernel runs each pixel's paths from the camera to their end.
    Megakernel,
    /// Kernels per stage over a queue of the paths still alive (`render::passes::wavefront`): a bounce costs
    /// what its live paths cost. Renders that record the denoisers' inputs or the primary-hit AOV use the
    /// megakernel.
    Wavefront,
}

impl Integrator {
    /// The name `--integrator` takes, as the bench's records and the statistics panel print it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Megakernel => "megakernel",
            Self::Wavefront => "wavefront",
        }
    }
}

/// A thin lens (pbrt-v4's perspective camera): depth of field around the plane at `focus_distance`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ThinLens {
    /// Radius of the aperture in scene units (glTF: metres); 0 is a pinhole, everything sharp.
    pub aperture_radius: f32,
    /// Distance from the lens to the sharp plane, along the view axis.
    pub focus_distance: f32,
}

impl Default for ThinLens {
    fn default() -> Self {
        Self {
            aperture_radius: 0.0,
            focus_distance: 1.0,
        }
    }
}

impl ThinLens {
    /// Height of the 35 mm full-frame sensor the f-number is converted with (metres).
    pub const SENSOR_HEIGHT: f32 = 0.024;

    /// The lens of a camera with vertical field of view `yfov` (radians) on a 35 mm full-frame sensor at
    /// f-number `f_number`, in a scene measured in metres: focal length = (sensor height / 2) / tan(yfov / 2),
    /// aperture diameter = focal length / f-number.
    pub fn from_f_number(f_number: f32, yfov: f32, focus_distance: f32) -> Self {
        let focal_length = 0.5 * Self::SENSOR_HEIGHT / (0.5 * yfov).tan();
        Self {
            aperture_radius: 0.5 * focal_length / f_number,
            focus_distance,
        }
    }

    /// Diameter in pixels of the circle a point at camera depth `depth` blurs into, for an image `height`
    /// pixels tall seen through `yfov` (the thin-lens formula: aperture x |1/depth - 1/focus| in units of
    /// the film at distance 1).
    pub fn circle_of_confusion_pixels(&self, depth: f32, yfov: f32, height: u32) -> f32 {
        2.0 * self.aperture_radius * (1.0 / depth - 1.0 / self.focus_distance).abs() * height as f32
            / (2.0 * (0.5 * yfov).tan())
    }
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

#[derive(Resource, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel traced each frame.
    pub spp_per_frame: u32,
    /// Surface interactions after the camera ray.
    pub max_depth: u32,
    pub environment: Environment,
    /// The camera's lens (a pinhole by default).
    #[serde(default)]
    pub lens: ThinLens,
    /// Exposure in stops (display only; EXR output is never exposed).
    pub exposure: f32,
    pub tonemapper: Tonemapper,
    pub view: AovView,
    /// Depth view: brightness exp(-depth * scale).
    pub depth_view_scale: f32,
    pub seed: u32,
    pub russian_roulette: bool,
    /// First path depth at which Russian roulette may end a path: 4, measured against 3 and 5 on the bench's
    /// five static scenes (docs/BENCHMARKS.md, "Where Russian roulette starts").
    pub rr_depth: u32,
    /// Next-event estimation on every light (with MIS).
    pub nee: bool,
    /// How next-event estimation picks the light.
    #[serde(default)]
    pub light_sampler: LightSampler,
    /// Build preset of the trees built while the scene plays on the render thread: deformable meshes' where the
    /// CPU deforms them (their rebuilds run inside the frame), static meshes' outside the merged tree.
    pub bvh_quality: crate::bvh::BvhQuality,
    /// Build preset of deformable meshes' trees where the GPU deforms them (`deform` resolves to `Gpu`): built at
    /// upload and rebuilt on a worker thread as the meshes deform, so a slower build costs latency, not frame
    /// time. `VerySlow` traced the seed-like interior in 0.966x and the crowd in 0.949x `Medium`'s time on an
    /// H100 (docs/BENCHMARKS.md, "Deforming meshes' trees built with the slowest preset"). Settings saved
    /// before it existed load with that default.
    #[serde(default = "gpu_deformed_bvh_quality_default")]
    pub gpu_deformed_bvh_quality: crate::bvh::BvhQuality,
    /// Show the denoised image (display-side: turning it on or off keeps the accumulated samples).
    #[serde(default)]
    pub denoise: bool,
    #[serde(default)]
    pub denoise_params: DenoiseParams,

    #[serde(default)]
    pub denoiser: DenoiserKind,
    /// OIDN's quality and AOV treatment.
    #[serde(default)]
    pub oidn: DenoiseOptions,
    /// BVH layout of static meshes (deformable meshes always refit a BVH2).
    pub static_bvh: crate::bvh::StaticLayout,
    /// With the wide layout: the instances that never move traced through one merged tree
    /// (`render::gpu_scene::static_merge`). Settings saved before it existed load with it on.
    #[serde(default = "merge_static_default")]
    pub merge_static: bool,
    /// Build quality of the merged static tree: built once and never refit, so it takes the slowest preset and
    /// its spatial splits by default (`bvh::WideBvh::build_static`); `bvh_quality` is for the trees rebuilt
    /// while the scene plays.
    #[serde(default = "merged_bvh_quality_default")]
    pub merged_bvh_quality: crate::bvh::BvhQuality,
    /// Where deformable meshes are skinned, morphed and refit (`Auto`: GPU on real GPUs).
    pub deform: DeformBackend,
    /// Accumulate, or the real-time path while anything moves.
    #[serde(default)]
    pub mode: RenderMode,
    #[serde(default)]
    pub realtime: RealtimeSettings,
    /// How the accumulation's paths are traced (the same image either way).
    #[serde(default)]
    pub integrator: Integrator,
}

fn merge_static_default() -> bool {
    true
}

fn merged_bvh_quality_default() -> crate::bvh::BvhQuality {
    crate::bvh::BvhQuality::VerySlow
}

fn gpu_deformed_bvh_quality_default() -> crate::bvh::BvhQuality {
    crate::bvh::BvhQuality::VerySlow
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 640,
            height: 360,
            spp_per_frame: 1,
            max_depth: 6,
            environment: Environment::Sky,
            lens: ThinLens::default(),
            exposure: 0.0,
            tonemapper: Tonemapper::AcesFitted,
            view: AovView::Color,
            depth_view_scale: 0.1,
            seed: 0,
            russian_roulette: true,
            rr_depth: 4,
            nee: true,
            light_sampler: LightSampler::default(),
            bvh_quality: crate::bvh::BvhQuality::Medium,
            denoise: false,
            denoise_params: Default::default(),
            denoiser: DenoiserKind::default(),
            oidn: Default::default(),
            static_bvh: crate::bvh::StaticLayout::Wide,
            merge_static: true,
            merged_bvh_quality: merged_bvh_quality_default(),
            gpu_deformed_bvh_quality: gpu_deformed_bvh_quality_default(),
            deform: DeformBackend::Auto,
            mode: RenderMode::Accumulate,
            realtime: RealtimeSettings::default(),
            integrator: Integrator::default(),
        }
    }
}

impl RenderSettings {
    /// The build preset of deformable meshes' trees on an adapter of this type: every build of such a tree (at
    /// upload and each rebuild) takes the same one, so that a tree rebuilt from the upload pose is the upload's.
    pub fn deformable_bvh_quality(&self, device_type: wgpu::DeviceType) -> crate::bvh::BvhQuality {
        match self.deform.resolve(device_type) {
            DeformBackend::Gpu => self.gpu_deformed_bvh_quality,
            _ => self.bvh_quality,
        }
    }

    /// Whether the display shows the denoised image (colour view with the denoiser on).
    pub fn shows_denoised(&self) -> bool {
        self.denoise && self.view == AovView::Color
    }

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
            mode: RenderMode::Accumulate,
            realtime: RealtimeSettings::default(),
            denoiser: DenoiserKind::default(),
            oidn: Default::default(),
            integrator: Integrator::default(),
            ..s.clone()
        };
        image_part(self) != image_part(other)
    }
}

/// Where deformable meshes are skinned, morphed and refit.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
pub enum DeformBackend {
    /// GPU passes on real GPUs, the CPU on a CPU adapter (lavapipe), where it measured faster
    /// (docs/ANIMATION.md).
    #[default]
    Auto,
    Cpu,
    Gpu,
}

impl DeformBackend {
    /// `Auto` made concrete for this adapter.
    pub fn resolve(self, device_type: wgpu::DeviceType) -> Self {
        match self {
            Self::Auto if device_type == wgpu::DeviceType::Cpu => Self::Cpu,
            Self::Auto => Self::Gpu,
            other => other,
        }
    }
}

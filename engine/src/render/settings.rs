//! What a render looks like: size, sampling, environment, display transform.

use bevy_ecs::prelude::Resource;
use serde::{Deserialize, Serialize};

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

/// How frames are made while the camera or scene moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum RenderMode {
    /// Progressive accumulation, restarted whenever anything changes (1 sample per pixel per frame in motion).
    #[default]
    Accumulate,
    /// The real-time path while anything moves (G-buffer, ReSTIR DI, temporal accumulation with gradients,
    /// spatial filter), handing over to plain accumulation once nothing does.
    Realtime,
}

/// ReSTIR DI's stages and tuning (the real-time path's direct light at the first hit).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RestirSettings {
    /// ReSTIR DI at all (off: next-event estimation in the path, as accumulation does). Off by default: in
    /// motion on the H200 it is still worse than next-event estimation with reprojection and gradients (the
    /// animated interior's settled relMSE 0.0158 against 0.0069, at 1.56x the frame time; BENCHMARKS.md).
    pub enabled: bool,
    pub temporal: bool,
    pub spatial: bool,
    /// Visibility in the MIS weights of reuse: unbiased on static scenes, two shadow rays per neighbour.
    pub unbiased: bool,
    /// Test each pixel's initial candidate for visibility before it is shared (implied by `unbiased`).
    pub visibility_reuse: bool,
    /// Light samples resampled per pixel per frame.
    pub candidates: u32,
    /// Spatial neighbours per pixel (at most 8).
    pub neighbours: u32,
    /// Radius of the spatial neighbourhood in pixels; 0: 2.5% of the image height (at least 3).
    pub radius: f32,
    /// Cap of a reservoir's confidence, in frames' worth of candidates.
    pub max_confidence: f32,
}

impl Default for RestirSettings {
    fn default() -> Self {
        Self {
            enabled: false,
            temporal: true,
            spatial: true,
            unbiased: true,
            visibility_reuse: true,
            candidates: 8,
            neighbours: 2,
            radius: 0.0,
            max_confidence: 20.0,
        }
    }
}

/// The real-time path's stages and tuning (docs/ACCURACY.md, "Real-time path").
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RealtimeSettings {
    /// Temporal accumulation through the motion vectors (off: each frame starts afresh).
    pub temporal: bool,
    /// A-SVGF temporal gradients shorten the history where lighting changed.
    pub gradients: bool,
    /// The a-trous filter (the denoiser, with `denoise_params`) over the temporally accumulated signal.
    pub spatial: bool,
    /// Longest history in frames: beyond it, an exponential average with weight 1 / cap.
    pub history_cap: u32,
    /// Relative depth difference a history tap may have (plus the plane's slope over a pixel).
    pub depth_tolerance: f32,
    /// Smallest cosine between a history tap's normal and this frame's.
    pub normal_tolerance: f32,
    pub restir: RestirSettings,
    /// Once nothing moves, hand over to plain accumulation (a still converges exactly as in accumulate
    /// mode); off, the real-time path keeps running on a still (tests of its own convergence).
    pub handover: bool,
    /// Samples of plain accumulation over which the hand-over fades the real-time image out.
    pub handover_spp: u32,
    /// Tests only: the real-time trace writes NaN and infinite samples at some pixels.
    #[serde(skip)]
    pub inject_nonfinite: bool,
}

impl Default for RealtimeSettings {
    fn default() -> Self {
        Self {
            temporal: true,
            gradients: true,
            spatial: true,
            history_cap: 32,
            depth_tolerance: 0.02,
            normal_tolerance: 0.9,
            restir: RestirSettings::default(),
            handover: true,
            handover_spp: 64,
            inject_nonfinite: false,
        }
    }
}

/// Which denoiser `RenderSettings::denoise` turns on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum DenoiserKind {
    /// Intel Open Image Denoise on the host (the `oidn` module); where it cannot run, svgf is used instead.
    #[default]
    Oidn,
    /// The GPU a-trous filter (the `denoise` pass).
    Svgf,
}

/// OIDN's filter quality (`OIDN_QUALITY_*`): high for final frames, balanced and fast for interactive use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Quality {
    #[default]
    High,
    Balanced,
    Fast,
}

impl Quality {
    pub const ALL: [Quality; 3] = [Quality::High, Quality::Balanced, Quality::Fast];

    /// The `OIDNQuality` value.
    pub(crate) fn raw(self) -> i32 {
        match self {
            Quality::Fast => 4,
            Quality::Balanced => 5,
            Quality::High => 6,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Quality::High => "high",
            Quality::Balanced => "balanced",
            Quality::Fast => "fast",
        }
    }
}

impl std::str::FromStr for Quality {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Quality::ALL
            .into_iter()
            .find(|q| q.name() == s)
            .ok_or_else(|| format!("`{s}`: expected high, balanced or fast"))
    }
}

/// How an image is denoised (`RenderSettings::oidn`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(default)]
pub struct DenoiseOptions {
    pub quality: Quality,
    /// The colour is HDR scene-referred radiance (before exposure and tone mapping); OIDN then picks its own
    /// input scale from the image (`inputScale` = NaN), which is what it was trained with.
    pub hdr: bool,
    pub aux: AuxMode,
}

/// How the albedo and normal images are treated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AuxMode {
    /// As they are, with the main filter told they may be noisy (`cleanAux` off).
    Noisy,
    /// Denoised first by OIDN's own prefilters, then trusted (`cleanAux` on): OIDN's recommendation for noisy
    /// AOVs in final frames (and Blender's default), at the cost of two more filter runs.
    #[default]
    Prefilter,
    /// As they are, trusted (`cleanAux` on): for AOVs that have converged.
    Clean,
}

impl Default for DenoiseOptions {
    /// High quality, HDR input, prefiltered AOVs.
    fn default() -> Self {
        Self {
            quality: Quality::High,
            hdr: true,
            aux: AuxMode::Prefilter,
        }
    }
}

impl DenoiseOptions {
    /// The defaults at `quality`.
    pub fn at(quality: Quality) -> Self {
        Self {
            quality,
            ..Default::default()
        }
    }
}

impl AuxMode {
    pub const ALL: [AuxMode; 3] = [AuxMode::Prefilter, AuxMode::Noisy, AuxMode::Clean];

    pub fn name(self) -> &'static str {
        match self {
            AuxMode::Prefilter => "prefilter",
            AuxMode::Noisy => "noisy",
            AuxMode::Clean => "clean",
        }
    }
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
    /// First path depth at which Russian roulette may end a path.
    pub rr_depth: u32,
    /// Next-event estimation on every light (with MIS).
    pub nee: bool,
    /// How next-event estimation picks the light.
    #[serde(default)]
    pub light_sampler: LightSampler,
    pub bvh_quality: crate::bvh::BvhQuality,
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
    /// Where deformable meshes are skinned, morphed and refit (`Auto`: GPU on real GPUs).
    pub deform: DeformBackend,
    /// Accumulate, or the real-time path while anything moves.
    #[serde(default)]
    pub mode: RenderMode,
    #[serde(default)]
    pub realtime: RealtimeSettings,
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
            rr_depth: 3,
            nee: true,
            light_sampler: LightSampler::default(),
            bvh_quality: crate::bvh::BvhQuality::Medium,
            denoise: false,
            denoise_params: Default::default(),
            denoiser: DenoiserKind::default(),
            oidn: Default::default(),
            static_bvh: crate::bvh::StaticLayout::Wide,
            deform: DeformBackend::Auto,
            mode: RenderMode::Accumulate,
            realtime: RealtimeSettings::default(),
        }
    }
}

impl RenderSettings {
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

/// The a-trous filter's parameters (the `denoise` pass; here because the settings name them). The defaults
/// are SVGF's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DenoiseParams {
    /// A-trous iterations; iteration k places its taps 2^k pixels apart (5 iterations: 125 pixels across).
    pub iterations: u32,
    /// Luminance edge-stopping, in standard deviations of the pixel's mean.
    pub sigma_luminance: f32,
    /// Exponent of the normal weight max(0, n_p . n_q)^sigma.
    pub sigma_normal: f32,
    /// Depth edge-stopping, in units of the depth change the centre's tangent plane predicts.
    pub sigma_depth: f32,
}

impl Default for DenoiseParams {
    fn default() -> Self {
        Self {
            iterations: 5,
            sigma_luminance: 4.0,
            sigma_normal: 128.0,
            sigma_depth: 1.0,
        }
    }
}

impl DenoiseParams {
    pub const MAX_ITERATIONS: u32 = 8;

    /// Iterations clamped to 1..=[`Self::MAX_ITERATIONS`]; a sigma that is not a positive finite number
    /// takes its default.
    pub fn sanitized(&self) -> Self {
        let d = Self::default();
        let sigma = |v: f32, default: f32| if v.is_finite() && v > 0.0 { v } else { default };
        Self {
            iterations: self.iterations.clamp(1, Self::MAX_ITERATIONS),
            sigma_luminance: sigma(self.sigma_luminance, d.sigma_luminance),
            sigma_normal: sigma(self.sigma_normal, d.sigma_normal),
            sigma_depth: sigma(self.sigma_depth, d.sigma_depth),
        }
    }
}

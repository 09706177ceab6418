//! The denoisers' settings: which one, OIDN's options and the a-trous filter's parameters.

use serde::{Deserialize, Serialize};

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

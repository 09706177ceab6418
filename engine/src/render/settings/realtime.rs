//! The real-time path's settings (`RenderMode::Realtime`): its passes, ReSTIR DI and the still's hand-over.

use super::denoise::Quality;
use serde::{Deserialize, Serialize};

/// How frames are made while the camera or scene moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum RenderMode {
    /// Progressive accumulation, restarted whenever anything changes (1 sample per pixel per frame in motion).
    /// The default of renders, recordings and the bench (each frame converged); the viewer starts in
    /// `Realtime` (`editor::prefs`).
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
    /// Open Image Denoise over the temporally accumulated signal each frame, in place of the a-trous filter
    /// (with `spatial` on and `RenderSettings::denoiser` OIDN).
    pub oidn: FrameOidn,
    /// The per-frame OIDN filter's quality (its albedo and normal come from the history of one camera ray per
    /// pixel, so they are used as they are, without prefiltering).
    pub oidn_quality: Quality,
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
            oidn: FrameOidn::default(),
            oidn_quality: Quality::Balanced,
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

/// When the real-time path denoises each frame with Open Image Denoise. Off by default: on the H200 it lowered
/// the animated interior's settled relMSE by 16% and left the crowd's unchanged (FLIP 7% worse) at 1280x720,
/// while the viewer's 1440p crowd frame went from 19.9 to 30.6 ms (OIDN balanced 7.3 ms, the rest the frame's
/// CPU and GPU work no longer overlapping: the frame waits for its history); docs/BENCHMARKS.md.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum FrameOidn {
    /// Never: the a-trous filter.
    #[default]
    Off,
    /// Where OIDN's GPU device reads the history in GPU memory it shares with wgpu (CUDA beside Vulkan on
    /// NVIDIA): 5-13 ms per 1440p frame on the H200 by quality. Elsewhere the a-trous filter.
    Shared,
    /// On every device, through host copies where memory cannot be shared (OIDN's CPU device takes a
    /// second or more per 1080p frame on a few cores).
    Always,
}

impl FrameOidn {
    pub const ALL: [FrameOidn; 3] = [FrameOidn::Off, FrameOidn::Shared, FrameOidn::Always];

    pub fn name(self) -> &'static str {
        match self {
            FrameOidn::Off => "off",
            FrameOidn::Shared => "shared",
            FrameOidn::Always => "always",
        }
    }
}

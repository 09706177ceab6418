//! What each suite measures, and how it shrinks on a CPU adapter.
//!
//! `full` is sized for a GPU (1920x1080 and 2560x1440, 300 frames). On a CPU adapter (lavapipe traces about
//! 10,000x slower) the same suite runs with every image side divided by [`CPU_LINEAR_SCALE`] and fewer
//! frames and samples, so it finishes in well under an hour on two cores; the factor is recorded in the JSON
//! and in every chart title. `quick` is tiny everywhere (CI).

use raykin::gpu::DeviceType;

/// Image sides are divided by this on CPU adapters in the full suite.
pub const CPU_LINEAR_SCALE: u32 = 16;

#[derive(Clone, Debug, serde::Serialize)]
pub struct Suite {
    pub name: String,
    /// Image sides were divided by this (1 on GPUs).
    pub linear_scale: u32,
    /// "" on GPUs; otherwise what was scaled, for chart titles.
    pub scaling_note: String,
    /// Named scenes run when no --scene is given.
    pub scenes: Vec<String>,
    /// Frame-time runs (throughput table and per-pass breakdown).
    pub sizes: Vec<(u32, u32)>,
    pub frames: usize,
    pub warmup: usize,
    /// Error-vs-time runs: image size, samples per pixel of the reference (two halves), the largest sample
    /// count on each curve, and how many times each curve is run (different seeds).
    pub error_size: (u32, u32),
    pub reference_spp: u32,
    pub error_max_spp: u32,
    pub error_repeats: usize,
    /// BVH presets: scenes and frames per preset.
    pub bvh_scenes: Vec<String>,
    pub bvh_frames: usize,
    /// Refit vs rebuild along CesiumMan's walk: image size, poses per second of animation, clip seconds,
    /// traced frames per pose.
    pub refit_size: (u32, u32),
    pub refit_fps: f32,
    pub refit_seconds: f32,
    pub refit_trace_repeats: usize,
    /// Scaling: instanced copies of one asset at one size, and one scene at several sizes.
    pub scaling_copies: Vec<usize>,
    pub scaling_size: (u32, u32),
    pub scaling_resolutions: Vec<(u32, u32)>,
    pub scaling_frames: usize,
    /// The real-time path in motion: scenes, image size, frames at 1/60 s, every how many frames the displayed
    /// image is compared, the references' samples per pixel, and the frames evaluated after a light switch.
    pub motion_scenes: Vec<String>,
    pub motion_size: (u32, u32),
    pub motion_frames: usize,
    pub motion_eval_every: usize,
    pub motion_reference_spp: u32,
    pub motion_lag_window: usize,
    /// OIDN: frame sizes its cost is measured at, and runs per measurement; the image size of its error
    /// gains at 1, 4, 16 and 64 spp (the reference is the error curves' when the sizes agree).
    pub oidn_sizes: Vec<(u32, u32)>,
    pub oidn_repeats: usize,
    pub gain_size: (u32, u32),
}

fn named(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

impl Suite {
    pub fn new(name: &str, device: DeviceType) -> anyhow::Result<Self> {
        let cpu = device == DeviceType::Cpu;
        match (name, cpu) {
            ("quick", _) => Ok(Self {
                name: "quick".into(),
                linear_scale: 1,
                scaling_note: String::new(),
                scenes: named(&["cornell", "flight-helmet", "crowd"]),
                sizes: vec![(48, 27)],
                frames: 5,
                warmup: 1,
                error_size: (24, 16),
                reference_spp: 512,
                error_max_spp: 64,
                error_repeats: 1,
                bvh_scenes: named(&["flight-helmet"]),
                bvh_frames: 3,
                refit_size: (24, 32),
                refit_fps: 8.0,
                refit_seconds: 1.0,
                refit_trace_repeats: 2,
                scaling_copies: vec![1, 4, 16],
                scaling_size: (32, 18),
                scaling_resolutions: vec![(16, 9), (32, 18), (64, 36)],
                scaling_frames: 3,
                motion_scenes: named(&["interior", "crowd"]),
                motion_size: (40, 30),
                motion_frames: 32,
                motion_eval_every: 8,
                motion_reference_spp: 128,
                motion_lag_window: 8,
                oidn_sizes: vec![(64, 36)],
                oidn_repeats: 1,
                gain_size: (24, 16),
            }),
            ("full", false) => Ok(Self {
                name: "full".into(),
                linear_scale: 1,
                scaling_note: String::new(),
                scenes: named(&["cornell", "flight-helmet", "spheres", "crowd"]),
                sizes: vec![(1920, 1080), (2560, 1440)],
                frames: 300,
                warmup: 10,
                error_size: (960, 540),
                reference_spp: 4096,
                error_max_spp: 1024,
                error_repeats: 2,
                bvh_scenes: named(&["flight-helmet", "spheres"]),
                bvh_frames: 50,
                refit_size: (960, 540),
                refit_fps: 30.0,
                refit_seconds: 2.0,
                refit_trace_repeats: 5,
                scaling_copies: vec![1, 4, 16, 64, 256],
                scaling_size: (1920, 1080),
                scaling_resolutions: vec![
                    (640, 360),
                    (1280, 720),
                    (1920, 1080),
                    (2560, 1440),
                    (3840, 2160),
                ],
                scaling_frames: 50,
                motion_scenes: named(&["crowd", "interior"]),
                motion_size: (2560, 1440),
                motion_frames: 120,
                motion_eval_every: 15,
                motion_reference_spp: 1024,
                motion_lag_window: 12,
                oidn_sizes: vec![(1920, 1080), (2560, 1440)],
                oidn_repeats: 10,
                gain_size: (960, 540),
            }),
            ("full", true) => {
                let s = CPU_LINEAR_SCALE;
                let scaled = |w: u32, h: u32| (w.div_ceil(s), h.div_ceil(s));
                Ok(Self {
                    name: "full".into(),
                    linear_scale: s,
                    scaling_note: format!(
                        "CPU adapter: image sides /{s} (errors /20), 20 frames, 1024-spp references"
                    ),
                    scenes: named(&["cornell", "flight-helmet", "spheres", "crowd"]),
                    sizes: vec![scaled(1920, 1080), scaled(2560, 1440)],
                    frames: 20,
                    warmup: 2,
                    error_size: (48, 27),
                    reference_spp: 1024,
                    error_max_spp: 128,
                    error_repeats: 1,
                    bvh_scenes: named(&["flight-helmet", "spheres"]),
                    bvh_frames: 6,
                    refit_size: scaled(960, 540),
                    refit_fps: 10.0,
                    refit_seconds: 2.0,
                    refit_trace_repeats: 5,
                    scaling_copies: vec![1, 4, 16, 64],
                    scaling_size: scaled(1920, 1080),
                    scaling_resolutions: [(640, 360), (1280, 720), (1920, 1080), (2560, 1440)]
                        .iter()
                        .map(|&(w, h)| scaled(w, h))
                        .collect(),
                    scaling_frames: 6,
                    motion_scenes: named(&["crowd", "interior"]),
                    motion_size: scaled(2560, 1440),
                    motion_frames: 48,
                    motion_eval_every: 12,
                    motion_reference_spp: 256,
                    motion_lag_window: 12,
                    // OIDN's CPU device is what is measured here, at full size; a 1-spp input traces in
                    // seconds even on lavapipe.
                    oidn_sizes: vec![(1920, 1080), (2560, 1440)],
                    oidn_repeats: 3,
                    gain_size: (128, 72),
                })
            }
            (other, _) => anyhow::bail!("unknown suite `{other}`: quick or full"),
        }
    }
}

//! What a recording is: the frame schedule (frame k = the pose at T0 + k/F), per-frame seeds, sampling,
//! outputs and file names, resolved once against the scene so every frame is a pure function of its index.

use super::RecordError;
use crate::camera::CameraChoice;
use crate::render::RenderSettings;
use crate::scene::SceneAsset;
use serde::{Deserialize, Serialize};
use std::ops::Range;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FrameFormat {
    /// Tone-mapped sRGB (exposure applied).
    Png,
    /// Linear scene-referred radiance.
    Exr,
}

impl FrameFormat {
    pub fn extension(self) -> &'static str {
        match self {
            Self::Png => "png",
            Self::Exr => "exr",
        }
    }
}

impl std::str::FromStr for FrameFormat {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "png" => Ok(Self::Png),
            "exr" => Ok(Self::Exr),
            _ => Err(format!(
                "`{s}`: expected png (tone-mapped sRGB) or exr (linear radiance)"
            )),
        }
    }
}

/// Extra per-frame images, each its own linear EXR beside the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Aov {
    /// First-hit base colour (mean over the pixel's samples).
    Albedo,
    /// First-hit shading normal, world space (mean, renormalised).
    Normal,
    /// Distance along the camera's forward axis to the first hit (+inf where nothing was hit).
    Depth,
    /// Screen-space motion to the previous frame, in pixels ([`crate::motion`]).
    Motion,
}

impl Aov {
    pub const ALL: [Aov; 4] = [Aov::Albedo, Aov::Normal, Aov::Depth, Aov::Motion];

    pub fn name(self) -> &'static str {
        match self {
            Self::Albedo => "albedo",
            Self::Normal => "normal",
            Self::Depth => "depth",
            Self::Motion => "motion",
        }
    }
}

impl std::str::FromStr for Aov {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let wanted = s.trim().to_ascii_lowercase();
        Self::ALL
            .into_iter()
            .find(|a| a.name() == wanted)
            .ok_or_else(|| format!("`{s}`: expected albedo, normal, depth or motion"))
    }
}

/// How many samples each frame gets.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Sampling {
    /// Exactly this many samples per pixel: frames are bit-reproducible.
    Spp(u32),
    /// As many samples as fit this wall-clock budget (at least one): the spp reached is recorded per frame,
    /// and such frames are NOT bit-reproducible (the count depends on the machine's speed at that moment).
    TimeBudgetMs(f64),
}

/// The camera, in a form the manifest can store.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CameraSpec {
    /// The scene's first camera (following its node), else a framing of the scene's rest bounds.
    Auto,
    /// The i-th camera node (following its node's animation).
    Index(usize),
    LookAt {
        eye: [f32; 3],
        target: [f32; 3],
        yfov_degrees: f32,
    },
}

impl CameraSpec {
    pub fn choice(&self) -> CameraChoice {
        match self {
            Self::Auto => CameraChoice::Auto,
            Self::Index(i) => CameraChoice::Index(*i),
            Self::LookAt {
                eye,
                target,
                yfov_degrees,
            } => CameraChoice::LookAt {
                eye: (*eye).into(),
                target: (*target).into(),
                yfov: yfov_degrees.to_radians(),
            },
        }
    }
}

/// How each frame is sampled, framed and written: passed from a request to the settings as is.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameOptions {
    pub sampling: Sampling,
    /// Samples per GPU submission (part of the settings: it fixes the order in which samples are summed).
    pub spp_per_dispatch: u32,
    pub camera: CameraSpec,
    pub format: FrameFormat,
    /// Sorted, without repeats once planned.
    pub aovs: Vec<Aov>,
    /// Size, depth, environment, base seed, exposure (PNG) and the rest of the image-affecting settings.
    pub render: RenderSettings,
}

/// Everything that determines a recording's files. Two runs with equal settings (and scene) write equal
/// frames, so resuming, re-rendering one frame and merging slices are safe exactly when these match.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecordSettings {
    /// Animation clip posed (`None`: a scene without animations, recorded as a still scene).
    pub clip: Option<usize>,
    pub clip_name: Option<String>,
    pub fps: f32,
    /// T0, seconds into the clip.
    pub start: f32,
    /// Frames in the whole recording (indices 0..frames).
    pub frames: u32,
    #[serde(flatten)]
    pub frame: FrameOptions,
    /// The glTF scene chosen with `--scene` (absent: the file's default; recordings made before the
    /// option read as absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<usize>,
}

impl RecordSettings {
    /// Pose time of frame `k`: T0 + k/F (computed in f64, so it does not drift with k).
    pub fn time(&self, k: u32) -> f32 {
        (self.start as f64 + k as f64 / self.fps as f64) as f32
    }

    /// Pose time one frame before frame `k` (motion vectors' previous frame; clip times clamp to the clip's
    /// ends like the pose itself).
    pub fn previous_time(&self, k: u32) -> f32 {
        (self.start as f64 + (k as f64 - 1.0) / self.fps as f64) as f32
    }

    /// The random seed of frame `k`.
    pub fn seed(&self, k: u32) -> u32 {
        frame_seed(self.frame.render.seed, k)
    }

    pub fn frame_file(&self, k: u32) -> String {
        format!("frame_{k:05}.{}", self.frame.format.extension())
    }

    pub fn aov_file(k: u32, aov: Aov) -> String {
        format!("frame_{k:05}.{}.exr", aov.name())
    }

    /// Every file of frame `k`: AOVs first, the frame itself last (the order they are written in).
    pub fn files(&self, k: u32) -> Vec<String> {
        self.frame
            .aovs
            .iter()
            .map(|&a| Self::aov_file(k, a))
            .chain([self.frame_file(k)])
            .collect()
    }

    pub fn clip_description(&self) -> String {
        match (&self.clip, &self.clip_name) {
            (Some(i), Some(name)) if !name.is_empty() => format!("clip {i} `{name}`"),
            (Some(i), _) => format!("clip {i}"),
            _ => "the still scene".into(),
        }
    }
}

/// Seed of frame `k` from the recording's seed: SplitMix64's finaliser over (seed, k), a bijection on the
/// 64-bit pair, so neighbouring frames get unrelated streams (the kernel then hashes per pixel and sample).
pub fn frame_seed(seed: u32, k: u32) -> u32 {
    let mut z = (((seed as u64) << 32) | k as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 32) as u32
}

/// What a user asks for; [`plan`] checks it against the scene and resolves the clip and frame count.
#[derive(Clone, Debug)]
pub struct RecordRequest {
    /// Clip name or index (clip 0 when `None` and the scene has animations).
    pub animation: Option<String>,
    pub fps: f32,
    pub start: f32,
    /// T1: frames cover [T0, T1); default the clip's end.
    pub end: Option<f32>,
    /// Frame count instead of T1.
    pub frames: Option<u32>,
    pub frame: FrameOptions,
    /// The glTF scene chosen with `--scene` (`None`: the file's default).
    pub scene: Option<usize>,
}

/// Resolves a request against the scene: the clip, T0..T1 inside it, and the frame count.
pub fn plan(scene: &SceneAsset, req: &RecordRequest) -> Result<RecordSettings, RecordError> {
    let fail = |msg: String| Err(RecordError::Plan(msg));
    if !(req.fps.is_finite() && req.fps > 0.0) {
        return fail(format!(
            "--fps {}: must be a positive number of frames per second",
            req.fps
        ));
    }
    if !req.start.is_finite() || req.start < 0.0 {
        return fail(format!(
            "--start {}: must be a time >= 0 seconds",
            req.start
        ));
    }
    match req.frame.sampling {
        Sampling::Spp(0) => return fail("--spp 0: a frame needs at least one sample".into()),
        Sampling::TimeBudgetMs(ms) if !(ms.is_finite() && ms > 0.0) => {
            return fail(format!(
                "--time-budget-ms {ms}: must be a positive number of milliseconds"
            ));
        }
        _ => {}
    }
    let clip = if scene.animations.is_empty() {
        if let Some(a) = &req.animation {
            return fail(format!(
                "{}: --animation {a}: the scene has no animations",
                scene.source
            ));
        }
        None
    } else {
        let i = match &req.animation {
            Some(a) => crate::animation::find_clip(scene, a).map_err(RecordError::Plan)?,
            None => 0,
        };
        Some(i)
    };
    let duration = clip.map(|c| scene.animations[c].duration);
    let clip_text = |c: usize| {
        format!(
            "clip {c} `{}` ({:.3} s)",
            scene.animations[c].name, scene.animations[c].duration
        )
    };
    if let (Some(c), Some(d)) = (clip, duration)
        && req.start >= d.max(f32::MIN_POSITIVE)
    {
        return fail(format!(
            "{}: --start {} is not inside {}",
            scene.source,
            req.start,
            clip_text(c)
        ));
    }
    let frames = match (req.frames, req.end, duration) {
        (Some(0), _, _) => return fail("--frames 0: nothing to record".into()),
        (Some(n), _, _) => n,
        (None, Some(end), _) | (None, None, Some(end)) => {
            if !end.is_finite() || end <= req.start {
                return fail(format!("--end {end}: must be after --start {}", req.start));
            }
            // Frames cover [T0, T1): a looping clip's end is its start again.
            ((end - req.start) as f64 * req.fps as f64 - 1e-4)
                .ceil()
                .max(1.0) as u32
        }
        (None, None, None) => {
            return fail(format!(
                "{}: the scene has no animations, so no clip gives the recording's length; pass --frames N \
                 to record N frames of the still scene (each with its own seed)",
                scene.source
            ));
        }
    };
    if let CameraSpec::Index(_) = req.frame.camera {
        crate::camera::check_camera_choice(scene, &req.frame.camera.choice())
            .map_err(|e| RecordError::Plan(format!("--camera: {e}")))?;
    }
    let mut frame = req.frame.clone();
    frame.aovs.sort();
    frame.aovs.dedup();
    frame.spp_per_dispatch = frame.spp_per_dispatch.max(1);
    frame.render.spp_per_frame = frame.spp_per_dispatch;
    let settings = RecordSettings {
        clip,
        clip_name: clip.map(|c| scene.animations[c].name.clone()),
        fps: req.fps,
        start: req.start,
        frames,
        frame,
        scene: req.scene,
    };
    if let (Some(c), Some(d)) = (clip, duration) {
        let last = settings.time(frames - 1);
        if last > d + 1e-4 {
            return fail(format!(
                "{}: {frames} frames at {} fps from {} s run to {last:.3} s, past the end of {}",
                scene.source,
                settings.fps,
                settings.start,
                clip_text(c)
            ));
        }
    }
    Ok(settings)
}

/// Parses `A..B` (frames A to B-1), `A..=B`, `A..` or `..B`; the open ends are resolved by [`resolve_range`].
pub fn parse_range(text: &str) -> Result<(Option<u32>, Option<u32>), String> {
    let (a, b, inclusive) = if let Some((a, b)) = text.split_once("..=") {
        (a, b, true)
    } else if let Some((a, b)) = text.split_once("..") {
        (a, b, false)
    } else {
        return Err(format!(
            "`{text}`: expected a frame range A..B (frames A to B-1), A..=B, A.. or ..B"
        ));
    };
    let number = |s: &str| -> Result<Option<u32>, String> {
        let s = s.trim();
        if s.is_empty() {
            return Ok(None);
        }
        s.parse::<u32>()
            .map(Some)
            .map_err(|e| format!("`{text}`: `{s}` is not a frame index ({e})"))
    };
    let (a, b) = (number(a)?, number(b)?);
    let b = match (b, inclusive) {
        (Some(b), true) => Some(b.checked_add(1).ok_or(format!("`{text}`: too large"))?),
        (None, true) => return Err(format!("`{text}`: A..= needs an end")),
        (b, false) => b,
    };
    Ok((a, b))
}

/// The frames a `--range` names, checked against the recording.
pub fn resolve_range(
    settings: &RecordSettings,
    range: (Option<u32>, Option<u32>),
) -> Result<Range<u32>, RecordError> {
    let n = settings.frames;
    let (a, b) = (range.0.unwrap_or(0), range.1.unwrap_or(n));
    if a >= b || b > n {
        let last = settings.time(n - 1);
        return Err(RecordError::Plan(format!(
            "--range {a}..{b} is outside the recording: it has {n} frames (0..{n}) at {} fps, {} from {} s to \
             {last:.3} s",
            settings.fps,
            settings.clip_description(),
            settings.start
        )));
    }
    Ok(a..b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_parse() {
        assert_eq!(parse_range("2..5"), Ok((Some(2), Some(5))));
        assert_eq!(parse_range("2..=5"), Ok((Some(2), Some(6))));
        assert_eq!(parse_range("3.."), Ok((Some(3), None)));
        assert_eq!(parse_range("..4"), Ok((None, Some(4))));
        assert!(parse_range("3").is_err());
        assert!(parse_range("a..4").is_err());
        assert!(parse_range("1..=").is_err());
    }

    #[test]
    fn frame_seeds_differ_and_repeat() {
        let seeds: std::collections::HashSet<u32> = (0..10_000).map(|k| frame_seed(7, k)).collect();
        assert_eq!(seeds.len(), 10_000);
        assert_eq!(frame_seed(7, 3), frame_seed(7, 3));
        assert_ne!(frame_seed(7, 3), frame_seed(8, 3));
    }
}

//! Recording frame sequences of an animated scene: deterministic, resumable, shardable across machines.
//!
//! Frame k is the pose at T0 + k/F rendered with the seed derived from (seed, k) ([`plan`]); the BVH of a
//! deformed mesh depends on the pose alone ([`crate::bvh::refit::RebuildPolicy::PoseDetermined`]), so any
//! frame re-rendered alone is bit-identical on the same adapter. Every file is written to a temporary name and
//! renamed; the [`manifest`] lists finished frames with their size and SHA-256, so a re-run skips them and a
//! crash or Ctrl-C never leaves a truncated frame. The CLI (`raykin record`) and the viewer's record button
//! both drive a [`Recorder`]. docs/RECORDING.md is the user's guide.

pub mod manifest;
pub mod output;
pub mod plan;
mod realtime;
mod recorder;

pub use manifest::{FrameRecord, Manifest, MergeSummary, merge};
pub use output::{FileRecord, scene_hash};
pub use plan::{
    Aov, CameraSpec, FrameFormat, FrameOptions, RecordRequest, RecordSettings, Sampling,
    frame_seed, parse_range, plan, resolve_range,
};
pub use realtime::{RealtimeRecording, record_realtime};
pub use recorder::{RecordEvent, RecordJob, RecordSummary, Recorder};

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// Arguments that do not fit the scene (clip, times, range).
    #[error("{0}")]
    Plan(String),
    #[error("output folder {dir}: {reason}")]
    Folder { dir: PathBuf, reason: String },
    #[error(
        "{path}: {reason}; move it away, or pass --force to start a new recording in its folder"
    )]
    BadManifest { path: PathBuf, reason: String },
    #[error(
        "{dir} already holds a recording of another scene or with other settings ({manifest}): {}. Refusing \
         to mix them: use another --out, or pass --force to start a new recording there (the old manifests are \
         kept as NAME.replaced-TIME; old frames are overwritten as new ones are written)",
        differences.join("; ")
    )]
    Mismatch {
        dir: PathBuf,
        manifest: PathBuf,
        differences: Vec<String>,
    },
    #[error(
        "{dir} holds {count} frame file(s) (e.g. {example}) but no raykin manifest: they would be \
         overwritten. Use another --out, or pass --force to record over them"
    )]
    ForeignFiles {
        dir: PathBuf,
        example: PathBuf,
        count: usize,
    },
    #[error("{path}: {reason}")]
    Write { path: PathBuf, reason: String },
    #[error(transparent)]
    Setup(#[from] crate::headless::HeadlessError),
    #[error("frame {frame}: {reason}")]
    Render { frame: u32, reason: String },
    /// A failure after some frames were finished: they stay on disk and in the manifest.
    #[error(
        "{error}\n  {complete} of {total} frames of the recording are complete and listed in {}; fix the \
         problem and re-run the same command to resume",
        manifest.display()
    )]
    Stopped {
        error: Box<RecordError>,
        complete: usize,
        total: u32,
        manifest: PathBuf,
    },
}

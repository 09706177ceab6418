//! The manifest: what a recording folder holds (scene hash, settings, and per frame its time, seed, spp,
//! render time, adapter and files with size and SHA-256), written atomically after every frame.
//!
//! A run over the whole recording owns `DIR/manifest.json`. A `--range A..B` slice owns
//! `DIR/manifest.part-A-B.json` instead, so slices running at once (a Slurm array) never write the same
//! file; `raykin record --merge DIR` folds the parts into `manifest.json`.

use super::output::{self, FileRecord};
use super::{RecordError, RecordSettings};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

pub const MANIFEST: &str = "manifest.json";
const PART_PREFIX: &str = "manifest.part-";
const FORMAT_VERSION: u32 = 1;

/// One finished frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    pub index: u32,
    /// Pose time, seconds into the clip.
    pub time: f32,
    pub seed: u32,
    /// Samples per pixel actually traced.
    pub spp: u32,
    /// Wall-clock milliseconds from posing to the last file written.
    pub render_ms: f64,
    /// The adapter that rendered it (bit-identical re-renders are promised per adapter).
    pub adapter: String,
    /// AOVs first, the frame last.
    pub files: Vec<FileRecord>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub format_version: u32,
    /// The scene file as given on the command line (informational; `scene_hash` decides).
    pub scene: String,
    pub scene_hash: String,
    pub settings: RecordSettings,
    /// The slice this part manifest belongs to; `None` for `manifest.json`.
    pub range: Option<[u32; 2]>,
    /// Sorted by index.
    pub frames: Vec<FrameRecord>,
}

impl Manifest {
    pub fn new(
        scene: &str,
        scene_hash: &str,
        settings: &RecordSettings,
        range: Option<Range<u32>>,
    ) -> Self {
        Self {
            format_version: FORMAT_VERSION,
            scene: scene.to_string(),
            scene_hash: scene_hash.to_string(),
            settings: settings.clone(),
            range: range.map(|r| [r.start, r.end]),
            frames: Vec::new(),
        }
    }

    /// Adds or replaces a frame, keeping the list sorted.
    pub fn insert(&mut self, frame: FrameRecord) {
        match self.frames.binary_search_by_key(&frame.index, |f| f.index) {
            Ok(i) => self.frames[i] = frame,
            Err(i) => self.frames.insert(i, frame),
        }
    }

    /// The differences that make this manifest another recording than (`scene_hash`, `settings`), as
    /// `field: here vs now` lines; empty when they match.
    pub fn differences(&self, scene_hash: &str, settings: &RecordSettings) -> Vec<String> {
        let mut out = Vec::new();
        if self.scene_hash != scene_hash {
            out.push(format!(
                "scene: {} ({}) there, {scene_hash} now",
                self.scene_hash, self.scene
            ));
        }
        if self.settings != *settings {
            let (a, b) = (
                serde_json::to_value(&self.settings).unwrap_or_default(),
                serde_json::to_value(settings).unwrap_or_default(),
            );
            diff_values("settings", &a, &b, &mut out);
        }
        out
    }
}

fn diff_values(at: &str, a: &serde_json::Value, b: &serde_json::Value, out: &mut Vec<String>) {
    use serde_json::Value;
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let keys: std::collections::BTreeSet<&String> = x.keys().chain(y.keys()).collect();
            for k in keys {
                let null = Value::Null;
                diff_values(
                    &format!("{at}.{k}"),
                    x.get(k).unwrap_or(&null),
                    y.get(k).unwrap_or(&null),
                    out,
                );
            }
        }
        _ if a != b => out.push(format!("{at}: {a} there, {b} now")),
        _ => {}
    }
}

/// Where a run's manifest goes: `manifest.json` for the whole recording, a part file for a slice.
pub fn manifest_path(dir: &Path, slice: Option<&Range<u32>>) -> PathBuf {
    match slice {
        None => dir.join(MANIFEST),
        Some(r) => dir.join(format!("{PART_PREFIX}{:05}-{:05}.json", r.start, r.end)),
    }
}

/// `manifest.json` and every part manifest in `dir`, sorted.
pub fn paths(dir: &Path) -> Vec<PathBuf> {
    let mut paths: Vec<PathBuf> = match std::fs::read_dir(dir) {
        Ok(entries) => entries
            .flatten()
            .map(|e| e.path())
            .filter(|p| {
                p.file_name().and_then(|n| n.to_str()).is_some_and(|n| {
                    n == MANIFEST || (n.starts_with(PART_PREFIX) && n.ends_with(".json"))
                })
            })
            .collect(),
        Err(_) => Vec::new(),
    };
    paths.sort();
    paths
}

/// Every manifest in `dir`, read and parsed (a manifest that does not parse is an error naming it: it is
/// never silently replaced).
pub fn read_all(dir: &Path) -> Result<Vec<(PathBuf, Manifest)>, RecordError> {
    paths(dir)
        .into_iter()
        .map(|path| {
            let bad = |reason: String| RecordError::BadManifest {
                path: path.clone(),
                reason,
            };
            let text = std::fs::read_to_string(&path).map_err(|e| bad(e.to_string()))?;
            let manifest: Manifest = serde_json::from_str(&text)
                .map_err(|e| bad(format!("not a raykin manifest: {e}")))?;
            if manifest.format_version != FORMAT_VERSION {
                return Err(bad(format!(
                    "manifest format {} (this raykin reads {FORMAT_VERSION})",
                    manifest.format_version
                )));
            }
            Ok((path, manifest))
        })
        .collect()
}

/// Writes a manifest atomically (temporary file + rename): a reader sees the old or the new one, whole.
pub fn write(path: &Path, manifest: &Manifest) -> Result<(), RecordError> {
    let json = serde_json::to_string_pretty(manifest).map_err(|e| RecordError::Write {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    crate::image_io::write_bytes_atomically(path, json.as_bytes()).map_err(|e| RecordError::Write {
        path: path.to_path_buf(),
        reason: e.reason,
    })
}

/// Frames of all `manifests` whose files are all on disk with their recorded size and hash, by index
/// (the first manifest listing a verified copy wins; equal settings make the copies equal anyway).
pub fn verified_frames(
    dir: &Path,
    manifests: &[(PathBuf, Manifest)],
) -> BTreeMap<u32, FrameRecord> {
    let mut out = BTreeMap::new();
    for (_, m) in manifests {
        for f in &m.frames {
            if f.index < m.settings.frames
                && !out.contains_key(&f.index)
                && f.files.iter().all(|file| output::verify(dir, file))
            {
                out.insert(f.index, f.clone());
            }
        }
    }
    out
}

/// Moves the manifests of an earlier recording aside (`NAME.replaced-UNIXTIME`) for `--force`.
pub fn set_aside(paths: &[PathBuf]) -> Result<(), RecordError> {
    let stamp = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    for path in paths {
        let aside = PathBuf::from(format!("{}.replaced-{stamp}", path.display()));
        std::fs::rename(path, &aside).map_err(|e| RecordError::Write {
            path: path.clone(),
            reason: format!("cannot move it aside: {e}"),
        })?;
    }
    Ok(())
}

/// What `raykin record --merge DIR` found and wrote.
#[derive(Clone, Debug)]
pub struct MergeSummary {
    pub manifest: PathBuf,
    pub frame_count: u32,
    pub complete: usize,
    /// Frames no manifest lists with intact files.
    pub missing: Vec<u32>,
    /// Part manifests folded in (and removed).
    pub parts_merged: usize,
    /// Entries whose files were missing or did not match their size/hash (they count as missing).
    pub unverified: usize,
    /// Temporary files of interrupted writes removed.
    pub partials_removed: usize,
    pub adapters: Vec<String>,
}

/// Folds every manifest in `dir` into `manifest.json`, keeping only frames whose files verify, and removes
/// the merged part files and leftover temporary files (all writers are done when a merge runs).
pub fn merge(dir: &Path) -> Result<MergeSummary, RecordError> {
    let manifests = read_all(dir)?;
    let Some((first_path, first)) = manifests.first() else {
        return Err(RecordError::Plan(format!(
            "{}: no raykin manifest (manifest.json or manifest.part-*.json) to merge",
            dir.display()
        )));
    };
    for (path, m) in &manifests[1..] {
        let diff = m.differences(&first.scene_hash, &first.settings);
        if !diff.is_empty() {
            return Err(RecordError::Plan(format!(
                "{} and {} belong to different recordings, refusing to merge them: {}",
                first_path.display(),
                path.display(),
                diff.join("; ")
            )));
        }
    }
    let verified = verified_frames(dir, &manifests);
    let listed: std::collections::BTreeSet<u32> = manifests
        .iter()
        .flat_map(|(_, m)| m.frames.iter().map(|f| f.index))
        .collect();
    let mut merged = Manifest::new(&first.scene, &first.scene_hash, &first.settings, None);
    merged.frames = verified.values().cloned().collect();
    let path = dir.join(MANIFEST);
    write(&path, &merged)?;
    let mut parts_merged = 0;
    for (p, m) in &manifests {
        if m.range.is_some() && *p != path && std::fs::remove_file(p).is_ok() {
            parts_merged += 1;
        }
    }
    let partials = output::stale_partials(dir);
    let partials_removed = partials
        .iter()
        .filter(|p| std::fs::remove_file(p).is_ok())
        .count();
    let mut adapters: Vec<String> = merged.frames.iter().map(|f| f.adapter.clone()).collect();
    adapters.sort();
    adapters.dedup();
    Ok(MergeSummary {
        manifest: path,
        frame_count: first.settings.frames,
        complete: verified.len(),
        missing: (0..first.settings.frames)
            .filter(|k| !verified.contains_key(k))
            .collect(),
        parts_merged,
        unverified: listed.iter().filter(|k| !verified.contains_key(k)).count(),
        partials_removed,
        adapters,
    })
}

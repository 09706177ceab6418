//! Frame files on disk: atomic, durable writes with their size and SHA-256, verification on resume, the
//! scene's fingerprint, and cleanup of temporary files an earlier crash left behind.

use super::RecordError;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

/// One file of a frame as written: what resume and merge check it against.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileRecord {
    pub name: String,
    pub bytes: u64,
    pub sha256: String,
}

pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

/// Lower-case hexadecimal of `bytes` (digests in manifests and cache keys).
pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Writes `DIR/name` atomically (temporary file, flush, rename) and returns its record.
pub fn write_file(dir: &Path, name: &str, bytes: &[u8]) -> Result<FileRecord, RecordError> {
    let path = dir.join(name);
    crate::image_io::write_bytes_atomically(&path, bytes).map_err(|e| RecordError::Write {
        path: path.clone(),
        reason: e.reason,
    })?;
    Ok(FileRecord {
        name: name.to_string(),
        bytes: bytes.len() as u64,
        sha256: sha256_hex(bytes),
    })
}

/// True when `DIR/file.name` exists with the recorded size and hash.
pub fn verify(dir: &Path, file: &FileRecord) -> bool {
    let path = dir.join(&file.name);
    match std::fs::metadata(&path) {
        Ok(m) if m.is_file() && m.len() == file.bytes => {}
        _ => return false,
    }
    std::fs::read(&path).is_ok_and(|bytes| sha256_hex(&bytes) == file.sha256)
}

/// Creates `dir` if needed and proves it writable (a probe file), before any GPU work.
pub fn prepare_dir(dir: &Path) -> Result<(), RecordError> {
    let fail = |reason: String| RecordError::Folder {
        dir: dir.to_path_buf(),
        reason,
    };
    std::fs::create_dir_all(dir).map_err(|e| fail(format!("cannot create it: {e}")))?;
    let probe = dir.join(format!(".raykin-probe.{}", std::process::id()));
    let written = std::fs::write(&probe, b"probe");
    // Removed whatever happened: a full disk can create the file and then fail the write.
    let _ = std::fs::remove_file(&probe);
    written.map_err(|e| fail(format!("it is not writable: {e}")))
}

/// Temporary files of interrupted writes (`.NAME.PID.partial`) in `dir`.
pub fn stale_partials(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with('.') && n.ends_with(crate::image_io::PARTIAL_SUFFIX))
        })
        .collect()
}

/// Frame files (`frame_*`) in `dir`, to refuse overwriting files no manifest accounts for.
pub fn frame_files(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut files: Vec<PathBuf> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("frame_"))
        })
        .collect();
    files.sort();
    files
}

/// SHA-256 over a scene file and, for a `.gltf`, every external buffer and image it names (in order), so an
/// edited texture or .bin makes another scene.
pub fn scene_hash(path: &Path) -> Result<String, RecordError> {
    let read =
        |p: &Path| std::fs::read(p).map_err(|e| RecordError::Plan(format!("{}: {e}", p.display())));
    let bytes = read(path)?;
    let mut hasher = Sha256::new();
    hasher.update(&bytes);
    if let Ok(json) = serde_json::from_slice::<serde_json::Value>(&bytes) {
        let base = path.parent().unwrap_or(Path::new("."));
        for list in ["buffers", "images"] {
            let uris = json[list].as_array().into_iter().flatten();
            for uri in uris.filter_map(|b| b["uri"].as_str()) {
                if uri.starts_with("data:") {
                    continue;
                }
                let decoded = crate::scene::percent_decode(uri);
                // A missing file is the loader's error to report; hash what exists.
                if let Ok(data) = std::fs::read(base.join(&decoded)) {
                    hasher.update(uri.as_bytes());
                    hasher.update(&data);
                }
            }
        }
    }
    Ok(format!("sha256:{}", hex(&hasher.finalize())))
}

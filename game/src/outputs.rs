//! Output paths, checked before any rendering: no output may overwrite one of the scene's input files (the
//! scene itself, its buffers and images) or another output, and each output's folder must be writable. A
//! mistake in a long command line then costs nothing: the error names the output and the file it would
//! destroy.

use anyhow::{Result, bail};
use std::path::{Path, PathBuf};

/// The identity of a file as the file system sees it: canonical path and, on Unix, device and inode (so a
/// hard link or a symlink to an input is caught too).
#[derive(Debug, PartialEq, Eq)]
struct FileId {
    path: PathBuf,
    inode: Option<(u64, u64)>,
}

impl FileId {
    /// `None` when neither the file nor its folder exists (then it cannot be an existing input).
    fn of(path: &Path) -> Option<Self> {
        let canonical = path.canonicalize().ok().or_else(|| {
            let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
            let folder = parent.unwrap_or(Path::new(".")).canonicalize().ok()?;
            Some(folder.join(path.file_name()?))
        })?;
        Some(Self {
            inode: inode(&canonical),
            path: canonical,
        })
    }

    fn same_file(&self, other: &Self) -> bool {
        self.path == other.path || (self.inode.is_some() && self.inode == other.inode)
    }
}

#[cfg(unix)]
fn inode(path: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
}

#[cfg(not(unix))]
fn inode(_: &Path) -> Option<(u64, u64)> {
    None
}

/// One output of a command: what it is (for messages) and where.
pub struct Output<'a> {
    pub what: &'a str,
    pub path: PathBuf,
}

/// Refuses outputs that would overwrite an input file (`inputs`: the scene's files) or each other.
pub fn refuse_overwrites(outputs: &[Output], inputs: &[PathBuf]) -> Result<()> {
    let inputs: Vec<(FileId, &PathBuf)> = inputs
        .iter()
        .filter_map(|p| Some((FileId::of(p)?, p)))
        .collect();
    let mut seen: Vec<(FileId, &Output)> = Vec::new();
    for out in outputs {
        let Some(id) = FileId::of(&out.path) else {
            continue;
        };
        if let Some((_, input)) = inputs.iter().find(|(i, _)| i.same_file(&id)) {
            bail!(
                "{} {} is the scene's input file {}: refusing to overwrite it (nothing was rendered)",
                out.what,
                out.path.display(),
                input.display()
            );
        }
        if let Some((_, other)) = seen.iter().find(|(s, _)| s.same_file(&id)) {
            bail!(
                "{} {} and {} {} are the same file: one would overwrite the other (nothing was rendered)",
                out.what,
                out.path.display(),
                other.what,
                other.path.display()
            );
        }
        seen.push((id, out));
    }
    Ok(())
}

/// Refuses a recording folder that holds an input file with a name the recorder writes (`frame_*`,
/// `manifest*`): resuming or `--force` would overwrite it.
pub fn refuse_recording_over_inputs(dir: &Path, inputs: &[PathBuf]) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        bail!(
            "--out {}: not a folder (a recording writes a folder of frames); nothing was rendered",
            dir.display()
        );
    }
    let Ok(folder) = dir.canonicalize() else {
        return Ok(());
    };
    for input in inputs {
        let Ok(file) = input.canonicalize() else {
            continue;
        };
        let name = file
            .file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned());
        if file.parent() == Some(folder.as_path())
            && (name.starts_with("frame_") || name.starts_with("manifest"))
        {
            bail!(
                "--out {}: the recording would overwrite the scene's input file {} (frames and manifests are \
                 named frame_* and manifest*); record into another folder (nothing was rendered)",
                dir.display(),
                input.display()
            );
        }
    }
    Ok(())
}

/// Creates `file`'s folder if needed and proves it writable with a probe file (removed again, also when
/// the write fails), before the render: a read-only folder fails at once, naming the output.
pub fn check_writable(what: &str, file: &Path) -> Result<()> {
    let folder = file
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(folder).map_err(|e| {
        anyhow::anyhow!(
            "{what} {}: cannot create its folder {}: {e}",
            file.display(),
            folder.display()
        )
    })?;
    let name = file
        .file_name()
        .map_or("output".into(), |n| n.to_string_lossy().into_owned());
    let probe = folder.join(format!(".{name}.{}.probe", std::process::id()));
    let written = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .and_then(|mut f| std::io::Write::write_all(&mut f, b"probe"));
    let _ = std::fs::remove_file(&probe);
    written.map_err(|e| {
        anyhow::anyhow!(
            "{what} {}: its folder {} is not writable: {e} (nothing was rendered)",
            file.display(),
            folder.display()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("raykin-outputs-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn out(what: &'static str, path: PathBuf) -> Output<'static> {
        Output { what, path }
    }

    #[test]
    fn an_output_at_an_input_or_another_output_is_refused() {
        let dir = scratch("collide");
        let scene = dir.join("scene.png");
        std::fs::write(&scene, b"{}").unwrap();
        let inputs = vec![scene.canonicalize().unwrap()];
        // The same file through another spelling of its path.
        let spelled = dir.join(".").join("scene.png");
        let err = refuse_overwrites(&[out("--out", spelled)], &inputs).unwrap_err();
        assert!(err.to_string().contains("refusing to overwrite"), "{err}");
        let a = dir.join("r.json");
        let err =
            refuse_overwrites(&[out("--out", a.clone()), out("--report", a)], &inputs).unwrap_err();
        assert!(err.to_string().contains("are the same file"), "{err}");
        assert!(refuse_overwrites(&[out("--out", dir.join("image.png"))], &inputs).is_ok());
        // Outputs in folders that do not exist yet cannot be inputs.
        assert!(refuse_overwrites(&[out("--out", dir.join("new/x.png"))], &inputs).is_ok());
        #[cfg(unix)]
        {
            let link = dir.join("hard.png");
            std::fs::hard_link(&scene, &link).unwrap();
            assert!(refuse_overwrites(&[out("--out", link)], &inputs).is_err());
        }
    }

    #[test]
    fn a_recording_folder_holding_an_input_frame_name_is_refused() {
        let dir = scratch("record");
        let scene = dir.join("frame_00000.png");
        std::fs::write(&scene, b"x").unwrap();
        assert!(refuse_recording_over_inputs(&dir, std::slice::from_ref(&scene)).is_err());
        assert!(
            refuse_recording_over_inputs(&dir.join("sub"), std::slice::from_ref(&scene)).is_ok()
        );
        assert!(
            refuse_recording_over_inputs(&scene, &[]).is_err(),
            "a file is not a folder"
        );
    }

    #[test]
    fn the_writability_probe_leaves_nothing_behind() {
        let dir = scratch("probe");
        check_writable("--out", &dir.join("deep/x.png")).unwrap();
        let left: Vec<_> = std::fs::read_dir(dir.join("deep")).unwrap().collect();
        assert!(left.is_empty(), "{left:?}");
    }
}

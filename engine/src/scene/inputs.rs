//! What a glTF scene reads besides its own JSON: data URIs, and the files its URIs name. A scene from
//! someone else must not read any file the user can, nor make the process read without end:
//! - a URI resolves inside the scene's folder (after following symlinks); an absolute path, a `..` that
//!   leaves the folder, or a symlink out of it is refused unless [`Access::external_files`] is set (the
//!   CLI's `--allow-external-files`, for trusted files); URIs with a scheme other than `data:` are refused;
//! - only regular files are read (never a device, a FIFO or a folder);
//! - a buffer reads at most its `byteLength` (a shorter file is an error), an image file at most
//!   [`MAX_IMAGE_FILE_BYTES`], and an image decodes only within [`image_limits`].

use base64::Engine as _;
use std::io::Read as _;
use std::path::{Path, PathBuf};

/// Largest encoded image file a scene may reference (PNG and JPEG files of 16k textures are far smaller).
pub const MAX_IMAGE_FILE_BYTES: u64 = 256 << 20;
/// Largest image side decoded, in pixels.
pub const MAX_IMAGE_SIDE: u32 = 16384;
/// Most memory one image decode may allocate (a 16384 x 16384 RGBA8 image).
pub const MAX_IMAGE_DECODE_BYTES: u64 = 1 << 30;

/// Which files a scene may read.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Access {
    /// Allow absolute paths and paths outside the scene's folder (trusted files only).
    pub external_files: bool,
}

/// How much of a file to read.
#[derive(Clone, Copy, Debug)]
pub enum ReadLimit {
    /// A buffer: exactly this many bytes; a shorter file is an error, a longer one is read this far.
    Exactly(u64),
    /// An image: the whole file, which must not be larger than this.
    AtMost(u64),
}

/// The bytes behind a glTF URI: a base64 data URI, or a percent-encoded path relative to `base_dir`,
/// confined by `access` and bounded by `limit`. `opened` receives the file's canonical path.
pub fn read_uri(
    base_dir: &Path,
    uri: &str,
    access: Access,
    limit: ReadLimit,
    opened: &mut dyn FnMut(PathBuf),
) -> Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, payload) = rest
            .split_once(";base64,")
            .ok_or("data URI is not base64")?;
        let mut bytes = base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| format!("bad base64 data URI: {e}"))?;
        return match limit {
            ReadLimit::Exactly(n) if (bytes.len() as u64) < n => Err(format!(
                "truncated: the data URI holds {} bytes, but byteLength is {n}",
                bytes.len()
            )),
            ReadLimit::Exactly(n) => {
                bytes.truncate(n as usize);
                Ok(bytes)
            }
            ReadLimit::AtMost(_) => Ok(bytes),
        };
    }
    let file = resolve(base_dir, uri, access)?;
    opened(file.clone());
    read_bounded(&file, limit)
}

/// The canonical path a (non-data) URI names, if `access` allows reading it.
pub fn resolve(base_dir: &Path, uri: &str, access: Access) -> Result<PathBuf, String> {
    if let Some(scheme) = uri_scheme(uri) {
        return Err(format!(
            "URI scheme `{scheme}:` is not supported: a scene reads data URIs and files beside it"
        ));
    }
    let relative = PathBuf::from(percent_decode(uri));
    if relative.is_absolute() && !access.external_files {
        return Err(format!(
            "`{uri}` is an absolute path; a scene may only read files in its own folder (pass \
             --allow-external-files for a trusted scene)"
        ));
    }
    let joined = base_dir.join(&relative);
    let file = joined
        .canonicalize()
        .map_err(|e| format!("cannot read {}: {e}", joined.display()))?;
    if !access.external_files {
        let folder = base_dir
            .canonicalize()
            .map_err(|e| format!("cannot read the scene's folder {}: {e}", base_dir.display()))?;
        if !file.starts_with(&folder) {
            return Err(format!(
                "`{uri}` resolves to {}, outside the scene's folder {}; a scene may only read files in its \
                 own folder (pass --allow-external-files for a trusted scene)",
                file.display(),
                folder.display()
            ));
        }
    }
    Ok(file)
}

/// `http` for `http://...`; `None` for a relative or absolute path (also `C:\...`, a drive letter).
fn uri_scheme(uri: &str) -> Option<&str> {
    let (scheme, _) = uri.split_once(':')?;
    let mut chars = scheme.chars();
    let valid = chars.next().is_some_and(|c| c.is_ascii_alphabetic())
        && chars.all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'))
        && scheme.len() > 1;
    valid.then_some(scheme)
}

/// Reads a regular file within `limit`.
pub fn read_bounded(file: &Path, limit: ReadLimit) -> Result<Vec<u8>, String> {
    let fail = |e: std::io::Error| format!("cannot read {}: {e}", file.display());
    let handle = std::fs::File::open(file).map_err(fail)?;
    // Checked on the open handle, so the file cannot be swapped for a FIFO in between.
    let meta = handle.metadata().map_err(fail)?;
    if !meta.is_file() {
        return Err(format!("{} is not a regular file", file.display()));
    }
    let wanted = match limit {
        ReadLimit::Exactly(n) => n,
        ReadLimit::AtMost(cap) => {
            if meta.len() > cap {
                return Err(format!(
                    "{} is {} MiB, over the {} MiB limit for an image file",
                    file.display(),
                    meta.len() >> 20,
                    cap >> 20
                ));
            }
            cap
        }
    };
    let mut bytes = Vec::with_capacity(meta.len().min(wanted) as usize);
    handle.take(wanted).read_to_end(&mut bytes).map_err(fail)?;
    if let ReadLimit::Exactly(n) = limit
        && (bytes.len() as u64) < n
    {
        return Err(format!(
            "truncated: {} has {} bytes, but byteLength is {n}",
            file.display(),
            bytes.len()
        ));
    }
    Ok(bytes)
}

/// Decoder limits for scene images: at most [`MAX_IMAGE_SIDE`] pixels a side and
/// [`MAX_IMAGE_DECODE_BYTES`] of memory.
pub fn image_limits() -> image::Limits {
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_IMAGE_SIDE);
    limits.max_image_height = Some(MAX_IMAGE_SIDE);
    limits.max_alloc = Some(MAX_IMAGE_DECODE_BYTES);
    limits
}

/// Decodes a PNG or JPEG (recognised by its bytes) within [`image_limits`] to RGBA8.
pub fn decode_image(bytes: &[u8]) -> Result<image::RgbaImage, String> {
    let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("cannot decode: {e}"))?;
    reader.limits(image_limits());
    reader
        .decode()
        .map(|img| img.to_rgba8())
        .map_err(|e| format!("cannot decode: {e}"))
}

/// glTF URIs are percent-encoded (`%20` for a space).
pub(crate) fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%'
            && i + 2 < bytes.len()
            && let Ok(v) = u8::from_str_radix(
                std::str::from_utf8(&bytes[i + 1..i + 3]).unwrap_or("zz"),
                16,
            )
        {
            out.push(v);
            i += 3;
            continue;
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("raykin-inputs-{}-{name}", std::process::id()));
        std::fs::create_dir_all(dir.join("scene")).unwrap();
        dir
    }

    fn read(base: &Path, uri: &str, access: Access, limit: ReadLimit) -> Result<Vec<u8>, String> {
        read_uri(base, uri, access, limit, &mut |_| {})
    }

    #[test]
    fn files_outside_the_scene_folder_need_permission() {
        let dir = scratch("confine");
        std::fs::write(dir.join("outside.bin"), [7u8; 8]).unwrap();
        std::fs::write(dir.join("scene/inside.bin"), [1u8; 8]).unwrap();
        let base = dir.join("scene");
        let exact = ReadLimit::Exactly(8);
        assert_eq!(
            read(&base, "inside.bin", Access::default(), exact).unwrap(),
            [1u8; 8]
        );
        // `..` that stays inside is fine; one that leaves is not.
        assert!(read(&base, "../scene/inside.bin", Access::default(), exact).is_ok());
        let err = read(&base, "../outside.bin", Access::default(), exact).unwrap_err();
        assert!(
            err.contains("outside the scene's folder") && err.contains("--allow-external-files"),
            "{err}"
        );
        let absolute = dir.join("outside.bin").display().to_string();
        let err = read(&base, &absolute, Access::default(), exact).unwrap_err();
        assert!(err.contains("absolute path"), "{err}");
        let trusted = Access {
            external_files: true,
        };
        assert_eq!(
            read(&base, "../outside.bin", trusted, exact).unwrap(),
            [7u8; 8]
        );
        assert_eq!(read(&base, &absolute, trusted, exact).unwrap(), [7u8; 8]);
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(dir.join("outside.bin"), base.join("link.bin")).unwrap();
            let err = read(&base, "link.bin", Access::default(), exact).unwrap_err();
            assert!(err.contains("outside the scene's folder"), "{err}");
        }
        let err = read(&base, "http://example.com/x.bin", trusted, exact).unwrap_err();
        assert!(err.contains("scheme `http:`"), "{err}");
    }

    #[test]
    fn reads_are_bounded() {
        let dir = scratch("bounded");
        let base = dir.join("scene");
        std::fs::write(base.join("ten.bin"), [3u8; 10]).unwrap();
        let open = Access::default();
        assert_eq!(
            read(&base, "ten.bin", open, ReadLimit::Exactly(4)).unwrap(),
            [3u8; 4]
        );
        let err = read(&base, "ten.bin", open, ReadLimit::Exactly(11)).unwrap_err();
        assert!(
            err.contains("truncated") && err.contains("10 bytes"),
            "{err}"
        );
        let err = read(&base, "ten.bin", open, ReadLimit::AtMost(9)).unwrap_err();
        assert!(err.contains("limit for an image file"), "{err}");
        let err = read(&base, ".", open, ReadLimit::Exactly(1)).unwrap_err();
        assert!(err.contains("not a regular file"), "{err}");
        #[cfg(unix)]
        {
            let trusted = Access {
                external_files: true,
            };
            let err = read(&base, "/dev/zero", trusted, ReadLimit::Exactly(1 << 40)).unwrap_err();
            assert!(err.contains("not a regular file"), "{err}");
        }
        // Data URIs: a longer payload is cut at byteLength, a shorter one is an error.
        let uri = "data:application/octet-stream;base64,AAECAwQF";
        assert_eq!(
            read(&base, uri, open, ReadLimit::Exactly(3)).unwrap(),
            [0, 1, 2]
        );
        assert!(read(&base, uri, open, ReadLimit::Exactly(7)).is_err());
    }

    #[test]
    fn drive_letters_and_paths_are_not_schemes() {
        assert_eq!(uri_scheme("http://x"), Some("http"));
        assert_eq!(uri_scheme("file:///etc/passwd"), Some("file"));
        assert_eq!(uri_scheme("C:/textures/a.png"), None);
        assert_eq!(uri_scheme("textures/a.png"), None);
        assert_eq!(uri_scheme("a b:c.png"), None);
    }
}

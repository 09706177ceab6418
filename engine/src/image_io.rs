//! Image files: linear EXR (scene-referred radiance) and tone-mapped sRGB PNG.

use std::path::Path;

#[derive(Debug, thiserror::Error)]
#[error("{path}: {reason}")]
pub struct ImageError {
    pub path: String,
    pub reason: String,
}

fn err(path: &Path, reason: impl ToString) -> ImageError {
    ImageError {
        path: path.display().to_string(),
        reason: reason.to_string(),
    }
}

/// Writes linear RGB as a float EXR.
pub fn write_exr(path: &Path, width: u32, height: u32, rgb: &[[f32; 3]]) -> Result<(), ImageError> {
    let bytes = encode_exr(width, height, rgb).map_err(|reason| err(path, reason))?;
    std::fs::write(path, bytes).map_err(|e| err(path, e))
}

pub fn write_png(path: &Path, width: u32, height: u32, rgba8: &[u8]) -> Result<(), ImageError> {
    let bytes = encode_png(width, height, rgba8).map_err(|reason| err(path, reason))?;
    std::fs::write(path, bytes).map_err(|e| err(path, e))
}

/// Linear RGB as the bytes of a float EXR file.
pub fn encode_exr(width: u32, height: u32, rgb: &[[f32; 3]]) -> Result<Vec<u8>, String> {
    let data: Vec<f32> = rgb.iter().flatten().copied().collect();
    let img = image::Rgb32FImage::from_raw(width, height, data)
        .ok_or("pixel count does not match the size")?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    image::DynamicImage::ImageRgb32F(img)
        .write_to(&mut bytes, image::ImageFormat::OpenExr)
        .map_err(|e| e.to_string())?;
    Ok(bytes.into_inner())
}

/// sRGB RGBA8 as the bytes of a PNG file.
pub fn encode_png(width: u32, height: u32, rgba8: &[u8]) -> Result<Vec<u8>, String> {
    let img = image::RgbaImage::from_raw(width, height, rgba8.to_vec())
        .ok_or("pixel count does not match the size")?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png)
        .map_err(|e| e.to_string())?;
    Ok(bytes.into_inner())
}

/// Reads an EXR (or any float image) as linear RGB.
pub fn read_exr(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>), ImageError> {
    let img = image::open(path).map_err(|e| err(path, e))?.to_rgb32f();
    let (w, h) = img.dimensions();
    Ok((w, h, img.pixels().map(|p| p.0).collect()))
}

/// Marks the temporary files of [`write_atomically`]: `.NAME.PID.partial`, hidden, in the target's folder.
pub const PARTIAL_SUFFIX: &str = ".partial";

/// Writes `path` atomically: `write` fills a temporary file in the same folder (named per process, so
/// concurrent writers never share one), then a rename replaces `path`. On failure the temporary file is
/// removed and `path` is untouched: no reader ever sees a truncated file. Errors name `path`, never the
/// temporary file the user did not ask for.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), ImageError>,
) -> Result<(), ImageError> {
    let file_name = path
        .file_name()
        .ok_or_else(|| err(path, "no file name"))?
        .to_string_lossy();
    let tmp = path.with_file_name(format!(
        ".{file_name}.{}{PARTIAL_SUFFIX}",
        std::process::id()
    ));
    let result = write(&tmp).and_then(|()| std::fs::rename(&tmp, path).map_err(|e| err(path, e)));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(|e| ImageError {
        path: path.display().to_string(),
        reason: e.reason,
    })
}

/// Writes `bytes` to `path` atomically and durably (flushed to the device before the rename).
pub fn write_bytes_atomically(path: &Path, bytes: &[u8]) -> Result<(), ImageError> {
    write_atomically(path, |tmp| {
        use std::io::Write;
        let mut file = std::fs::File::create(tmp).map_err(|e| err(path, e))?;
        file.write_all(bytes).map_err(|e| err(path, e))?;
        file.sync_all().map_err(|e| err(path, e))
    })
}

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
    let data: Vec<f32> = rgb.iter().flatten().copied().collect();
    let img = image::Rgb32FImage::from_raw(width, height, data)
        .ok_or_else(|| err(path, "pixel count does not match the size"))?;
    image::DynamicImage::ImageRgb32F(img)
        .save_with_format(path, image::ImageFormat::OpenExr)
        .map_err(|e| err(path, e))
}

pub fn write_png(path: &Path, width: u32, height: u32, rgba8: &[u8]) -> Result<(), ImageError> {
    let img = image::RgbaImage::from_raw(width, height, rgba8.to_vec())
        .ok_or_else(|| err(path, "pixel count does not match the size"))?;
    img.save_with_format(path, image::ImageFormat::Png)
        .map_err(|e| err(path, e))
}

/// Reads an EXR (or any float image) as linear RGB.
pub fn read_exr(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>), ImageError> {
    let img = image::open(path).map_err(|e| err(path, e))?.to_rgb32f();
    let (w, h) = img.dimensions();
    Ok((w, h, img.pixels().map(|p| p.0).collect()))
}

/// Writes `image` to `path` atomically: a temporary file in the same folder, then a rename.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), ImageError>,
) -> Result<(), ImageError> {
    let file_name = path
        .file_name()
        .ok_or_else(|| err(path, "no file name"))?
        .to_string_lossy();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_string())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{file_name}.partial.{ext}"));
    write(&tmp)?;
    std::fs::rename(&tmp, path).map_err(|e| err(path, e))
}

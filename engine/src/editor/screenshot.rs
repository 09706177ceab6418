//! Screenshots: the image as displayed (tone-mapped sRGB PNG) and its linear radiance (EXR) side by side.

use crate::gpu::GpuContext;
use crate::image_io::{ImageError, write_atomically, write_exr, write_png};
use crate::render::{Accumulation, ViewTargets};
use bevy_ecs::prelude::*;
use std::path::{Path, PathBuf};

/// What a screenshot holds.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ScreenshotInfo {
    pub png: PathBuf,
    pub exr: PathBuf,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel accumulated in the image.
    pub samples: u32,
}

/// Writes `path` with the extension replaced by `.png` (display) and `.exr` (linear radiance); creates the
/// folder. Reads back the image the last frame displayed.
pub fn write(world: &World, path: &Path) -> Result<ScreenshotInfo, ImageError> {
    let ctx = world.resource::<GpuContext>();
    let view = world.resource::<ViewTargets>();
    let (png, exr) = (path.with_extension("png"), path.with_extension("exr"));
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| ImageError {
            path: dir.display().to_string(),
            reason: format!("cannot create the folder: {e}"),
        })?;
    }
    let (w, h) = (view.width, view.height);
    let rgba = view.read_rgba8(ctx);
    write_atomically(&png, |p| write_png(p, w, h, &rgba))?;
    let radiance = view.read_radiance(ctx);
    write_atomically(&exr, |p| write_exr(p, w, h, &radiance))?;
    Ok(ScreenshotInfo {
        png,
        exr,
        width: w,
        height: h,
        samples: world.resource::<Accumulation>().samples,
    })
}

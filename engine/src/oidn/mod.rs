//! Intel Open Image Denoise (OIDN): the learned denoiser offline renderers ship (Cycles, Houdini), run on
//! host images of linear radiance with first-hit albedo and normal AOVs.
//!
//! - [`library`]: finding and loading the library at run time (a missing one is an error, never a crash);
//! - [`device`]: which OIDN device runs it (the GPU behind the wgpu adapter when OIDN supports it, else the
//!   CPU);
//! - [`filter`]: [`Oidn`], the denoiser over host images (`RT` filter, AOV prefiltering, quality modes,
//!   timings of each step);
//! - [`inputs`]: the path tracer's accumulation sums turned into OIDN's inputs;
//! - [`shared`]: the same filter over GPU memory shared with wgpu (no copies through the host), where OIDN's
//!   GPU device and the adapter allow it;
//! - [`headless`]: OIDN for renders that wait for their image (CLI, recorder, benches);
//! - [`worker`]: a background thread, so a denoise never blocks the viewer's frame loop;
//! - [`viewer`]: when the viewer denoises with OIDN (a still image) and how its result reaches the display;
//! - [`per_frame`]: OIDN over each real-time frame's history, in place of the a-trous filter, where fast.

pub mod device;
pub mod filter;
pub mod headless;
pub mod inputs;
pub mod library;
pub mod per_frame;
pub mod shared;
pub mod viewer;
pub mod worker;

pub use device::{AdapterIdentity, DeviceKind};
pub use filter::{Denoised, Oidn, SharedImages, Timings};
pub use headless::{HeadlessOidn, OidnImage};
pub use inputs::{OidnInputs, read_inputs};
pub use per_frame::OidnPerFrame;
pub use viewer::{OidnStatus, OidnViewerPlugin, ViewerOidn};

pub use crate::render::settings::{AuxMode, DenoiseOptions, Quality};

/// Why OIDN cannot run. Every variant's message names what failed; callers fall back to the svgf denoiser.
#[derive(Clone, Debug, thiserror::Error)]
pub enum OidnError {
    #[error("raykin was built without the `oidn` cargo feature")]
    NotBuilt,
    #[error("{path}: {reason}")]
    Load { path: String, reason: String },
    #[error(
        "Open Image Denoise is not installed: {} (run scripts/setup.sh, or set {} to the folder holding {})",
        tried.join("; "), library::DIR_VARIABLE, library::LIBRARY_FILE
    )]
    LibraryNotFound { tried: Vec<String> },
    #[error("Open Image Denoise {device} device: {message}")]
    Device { device: String, message: String },
    #[error("Open Image Denoise input: {0}")]
    Input(String),
}

/// Host images, row-major from the top-left, linear RGB per pixel. `albedo` in [0, 1], `normal` in [-1, 1].
#[derive(Clone, Copy, Debug)]
pub struct Images<'a> {
    pub width: u32,
    pub height: u32,
    pub color: &'a [[f32; 3]],
    pub albedo: Option<&'a [[f32; 3]]>,
    pub normal: Option<&'a [[f32; 3]]>,
    /// Radiance added to the output as it is, not denoised: what reached the camera unscattered (exact).
    pub unscattered: Option<&'a [[f32; 3]]>,
    /// Pixels shown as their input colour, not denoised (where no sample met a surface: exact).
    pub kept: Option<&'a [bool]>,
}

impl Images<'_> {
    /// Errors when a size is zero or an image's length is not width x height.
    pub fn validate(&self) -> Result<(), OidnError> {
        let pixels = self.width as usize * self.height as usize;
        if pixels == 0 {
            return Err(OidnError::Input(format!(
                "empty image ({}x{})",
                self.width, self.height
            )));
        }
        for (what, len) in [
            ("colour", Some(self.color.len())),
            ("albedo", self.albedo.map(<[_]>::len)),
            ("normal", self.normal.map(<[_]>::len)),
            ("unscattered", self.unscattered.map(<[_]>::len)),
            ("kept", self.kept.map(<[_]>::len)),
        ] {
            if let Some(len) = len
                && len != pixels
            {
                return Err(OidnError::Input(format!(
                    "the {what} image has {len} pixels, expected {}x{} = {pixels}",
                    self.width, self.height
                )));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quality_names_round_trip() {
        for q in Quality::ALL {
            assert_eq!(q.name().parse::<Quality>(), Ok(q));
        }
        assert!("ultra".parse::<Quality>().unwrap_err().contains("ultra"));
    }

    #[test]
    fn mismatched_image_sizes_are_named() {
        let color = vec![[0.0; 3]; 6];
        let albedo = vec![[0.0; 3]; 5];
        let images = Images {
            width: 3,
            height: 2,
            color: &color,
            albedo: Some(&albedo),
            normal: None,
            unscattered: None,
            kept: None,
        };
        let text = images.validate().unwrap_err().to_string();
        assert!(
            text.contains("albedo") && text.contains("5") && text.contains("3x2"),
            "{text}"
        );
        let empty = Images {
            width: 0,
            height: 2,
            color: &[],
            albedo: None,
            normal: None,
            unscattered: None,
            kept: None,
        };
        assert!(empty.validate().is_err());
    }
}

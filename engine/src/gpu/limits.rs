//! The image sizes an adapter can render, checked before the renderer creates any buffer: a size over the
//! adapter's limits must be a clear error, not a wgpu validation panic in the middle of buffer creation.

/// Bytes per pixel of the renderer's largest per-pixel storage buffer: the `vec4<f32>` accumulation (and the
/// AOV, moments, denoiser and primary-hit buffers of the same size), each bound whole.
pub const MAX_BYTES_PER_PIXEL: u64 = 16;
/// Pixels per side of the image kernels' workgroups (`@workgroup_size(8, 8)`).
pub const WORKGROUP_SIDE: u32 = 8;

#[derive(Debug, thiserror::Error)]
#[error("image size {width}x{height}: {reason}")]
pub struct ImageSizeError {
    pub width: u32,
    pub height: u32,
    pub reason: String,
}

/// The bytes one storage buffer bound whole may hold on this adapter.
pub fn max_binding_bytes(limits: &wgpu::Limits) -> u64 {
    limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size)
}

/// Checks that a `width` x `height` image fits the adapter's buffer, binding and dispatch limits.
pub fn check_image_size(
    limits: &wgpu::Limits,
    width: u32,
    height: u32,
) -> Result<(), ImageSizeError> {
    let fail = |reason: String| ImageSizeError {
        width,
        height,
        reason,
    };
    if width == 0 || height == 0 {
        return Err(fail("an image needs at least one pixel each way".into()));
    }
    let max_side = limits
        .max_compute_workgroups_per_dimension
        .saturating_mul(WORKGROUP_SIDE);
    if width > max_side || height > max_side {
        return Err(fail(format!(
            "this adapter dispatches at most {} workgroups of {WORKGROUP_SIDE} pixels per side, so images \
             are at most {max_side} pixels wide and high",
            limits.max_compute_workgroups_per_dimension
        )));
    }
    let binding = max_binding_bytes(limits);
    let bytes = width as u64 * height as u64 * MAX_BYTES_PER_PIXEL;
    if bytes > binding {
        let max_pixels = binding / MAX_BYTES_PER_PIXEL;
        let side = (max_pixels as f64).sqrt() as u64;
        return Err(fail(format!(
            "its per-pixel buffers need {} MiB each ({MAX_BYTES_PER_PIXEL} bytes a pixel), but this adapter \
             binds at most {} MiB per buffer: at most {:.1} megapixels, e.g. {side}x{side}",
            bytes >> 20,
            binding >> 20,
            max_pixels as f64 / 1e6
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lavapipe's limits: 128 MiB bindings, 2 GiB buffers, 65535 workgroups.
    fn lavapipe() -> wgpu::Limits {
        wgpu::Limits {
            max_storage_buffer_binding_size: 128 << 20,
            max_buffer_size: (2 << 30) - 1,
            max_compute_workgroups_per_dimension: 65535,
            ..wgpu::Limits::default()
        }
    }

    #[test]
    fn sizes_within_the_limits_pass() {
        assert!(check_image_size(&lavapipe(), 1920, 1080).is_ok());
        // 128 MiB / 16 B = 8 Mi pixels exactly.
        assert!(check_image_size(&lavapipe(), 4096, 2048).is_ok());
    }

    #[test]
    fn oversized_images_name_the_limit() {
        let err = check_image_size(&lavapipe(), 4096, 2049)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("4096x2049") && err.contains("128 MiB") && err.contains("2896x2896"),
            "{err}"
        );
        let err = check_image_size(&lavapipe(), 100_000, 100_000)
            .unwrap_err()
            .to_string();
        assert!(err.contains("152587 MiB"), "{err}");
        let err = check_image_size(&lavapipe(), 600_000, 1)
            .unwrap_err()
            .to_string();
        assert!(err.contains("at most 524280 pixels"), "{err}");
        assert!(check_image_size(&lavapipe(), 0, 10).is_err());
    }
}

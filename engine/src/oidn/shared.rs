//! OIDN over GPU memory it shares with wgpu: a wgpu pass writes the accumulation's means as OIDN's inputs into
//! Vulkan memory that OIDN's GPU device imported (`gpu::external_memory`), OIDN filters them in place, and the
//! output is read where OIDN wrote it. Nothing crosses PCIe but the output, and that only when the host needs
//! the image (a file). The host path (`inputs::read_inputs` then [`Oidn::denoise`]) stays for every other
//! device: OIDN's CPU device, a GPU it has no backend for, a non-Vulkan adapter.

use super::filter::{Denoised, Oidn, SharedImages, Timings, ms_since};
use super::{DenoiseOptions, OidnError};
use crate::gpu::GpuContext;
use crate::render::passes::denoiser_planes::DenoiserSources;
use std::time::Instant;

/// The accumulation in `sources` denoised on OIDN's GPU device from shared memory, the output (with the
/// unscattered radiance added back) read back to the host. Call only where [`Oidn::shares_memory_with`] is
/// true. Timings: `upload_ms` is the wgpu pass that writes the inputs (with its wait), `download_ms` the pass
/// that writes the output and its readback; nothing is read back before.
pub fn denoise_view(
    oidn: &mut Oidn,
    ctx: &GpuContext,
    sources: &DenoiserSources,
    options: &DenoiseOptions,
) -> Result<Denoised, OidnError> {
    let shown = crate::render::HostDenoised::image_buffer_sized(ctx, sources.accum.size());
    let mut timings = denoise_into(oidn, ctx, sources, options, &shown)?;
    let start = Instant::now();
    // Count 1 per pixel: the means are the image.
    let color = ctx.read_buffers_with(&[&shown], crate::render::view::mean_rgb);
    timings.download_ms += ms_since(start);
    Ok(Denoised {
        color,
        timings,
        // The unpack pass replaced any non-finite output pixel by its noisy value; it does not count them.
        repaired: 0,
    })
}

/// As [`denoise_view`], but the output stays on the GPU: written into `shown` in the display's layout
/// (`render::HostDenoised::image_buffer`; non-finite pixels keep their noisy mean), `download_ms` being that
/// pass. Nothing crosses to the host.
pub fn denoise_into(
    oidn: &mut Oidn,
    ctx: &GpuContext,
    sources: &DenoiserSources,
    options: &DenoiseOptions,
    shown: &wgpu::Buffer,
) -> Result<Timings, OidnError> {
    let (images, mut timings) = filter_in_place(oidn, ctx, sources, options)?;
    let start = Instant::now();
    crate::render::queries::write_denoised_output(
        ctx,
        sources,
        [&images.output, &images.color],
        shown,
    );
    timings.download_ms = ms_since(start);
    Ok(timings)
}

/// The inputs written into the shared images and OIDN run over them; the images and the timings so far.
fn filter_in_place(
    oidn: &mut Oidn,
    ctx: &GpuContext,
    sources: &DenoiserSources,
    options: &DenoiseOptions,
) -> Result<(SharedImages, Timings), OidnError> {
    let (images, setup_ms) = oidn.shared_images(ctx, sources.width, sources.height, options)?;
    let mut timings = Timings {
        setup_ms,
        ..Default::default()
    };
    let start = Instant::now();
    crate::render::queries::write_denoiser_inputs(
        ctx,
        sources,
        [&images.color, &images.albedo, &images.normal],
    );
    timings.upload_ms = ms_since(start);
    (timings.prefilter_ms, timings.filter_ms) = oidn.execute()?;
    Ok((images, timings))
}

/// How [`denoise_sources_into`] went.
pub struct DenoisedInto {
    /// The denoise, its `color` empty: the image is in the buffer it was given.
    pub result: Result<Denoised, OidnError>,
    /// It ran in GPU memory shared with OIDN (nothing went through the host).
    pub shared_memory: bool,
    /// Milliseconds copying the accumulation to the host (0 when shared).
    pub readback_ms: f64,
}

/// The accumulation in `sources` denoised into `shown` (the display's layout,
/// `render::HostDenoised::image_buffer`): in GPU memory shared with OIDN unless that is not possible here or
/// failed once (`failed`, as [`attempt`] keeps it), else through host copies where `through_host` allows;
/// `None` when neither may run.
pub fn denoise_sources_into(
    oidn: &mut Oidn,
    ctx: &GpuContext,
    failed: &mut bool,
    (sources, shown): (&DenoiserSources, &wgpu::Buffer),
    options: &DenoiseOptions,
    through_host: bool,
) -> Option<DenoisedInto> {
    if let Some(timings) = attempt(oidn, ctx, failed, |o| {
        denoise_into(o, ctx, sources, options, shown)
    }) {
        return Some(DenoisedInto {
            result: Ok(Denoised {
                color: Vec::new(),
                timings,
                repaired: 0,
            }),
            shared_memory: true,
            readback_ms: 0.0,
        });
    }
    if !through_host {
        return None;
    }
    let (inputs, readback_s) = super::inputs::read_sources(ctx, sources);
    Some(DenoisedInto {
        result: oidn.denoise(&inputs.images(), options).map(|mut d| {
            crate::render::HostDenoised::write_image(ctx, shown, &d.color);
            d.color = Vec::new();
            d
        }),
        shared_memory: false,
        readback_ms: readback_s * 1e3,
    })
}

/// Runs `denoise` in shared GPU memory where `oidn` and `ctx` allow it and it has not failed before; `None`
/// means "use the host path": not possible here, or it just failed (then `failed` is set, a warning says why,
/// and later calls go straight to the host path).
pub fn attempt<T>(
    oidn: &mut Oidn,
    ctx: &GpuContext,
    failed: &mut bool,
    denoise: impl FnOnce(&mut Oidn) -> Result<T, OidnError>,
) -> Option<T> {
    if *failed || !oidn.shares_memory_with(ctx) {
        return None;
    }
    match denoise(oidn) {
        Ok(result) => Some(result),
        Err(e) => {
            tracing::warn!("{e}; Open Image Denoise copies its images through the host instead");
            *failed = true;
            None
        }
    }
}

//! Open Image Denoise measured: what one denoise costs per frame size, quality and device (the copies
//! between GPU, host and OIDN included), and how much closer it brings an image to the converged one at 1,
//! 4, 16 and 64 spp, beside svgf.

use super::metrics::{flip_mean, rel_mse, srgb8, tonemap};
use super::scenes::BenchScene;
use anyhow::{Context, Result};
use raykin::gpu::GpuContext;
use raykin::oidn::device::{AdapterIdentity, DeviceRequest};
use raykin::oidn::{AuxMode, DenoiseOptions, Oidn, Quality, read_inputs};
use raykin::render::RenderSettings;

/// One denoise at one size, quality and device: median milliseconds of each step over the repeats.
#[derive(Clone, Debug, serde::Serialize)]
pub struct TimingRow {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub device: String,
    pub quality: Quality,
    /// "host": the images copied GPU -> host -> OIDN and back; "shared": OIDN's GPU device reads and writes
    /// them in GPU memory shared with wgpu (raykin::oidn::shared), only the output read back.
    pub memory: &'static str,
    /// How the albedo and normal were used: "prefilter" (OIDN's recommendation, the default) or "clean" (as
    /// they are, trusted: no prefilters).
    pub aux: &'static str,
    pub repeats: usize,
    /// Accumulation, albedo and normal buffers from the GPU to the host (wgpu readback; 0 when shared).
    pub readback_ms: f64,
    /// Host to OIDN buffers (shared: the wgpu pass writing OIDN's inputs), and OIDN's output to the host.
    pub upload_ms: f64,
    pub download_ms: f64,
    /// Albedo and normal prefilters, then the main filter.
    pub prefilter_ms: f64,
    pub filter_ms: f64,
    /// Everything above: the cost of each denoised frame.
    pub total_ms: f64,
    /// Shared rows: the denoise without the output's trip to the host (what an image that stays on the GPU,
    /// the viewer's, costs); host rows: the same steps, the upload being the host-to-device copy.
    pub on_device_ms: f64,
    /// Shared rows: relMSE of the output against the host path's output of the same accumulation (the two
    /// paths agree up to the GPU's rounding of the means).
    pub host_difference_rel_mse: Option<f64>,
    /// Shared rows: one more denoise with the output written for display on the GPU (the viewer's path,
    /// `shared::denoise_into`): its milliseconds without set-up, and the relMSE of that image against this
    /// row's output.
    pub display_path_ms: Option<f64>,
    pub display_path_difference_rel_mse: Option<f64>,
    /// Filter creation at this size (once).
    pub setup_ms: f64,
}

/// Error of one image against the scene's converged reference.
#[derive(Clone, Debug, serde::Serialize)]
pub struct GainRow {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// "none", "svgf", "oidn high", "oidn balanced", "oidn fast".
    pub method: String,
    /// relMSE of the tone-mapped image, and on linear radiance; FLIP of the tone-mapped image.
    pub rel_mse: f64,
    pub rel_mse_linear: f64,
    pub flip: f64,
    /// The noisy image's error over this one's (1 for "none").
    pub rel_mse_gain: f64,
    pub rel_mse_linear_gain: f64,
    pub flip_gain: f64,
    /// Mean of the image over the noisy image's (energy kept), luminance-weighted.
    pub mean_ratio: f64,
}

/// Which OIDN devices to time: the adapter's (its GPU where OIDN has a backend for it) and the CPU.
fn devices(ctx: &GpuContext) -> Vec<DeviceRequest> {
    let adapter = AdapterIdentity::from_wgpu(&ctx.info);
    let mut requests = vec![DeviceRequest::Cpu];
    if adapter.gpu_kind().is_some() {
        requests.insert(0, DeviceRequest::MatchAdapter(adapter));
    }
    requests
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// OIDN's cost on `scene` at each size, quality and device: a 1-spp image is traced, then read back and
/// denoised `repeats` times (after one untimed run that also sets the filters up).
pub fn timings(
    ctx: &GpuContext,
    scene: &BenchScene,
    base: &RenderSettings,
    sizes: &[(u32, u32)],
    repeats: usize,
) -> Result<Vec<TimingRow>> {
    let mut rows = Vec::new();
    for request in devices(ctx) {
        let mut oidn = match Oidn::new(&request) {
            Ok(o) => o,
            Err(e) => {
                eprintln!("raykin bench: OIDN timings for {request:?} left out: {e}");
                continue;
            }
        };
        for note in &oidn.notes {
            eprintln!("raykin bench: {note}");
        }
        for &(width, height) in sizes {
            let settings = super::at_size(base, (width, height));
            let mut app = super::open_app(ctx, scene, settings)?;
            app.accumulate(1, 1, |_| {});
            let shares = oidn.shares_memory_with(ctx);
            for quality in Quality::ALL {
                let mut host_output = Vec::new();
                // The host path as before; where OIDN shares the GPU's memory, the same in shared memory
                // (compared with the host path's output), and without the prefilters.
                for (memory, aux) in [
                    ("host", AuxMode::Prefilter),
                    ("shared", AuxMode::Prefilter),
                    ("shared", AuxMode::Clean),
                ] {
                    if memory == "shared" && !shares {
                        continue;
                    }
                    let options = DenoiseOptions {
                        aux,
                        ..DenoiseOptions::at(quality)
                    };
                    let mut steps: [Vec<f64>; 7] = Default::default();
                    let mut setup_ms = 0.0;
                    let mut output = Vec::new();
                    for run in 0..=repeats.max(1) {
                        let (d, readback_s) = if memory == "shared" {
                            let d = raykin::oidn::shared::denoise_view(
                                &mut oidn,
                                &app.ctx,
                                &app.view().denoiser_sources(),
                                &options,
                            );
                            (d, 0.0)
                        } else {
                            let (inputs, readback_s) = read_inputs(&app.ctx, app.view());
                            (oidn.denoise(&inputs.images(), &options), readback_s)
                        };
                        let d = d.with_context(|| {
                            format!("OIDN at {width}x{height} ({memory} memory)")
                        })?;
                        let t = d.timings;
                        output = d.color;
                        if run == 0 {
                            setup_ms = t.setup_ms;
                            continue;
                        }
                        let values = [
                            readback_s * 1e3,
                            t.upload_ms,
                            t.download_ms,
                            t.prefilter_ms,
                            t.filter_ms,
                            readback_s * 1e3 + t.total_ms() - t.setup_ms,
                            t.on_device_ms(),
                        ];
                        for (s, v) in steps.iter_mut().zip(values) {
                            s.push(v);
                        }
                    }
                    let host_difference_rel_mse = match (memory, aux) {
                        ("host", _) => {
                            host_output = std::mem::take(&mut output);
                            None
                        }
                        (_, AuxMode::Prefilter) => Some(rel_mse(&output, &host_output)),
                        _ => None,
                    };
                    let (display_path_ms, display_path_difference_rel_mse) = if memory == "shared" {
                        let (ms, image) = display_path(&mut oidn, &app, &options)?;
                        (Some(ms), Some(rel_mse(&image, &output)))
                    } else {
                        (None, None)
                    };
                    let [
                        readback,
                        upload,
                        download,
                        prefilter,
                        filter,
                        total,
                        on_device,
                    ] = steps.map(median);
                    let row = TimingRow {
                        scene: scene.name.clone(),
                        width,
                        height,
                        device: oidn.device_description(),
                        quality,
                        memory,
                        aux: aux.name(),
                        repeats: repeats.max(1),
                        readback_ms: readback,
                        upload_ms: upload,
                        download_ms: download,
                        prefilter_ms: prefilter,
                        filter_ms: filter,
                        total_ms: total,
                        on_device_ms: on_device,
                        host_difference_rel_mse,
                        display_path_ms,
                        display_path_difference_rel_mse,
                        setup_ms,
                    };
                    eprintln!(
                        "raykin bench: OIDN {} {width}x{height} on {} ({memory} memory, {} AOVs): {:.1} ms per frame, {:.1} without the output's readback (readback {:.1}, upload {:.1}, prefilter {:.1}, filter {:.1}, download {:.1}; set-up {:.0} once){}",
                        quality.name(),
                        row.device,
                        row.aux,
                        row.total_ms,
                        row.on_device_ms,
                        row.readback_ms,
                        row.upload_ms,
                        row.prefilter_ms,
                        row.filter_ms,
                        row.download_ms,
                        row.setup_ms,
                        row.host_difference_rel_mse
                            .map(|d| format!("; relMSE against the host path's output {d:.2e}"))
                            .unwrap_or_default()
                    );
                    if let (Some(ms), Some(d)) = (display_path_ms, display_path_difference_rel_mse)
                    {
                        eprintln!(
                            "raykin bench:   written for display on the GPU instead (the viewer's path): {ms:.1} ms, relMSE against the read-back output {d:.2e}"
                        );
                    }
                    rows.push(row);
                }
            }
        }
    }
    Ok(rows)
}

/// The viewer's shared-memory path once (filters already made): OIDN's output written into a display buffer on
/// the GPU; its milliseconds, and that buffer read back as an image to compare.
fn display_path(
    oidn: &mut Oidn,
    app: &raykin::headless::HeadlessApp,
    options: &DenoiseOptions,
) -> Result<(f64, Vec<[f32; 3]>)> {
    let shown = raykin::render::HostDenoised::image_buffer(&app.ctx, app.view());
    let start = std::time::Instant::now();
    raykin::oidn::shared::denoise_into(
        oidn,
        &app.ctx,
        &app.view().denoiser_sources(),
        options,
        &shown,
    )
    .context("OIDN written for display")?;
    let ms = start.elapsed().as_secs_f64() * 1e3;
    // Count 1 per pixel: the means are the image.
    let bytes = app.ctx.read_buffer(&shown, shown.size());
    Ok((ms, raykin::render::view::mean_rgb(&bytes)))
}

/// The samples per pixel the gains are measured at.
pub const GAIN_SPP: [u32; 4] = [1, 4, 16, 64];
/// Samples per pixel of the converged AOVs of the bound row.
const CONVERGED_AOV_SPP: u32 = 256;

/// Error against the cached reference at [`GAIN_SPP`] of the noisy image, svgf's and OIDN's at each quality.
/// Animated scenes are measured in their rest pose (no players).
pub fn gains(
    ctx: &GpuContext,
    scene: &BenchScene,
    base: &RenderSettings,
    suite: &super::suite::Suite,
    cache: &std::path::Path,
) -> Result<Vec<GainRow>> {
    let still = BenchScene {
        name: scene.name.clone(),
        scene: scene.scene.clone(),
        camera: scene.camera.clone(),
        environment: scene.environment.clone(),
        players: Vec::new(),
        source_files: scene.source_files.clone(),
        switchable_light: scene.switchable_light,
    };
    let reference = super::error_curves::reference(ctx, &still, base, suite, cache)?;
    let reference_display = tonemap(&reference.mean);
    let reference_srgb8 = srgb8(&reference_display);
    let (w, h) = (base.width, base.height);
    let mut oidn = Oidn::new(&DeviceRequest::MatchAdapter(AdapterIdentity::from_wgpu(
        &ctx.info,
    )))
    .map_err(|e| anyhow::anyhow!("OIDN gains need Open Image Denoise: {e}"))?;
    let settings = RenderSettings {
        seed: 0xD0_0015E,
        ..base.clone()
    };
    // An upper bound, not a method: the albedo and normal of a long accumulation (another seed), as if the AOVs
    // had converged, given to OIDN with the noisy colour (`cleanAux`, no prefilters).
    let converged_aovs = {
        let mut app = super::open_app(
            ctx,
            &still,
            RenderSettings {
                seed: 0xA0_5EED,
                ..base.clone()
            },
        )?;
        app.set_keep_denoiser_inputs(true);
        app.accumulate(CONVERGED_AOV_SPP, 16, |_| {});
        let (inputs, _) = read_inputs(&app.ctx, app.view());
        (inputs.albedo, inputs.normal)
    };
    let mut app = super::open_app(ctx, &still, settings)?;
    // svgf's row filters these samples too: its moments must accumulate although the settings do not denoise.
    app.set_keep_denoiser_inputs(true);
    let mut rows = Vec::new();
    for spp in GAIN_SPP {
        app.accumulate(spp - app.samples(), 16, |_| {});
        let noisy = app.radiance();
        let mut images = vec![
            ("none".to_string(), noisy.clone()),
            ("svgf".to_string(), app.denoised_radiance()),
        ];
        let (inputs, _) = read_inputs(&app.ctx, app.view());
        for quality in Quality::ALL {
            let d = oidn.denoise(&inputs.images(), &DenoiseOptions::at(quality))?;
            images.push((format!("oidn {}", quality.name()), d.color));
        }
        let mut bound = inputs.clone();
        (bound.albedo, bound.normal) = converged_aovs.clone();
        let options = DenoiseOptions {
            aux: AuxMode::Clean,
            ..DenoiseOptions::at(Quality::High)
        };
        let d = oidn.denoise(&bound.images(), &options)?;
        images.push(("oidn high, converged AOVs (bound)".to_string(), d.color));
        let luminance = |img: &[[f32; 3]]| -> f64 {
            img.iter()
                .map(|p| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64)
                .sum()
        };
        let metrics = |img: &[[f32; 3]]| {
            let display = tonemap(img);
            (
                rel_mse(&display, &reference_display),
                rel_mse(img, &reference.mean),
                flip_mean(&reference_srgb8, &srgb8(&display), w, h),
            )
        };
        let (n_rel, n_lin, n_flip) = metrics(&noisy);
        for (method, image) in images {
            let (rel, lin, flip) = metrics(&image);
            let row = GainRow {
                scene: scene.name.clone(),
                width: w,
                height: h,
                spp,
                method,
                rel_mse: rel,
                rel_mse_linear: lin,
                flip,
                rel_mse_gain: n_rel / rel,
                rel_mse_linear_gain: n_lin / lin,
                flip_gain: n_flip / flip,
                mean_ratio: luminance(&image) / luminance(&noisy),
            };
            eprintln!(
                "raykin bench: {} {w}x{h} {spp} spp {}: relMSE {:.3e} ({:.1}x lower), linear {:.3e} ({:.1}x), FLIP {:.4} ({:.1}x), mean {:.4}",
                row.scene,
                row.method,
                row.rel_mse,
                row.rel_mse_gain,
                row.rel_mse_linear,
                row.rel_mse_linear_gain,
                row.flip,
                row.flip_gain,
                row.mean_ratio
            );
            rows.push(row);
        }
    }
    Ok(rows)
}

//! `raykin view --offscreen --frames N --report out.json`: the viewer's frame loop without a window (the same
//! editor UI pass, frame schedule and UI + display pass, into a texture instead of a surface), timed per pass:
//! CPU phases from `frame_timing`, GPU passes from timestamp queries read back without stalling. For timing
//! the interactive path on a GPU machine with no display.

use super::script::{Flow, ScriptHost, ScriptRunner};
use super::session::{SceneSource, Session, SessionOptions};
use super::ui_render::UiRenderer;
use crate::stats::Spread;
use anyhow::{Context, Result};
use raykin::frame_timing::FrameTimings;
use raykin::gpu::GpuContext;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Width the editor panel takes beside the image.
const PANEL_WIDTH: u32 = 340;

/// The bench's spread (min, median, p10, p90, p99) of a series, with its mean and count.
#[derive(serde::Serialize)]
struct Series {
    #[serde(flatten)]
    spread: Spread,
    mean: f64,
    n: usize,
}

fn spread(values: &[f64]) -> Option<Series> {
    let finite: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    (!finite.is_empty()).then(|| Series {
        spread: Spread::of(&finite),
        mean: finite.iter().sum::<f64>() / finite.len() as f64,
        n: finite.len(),
    })
}

/// Blocks until the GPU is idle; the milliseconds it took.
fn wait_ms(ctx: &GpuContext) -> f64 {
    let t = Instant::now();
    ctx.wait_idle();
    t.elapsed().as_secs_f64() * 1e3
}

fn rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.split_whitespace().next()?.parse().ok())
}

/// Per-frame CPU figures, in ms.
#[derive(Default)]
struct CpuSeries {
    ui: Vec<f64>,
    animate: Vec<f64>,
    transform: Vec<f64>,
    deform: Vec<f64>,
    bvh: Vec<f64>,
    upload: Vec<f64>,
    render_submit: Vec<f64>,
    ui_paint: Vec<f64>,
    frame: Vec<f64>,
}

pub struct OffscreenSetup {
    pub source: SceneSource,
    pub options: SessionOptions,
    pub frames: u64,
    pub report: Option<PathBuf>,
    /// Wait for the GPU after the schedule and after the UI pass, timing each wait.
    pub sync_passes: bool,
    pub script: Option<ScriptRunner>,
}

pub fn run(ctx: GpuContext, setup: OffscreenSetup) -> Result<()> {
    let stored = super::session::load_settings(&setup.options);
    let mut session = Session::new(ctx.clone(), setup.source, setup.options, stored)?;
    if let Some(report) = &setup.report {
        let output = crate::outputs::Output {
            what: "--report",
            path: report.clone(),
        };
        crate::outputs::refuse_overwrites(&[output], &session.scene().files)?;
        crate::outputs::check_writable("--report", report)?;
    }
    let (iw, ih) = session
        .options
        .fixed_render_size
        .context("the offscreen loop needs a fixed image size")?;
    let size = [iw + PANEL_WIDTH, ih + 48];
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let target = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("offscreen ui"),
        size: wgpu::Extent3d {
            width: size[0],
            height: size[1],
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = target.create_view(&Default::default());
    let mut ui = UiRenderer::new(&ctx, format);
    let mut script = setup.script;
    let warmup = (setup.frames / 10).min(10);
    let mut cpu = CpuSeries::default();
    let (mut trace, mut tonemap, mut denoise, mut rays_per_s, mut ui_gpu) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut wait_schedule, mut wait_ui) = (Vec::new(), Vec::new());
    // The real-time path's passes (on its frames): G-buffer, ReSTIR DI, gradients, temporal, and the sum of
    // every pass of the frame.
    let (mut gbuffer, mut restir, mut gradient, mut temporal, mut realtime_total) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    // OIDN per real-time frame (wall ms of each denoise, once the frame before it finished on the GPU).
    let (mut oidn_frame, mut oidn_device, mut oidn_failed) = (Vec::new(), None, None);
    let mut pacer = super::ui_render::FramePacer::default();
    let mut rss_after_warmup = None;
    // Resident memory every tenth of the run, to see that it stays flat.
    let mut rss_samples: Vec<(u64, Option<u64>)> = Vec::new();
    let sample_every = (setup.frames / 10).max(1);
    let start = Instant::now();
    for frame in 0..setup.frames {
        let t0 = Instant::now();
        let raw = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(
                egui::Pos2::ZERO,
                egui::vec2(size[0] as f32, size[1] as f32),
            )),
            ..Default::default()
        };
        let mut output = session.ui(raw);
        let ui_ms = t0.elapsed().as_secs_f64() * 1e3;
        let gpu = session.step();
        let oidn_report = session.engine.take_frame_denoise_report();
        let waited_schedule = setup.sync_passes.then(|| wait_ms(&ctx));
        let t1 = Instant::now();
        let submission = ui.render(
            &ctx,
            &session.egui,
            &mut output,
            &view,
            size,
            session.engine.view(),
        );
        let paint_ms = t1.elapsed().as_secs_f64() * 1e3;
        let waited_ui = setup.sync_passes.then(|| wait_ms(&ctx));
        pacer.submitted(&ctx, submission);
        let frame_ms = t0.elapsed().as_secs_f64() * 1e3;
        let measured = frame >= warmup;
        if measured {
            let phases = session.engine.app.world().resource::<FrameTimings>().last;
            cpu.ui.push(ui_ms);
            cpu.animate.push(phases.animate_ms);
            cpu.transform.push(phases.transform_ms);
            cpu.deform.push(phases.deform_ms);
            cpu.bvh.push(phases.bvh_ms);
            cpu.upload.push(phases.upload_ms);
            cpu.render_submit.push(phases.render_ms);
            cpu.ui_paint.push(paint_ms);
            cpu.frame.push(frame_ms);
            wait_schedule.extend(waited_schedule);
            wait_ui.extend(waited_ui);
            match oidn_report {
                Ok(Some(r)) => {
                    oidn_frame.push(r.ms);
                    oidn_device = Some(r.device);
                }
                Ok(None) => {}
                Err(why) => oidn_failed = Some(why),
            }
            for g in &gpu {
                if let Some(p) = g.passes {
                    trace.push(p.trace_ms);
                    tonemap.push(p.tonemap_ms);
                    if p.denoise_ms > 0.0 {
                        denoise.push(p.denoise_ms);
                    }
                    if p.trace_ms > 0.0 {
                        rays_per_s.push(g.rays as f64 / (p.trace_ms * 1e-3));
                    }
                    if p.gbuffer_ms > 0.0 {
                        gbuffer.push(p.gbuffer_ms);
                        restir.push(p.restir_ms);
                        gradient.push(p.gradient_ms);
                        temporal.push(p.temporal_ms);
                        realtime_total.push(
                            p.gbuffer_ms
                                + p.restir_ms
                                + p.gradient_ms
                                + p.trace_ms
                                + p.temporal_ms
                                + p.denoise_ms
                                + p.tonemap_ms
                                + p.skin_ms
                                + p.refit_ms,
                        );
                    }
                }
            }
            ui_gpu.extend(ui.poll_gpu_ms(&ctx));
        } else {
            ui.poll_gpu_ms(&ctx);
            if frame + 1 == warmup {
                rss_after_warmup = rss_kib();
            }
        }
        if (frame + 1) % sample_every == 0 {
            rss_samples.push((frame + 1, rss_kib()));
        }
        if let Some(s) = &mut script {
            let mut host = OffscreenHost {
                ctx: &ctx,
                target: &target,
                size,
            };
            if s.advance(&mut session, &mut host)? == Flow::Quit {
                break;
            }
        }
        if session.quit_requested {
            break;
        }
    }
    ctx.wait_idle();
    let wall_s = start.elapsed().as_secs_f64();
    let rss_end = rss_kib();
    let world = session.engine.app.world();
    let samples_at_end = world.resource::<raykin::render::Accumulation>().samples;
    let settings = world.resource::<raykin::render::RenderSettings>();
    let report = serde_json::json!({
        "scene": session.scene().source,
        "adapter": ctx.info.name,
        "backend": format!("{:?}", ctx.info.backend),
        "device_type": format!("{:?}", ctx.info.device_type),
        "driver": format!("{} {}", ctx.info.driver, ctx.info.driver_info),
        "commit": crate::provenance::commit(),
        "image": [iw, ih],
        "ui_target": size,
        "frames": session.frames,
        "warmup_frames": warmup,
        "wall_s": wall_s,
        "spp_per_frame": settings.spp_per_frame,
        "max_depth": settings.max_depth,
        "samples_at_end": samples_at_end,
        "timing": "CPU: Instant around each frame-schedule phase and the UI passes; GPU: timestamp queries per pass, read back asynchronously (a few frames may go unreported); gpu_wait_ms (--sync-passes): wall time of waiting for the GPU after the schedule and after the UI pass",
        "cpu_ms": {
            "editor_ui": spread(&cpu.ui),
            "animate": spread(&cpu.animate),
            "transform": spread(&cpu.transform),
            "deform": spread(&cpu.deform),
            "bvh_refit_tlas": spread(&cpu.bvh),
            "upload": spread(&cpu.upload),
            "render_submit": spread(&cpu.render_submit),
            "ui_paint_submit": spread(&cpu.ui_paint),
            "frame": spread(&cpu.frame),
        },
        "gpu_ms": {
            "trace": spread(&trace),
            "tonemap": spread(&tonemap),
            "denoise": spread(&denoise),
            "ui_and_display": spread(&ui_gpu),
            "gbuffer": spread(&gbuffer),
            "restir_di": spread(&restir),
            "gradients": spread(&gradient),
            "temporal": spread(&temporal),
            "realtime_frame_total": spread(&realtime_total),
        },
        "oidn_per_frame": {
            "frames": oidn_frame.len(),
            "wall_ms": spread(&oidn_frame),
            "device": oidn_device,
            "failed": oidn_failed,
        },
        "mode": format!("{:?}", settings.mode),
        "realtime": settings.realtime,
        "gpu_wait_ms": setup.sync_passes.then(|| serde_json::json!({
            "frame_schedule": spread(&wait_schedule),
            "ui_and_display": spread(&wait_ui),
        })),
        "rays_per_second_of_trace": spread(&rays_per_s),
        "memory": {
            "rss_kib_after_warmup": rss_after_warmup,
            "rss_kib_end": rss_end,
            "rss_kib_by_frame": rss_samples,
            "gpu_scene_bytes": world.resource::<raykin::render::GpuScene>().memory.total(),
        },
    });
    let frame = spread(&cpu.frame);
    let trace_ms = spread(&trace);
    eprintln!(
        "raykin: offscreen {} frames at {iw}x{ih}: frame {} ms median, trace {} ms median (GPU), RSS {} -> {} KiB",
        session.frames,
        frame.map_or("-".into(), |s| format!("{:.2}", s.spread.median)),
        trace_ms.map_or("-".into(), |s| format!("{:.2}", s.spread.median)),
        rss_after_warmup.map_or("-".into(), |v| v.to_string()),
        rss_end.map_or("-".into(), |v| v.to_string()),
    );
    if let Some(path) = &setup.report {
        raykin::image_io::write_bytes_atomically(
            path,
            serde_json::to_string_pretty(&report)?.as_bytes(),
        )
        .with_context(|| format!("--report {}: cannot write the report", path.display()))?;
        eprintln!("raykin: wrote {}", path.display());
    }
    Ok(())
}

struct OffscreenHost<'a> {
    ctx: &'a GpuContext,
    target: &'a wgpu::Texture,
    size: [u32; 2],
}

impl ScriptHost for OffscreenHost<'_> {
    /// Offscreen, "the screen" is the UI texture the frame was painted into.
    fn capture_screen(&mut self, path: &Path) -> Result<()> {
        let [w, h] = self.size;
        let row = (w * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ui capture"),
            size: row as u64 * h as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            self.target.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        self.ctx.queue.submit([encoder.finish()]);
        let bytes = self.ctx.read_buffer(&buffer, buffer.size());
        let pixels: Vec<u8> = bytes
            .chunks(row as usize)
            .flat_map(|r| r[..(w * 4) as usize].to_vec())
            .collect();
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)?;
        }
        raykin::image_io::write_atomically(path, |p| {
            raykin::image_io::write_png(p, w, h, &pixels)
        })?;
        Ok(())
    }

    fn resize(&mut self, _width: u32, _height: u32) -> Result<()> {
        anyhow::bail!("resize needs a window (the offscreen target has a fixed size)")
    }

    fn window_origin(&self) -> Option<(i32, i32)> {
        Some((0, 0))
    }
}

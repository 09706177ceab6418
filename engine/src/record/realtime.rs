//! `raykin record --realtime`: what the viewer shows, frame after frame. Frame k is the pose at T0 + k/F as in
//! a converged recording, but the frames are made in sequence by the real-time path with its history
//! carried from frame to frame (one path per pixel per frame, temporal reuse, ReSTIR DI, the spatial
//! filter), so a frame depends on every frame before it: such a recording is not resumable or shardable, and
//! is written whole. `DIR/realtime.json` records the settings and each frame's time.

use super::RecordError;
use super::output::{self, FileRecord};
use super::plan::{FrameFormat, RecordSettings};
use crate::headless::HeadlessApp;
use crate::render::RenderMode;
use crate::scene::SceneAsset;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// What a real-time recording wrote.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RealtimeRecording {
    pub frames: u32,
    pub files: Vec<FileRecord>,
    /// Wall milliseconds of each frame (pose, real-time frame, readback, encoding and writing).
    pub frame_ms: Vec<f64>,
    pub interrupted: bool,
}

/// Records `settings`' frames in order with the real-time path into `dir`; `progress(done)` after each.
pub fn record_realtime(
    ctx: crate::gpu::GpuContext,
    scene: Arc<SceneAsset>,
    settings: &RecordSettings,
    dir: &Path,
    cancel: &AtomicBool,
    progress: &mut dyn FnMut(u32),
) -> Result<RealtimeRecording, RecordError> {
    output::prepare_dir(dir)?;
    let render = crate::render::RenderSettings {
        mode: RenderMode::Realtime,
        ..settings.frame.render.clone()
    };
    let mut render = render;
    // Every frame is a new pose; a still scene's frames must not hand over to accumulation either.
    render.realtime.handover = false;
    let camera = settings.frame.camera.choice();
    let (w, h) = (render.width, render.height);
    let mut app = HeadlessApp::new(ctx, scene, render, &camera)?;
    app.set_keep_denoiser_inputs(false);
    let mut out = RealtimeRecording {
        frames: settings.frames,
        files: Vec::new(),
        frame_ms: Vec::new(),
        interrupted: false,
    };
    for k in 0..settings.frames {
        if cancel.load(Ordering::SeqCst) {
            out.interrupted = true;
            break;
        }
        let start = std::time::Instant::now();
        app.pose(settings.clip, settings.time(k), &camera)
            .map_err(|reason| RecordError::Render { frame: k, reason })?;
        app.step();
        let name = settings.frame_file(k);
        let encoded = match settings.frame.format {
            FrameFormat::Exr => {
                let radiance = app.displayed_radiance();
                if let Some(bad) = radiance.iter().flatten().find(|v| !v.is_finite()) {
                    return Err(RecordError::Render {
                        frame: k,
                        reason: format!("internal error: a non-finite pixel value ({bad})"),
                    });
                }
                crate::image_io::encode_exr(w, h, &radiance)
            }
            // The display transform the frame ran (the viewer's image).
            FrameFormat::Png => crate::image_io::encode_png(w, h, &app.view().read_rgba8(&app.ctx)),
        };
        let bytes = encoded.map_err(|reason| RecordError::Write {
            path: dir.join(&name),
            reason,
        })?;
        out.files.push(output::write_file(dir, &name, &bytes)?);
        out.frame_ms.push(start.elapsed().as_secs_f64() * 1e3);
        progress(k + 1);
    }
    let manifest = serde_json::json!({
        "kind": "raykin real-time recording: frames made in sequence with history carried; not resumable",
        "settings": settings,
        "recording": &out,
        "adapter": app.ctx.describe(),
    });
    let text = serde_json::to_vec_pretty(&manifest).map_err(|e| RecordError::Write {
        path: dir.join("realtime.json"),
        reason: e.to_string(),
    })?;
    output::write_file(dir, "realtime.json", &text)?;
    Ok(out)
}

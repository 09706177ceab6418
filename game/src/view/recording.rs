//! The record button: a `raykin::record` job (the same recorder, manifest and files as `raykin record`) run on
//! a worker thread beside the interactive loop, reporting progress to the panel and stoppable from it.

use anyhow::{Context, Result};
use raykin::editor::RecordStart;
use raykin::gpu::GpuContext;
use raykin::record::{
    CameraSpec, FrameFormat, FrameOptions, RecordEvent, RecordJob, RecordRequest, RecordSummary,
    Recorder, Sampling,
};
use raykin::scene::SceneAsset;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, channel};
use std::thread::JoinHandle;

pub struct Recording {
    cancel: Arc<AtomicBool>,
    progress: Receiver<String>,
    worker: Option<JoinHandle<Result<RecordSummary>>>,
    pub dir: std::path::PathBuf,
}

/// Plans the recording against the scene, claims the folder (refusing another scene's recording there, as the
/// CLI does), and starts rendering on a worker thread.
pub fn start(
    ctx: &GpuContext,
    scene: Arc<SceneAsset>,
    scene_file: &Path,
    scene_index: Option<usize>,
    request: RecordStart,
) -> Result<Recording> {
    let camera = match request.scene_camera {
        Some(i) => CameraSpec::Index(i),
        None => {
            let eye = request.camera.position();
            CameraSpec::LookAt {
                eye: eye.to_array(),
                target: (eye + request.camera.forward()).to_array(),
                yfov_degrees: request.camera.yfov.to_degrees(),
            }
        }
    };
    let plan_request = RecordRequest {
        animation: request.clip.map(|c| c.to_string()),
        fps: request.fps,
        start: request.start,
        end: None,
        frames: Some(request.frames),
        frame: FrameOptions {
            sampling: Sampling::Spp(request.spp.max(1)),
            spp_per_dispatch: request.spp.clamp(1, 16),
            camera,
            format: FrameFormat::Png,
            aovs: Vec::new(),
            render: request.settings.clone(),
        },
        scene: scene_index,
    };
    let settings = raykin::record::plan(&scene, &plan_request)?;
    let job = RecordJob {
        scene,
        scene_label: scene_file.display().to_string(),
        scene_hash: raykin::record::scene_hash(scene_file)?,
        settings,
        dir: request.out_dir.clone(),
        slice: None,
        force: false,
    };
    let recorder = Recorder::prepare(job)?;
    let cancel = Arc::new(AtomicBool::new(false));
    let (send, progress) = channel();
    let worker = {
        let (ctx, cancel) = (ctx.clone(), cancel.clone());
        std::thread::Builder::new()
            .name("raykin recorder".into())
            .spawn(move || {
                let mut frame = 0;
                recorder
                    .run(ctx, &cancel, &mut |event| {
                        let text = match event {
                            RecordEvent::Started { todo, skipped, .. } => {
                                format!(
                                    "recording: {todo} frame(s) to render, {skipped} already done"
                                )
                            }
                            RecordEvent::Samples { frame: f, spp } => {
                                frame = f;
                                format!("recording frame {f}: {spp} spp")
                            }
                            RecordEvent::FrameDone { done, todo, .. } => {
                                format!("recording: frame {frame} written ({done} of {todo})")
                            }
                        };
                        let _ = send.send(text);
                    })
                    .map_err(anyhow::Error::from)
            })
            .context("cannot start the recorder thread")?
    };
    Ok(Recording {
        cancel,
        progress,
        worker: Some(worker),
        dir: request.out_dir,
    })
}

impl Recording {
    /// The latest progress line, if any arrived.
    pub fn progress(&self) -> Option<String> {
        self.progress.try_iter().last()
    }

    /// Asks the recorder to stop after (or abandoning) the frame in progress.
    pub fn stop(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    /// The run's result once the worker has finished (`None` while it runs).
    pub fn finished(&mut self) -> Option<Result<RecordSummary>> {
        if !self.worker.as_ref()?.is_finished() {
            return None;
        }
        let worker = self.worker.take()?;
        Some(
            worker
                .join()
                .unwrap_or_else(|_| Err(anyhow::anyhow!("the recorder thread panicked"))),
        )
    }
}

impl Drop for Recording {
    /// Closing the viewer stops a recording cleanly (finished frames stay; a re-run resumes).
    fn drop(&mut self) {
        self.stop();
        if let Some(worker) = self.worker.take() {
            let _ = worker.join();
        }
    }
}

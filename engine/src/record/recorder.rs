//! The recording loop: claim the folder, skip finished frames, then pose, sample and write each frame.

use super::RecordError;
use super::manifest::{self, FrameRecord, Manifest};
use super::output;
use super::plan::{Aov, FrameFormat, RecordSettings, Sampling};
use crate::bvh::refit::RebuildPolicy;
use crate::gpu::GpuContext;
use crate::headless::HeadlessApp;
use crate::motion::{PreviousPose, motion_vectors};
use crate::scene::SceneAsset;
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// One recording run: a scene, settings, an output folder and the frames to render.
#[derive(Clone)]
pub struct RecordJob {
    pub scene: Arc<SceneAsset>,
    /// The scene file as given (manifest and messages).
    pub scene_label: String,
    /// [`super::scene_hash`] of the scene file.
    pub scene_hash: String,
    pub settings: RecordSettings,
    pub dir: PathBuf,
    /// `None`: the whole recording (this run owns `manifest.json`); `Some`: one slice (it owns its part
    /// manifest, so slices can run at once into one folder).
    pub slice: Option<Range<u32>>,
    /// Start a new recording even if the folder holds another one (its manifests are set aside).
    pub force: bool,
}

/// What the recorder reports while it runs (the CLI draws its progress bar from these).
#[derive(Debug)]
pub enum RecordEvent<'a> {
    /// Before the first frame: `todo` frames to render in `range`, `skipped` already complete there.
    Started {
        range: Range<u32>,
        todo: usize,
        skipped: usize,
    },
    /// Samples per pixel traced so far for `frame`.
    Samples { frame: u32, spp: u32 },
    /// `frame` is on disk and in the manifest; `done` of `todo` frames of this run are finished.
    FrameDone {
        frame: &'a FrameRecord,
        done: usize,
        todo: usize,
    },
}

#[derive(Clone, Debug)]
pub struct RecordSummary {
    pub range: Range<u32>,
    pub rendered: usize,
    pub skipped: usize,
    /// The cancellation flag stopped the run (after a frame was written, or abandoning the frame in progress).
    pub interrupted: bool,
    pub wall_seconds: f64,
    /// Render time of each frame rendered by this run.
    pub frame_ms: Vec<f64>,
    pub spp: Vec<u32>,
    /// Frames of the whole recording complete in the folder (all slices), of `frame_count`.
    pub complete: usize,
    pub frame_count: u32,
    pub manifest: PathBuf,
    pub notes: Vec<String>,
}

pub struct Recorder {
    job: RecordJob,
    range: Range<u32>,
    manifest_path: PathBuf,
    manifest: Manifest,
    /// Verified frames of every manifest in the folder.
    done: BTreeMap<u32, FrameRecord>,
    notes: Vec<String>,
}

impl Recorder {
    /// Checks the folder (creatable, writable) and any recording already in it, before any GPU work: a
    /// recording of another scene or other settings is refused unless `force`; frames whose files verify are
    /// kept. Writes this run's manifest at once, so the folder is claimed before the first frame.
    pub fn prepare(job: RecordJob) -> Result<Self, RecordError> {
        let dir = &job.dir;
        output::prepare_dir(dir)?;
        let mut notes = Vec::new();
        let mut manifests = if job.force {
            let paths = manifest::paths(dir);
            manifest::set_aside(&paths)?;
            if !paths.is_empty() {
                notes.push(format!(
                    "--force: set aside {} earlier manifest(s) in {} (NAME.replaced-TIME)",
                    paths.len(),
                    dir.display()
                ));
            }
            Vec::new()
        } else {
            manifest::read_all(dir)?
        };
        let own_path = manifest::manifest_path(dir, job.slice.as_ref());
        // This run's own manifest from an attempt that finished no frame holds nothing to protect.
        manifests.retain(|(path, m)| {
            let stale = *path == own_path
                && m.frames.is_empty()
                && !m.differences(&job.scene_hash, &job.settings).is_empty();
            if stale {
                notes.push(format!(
                    "replaced {} (other settings, no frame finished)",
                    path.display()
                ));
            }
            !stale
        });
        for (path, m) in &manifests {
            let differences = m.differences(&job.scene_hash, &job.settings);
            if !differences.is_empty() {
                return Err(RecordError::Mismatch {
                    dir: dir.clone(),
                    manifest: path.clone(),
                    differences,
                });
            }
        }
        if manifests.is_empty() && !job.force {
            let foreign = output::frame_files(dir);
            if let Some(example) = foreign.first() {
                return Err(RecordError::ForeignFiles {
                    dir: dir.clone(),
                    example: example.clone(),
                    count: foreign.len(),
                });
            }
        }
        if job.slice.is_none() {
            // A whole-recording run owns the folder: temporary files left by a crash are garbage.
            for partial in output::stale_partials(dir) {
                if std::fs::remove_file(&partial).is_ok() {
                    notes.push(format!(
                        "removed {} (left by an interrupted write)",
                        partial.display()
                    ));
                }
            }
        }
        let done = manifest::verified_frames(dir, &manifests);
        let range = job.slice.clone().unwrap_or(0..job.settings.frames);
        let manifest_path = own_path;
        let own = manifests
            .iter()
            .position(|(p, _)| *p == manifest_path)
            .map(|i| manifests.swap_remove(i).1);
        let mut manifest = own.unwrap_or_else(|| {
            Manifest::new(
                &job.scene_label,
                &job.scene_hash,
                &job.settings,
                job.slice.clone(),
            )
        });
        // Keep only entries whose files are intact; the whole-recording manifest also lists every verified
        // frame of the slices, so it describes the folder.
        manifest.frames.retain(|f| done.get(&f.index) == Some(f));
        if job.slice.is_none() {
            for f in done.values() {
                manifest.insert(f.clone());
            }
        }
        manifest::write(&manifest_path, &manifest)?;
        Ok(Self {
            job,
            range,
            manifest_path,
            manifest,
            done,
            notes,
        })
    }

    /// Frames of this run's range still to render, in order.
    pub fn todo(&self) -> Vec<u32> {
        self.range
            .clone()
            .filter(|k| !self.done.contains_key(k))
            .collect()
    }

    pub fn range(&self) -> Range<u32> {
        self.range.clone()
    }

    pub fn manifest_path(&self) -> &std::path::Path {
        &self.manifest_path
    }

    /// Renders the missing frames of the range. `cancel` is polled between sample chunks: once set, the frame
    /// in progress is abandoned (nothing of it is written) or, if it is being written, finished; then the run
    /// stops and reports `interrupted`.
    pub fn run(
        mut self,
        ctx: GpuContext,
        cancel: &AtomicBool,
        events: &mut dyn FnMut(RecordEvent),
    ) -> Result<RecordSummary, RecordError> {
        let start = Instant::now();
        let todo = self.todo();
        let skipped = self.range.len() - todo.len();
        events(RecordEvent::Started {
            range: self.range.clone(),
            todo: todo.len(),
            skipped,
        });
        let mut summary = RecordSummary {
            range: self.range.clone(),
            rendered: 0,
            skipped,
            interrupted: false,
            wall_seconds: 0.0,
            frame_ms: Vec::new(),
            spp: Vec::new(),
            complete: self.done.len(),
            frame_count: self.job.settings.frames,
            manifest: self.manifest_path.clone(),
            notes: std::mem::take(&mut self.notes),
        };
        if todo.is_empty() {
            return Ok(summary);
        }
        let settings = self.job.settings.clone();
        let camera = settings.frame.camera.choice();
        // Recordings deform on the CPU: a frame must re-render alone bit-identically, so each pose's trees
        // must depend on that pose alone (PoseDetermined), which the GPU backend's asynchronous rebuilds
        // cannot promise.
        let render = crate::render::RenderSettings {
            deform: crate::gpu_deform::DeformBackend::Cpu,
            ..settings.frame.render.clone()
        };
        let mut app = HeadlessApp::new(ctx, self.job.scene.clone(), render, &camera)?;
        // `--denoise` holds for the whole recording: the denoiser's inputs (moments, first-hit AOVs) accumulate
        // only when it runs, or when the AOVs are written.
        app.set_keep_denoiser_inputs(!settings.frame.aovs.is_empty());
        summary.notes.append(&mut app.notes);
        if let Some(Err(e)) = app.resolve_denoiser() {
            let note = format!("{e}; frames are denoised with svgf instead");
            tracing::warn!("{note}");
            summary.notes.push(note);
        }
        app.set_rebuild_policy(RebuildPolicy::PoseDetermined);
        let motion = settings.frame.aovs.contains(&Aov::Motion);
        app.set_hit_aov(motion);
        let mut previous = motion.then(|| {
            PreviousPose::new(
                self.job.scene.clone(),
                settings.frame.render.width,
                settings.frame.render.height,
            )
        });
        let adapter = app.ctx.describe();
        for (position, &k) in todo.iter().enumerate() {
            if cancel.load(Ordering::SeqCst) {
                summary.interrupted = true;
                break;
            }
            let frame_start = Instant::now();
            let stopped = |e: RecordError, done: usize| RecordError::Stopped {
                error: Box::new(e),
                complete: done,
                total: settings.frames,
                manifest: self.manifest_path.clone(),
            };
            let pose = app
                .pose(settings.clip, settings.time(k), &camera)
                .and_then(|()| match &mut previous {
                    Some(p) => p.pose(settings.clip, settings.previous_time(k), &camera),
                    None => Ok(()),
                });
            if let Err(reason) = pose {
                return Err(stopped(
                    RecordError::Render { frame: k, reason },
                    self.done.len(),
                ));
            }
            app.settings_mut().seed = settings.seed(k);
            app.restart_accumulation();
            let (spp, complete) = sample(&mut app, &settings, k, cancel, events);
            if !complete {
                summary.interrupted = true;
                break;
            }
            let files = write_frame(&app, &self.job.dir, &settings, k, previous.as_ref())
                .map_err(|e| stopped(e, self.done.len()))?;
            let record = FrameRecord {
                index: k,
                time: settings.time(k),
                seed: settings.seed(k),
                spp,
                render_ms: frame_start.elapsed().as_secs_f64() * 1e3,
                adapter: adapter.clone(),
                files,
            };
            self.manifest.insert(record.clone());
            manifest::write(&self.manifest_path, &self.manifest)
                .map_err(|e| stopped(e, self.done.len()))?;
            summary.frame_ms.push(record.render_ms);
            summary.spp.push(spp);
            summary.rendered += 1;
            events(RecordEvent::FrameDone {
                frame: &record,
                done: position + 1,
                todo: todo.len(),
            });
            self.done.insert(k, record);
        }
        summary.complete = self.done.len();
        summary.wall_seconds = start.elapsed().as_secs_f64();
        Ok(summary)
    }
}

/// Traces frame `k`'s samples; returns the spp reached and whether the frame is complete (false when
/// `cancel` was set, and the frame must be abandoned).
fn sample(
    app: &mut HeadlessApp,
    settings: &RecordSettings,
    k: u32,
    cancel: &AtomicBool,
    events: &mut dyn FnMut(RecordEvent),
) -> (u32, bool) {
    let mut report = |spp: u32| {
        events(RecordEvent::Samples { frame: k, spp });
        !cancel.load(Ordering::SeqCst)
    };
    match settings.frame.sampling {
        Sampling::Spp(n) => {
            let spp = app.accumulate_while(n, settings.frame.spp_per_dispatch, &mut report);
            (spp, spp == n && !cancel.load(Ordering::SeqCst))
        }
        Sampling::TimeBudgetMs(budget) => {
            let start = Instant::now();
            let (mut done, mut chunk) = (0u32, 1u32);
            loop {
                app.settings_mut().spp_per_frame = chunk;
                app.step();
                app.ctx.wait_idle();
                done += chunk;
                if !report(done) {
                    return (done, false);
                }
                // Size the next chunk from the time per sample so far, to land near the budget.
                let elapsed = start.elapsed().as_secs_f64() * 1e3;
                let per_sample = elapsed / done as f64;
                let left = budget - elapsed;
                if left < per_sample {
                    return (done, true);
                }
                chunk = ((left / per_sample) as u32).clamp(1, settings.frame.spp_per_dispatch);
            }
        }
    }
}

/// Encodes and writes frame `k`'s AOVs, then the frame itself (each atomically); returns their records.
fn write_frame(
    app: &HeadlessApp,
    dir: &std::path::Path,
    settings: &RecordSettings,
    k: u32,
    previous: Option<&PreviousPose>,
) -> Result<Vec<output::FileRecord>, RecordError> {
    let (w, h) = (settings.frame.render.width, settings.frame.render.height);
    let encoded = |name: &str, result: Result<Vec<u8>, String>| {
        result.map_err(|reason| RecordError::Write {
            path: dir.join(name),
            reason,
        })
    };
    let mut files = Vec::new();
    if !settings.frame.aovs.is_empty() {
        let aovs = app.aovs();
        for &aov in &settings.frame.aovs {
            let data: Vec<[f32; 3]> = match aov {
                Aov::Albedo => aovs.albedo.clone(),
                Aov::Normal => aovs.normal.clone(),
                Aov::Depth => aovs.depth.iter().map(|d| [*d; 3]).collect(),
                Aov::Motion => previous.map_or_else(Vec::new, |p| motion_vectors(app, p)),
            };
            let name = RecordSettings::aov_file(k, aov);
            let bytes = encoded(&name, crate::image_io::encode_exr(w, h, &data))?;
            files.push(output::write_file(dir, &name, &bytes)?);
        }
    }
    let name = settings.frame_file(k);
    let bytes = match settings.frame.format {
        FrameFormat::Exr => {
            // `--denoise`: the PNG path's display pass denoises on its own; EXR frames take the same filter.
            let radiance = app.output_radiance();
            if let Some(bad) = radiance.iter().flatten().find(|v| !v.is_finite()) {
                return Err(RecordError::Render {
                    frame: k,
                    reason: format!("internal error: a non-finite pixel value ({bad})"),
                });
            }
            encoded(&name, crate::image_io::encode_exr(w, h, &radiance))?
        }
        FrameFormat::Png => encoded(
            &name,
            crate::image_io::encode_png(w, h, &app.display_rgba8()),
        )?,
    };
    files.push(output::write_file(dir, &name, &bytes)?);
    Ok(files)
}

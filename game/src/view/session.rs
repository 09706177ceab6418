//! One viewer session: the engine (the same `FrameSet` schedule as headless renders, plus the editor), egui,
//! and what the editor asks for (open, save, screenshot, record). The window and the offscreen loop both drive
//! it frame by frame: [`Session::ui`] then [`Session::step`], then they paint the UI.

use anyhow::{Context, Result};
use raykin::animation::{AnimationPlayer, FrameClock};
use raykin::camera::CameraChoice;
use raykin::editor::{EditorAction, EditorPlugin, EditorState, Severity, ViewerPrefs, ViewerStats};
use raykin::gpu::GpuContext;
use raykin::headless::HeadlessApp;
use raykin::render::{Accumulation, FrameStats, RenderSettings};
use raykin::scene::{LoadOptions, Materials, SceneAsset};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// Where the scene came from (what File > Save as re-reads).
#[derive(Clone, Debug)]
pub enum SceneSource {
    File(PathBuf),
    /// The Cornell box built into the binary.
    Embedded,
    /// The animated crowd bench scene, composed from the shared assets folder.
    Crowd(PathBuf),
}

impl SceneSource {
    /// `crowd` names the bench crowd scene unless a file of that name exists.
    pub fn from_arg(arg: Option<&Path>, assets: &Path) -> Self {
        match arg {
            None => Self::Embedded,
            Some(p) if p == Path::new(crate::scenes::CROWD.name) && !p.exists() => {
                Self::Crowd(assets.to_path_buf())
            }
            Some(p) => Self::File(p.to_path_buf()),
        }
    }
}

/// Session options from the command line.
#[derive(Clone, Debug, Default)]
pub struct SessionOptions {
    pub fixed_render_size: Option<(u32, u32)>,
    /// Seconds per frame for animation (scripts and offscreen runs are deterministic); else wall time.
    pub fixed_dt: Option<f32>,
    pub camera: CameraChoice,
    pub animation: Option<String>,
    /// Where settings persist; `None` keeps nothing.
    pub prefs_path: Option<PathBuf>,
    /// Command-line overrides of the persisted render settings.
    pub spp_per_frame: Option<u32>,
    pub max_depth: Option<u32>,
    /// How scene files are read (`--scene`, `--allow-external-files`).
    pub load: LoadOptions,
    /// Real-time or accumulation (default: the settings file's, else real-time while anything moves).
    pub mode: Option<raykin::render::RenderMode>,
    /// OIDN per real-time frame, and its quality (default: the settings file's).
    pub frame_oidn: Option<raykin::render::FrameOidn>,
    pub frame_oidn_quality: Option<raykin::oidn::Quality>,
}

/// Settings as read at start-up.
#[derive(Default)]
pub struct StoredSettings {
    pub prefs: ViewerPrefs,
    /// Why the file could not be used (reported in the panel).
    pub problem: Option<String>,
    /// The settings came from a file (not defaults).
    pub from_file: bool,
}

/// Reads the settings file once (a corrupt one is set aside by [`ViewerPrefs::load`], so it must not be read
/// twice).
pub fn load_settings(options: &SessionOptions) -> StoredSettings {
    let Some(path) = options.prefs_path.as_deref() else {
        return StoredSettings::default();
    };
    match ViewerPrefs::load(path) {
        Ok(Some(prefs)) => StoredSettings {
            prefs,
            problem: None,
            from_file: true,
        },
        Ok(None) => StoredSettings::default(),
        Err(e) => StoredSettings {
            problem: Some(e.to_string()),
            ..Default::default()
        },
    }
}

struct LoadedScene {
    scene: Arc<SceneAsset>,
    players: Vec<(usize, AnimationPlayer)>,
}

fn load(source: &SceneSource, options: &LoadOptions) -> Result<LoadedScene> {
    Ok(match source {
        SceneSource::File(path) => LoadedScene {
            scene: crate::scenes::load_scene(path, options)?,
            players: Vec::new(),
        },
        SceneSource::Embedded => LoadedScene {
            scene: Arc::new(crate::scenes::embedded_scene()?),
            players: Vec::new(),
        },
        SceneSource::Crowd(assets) => {
            let crowd = crate::scenes::CROWD.load(assets)?;
            LoadedScene {
                scene: crowd.scene,
                players: crowd.players,
            }
        }
    })
}

pub struct Session {
    pub ctx: GpuContext,
    pub engine: HeadlessApp,
    pub source: SceneSource,
    pub egui: egui::Context,
    pub options: SessionOptions,
    pub prefs: ViewerPrefs,
    pub quit_requested: bool,
    pub frames: u64,
    last_frame: Option<Instant>,
    recording: Option<super::recording::Recording>,
}

impl Session {
    /// `stored` is what [`load_settings`] read (the settings and a problem to report, if any).
    pub fn new(
        ctx: GpuContext,
        source: SceneSource,
        options: SessionOptions,
        stored: StoredSettings,
    ) -> Result<Self> {
        let StoredSettings {
            mut prefs,
            problem: prefs_problem,
            from_file,
        } = stored;
        // A CPU adapter (lavapipe) traces ~0.1 M rays/s: start at a fraction of the image area so the window
        // stays responsive; a saved setting wins.
        if !from_file && ctx.info.device_type == wgpu::DeviceType::Cpu {
            prefs.render_scale = 0.25;
        }
        if let Some((w, h)) = options.fixed_render_size {
            crate::render_cmd::check_size(&ctx, w, h)?;
        }
        let loaded = load(&source, &options.load)?;
        let engine = build_engine(&ctx, &loaded, &source, &prefs, &options)?;
        let egui = egui::Context::default();
        let mut session = Self {
            ctx,
            engine,
            source,
            egui,
            options,
            prefs,
            quit_requested: false,
            frames: 0,
            last_frame: None,
            recording: None,
        };
        if let Some(problem) = prefs_problem {
            eprintln!("raykin: warning: {problem}");
            session.state_mut().report(Severity::Warning, problem);
        }
        Ok(session)
    }

    pub fn world(&mut self) -> &mut bevy_ecs::world::World {
        self.engine.app.world_mut()
    }

    pub fn state_mut(&mut self) -> bevy_ecs::world::Mut<'_, EditorState> {
        self.world().resource_mut::<EditorState>()
    }

    pub fn scene(&self) -> Arc<SceneAsset> {
        self.engine
            .app
            .world()
            .resource::<raykin::scene::SceneAssets>()
            .0
            .clone()
    }

    /// Loads `path` in place of the current scene; on failure the current scene stays and the editor shows why.
    pub fn open(&mut self, path: &Path) -> Result<(), String> {
        let source = SceneSource::File(path.to_path_buf());
        // A file opened from the window is a new scene: the command line's --scene and --variant were for the
        // first one.
        let options = LoadOptions {
            scene: None,
            variant: None,
            ..self.options.load.clone()
        };
        let result = load(&source, &options)
            .map_err(|e| format!("{e:#}"))
            .and_then(|loaded| {
                // Carry the session's settings over to the new scene.
                self.prefs.capture(self.engine.app.world());
                build_engine(&self.ctx, &loaded, &source, &self.prefs, &self.options)
                    .map_err(|e| format!("{e:#}"))
            });
        match result {
            Ok(engine) => {
                let messages = std::mem::take(&mut self.state_mut().messages);
                self.engine = engine;
                self.source = source;
                let mut state = self.state_mut();
                let kept: Vec<_> = messages
                    .into_iter()
                    .filter(|(s, _)| *s != Severity::Error)
                    .collect();
                state.messages.splice(0..0, kept);
                state.report(Severity::Info, format!("opened {}", path.display()));
                Ok(())
            }
            Err(e) => {
                self.state_mut().report(
                    Severity::Error,
                    format!("{e} (the current scene stays loaded)"),
                );
                Err(e)
            }
        }
    }

    /// Runs the editor UI for this frame and carries out what it asked for.
    pub fn ui(&mut self, raw_input: egui::RawInput) -> egui::FullOutput {
        let start = Instant::now();
        let mut actions = Vec::new();
        let world = self.engine.app.world_mut();
        let output = self.egui.run_ui(raw_input, |ui| {
            actions = raykin::editor::show(ui, world);
        });
        self.world().resource_mut::<ViewerStats>().ui_ms = start.elapsed().as_secs_f64() * 1e3;
        for action in actions {
            self.handle(action);
        }
        output
    }

    fn handle(&mut self, action: EditorAction) {
        match action {
            EditorAction::Open(path) => {
                let _ = self.open(&path);
            }
            EditorAction::SaveAs(path) => {
                let result = self.save_as(&path);
                let mut state = self.state_mut();
                match result {
                    Ok(()) => state.report(Severity::Info, format!("saved {}", path.display())),
                    Err(e) => state.report(Severity::Error, format!("{e:#}")),
                }
            }
            EditorAction::Screenshot(path) => {
                let result = raykin::editor::screenshot::write(self.engine.app.world(), &path);
                let mut state = self.state_mut();
                match result {
                    Ok(info) => state.report(
                        Severity::Info,
                        format!("wrote {} and {}", info.png.display(), info.exr.display()),
                    ),
                    Err(e) => state.report(Severity::Error, e.to_string()),
                }
            }
            EditorAction::Record(request) => self.start_recording(*request),
            EditorAction::StopRecording => {
                if let Some(r) = &self.recording {
                    r.stop();
                }
            }
            EditorAction::Quit => self.quit_requested = true,
        }
    }

    pub fn recording(&self) -> bool {
        self.recording.is_some()
    }

    pub fn start_recording(&mut self, request: raykin::editor::RecordStart) {
        let SceneSource::File(file) = self.source.clone() else {
            return;
        };
        let dir = request.out_dir.clone();
        let scene_index = self.options.load.scene;
        match super::recording::start(&self.ctx, self.scene(), &file, scene_index, request) {
            Ok(recording) => {
                self.recording = Some(recording);
                self.state_mut().recording = Some(format!("recording into {}", dir.display()));
            }
            Err(e) => self.state_mut().report(Severity::Error, format!("{e:#}")),
        }
    }

    /// Follows the recording in progress: its progress line, and its outcome when it ends.
    fn poll_recording(&mut self) {
        let Some(recording) = &mut self.recording else {
            return;
        };
        let progress = recording.progress();
        let finished = recording.finished();
        let dir = recording.dir.clone();
        let mut state = self.world().resource_mut::<EditorState>();
        if let Some(p) = progress {
            state.recording = Some(p);
        }
        let Some(result) = finished else {
            return;
        };
        state.recording = None;
        match result {
            Ok(s) => state.report(
                Severity::Info,
                format!(
                    "recorded {} frame(s) into {} ({} of {} complete{}; manifest {})",
                    s.rendered,
                    dir.display(),
                    s.complete,
                    s.frame_count,
                    if s.interrupted { ", stopped" } else { "" },
                    s.manifest.display()
                ),
            ),
            Err(e) => state.report(Severity::Error, format!("{e:#}")),
        }
        self.recording = None;
    }

    /// File > Save as: the source glTF with the edited materials and lights.
    pub fn save_as(&mut self, out: &Path) -> Result<()> {
        let (bytes, dir, name) = match &self.source {
            SceneSource::File(p) => (
                std::fs::read(p).with_context(|| format!("{}: cannot re-read", p.display()))?,
                p.parent().map(Path::to_path_buf).unwrap_or_default(),
                p.display().to_string(),
            ),
            SceneSource::Embedded => (
                crate::scenes::DEFAULT_SCENE.to_vec(),
                PathBuf::from("."),
                "<embedded default scene>".to_string(),
            ),
            SceneSource::Crowd(_) => {
                anyhow::bail!("the crowd scene is composed from several files and cannot be saved")
            }
        };
        let materials = self.world().resource::<Materials>().0.clone();
        let world = self.world();
        let mut lights: Vec<(usize, raykin::scene::PunctualLight)> = world
            .query::<(&raykin::scene::SceneNode, &raykin::scene::LightSource)>()
            .iter(world)
            .map(|(n, l)| (n.node, l.0.clone()))
            .collect();
        lights.sort_by_key(|(node, _)| *node);
        let access = self.options.load.access();
        raykin::scene::save_edited(&bytes, &dir, &name, access, &materials, Some(&lights), out)?;
        Ok(())
    }

    /// Runs the frame schedule once (animation by this frame's time step) and collects statistics; returns
    /// the GPU statistics of earlier frames that arrived.
    pub fn step(&mut self) -> Vec<raykin::render::GpuFrameStats> {
        let now = Instant::now();
        let measured_dt = self.last_frame.is_some();
        let wall_dt = self
            .last_frame
            .map_or(1.0 / 60.0, |t| now.duration_since(t).as_secs_f64());
        self.last_frame = Some(now);
        let dt = self.options.fixed_dt.unwrap_or((wall_dt as f32).min(0.1));
        self.world().resource_mut::<FrameClock>().delta = dt;
        self.engine.step();
        self.frames += 1;
        self.poll_recording();
        let ctx = self.ctx.clone();
        let cpu_adapter = ctx.info.device_type == wgpu::DeviceType::Cpu;
        let world = self.world();
        let gpu = world.resource_mut::<FrameStats>().poll(&ctx);
        let mut stats = world.resource_mut::<ViewerStats>();
        stats.frames += 1;
        if measured_dt {
            // Smoothed frame time (the first measured frame sets it).
            stats.frame_ms = if stats.frame_ms > 0.0 {
                0.8 * stats.frame_ms + 0.2 * wall_dt * 1e3
            } else {
                wall_dt * 1e3
            };
            stats.fps = 1e3 / stats.frame_ms.max(1e-6);
        }
        if let Some(last) = gpu.last() {
            // A CPU adapter's (lavapipe's) timestamps can miss the compute work: use wall time there.
            stats.rays_per_second = Some(match last.passes {
                Some(p) if p.trace_ms > 0.0 && !cpu_adapter => {
                    last.rays as f64 / (p.trace_ms * 1e-3)
                }
                _ => last.rays as f64 / wall_dt.max(1e-6),
            });
            stats.last_gpu = Some(*last);
        }
        gpu
    }

    /// Samples per pixel in the image the display shows.
    pub fn samples(&self) -> u32 {
        self.engine.samples()
    }

    /// Writes the settings file (when persistence is on).
    pub fn save_prefs(&mut self, window_size: Option<(u32, u32)>) {
        let Some(path) = self.options.prefs_path.clone() else {
            return;
        };
        self.prefs.capture(self.engine.app.world());
        if let Some((w, h)) = window_size {
            (self.prefs.window_width, self.prefs.window_height) = (w, h);
        }
        if let SceneSource::File(p) = &self.source {
            self.prefs.last_scene = Some(p.clone());
        }
        if let Err(e) = self.prefs.save(&path) {
            eprintln!("raykin: warning: {e}");
        }
    }

    /// True when nothing will change without input: accumulation stopped at the sample limit and no
    /// animation plays.
    pub fn idle(&mut self) -> bool {
        let world = self.world();
        let converged = world.resource::<Accumulation>().converged();
        let playing = world
            .query::<&AnimationPlayer>()
            .iter(world)
            .any(|p| p.playing);
        // An OIDN denoise under way must reach the display.
        let denoising = world
            .get_resource::<raykin::oidn::ViewerOidn>()
            .is_some_and(|o| o.busy());
        converged && !playing && self.recording.is_none() && !denoising
    }
}

/// The engine for a loaded scene: the headless frame schedule, plus the editor, camera controller and the
/// display transform each frame.
fn build_engine(
    ctx: &GpuContext,
    loaded: &LoadedScene,
    source: &SceneSource,
    prefs: &ViewerPrefs,
    options: &SessionOptions,
) -> Result<HeadlessApp> {
    let scene = &loaded.scene;
    let settings = RenderSettings {
        spp_per_frame: prefs.spp_per_frame.max(1),
        ..Default::default()
    };
    // The embedded Cornell box is lit by its ceiling light only and framed like `raykin` renders it.
    let camera = match (source, &options.camera) {
        (SceneSource::Embedded, CameraChoice::Auto) => crate::scenes::embedded_camera(),
        // The crowd opens on the bench's fixed view (the automatic framing fits the whole ground).
        (SceneSource::Crowd(_), CameraChoice::Auto) => crate::scenes::CROWD.camera(),
        (_, c) => c.clone(),
    };
    let mut engine = HeadlessApp::new(ctx.clone(), scene.clone(), settings, &camera)?;
    {
        let world = engine.app.world_mut();
        if !loaded.players.is_empty() {
            let root = world
                .query_filtered::<bevy_ecs::entity::Entity, bevy_ecs::query::With<raykin::scene::SceneRoot>>()
                .iter(world)
                .next();
            if let Some(root) = root {
                raykin::animation::attach_players(world, root, &loaded.players);
            }
        }
    }
    engine.app.add_plugins(EditorPlugin);
    engine.app.add_plugins(raykin::oidn::OidnViewerPlugin);
    let world = engine.app.world_mut();
    prefs.apply(world);
    {
        let mut s = world.resource_mut::<RenderSettings>();
        if let Some(n) = options.spp_per_frame {
            s.spp_per_frame = n.max(1);
        }
        if let Some(d) = options.max_depth {
            s.max_depth = d;
        }
        if let Some(mode) = options.mode {
            s.mode = mode;
        }
        if let Some(o) = options.frame_oidn {
            s.realtime.oidn = o;
        }
        if let Some(q) = options.frame_oidn_quality {
            s.realtime.oidn_quality = q;
        }
    }
    if matches!(source, SceneSource::Embedded) {
        world.resource_mut::<RenderSettings>().environment =
            raykin::render::Environment::Constant([0.0; 3]);
    }
    if let Some(name) = &options.animation {
        let clip = raykin::animation::find_clip(scene, name).map_err(anyhow::Error::msg)?;
        for mut player in world.query::<&mut AnimationPlayer>().iter_mut(world) {
            player.clip = clip;
        }
    }
    {
        world.resource_mut::<Accumulation>().display_each_frame = true;
        world.resource_mut::<FrameStats>().enable_async(ctx);
    }
    let notes = engine.notes.clone();
    let world = engine.app.world_mut();
    let mut state = world.resource_mut::<EditorState>();
    state.fixed_render_size = options.fixed_render_size;
    state.can_save = !matches!(source, SceneSource::Crowd(_));
    state.can_record = matches!(source, SceneSource::File(_));
    match (source, &prefs.last_scene) {
        (SceneSource::File(p), _) => state.open_path = p.display().to_string(),
        // Offer the scene of the last session in File > Open.
        (_, Some(last)) => state.open_path = last.display().to_string(),
        _ => {}
    }
    for w in &scene.warnings {
        state.report(Severity::Warning, w.clone());
    }
    for n in notes {
        state.report(Severity::Warning, n);
    }
    Ok(engine)
}

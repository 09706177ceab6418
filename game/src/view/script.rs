//! `raykin view --script FILE`: scripted steps for tests and reproducible captures. One command per line, `#`
//! starts a comment; commands run between frames, after the previous frame is on screen, until a `wait`.
//! docs/VIEWER.md lists the commands.

use super::session::Session;
use anyhow::{Context, Result, bail};
use raykin::animation::AnimationPlayer;
use raykin::camera::{CameraInput, CameraMode, CameraRig};
use raykin::editor::EditorState;
use raykin::render::{
    Accumulation, AovView, DenoiserKind, Environment, RenderMode, RenderSettings, Tonemapper,
};
use raykin::scene::{AlphaMode, Materials};
use std::path::{Path, PathBuf};

/// Most frames a `wait_samples` may take before the script fails (a stuck accumulation must not hang CI).
const MAX_WAIT_FRAMES: u64 = 20_000;

#[derive(Clone, Debug, PartialEq)]
pub enum MaterialEdit {
    BaseColor([f32; 4]),
    Metallic(f32),
    Roughness(f32),
    Emissive([f32; 3]),
    EmissiveStrength(f32),
    AlphaCutoff(f32),
    DoubleSided(bool),
    Revert,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Setting {
    Spp(u32),
    MaxDepth(u32),
    Exposure(f32),
    Tonemapper(Tonemapper),
    View(AovView),
    Sky,
    Env([f32; 3]),
    /// Thin-lens aperture radius (0: pinhole).
    Aperture(f32),
    FocusDistance(f32),
    SampleLimit(u32),
    Seed(u32),
    Mode(RenderMode),
    /// A real-time stage on or off: temporal, gradients, spatial, restir, restir_temporal, restir_spatial,
    /// restir_unbiased.
    Stage(String, bool),
    HistoryCap(u32),
    /// Off, or on with this denoiser (`on`: the default one).
    Denoise(Option<DenoiserKind>),
    DenoiseQuality(raykin::oidn::Quality),
    DenoiseAovs(raykin::oidn::AuxMode),
}

#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    Wait(u64),
    WaitSamples(u32),
    Material(String, MaterialEdit),
    Time(f32),
    Play(bool),
    Camera(CameraMode),
    ResetCamera,
    Pick(u32, u32),
    /// Ctrl+click: focus the lens on the surface at an image pixel.
    Focus(u32, u32),
    Set(Setting),
    Open(PathBuf),
    SaveAs(PathBuf),
    Screenshot(PathBuf),
    CaptureScreen(PathBuf),
    Resize(u32, u32),
    /// The record button: folder, frames, spp, fps.
    Record(PathBuf, u32, u32, f32),
    WaitRecording,
    Quit,
}

/// What only a window can do.
pub trait ScriptHost {
    /// Grabs the whole screen (the X root window) into `path`.
    fn capture_screen(&mut self, path: &Path) -> Result<()>;
    fn resize(&mut self, width: u32, height: u32) -> Result<()>;
    /// Where the window's inside sits on the screen, in pixels.
    fn window_origin(&self) -> Option<(i32, i32)>;
}

fn floats<const N: usize>(args: &[&str]) -> Result<[f32; N]> {
    if args.len() != N {
        bail!("expected {N} number(s), got {}", args.len());
    }
    let mut out = [0.0; N];
    for (o, a) in out.iter_mut().zip(args) {
        *o = a
            .parse::<f32>()
            .ok()
            .filter(|v| v.is_finite())
            .with_context(|| format!("`{a}` is not a finite number"))?;
    }
    Ok(out)
}

fn uint(args: &[&str]) -> Result<u64> {
    match args {
        [a] => a
            .parse::<u64>()
            .with_context(|| format!("`{a}` is not a whole number")),
        _ => bail!("expected one whole number"),
    }
}

fn path(args: &[&str]) -> Result<PathBuf> {
    match args {
        [] => bail!("expected a path"),
        _ => Ok(PathBuf::from(args.join(" "))),
    }
}

fn parse_line(line: &str) -> Result<Option<Command>> {
    let line = line.split('#').next().unwrap_or("").trim();
    let words: Vec<&str> = line.split_whitespace().collect();
    let Some((&name, args)) = words.split_first() else {
        return Ok(None);
    };
    Ok(Some(match name {
        "wait" => Command::Wait(uint(args)?),
        "wait_samples" => Command::WaitSamples(uint(args)? as u32),
        "material" => {
            let [material, param, values @ ..] = args else {
                bail!("usage: material NAME|INDEX PARAMETER VALUE...");
            };
            let edit = match *param {
                "base_color" => match values.len() {
                    3 => {
                        let [r, g, b] = floats::<3>(values)?;
                        MaterialEdit::BaseColor([r, g, b, 1.0])
                    }
                    _ => MaterialEdit::BaseColor(floats::<4>(values)?),
                },
                "metallic" => MaterialEdit::Metallic(floats::<1>(values)?[0]),
                "roughness" => MaterialEdit::Roughness(floats::<1>(values)?[0]),
                "emissive" => MaterialEdit::Emissive(floats::<3>(values)?),
                "emissive_strength" => MaterialEdit::EmissiveStrength(floats::<1>(values)?[0]),
                "alpha_cutoff" => MaterialEdit::AlphaCutoff(floats::<1>(values)?[0]),
                "double_sided" => MaterialEdit::DoubleSided(match values {
                    ["true"] => true,
                    ["false"] => false,
                    _ => bail!("double_sided takes true or false"),
                }),
                "revert" => MaterialEdit::Revert,
                other => bail!(
                    "unknown material parameter `{other}` (base_color, metallic, roughness, emissive, emissive_strength, alpha_cutoff, double_sided, revert)"
                ),
            };
            Command::Material(material.to_string(), edit)
        }
        "time" => Command::Time(floats::<1>(args)?[0]),
        "play" => Command::Play(true),
        "pause" => Command::Play(false),
        "camera" => match args {
            ["orbit"] => Command::Camera(CameraMode::Orbit),
            ["fly"] => Command::Camera(CameraMode::Fly),
            ["reset"] => Command::ResetCamera,
            [i] => Command::Camera(CameraMode::Scene(i.parse().with_context(|| {
                format!("`{i}`: expected orbit, fly, reset or a camera index")
            })?)),
            _ => bail!("usage: camera orbit|fly|reset|INDEX"),
        },
        "pick" => match args {
            [x, y] => Command::Pick(
                x.parse()
                    .with_context(|| format!("`{x}`: a pixel column"))?,
                y.parse().with_context(|| format!("`{y}`: a pixel row"))?,
            ),
            _ => bail!("usage: pick X Y (image pixels)"),
        },
        "focus" => match args {
            [x, y] => Command::Focus(
                x.parse()
                    .with_context(|| format!("`{x}`: a pixel column"))?,
                y.parse().with_context(|| format!("`{y}`: a pixel row"))?,
            ),
            _ => bail!("usage: focus X Y (image pixels)"),
        },
        "set" => {
            let [setting, values @ ..] = args else {
                bail!("usage: set SETTING VALUE");
            };
            Command::Set(match *setting {
                "spp" => Setting::Spp(uint(values)?.max(1) as u32),
                "max_depth" => Setting::MaxDepth(uint(values)? as u32),
                "exposure" => Setting::Exposure(floats::<1>(values)?[0]),
                "sample_limit" => Setting::SampleLimit(uint(values)? as u32),
                "seed" => Setting::Seed(uint(values)? as u32),
                "sky" => Setting::Sky,
                "denoise" => Setting::Denoise(match values {
                    ["on"] => Some(DenoiserKind::default()),
                    ["oidn"] => Some(DenoiserKind::Oidn),
                    ["svgf"] => Some(DenoiserKind::Svgf),
                    ["off"] => None,
                    _ => bail!("denoise: on, off, oidn or svgf"),
                }),
                "denoise_quality" => Setting::DenoiseQuality(match values {
                    [q] => q.parse().map_err(anyhow::Error::msg)?,
                    _ => bail!("denoise_quality: high, balanced or fast"),
                }),
                "denoise_aovs" => Setting::DenoiseAovs(
                    match values {
                        [a] => raykin::oidn::AuxMode::ALL
                            .into_iter()
                            .find(|m| m.name() == *a),
                        _ => None,
                    }
                    .context("denoise_aovs: prefilter, noisy or clean")?,
                ),
                "env" => Setting::Env(floats::<3>(values)?),
                "mode" => Setting::Mode(match values {
                    ["realtime"] => RenderMode::Realtime,
                    ["accumulate"] => RenderMode::Accumulate,
                    _ => bail!("mode: realtime or accumulate"),
                }),
                "history_cap" => Setting::HistoryCap(uint(values)?.clamp(1, 1 << 20) as u32),
                stage if REALTIME_STAGES.contains(&stage) => Setting::Stage(
                    stage.to_string(),
                    match values {
                        ["on"] => true,
                        ["off"] => false,
                        _ => bail!("{stage}: on or off"),
                    },
                ),
                "aperture" => Setting::Aperture(floats::<1>(values)?[0].max(0.0)),
                "focus_distance" => Setting::FocusDistance(floats::<1>(values)?[0].max(1e-3)),
                "tonemapper" => Setting::Tonemapper(match values {
                    ["aces"] => Tonemapper::AcesFitted,
                    ["reinhard"] => Tonemapper::Reinhard,
                    ["clamp"] => Tonemapper::Clamp,
                    _ => bail!("tonemapper: aces, reinhard or clamp"),
                }),
                "view" => Setting::View(match values {
                    ["color"] => AovView::Color,
                    ["albedo"] => AovView::Albedo,
                    ["normal"] => AovView::Normal,
                    ["depth"] => AovView::Depth,
                    _ => bail!("view: color, albedo, normal or depth"),
                }),
                other => bail!(
                    "unknown setting `{other}` (spp, max_depth, exposure, sample_limit, seed, sky, env, tonemapper, view, denoise, denoise_quality, denoise_aovs, mode, history_cap, {})",
                    REALTIME_STAGES.join(", ")
                ),
            })
        }
        "open" => Command::Open(path(args)?),
        "save_as" => Command::SaveAs(path(args)?),
        "screenshot" => Command::Screenshot(path(args)?),
        "capture_screen" => Command::CaptureScreen(path(args)?),
        "resize" => match args {
            [w, h] => Command::Resize(
                w.parse().with_context(|| format!("`{w}`: width"))?,
                h.parse().with_context(|| format!("`{h}`: height"))?,
            ),
            _ => bail!("usage: resize WIDTH HEIGHT"),
        },
        "record" => match args {
            [dir, frames, spp, rest @ ..] if rest.len() <= 1 => Command::Record(
                PathBuf::from(dir),
                uint(&[frames])? as u32,
                uint(&[spp])? as u32,
                match rest {
                    [] => 30.0,
                    fps => floats::<1>(fps)?[0],
                },
            ),
            _ => bail!("usage: record DIR FRAMES SPP [FPS]"),
        },
        "wait_recording" => Command::WaitRecording,
        "quit" => Command::Quit,
        other => bail!("unknown command `{other}`"),
    }))
}

/// Parses a whole script; errors name the file and line.
pub fn parse(text: &str, file: &Path) -> Result<Vec<(usize, Command)>> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let parsed = parse_line(line)
            .with_context(|| format!("{}:{}: `{}`", file.display(), i + 1, line.trim()))?;
        if let Some(c) = parsed {
            out.push((i + 1, c));
        }
    }
    Ok(out)
}

pub fn load(file: &Path) -> Result<Vec<(usize, Command)>> {
    let text = std::fs::read_to_string(file)
        .with_context(|| format!("{}: cannot read the script", file.display()))?;
    parse(&text, file)
}

enum Waiting {
    Nothing,
    Frames(u64),
    Samples { target: u32, frames: u64 },
    Recording,
}

/// Runs a parsed script against a session, a few commands between frames.
pub struct ScriptRunner {
    file: PathBuf,
    commands: Vec<(usize, Command)>,
    next: usize,
    waiting: Waiting,
}

/// What the host should do after [`ScriptRunner::advance`].
#[derive(Debug, PartialEq, Eq)]
pub enum Flow {
    Continue,
    Quit,
}

impl ScriptRunner {
    pub fn new(file: PathBuf, commands: Vec<(usize, Command)>) -> Self {
        Self {
            file,
            commands,
            next: 0,
            waiting: Waiting::Nothing,
        }
    }

    /// Call once per frame, after the frame is displayed: finishes a wait or runs commands up to the next
    /// wait. A script that ends without `quit` quits.
    pub fn advance(&mut self, session: &mut Session, host: &mut dyn ScriptHost) -> Result<Flow> {
        match &mut self.waiting {
            Waiting::Frames(n) if *n > 1 => {
                *n -= 1;
                return Ok(Flow::Continue);
            }
            Waiting::Samples { target, frames } => {
                let samples = session.samples();
                if samples < *target {
                    *frames += 1;
                    if *frames > MAX_WAIT_FRAMES {
                        bail!(
                            "{}: wait_samples {target}: still {samples} after {MAX_WAIT_FRAMES} frames",
                            self.file.display()
                        );
                    }
                    return Ok(Flow::Continue);
                }
            }
            Waiting::Recording if session.recording() => return Ok(Flow::Continue),
            _ => {}
        }
        self.waiting = Waiting::Nothing;
        while let Some((line, command)) = self.commands.get(self.next).cloned() {
            self.next += 1;
            let flow = run(session, host, &command)
                .with_context(|| format!("{}:{line}: {command:?}", self.file.display()))?;
            match flow {
                Step::Next => {}
                Step::Wait(w) => {
                    self.waiting = w;
                    return Ok(Flow::Continue);
                }
                Step::Quit => return Ok(Flow::Quit),
            }
        }
        Ok(Flow::Quit)
    }
}

enum Step {
    Next,
    Wait(Waiting),
    Quit,
}

fn run(session: &mut Session, host: &mut dyn ScriptHost, command: &Command) -> Result<Step> {
    match command {
        Command::Wait(0) => {}
        Command::Wait(n) => return Ok(Step::Wait(Waiting::Frames(*n))),
        Command::WaitSamples(n) => {
            return Ok(Step::Wait(Waiting::Samples {
                target: *n,
                frames: 0,
            }));
        }
        Command::Material(name, edit) => edit_material(session, name, edit)?,
        Command::Time(t) => {
            let world = session.world();
            let mut any = false;
            for mut p in world.query::<&mut AnimationPlayer>().iter_mut(world) {
                p.time = *t;
                p.playing = false;
                any = true;
            }
            if !any {
                bail!("the scene has no animation player");
            }
        }
        Command::Play(on) => {
            let world = session.world();
            for mut p in world.query::<&mut AnimationPlayer>().iter_mut(world) {
                p.playing = *on;
            }
        }
        Command::Camera(mode) => {
            if let CameraMode::Scene(i) = mode {
                let cameras = session
                    .scene()
                    .nodes
                    .iter()
                    .filter(|n| n.camera.is_some())
                    .count();
                if *i >= cameras {
                    bail!("camera {i} does not exist: the scene has {cameras} camera(s)");
                }
            }
            if session.world().get_resource::<CameraRig>().is_none() {
                bail!("no interactive camera");
            }
            raykin::editor::merge_camera_input(
                session.world(),
                CameraInput {
                    set_mode: Some(*mode),
                    ..Default::default()
                },
            );
        }
        Command::ResetCamera => raykin::editor::merge_camera_input(
            session.world(),
            CameraInput {
                reset: true,
                ..Default::default()
            },
        ),
        Command::Pick(x, y) => {
            let world = session.world();
            let hit = raykin::render::picking::pick_pixel(world, *x, *y);
            let mut state = world.resource_mut::<EditorState>();
            state.selection.entity = hit.map(|h| h.entity);
            state.selection.material = hit.and_then(|h| h.material);
            eprintln!("raykin: pick {x} {y}: {hit:?}");
        }
        Command::Focus(x, y) => {
            let world = session.world();
            let depth = raykin::render::picking::depth_at(world, *x, *y).with_context(|| {
                format!("focus {x} {y}: the ray through that pixel leaves the scene")
            })?;
            world.resource_mut::<RenderSettings>().lens.focus_distance = depth;
            eprintln!("raykin: focus {x} {y}: focus distance {depth}");
        }
        Command::Set(setting) => apply_setting(session, setting),
        // As when a file is dropped on the window: a bad file is reported in the panel, the scene stays.
        Command::Open(path) => {
            let _ = session.open(path);
        }
        Command::SaveAs(path) => session.save_as(path)?,
        Command::Screenshot(path) => screenshot(session, host, path)?,
        Command::CaptureScreen(path) => host.capture_screen(path)?,
        Command::Resize(w, h) => host.resize(*w, *h)?,
        Command::Record(dir, frames, spp, fps) => {
            let panel = raykin::editor::RecordSettings {
                out_dir: dir.display().to_string(),
                fps: *fps,
                start: 0.0,
                frames: *frames,
                spp: *spp,
            };
            let start = raykin::editor::record_start(session.world(), &panel);
            session.start_recording(start);
            if !session.recording() {
                bail!("the recording did not start (see the panel's message)");
            }
        }
        Command::WaitRecording => return Ok(Step::Wait(Waiting::Recording)),
        Command::Quit => return Ok(Step::Quit),
    }
    Ok(Step::Next)
}

fn edit_material(session: &mut Session, name: &str, edit: &MaterialEdit) -> Result<()> {
    let scene = session.scene();
    let world = session.world();
    let index = world.resource::<Materials>().find(name).with_context(|| {
        let names: Vec<String> = scene
            .materials
            .iter()
            .enumerate()
            .map(|(i, m)| format!("{i}: `{}`", m.name))
            .collect();
        format!(
            "no material `{name}`; the materials are {}",
            names.join(", ")
        )
    })?;
    let mut materials = world.resource_mut::<Materials>();
    let m = &mut materials.0[index];
    match *edit {
        MaterialEdit::BaseColor(c) => m.base_color = c.into(),
        MaterialEdit::Metallic(v) => m.metallic = v.clamp(0.0, 1.0),
        MaterialEdit::Roughness(v) => m.roughness = v.clamp(0.0, 1.0),
        MaterialEdit::Emissive(c) => m.emissive = glam::Vec3::from(c).max(glam::Vec3::ZERO),
        MaterialEdit::EmissiveStrength(v) => m.emissive_strength = v.max(0.0),
        MaterialEdit::AlphaCutoff(v) => m.alpha_mode = AlphaMode::Mask(v),
        MaterialEdit::DoubleSided(b) => m.double_sided = b,
        MaterialEdit::Revert => *m = scene.materials[index].clone(),
    }
    Ok(())
}

/// The real-time path's switchable stages, by their script names.
const REALTIME_STAGES: &[&str] = &[
    "temporal",
    "gradients",
    "spatial",
    "restir",
    "restir_temporal",
    "restir_spatial",
    "restir_unbiased",
];

/// The setting a stage name switches.
fn stage_flag<'a>(s: &'a mut RenderSettings, stage: &str) -> Option<&'a mut bool> {
    let r = &mut s.realtime;
    Some(match stage {
        "temporal" => &mut r.temporal,
        "gradients" => &mut r.gradients,
        "spatial" => &mut r.spatial,
        "restir" => &mut r.restir.enabled,
        "restir_temporal" => &mut r.restir.temporal,
        "restir_spatial" => &mut r.restir.spatial,
        "restir_unbiased" => &mut r.restir.unbiased,
        _ => return None,
    })
}

fn apply_setting(session: &mut Session, setting: &Setting) {
    let world = session.world();
    if let Setting::SampleLimit(n) = setting {
        world.resource_mut::<EditorState>().sample_limit = *n;
        // The viewport applies it during the UI pass; set it now too so the next frame already stops.
        world.resource_mut::<Accumulation>().sample_limit = (*n > 0).then_some(*n);
        return;
    }
    let mut s = world.resource_mut::<RenderSettings>();
    match *setting {
        Setting::Spp(n) => s.spp_per_frame = n,
        Setting::MaxDepth(n) => s.max_depth = n,
        Setting::Exposure(v) => s.exposure = v,
        Setting::Tonemapper(t) => s.tonemapper = t,
        Setting::View(v) => s.view = v,
        Setting::Sky => s.environment = Environment::Sky,
        Setting::Env(c) => s.environment = Environment::Constant(c),
        Setting::Aperture(r) => s.lens.aperture_radius = r,
        Setting::FocusDistance(d) => s.lens.focus_distance = d,
        Setting::Seed(n) => s.seed = n,
        Setting::Mode(mode) => s.mode = mode,
        Setting::HistoryCap(n) => s.realtime.history_cap = n,
        Setting::Stage(ref stage, on) => {
            if let Some(flag) = stage_flag(&mut s, stage) {
                *flag = on;
            }
        }
        Setting::Denoise(choice) => {
            s.denoise = choice.is_some();
            if let Some(kind) = choice {
                s.denoiser = kind;
            }
        }
        Setting::DenoiseQuality(q) => s.oidn.quality = q,
        Setting::DenoiseAovs(a) => s.oidn.aux = a,
        Setting::SampleLimit(_) => {}
    }
}

/// The app's own screenshot (PNG as displayed, EXR radiance) and a JSON record of the state it shows.
fn screenshot(session: &mut Session, host: &mut dyn ScriptHost, path: &Path) -> Result<()> {
    let info = raykin::editor::screenshot::write(session.engine.app.world(), path)?;
    let frames = session.frames;
    let world = session.world();
    let state = world.resource::<EditorState>();
    let image_rect = state.image_rect_px;
    let messages: Vec<String> = state.messages.iter().map(|(_, m)| m.clone()).collect();
    let mode = world
        .get_resource::<CameraRig>()
        .map(|r| format!("{:?}", r.mode));
    let mut players = world.query::<&AnimationPlayer>();
    let times: Vec<f32> = players.iter(world).map(|p| p.time).collect();
    let scene = world.resource::<raykin::scene::SceneAssets>().0.clone();
    let edited = world.resource::<Materials>().edited(&scene);
    let record = serde_json::json!({
        "png": info.png,
        "exr": info.exr,
        "width": info.width,
        "height": info.height,
        "samples": info.samples,
        "frame": frames,
        "image_rect_px": image_rect,
        "window_origin": host.window_origin(),
        "camera_mode": mode,
        "player_times": times,
        "edited_materials": edited,
        "scene": scene.source,
        "messages": messages,
    });
    let json = path.with_extension("json");
    std::fs::write(&json, serde_json::to_string_pretty(&record)?)
        .with_context(|| format!("{}: cannot write", json.display()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_script_parses_into_commands() {
        let text = "# comment\nwait 3\nmaterial Paint base_color 0 0 1  # blue\ntime 1.5\ncamera 1\ncamera orbit\nset view albedo\nset sample_limit 8\nscreenshot out/a.png\nquit\n";
        let commands = parse(text, Path::new("t.script")).expect("parses");
        let only: Vec<Command> = commands.into_iter().map(|(_, c)| c).collect();
        assert_eq!(
            only,
            vec![
                Command::Wait(3),
                Command::Material(
                    "Paint".into(),
                    MaterialEdit::BaseColor([0.0, 0.0, 1.0, 1.0])
                ),
                Command::Time(1.5),
                Command::Camera(CameraMode::Scene(1)),
                Command::Camera(CameraMode::Orbit),
                Command::Set(Setting::View(AovView::Albedo)),
                Command::Set(Setting::SampleLimit(8)),
                Command::Screenshot("out/a.png".into()),
                Command::Quit,
            ]
        );
    }

    #[test]
    fn errors_name_the_file_and_line() {
        let err = parse(
            "wait 1\nmaterial Paint base_color red 0 0\n",
            Path::new("s.txt"),
        )
        .expect_err("bad number");
        let text = format!("{err:#}");
        assert!(text.contains("s.txt:2"), "{text}");
        assert!(text.contains("`red` is not a finite number"), "{text}");
        let err = parse("teleport 1 2 3\n", Path::new("s.txt")).expect_err("unknown");
        assert!(format!("{err:#}").contains("unknown command `teleport`"));
        assert!(parse("time nan\n", Path::new("s")).is_err());
    }
}

//! `raykin view`: the interactive viewer (winit window, wgpu surface, egui editor) and its offscreen frame
//! loop. docs/VIEWER.md documents controls, the script format and where settings persist.

mod offscreen;
mod recording;
mod script;
mod session;
mod ui_render;
mod window;

use crate::cli::ViewArgs;
use anyhow::Result;
use raykin::camera::CameraChoice;
use session::{SceneSource, SessionOptions};
use std::path::PathBuf;

/// Where viewer settings persist: `$RAYKIN_CONFIG_DIR/viewer.toml`, else the platform's config folder
/// (`~/.config/raykin/viewer.toml` on Linux).
pub fn settings_path() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("RAYKIN_CONFIG_DIR") {
        return Some(PathBuf::from(dir).join("viewer.toml"));
    }
    directories::ProjectDirs::from("", "", "raykin").map(|d| d.config_dir().join("viewer.toml"))
}

/// True when a window can be opened (an X11 or Wayland display is named).
pub fn display_present() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()))
}

pub fn run(args: &ViewArgs) -> Result<()> {
    let source = SceneSource::from_arg(args.scene.as_deref(), &args.assets);
    if let SceneSource::File(p) = &source
        && !p.exists()
    {
        anyhow::bail!("{}: no such scene file", p.display());
    }
    let script = args
        .script
        .as_deref()
        .map(|file| script::load(file).map(|c| script::ScriptRunner::new(file.to_path_buf(), c)))
        .transpose()?;
    let deterministic = args.script.is_some() || args.offscreen;
    let image_size = match (args.image_size, args.offscreen) {
        (Some(s), _) => Some(s),
        (None, true) => Some((640, 360)),
        (None, false) => None,
    };
    let options = SessionOptions {
        fixed_render_size: image_size,
        fixed_dt: args.fixed_dt.or(deterministic.then_some(1.0 / 60.0)),
        camera: args.camera.map_or(CameraChoice::Auto, CameraChoice::Index),
        animation: args.animation.clone(),
        prefs_path: if args.no_settings {
            None
        } else {
            settings_path()
        },
        spp_per_frame: args.spp_per_frame,
        max_depth: args.max_depth,
        load: args.load.options(),
        mode: args.mode.map(Into::into),
        frame_oidn: args.frame_oidn.map(Into::into),
        frame_oidn_quality: args.frame_oidn_quality.map(Into::into),
    };
    if args.offscreen {
        let ctx = crate::adapter::open_gpu()?;
        return offscreen::run(
            ctx,
            offscreen::OffscreenSetup {
                source,
                options,
                frames: args.frames,
                report: args.report.clone(),
                sync_passes: args.sync_passes,
                script,
            },
        );
    }
    window::run(window::WindowSetup {
        source,
        options,
        window_size: args.window_size,
        no_vsync: args.no_vsync,
        script,
    })
}

/// `raykin` with no arguments on a machine with a display: the viewer on the embedded Cornell box. If no
/// window can be opened after all, the headless default render runs instead.
pub fn run_default() -> Result<()> {
    let args = ViewArgs {
        scene: None,
        load: Default::default(),
        script: None,
        offscreen: false,
        frames: 0,
        report: None,
        sync_passes: false,
        image_size: None,
        window_size: None,
        no_vsync: false,
        fixed_dt: None,
        spp_per_frame: None,
        max_depth: None,
        camera: None,
        animation: None,
        assets: PathBuf::from("../shared/assets"),
        no_settings: false,
        mode: None,
        frame_oidn: None,
        frame_oidn_quality: None,
    };
    match run(&args) {
        Err(e) if e.downcast_ref::<window::WindowUnavailable>().is_some() => {
            eprintln!("raykin: {e:#}; rendering out/default.png instead");
            crate::render_cmd::run_default()
        }
        other => other,
    }
}

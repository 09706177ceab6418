//! The viewer window: winit event loop, wgpu surface (resize, vsync on/off), egui input, and one frame per
//! redraw: editor UI -> frame schedule -> UI + image painted to the surface -> present -> script step.

use super::script::{Flow, ScriptHost, ScriptRunner};
use super::session::{SceneSource, Session, SessionOptions};
use super::ui_render::{FramePacer, UiRenderer};
use anyhow::{Context, Result};
use raykin::editor::EditorState;
use raykin::gpu::GpuContext;
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

/// No window could be opened on this display (the caller may fall back to a headless job).
#[derive(Debug)]
pub struct WindowUnavailable(pub String);

impl std::fmt::Display for WindowUnavailable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for WindowUnavailable {}

pub struct WindowSetup {
    pub source: SceneSource,
    pub options: SessionOptions,
    pub window_size: Option<(u32, u32)>,
    pub no_vsync: bool,
    pub script: Option<ScriptRunner>,
}

struct Running {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    egui_state: egui_winit::State,
    ui: UiRenderer,
    session: Session,
    script: Option<ScriptRunner>,
    /// When egui asked to be repainted again (tooltips, animations) while the image is idle.
    repaint_at: Option<Instant>,
    pacer: FramePacer,
}

struct Viewer {
    setup: Option<WindowSetup>,
    running: Option<Running>,
    error: Option<anyhow::Error>,
}

/// Opens the window and runs until it closes (or the script quits).
pub fn run(setup: WindowSetup) -> Result<()> {
    let event_loop = EventLoop::new().map_err(|e| {
        WindowUnavailable(format!(
            "cannot open a window ({e}); `raykin view --offscreen` runs without a display"
        ))
    })?;
    let mut viewer = Viewer {
        setup: Some(setup),
        running: None,
        error: None,
    };
    event_loop
        .run_app(&mut viewer)
        .context("the window's event loop failed")?;
    match viewer.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

fn surface_format(caps: &wgpu::SurfaceCapabilities) -> Option<wgpu::TextureFormat> {
    // egui blends in gamma space: prefer a non-sRGB target (the display pass handles either).
    caps.formats
        .iter()
        .copied()
        .find(|f| {
            matches!(
                f,
                wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
            )
        })
        .or_else(|| caps.formats.first().copied())
}

fn present_mode(vsync: bool) -> wgpu::PresentMode {
    if vsync {
        wgpu::PresentMode::AutoVsync
    } else {
        wgpu::PresentMode::AutoNoVsync
    }
}

impl Viewer {
    fn start(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let Some(setup) = self.setup.take() else {
            return Ok(());
        };
        let stored = super::session::load_settings(&setup.options);
        let (w, h) = setup.window_size.unwrap_or((
            stored.prefs.window_width.max(320),
            stored.prefs.window_height.max(240),
        ));
        let title = match &setup.source {
            SceneSource::File(p) => format!("raykin - {}", p.display()),
            SceneSource::Embedded => "raykin - Cornell box".into(),
            SceneSource::Crowd(_) => "raykin - crowd".into(),
        };
        let window = Arc::new(
            event_loop
                .create_window(
                    Window::default_attributes()
                        .with_title(title)
                        .with_inner_size(winit::dpi::PhysicalSize::new(w, h)),
                )
                .map_err(|e| WindowUnavailable(format!("cannot create the window: {e}")))?,
        );
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            flags: raykin::gpu::instance_flags(),
            ..wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(
                event_loop.owned_display_handle(),
            ))
        });
        let surface = instance.create_surface(window.clone()).map_err(|e| {
            WindowUnavailable(format!(
                "cannot create a drawing surface for the window: {e}"
            ))
        })?;
        let ctx = GpuContext::from_instance(&instance, Some(&surface))?;
        eprintln!("raykin: adapter: {}", ctx.describe());
        let caps = surface.get_capabilities(&ctx.adapter);
        let format = surface_format(&caps).with_context(|| {
            format!(
                "the adapter `{}` cannot present to this window",
                ctx.info.name
            )
        })?;
        let mut session = Session::new(ctx.clone(), setup.source, setup.options, stored)?;
        if setup.no_vsync {
            session.state_mut().vsync = false;
        }
        let vsync = session.world().resource::<EditorState>().vsync;
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: present_mode(vsync),
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            view_formats: Vec::new(),
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(&ctx.device, &config);
        let egui_state = egui_winit::State::new(
            session.egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            window.theme(),
            Some(ctx.limits.max_texture_dimension_2d as usize),
        );
        let ui = UiRenderer::new(&ctx, format);
        self.running = Some(Running {
            window,
            surface,
            config,
            egui_state,
            ui,
            session,
            script: setup.script,
            repaint_at: None,
            pacer: FramePacer::default(),
        });
        Ok(())
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.error.get_or_insert(e);
        event_loop.exit();
    }
}

impl Running {
    fn reconfigure(&mut self) {
        let size = self.window.inner_size();
        self.config.width = size.width.max(1);
        self.config.height = size.height.max(1);
        self.surface
            .configure(&self.session.ctx.device, &self.config);
    }

    /// One frame; returns false when the viewer should close.
    fn redraw(&mut self) -> Result<bool> {
        let raw = self.egui_state.take_egui_input(&self.window);
        let mut output = self.session.ui(raw);
        let platform = std::mem::take(&mut output.platform_output);
        self.egui_state
            .handle_platform_output(&self.window, platform);
        let vsync = self.session.world().resource::<EditorState>().vsync;
        if present_mode(vsync) != self.config.present_mode {
            self.config.present_mode = present_mode(vsync);
            self.reconfigure();
        }
        self.session.step();
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f)
            | wgpu::CurrentSurfaceTexture::Suboptimal(f) => Some(f),
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.reconfigure();
                None
            }
            _ => None,
        };
        self.repaint_at = output
            .viewport_output
            .get(&egui::ViewportId::ROOT)
            .map(|v| v.repaint_delay)
            .filter(|d| *d < Duration::from_secs(3600))
            .map(|d| Instant::now() + d);
        let ctx = self.session.ctx.clone();
        match frame {
            Some(frame) => {
                let view = frame.texture.create_view(&Default::default());
                let size = [self.config.width, self.config.height];
                let image = self.session.engine.view();
                let submission =
                    self.ui
                        .render(&ctx, &self.session.egui, &mut output, &view, size, image);
                ctx.queue.present(frame);
                self.pacer.submitted(&ctx, submission);
            }
            // No surface texture this time (resizing, occluded): the UI still consumes its texture updates.
            None => self.ui.discard(&ctx, &mut output),
        }
        if let Some(&ms) = self.ui.poll_gpu_ms(&ctx).last() {
            self.session
                .world()
                .resource_mut::<raykin::editor::ViewerStats>()
                .ui_gpu_ms = Some(ms);
        }
        if let Some(script) = &mut self.script {
            let mut host = WindowHost {
                window: &self.window,
                ctx: &ctx,
            };
            if script.advance(&mut self.session, &mut host)? == Flow::Quit {
                return Ok(false);
            }
        }
        Ok(!self.session.quit_requested)
    }
}

impl ApplicationHandler for Viewer {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if let Err(e) = self.start(event_loop) {
            self.fail(event_loop, e);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(running) = &mut self.running else {
            return;
        };
        let response = running.egui_state.on_window_event(&running.window, &event);
        match event {
            WindowEvent::CloseRequested => {
                let size = running.window.inner_size();
                running.session.save_prefs(Some((size.width, size.height)));
                event_loop.exit();
            }
            WindowEvent::Resized(_) => {
                running.reconfigure();
                running.window.request_redraw();
            }
            WindowEvent::RedrawRequested => match running.redraw() {
                Ok(true) => {}
                Ok(false) => {
                    let size = running.window.inner_size();
                    running.session.save_prefs(Some((size.width, size.height)));
                    event_loop.exit();
                }
                Err(e) => self.fail(event_loop, e),
            },
            _ => {}
        }
        if response.repaint
            && let Some(running) = &self.running
        {
            running.window.request_redraw();
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(running) = &mut self.running else {
            return;
        };
        // Keep drawing while the image accumulates or animates, or a script runs; idle otherwise.
        if running.script.is_some() || !running.session.idle() {
            running.window.request_redraw();
            event_loop.set_control_flow(ControlFlow::Poll);
        } else {
            match running.repaint_at {
                Some(t) if t <= Instant::now() => running.window.request_redraw(),
                Some(t) => event_loop.set_control_flow(ControlFlow::WaitUntil(t)),
                None => event_loop.set_control_flow(ControlFlow::Wait),
            }
        }
    }
}

struct WindowHost<'a> {
    window: &'a Window,
    ctx: &'a GpuContext,
}

impl ScriptHost for WindowHost<'_> {
    fn capture_screen(&mut self, path: &Path) -> Result<()> {
        // The frame was presented; make sure the GPU (and the present) finished before the X server is read.
        self.ctx.wait_idle();
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)?;
        }
        let status = std::process::Command::new("import")
            .args(["-window", "root"])
            .arg(path)
            .status()
            .context("capture_screen needs ImageMagick's `import` (apt-get install imagemagick)")?;
        anyhow::ensure!(status.success(), "`import -window root` failed: {status}");
        Ok(())
    }

    fn resize(&mut self, width: u32, height: u32) -> Result<()> {
        let _ = self
            .window
            .request_inner_size(winit::dpi::PhysicalSize::new(width, height));
        Ok(())
    }

    fn window_origin(&self) -> Option<(i32, i32)> {
        self.window.inner_position().ok().map(|p| (p.x, p.y))
    }
}

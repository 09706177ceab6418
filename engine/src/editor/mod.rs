//! The egui editor of `raykin view`: panels as functions over the ECS [`World`] and its resources. The host (the
//! viewer's window, or its offscreen loop) owns egui and the frame loop; each frame it calls [`show`] inside
//! an egui pass and carries out the [`EditorAction`]s returned (open, save, screenshot, record, quit), then
//! runs the frame schedule. Everything a panel changes is ordinary ECS data ([`crate::scene::Materials`],
//! [`crate::scene::ActiveVariant`], [`RenderSettings`], [`crate::animation::AnimationPlayer`]s, [`CameraInput`]),
//! so scripted tests drive the same state the panels do.

mod animation_panel;
mod inspector;
mod lights_panel;
mod material_panel;
pub mod prefs;
mod render_panel;
mod scene_tree;
pub mod screenshot;
mod stats_panel;
mod variant_switch;
mod viewport;

pub use prefs::ViewerPrefs;

use crate::animation::AnimationPlayer;
use crate::camera::{CameraInput, CameraMode, CameraRig, CameraView};
use crate::render::{GpuFrameStats, RenderSettings};
use crate::scene::{SceneAssets, SceneRoot};
use bevy_ecs::prelude::*;
use std::path::PathBuf;

/// What the editor has selected: an entity (scene tree, picking) and a material (inspector, picking).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Selection {
    pub entity: Option<Entity>,
    pub material: Option<usize>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Severity {
    Info,
    Warning,
    Error,
}

/// What the editor asks its host to do after this frame's UI.
#[derive(Clone, Debug, PartialEq)]
pub enum EditorAction {
    /// Load a scene file in place of the current one (the current one stays if it fails).
    Open(PathBuf),
    /// Write the scene with the edited materials (.gltf or .glb).
    SaveAs(PathBuf),
    /// Write the displayed image (PNG) and the linear radiance (EXR) beside it.
    Screenshot(PathBuf),
    /// Start a recording with the panel's settings (see [`RecordStart`]).
    Record(Box<RecordStart>),
    /// Stop the recording in progress (frames already written stay; re-running resumes).
    StopRecording,
    Quit,
}

/// The record panel's settings when Record is pressed; the host turns them into a `raykin::record` job.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordStart {
    pub out_dir: PathBuf,
    /// Clip of the first animation player, if any.
    pub clip: Option<usize>,
    pub fps: f32,
    pub start: f32,
    pub frames: u32,
    pub spp: u32,
    /// The view's render settings (size, depth, environment, ...).
    pub settings: RenderSettings,
    pub camera: CameraView,
    /// The scene camera looked through, if any (recorded following its node).
    pub scene_camera: Option<usize>,
}

/// Editor state that is not scene data.
#[derive(Resource)]
pub struct EditorState {
    pub selection: Selection,
    pub messages: Vec<(Severity, String)>,
    pub open_path: String,
    pub save_path: String,
    pub screenshot_path: String,
    /// Render resolution as a fraction of the image area (ignored with a fixed size).
    pub render_scale: f32,
    /// A fixed render size (`--image-size`, the offscreen loop); else the image area sets it.
    pub fixed_render_size: Option<(u32, u32)>,
    /// Where the image was drawn last frame, in window pixels: x, y, width, height.
    pub image_rect_px: Option<[f32; 4]>,
    /// Stop tracing at this many samples per pixel (0: never stop).
    pub sample_limit: u32,
    pub vsync: bool,
    /// The scene can be recorded (it came from a file, whose hash the recording's manifest keeps).
    pub can_record: bool,
    pub record: RecordSettings,
    /// Progress of the recording in progress, shown in the record section (`None`: none runs).
    pub recording: Option<String>,
    /// The loaded scene came from one glTF file, so File > Save as can write it back.
    pub can_save: bool,
    pub show_panel: bool,
}

#[derive(Clone, Debug, PartialEq)]
pub struct RecordSettings {
    pub out_dir: String,
    pub fps: f32,
    pub start: f32,
    pub frames: u32,
    pub spp: u32,
}

impl Default for EditorState {
    fn default() -> Self {
        Self {
            selection: Selection::default(),
            messages: Vec::new(),
            open_path: String::new(),
            save_path: "edited.glb".into(),
            screenshot_path: "screenshots/raykin.png".into(),
            render_scale: 1.0,
            fixed_render_size: None,
            image_rect_px: None,
            sample_limit: 0,
            vsync: true,
            can_record: false,
            recording: None,
            record: RecordSettings {
                out_dir: "recording".into(),
                fps: 30.0,
                start: 0.0,
                frames: 60,
                spp: 64,
            },
            can_save: false,
            show_panel: true,
        }
    }
}

impl EditorState {
    pub fn report(&mut self, severity: Severity, message: impl Into<String>) {
        let message = message.into();
        match severity {
            Severity::Error => tracing::error!("{message}"),
            Severity::Warning => tracing::warn!("{message}"),
            Severity::Info => tracing::info!("{message}"),
        }
        self.messages.push((severity, message));
        // Keep the panel readable in long sessions.
        if self.messages.len() > 20 {
            self.messages.remove(0);
        }
    }
}

/// Frame-loop figures the host measures (the GPU ones arrive a frame or two late).
#[derive(Resource, Clone, Debug, Default)]
pub struct ViewerStats {
    pub fps: f64,
    pub frame_ms: f64,
    /// CPU time of the editor UI pass.
    pub ui_ms: f64,
    /// GPU time of the UI + display pass, where timestamps are supported.
    pub ui_gpu_ms: Option<f64>,
    pub last_gpu: Option<GpuFrameStats>,
    /// Rays per second of trace time (GPU timestamps), else per second of wall time.
    pub rays_per_second: Option<f64>,
    pub frames: u64,
}

/// Editor resources, the camera controller, and animation players on every scene copy that has none, so
/// an animated file plays as soon as it opens. Add after the scene, render and camera view are set up.
pub struct EditorPlugin;

impl bevy_app::Plugin for EditorPlugin {
    fn build(&self, app: &mut bevy_app::App) {
        app.init_resource::<EditorState>()
            .init_resource::<ViewerStats>()
            .add_plugins(crate::camera::CameraControllerPlugin);
        let world = app.world_mut();
        let scene = world.resource::<SceneAssets>().0.clone();
        if world.get_resource::<CameraRig>().is_none()
            && let Some(view) = world.get_resource::<CameraView>().copied()
        {
            // Walks every vertex: once.
            let bounds = scene.rest_bounds();
            let extent = bounds.map_or(1.0, |(lo, hi)| (hi - lo).length() * 0.5);
            let has_cameras = scene.nodes.iter().any(|n| n.camera.is_some());
            let mode = if has_cameras {
                CameraMode::Scene(0)
            } else {
                CameraMode::Orbit
            };
            // Orbit around the scene's centre when the view frames it.
            let mut rig = CameraRig::new(view, mode, extent.max(1e-3));
            if let Some((lo, hi)) = bounds {
                rig.distance = view.position().distance((lo + hi) * 0.5).max(1e-3);
                rig.set_from_view(&view);
            }
            world.insert_resource(rig);
        }
        if !scene.animations.is_empty() {
            let has_players = world
                .query::<&AnimationPlayer>()
                .iter(world)
                .next()
                .is_some();
            if !has_players {
                let roots: Vec<Entity> = world
                    .query_filtered::<Entity, With<SceneRoot>>()
                    .iter(world)
                    .collect();
                for root in roots {
                    world.entity_mut(root).insert(AnimationPlayer::new(0));
                }
            }
        }
    }
}

/// Draws the whole editor (menu bar, side panel, image area) into the root `ui` for this frame.
pub fn show(ui: &mut egui::Ui, world: &mut World) -> Vec<EditorAction> {
    let mut actions = Vec::new();
    world.resource_scope(|world, mut state: Mut<EditorState>| {
        menu_bar(ui, &mut state, &mut actions);
        if state.show_panel {
            egui::Panel::right("raykin editor")
                .default_size(300.0)
                .size_range(220.0..=480.0)
                .resizable(true)
                .show(ui, |ui| {
                    egui::ScrollArea::vertical().show(ui, |ui| {
                        side_panel(ui, world, &mut state, &mut actions);
                    });
                });
        }
        egui::CentralPanel::no_frame().show(ui, |ui| {
            viewport::show(ui, world, &mut state);
        });
        let dropped: Vec<PathBuf> = ui.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .filter(|p| !p.as_os_str().is_empty())
                .collect()
        });
        actions.extend(dropped.into_iter().map(EditorAction::Open));
    });
    actions
}

fn menu_bar(ui: &mut egui::Ui, state: &mut EditorState, actions: &mut Vec<EditorAction>) {
    egui::Panel::top("raykin menu").show(ui, |ui| {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                ui.label("Open (.gltf/.glb; or drop a file on the window)");
                ui.horizontal(|ui| {
                    ui.text_edit_singleline(&mut state.open_path);
                    if ui.button("Open").clicked() && !state.open_path.trim().is_empty() {
                        actions.push(EditorAction::Open(state.open_path.trim().into()));
                    }
                });
                ui.separator();
                ui.label("Save as (.gltf/.glb) with the edited materials");
                ui.add_enabled_ui(state.can_save, |ui| {
                    ui.horizontal(|ui| {
                        ui.text_edit_singleline(&mut state.save_path);
                        if ui.button("Save").clicked() && !state.save_path.trim().is_empty() {
                            actions.push(EditorAction::SaveAs(state.save_path.trim().into()));
                        }
                    });
                });
                ui.separator();
                ui.label("Screenshot (PNG as shown + EXR radiance)");
                ui.horizontal(|ui| {
                    ui.text_edit_singleline(&mut state.screenshot_path);
                    if ui.button("Save").clicked() && !state.screenshot_path.trim().is_empty() {
                        actions.push(EditorAction::Screenshot(
                            state.screenshot_path.trim().into(),
                        ));
                    }
                });
                ui.separator();
                if ui.button("Quit").clicked() {
                    actions.push(EditorAction::Quit);
                }
            });
            ui.menu_button("View", |ui| {
                ui.checkbox(&mut state.show_panel, "Editor panel");
            });
        });
    });
}

fn side_panel(
    ui: &mut egui::Ui,
    world: &mut World,
    state: &mut EditorState,
    actions: &mut Vec<EditorAction>,
) {
    if !state.messages.is_empty() {
        let mut dismiss = None;
        for (i, (severity, text)) in state.messages.iter().enumerate() {
            let color = match severity {
                Severity::Error => egui::Color32::from_rgb(255, 110, 100),
                Severity::Warning => egui::Color32::from_rgb(240, 200, 80),
                Severity::Info => ui.visuals().text_color(),
            };
            ui.horizontal(|ui| {
                if ui.small_button("x").clicked() {
                    dismiss = Some(i);
                }
                ui.colored_label(color, text);
            });
        }
        if let Some(i) = dismiss {
            state.messages.remove(i);
        }
        ui.separator();
    }
    let source = world.resource::<SceneAssets>().0.source.clone();
    ui.label(egui::RichText::new(source).strong());
    egui::CollapsingHeader::new("Scene")
        .default_open(true)
        .show(ui, |ui| scene_tree::show(ui, world, state));
    egui::CollapsingHeader::new("Selection")
        .default_open(true)
        .show(ui, |ui| inspector::show(ui, world, state));
    egui::CollapsingHeader::new("Material")
        .default_open(true)
        .show(ui, |ui| {
            variant_switch::show(ui, world);
            material_panel::show(ui, world, state);
        });
    egui::CollapsingHeader::new("Lights")
        .default_open(false)
        .show(ui, |ui| lights_panel::show(ui, world, state));
    egui::CollapsingHeader::new("Animation")
        .default_open(true)
        .show(ui, |ui| animation_panel::show(ui, world));
    egui::CollapsingHeader::new("Camera")
        .default_open(false)
        .show(ui, |ui| camera_section(ui, world, state));
    egui::CollapsingHeader::new("Render")
        .default_open(false)
        .show(ui, |ui| render_panel::show(ui, world, state));
    egui::CollapsingHeader::new("Stats")
        .default_open(true)
        .show(ui, |ui| stats_panel::show(ui, world));
    egui::CollapsingHeader::new("Record")
        .default_open(false)
        .show(ui, |ui| record_section(ui, world, state, actions));
}

fn camera_section(ui: &mut egui::Ui, world: &mut World, state: &EditorState) {
    let scene = world.resource::<SceneAssets>().0.clone();
    let Some(mut rig) = world.get_resource::<CameraRig>().cloned() else {
        ui.label("no interactive camera");
        return;
    };
    let mut input = CameraInput::default();
    ui.horizontal(|ui| {
        if ui
            .selectable_label(rig.mode == CameraMode::Orbit, "Orbit")
            .clicked()
        {
            input.set_mode = Some(CameraMode::Orbit);
        }
        if ui
            .selectable_label(rig.mode == CameraMode::Fly, "Fly")
            .clicked()
        {
            input.set_mode = Some(CameraMode::Fly);
        }
    });
    let mut camera_nodes: Vec<usize> = (0..scene.nodes.len())
        .filter(|&n| scene.nodes[n].camera.is_some())
        .collect();
    camera_nodes.sort();
    for (i, node) in camera_nodes.iter().enumerate() {
        let name = &scene.nodes[*node].name;
        let label = if name.is_empty() {
            format!("Camera {i}")
        } else {
            format!("Camera {i}: {name}")
        };
        if ui
            .selectable_label(rig.mode == CameraMode::Scene(i), label)
            .clicked()
        {
            input.set_mode = Some(CameraMode::Scene(i));
        }
    }
    ui.horizontal(|ui| {
        if ui.button("Reset (Home)").clicked() {
            input.reset = true;
        }
        if ui.button("Frame selection (F)").clicked() {
            input.frame = viewport::selection_bounds(world, state);
        }
    });
    let before = rig.clone();
    ui.add(
        egui::Slider::new(&mut rig.move_speed, 0.001..=1000.0)
            .logarithmic(true)
            .text("move speed /s"),
    );
    let mut fov = rig.yfov.to_degrees();
    if ui
        .add(egui::Slider::new(&mut fov, 5.0..=120.0).text("vertical fov"))
        .changed()
    {
        rig.yfov = fov.to_radians();
    }
    lens_rows(ui, world);
    ui.add(
        egui::Label::new(
            "Drag: look/orbit; right or middle drag: pan; wheel: zoom (orbit) or speed (fly); WASD/QE: move; Shift: faster; click: select; Ctrl+click: focus the lens there",
        )
        .wrap(),
    );
    if rig != before {
        world.insert_resource(rig);
    }
    if input != CameraInput::default() {
        merge_camera_input(world, input);
    }
}

/// The thin lens: aperture radius (0: pinhole) and focus distance; edits restart accumulation next frame.
fn lens_rows(ui: &mut egui::Ui, world: &mut World) {
    let mut lens = world.resource::<RenderSettings>().lens;
    let before = lens;
    ui.horizontal(|ui| {
        ui.label("aperture radius");
        ui.add(
            egui::DragValue::new(&mut lens.aperture_radius)
                .speed(0.001)
                .range(0.0..=1.0e3),
        )
        .on_hover_text("scene units (glTF: metres); 0 is a pinhole");
    });
    ui.horizontal(|ui| {
        ui.label("focus distance");
        ui.add(
            egui::DragValue::new(&mut lens.focus_distance)
                .speed(0.01)
                .range(1.0e-3..=1.0e6),
        )
        .on_hover_text("along the view axis; Ctrl+click the image to focus on a surface");
    });
    if lens != before {
        world.resource_mut::<RenderSettings>().lens = lens;
    }
}

/// Adds `input` to this frame's camera input (the viewport may have written some already).
pub fn merge_camera_input(world: &mut World, input: CameraInput) {
    let mut current = world.get_resource_or_insert_with(CameraInput::default);
    current.rotate += input.rotate;
    current.pan += input.pan;
    current.scroll += input.scroll;
    current.movement += input.movement;
    current.fast |= input.fast;
    current.dt = current.dt.max(input.dt);
    current.reset |= input.reset;
    if input.frame.is_some() {
        current.frame = input.frame;
    }
    if input.set_mode.is_some() {
        current.set_mode = input.set_mode;
    }
}

fn record_section(
    ui: &mut egui::Ui,
    world: &mut World,
    state: &mut EditorState,
    actions: &mut Vec<EditorAction>,
) {
    if let Some(progress) = &state.recording {
        ui.label(progress.as_str());
        if ui.button("Stop").clicked() {
            actions.push(EditorAction::StopRecording);
        }
        return;
    }
    if !state.can_record {
        ui.label("Only scenes opened from a .gltf/.glb file can be recorded.");
        return;
    }
    let r = &mut state.record;
    egui::Grid::new("record").num_columns(2).show(ui, |ui| {
        ui.label("folder");
        ui.text_edit_singleline(&mut r.out_dir);
        ui.end_row();
        ui.label("fps");
        ui.add(egui::DragValue::new(&mut r.fps).range(1.0..=240.0));
        ui.end_row();
        ui.label("start (s)");
        ui.add(
            egui::DragValue::new(&mut r.start)
                .speed(0.01)
                .range(0.0..=1e6),
        );
        ui.end_row();
        ui.label("frames");
        ui.add(egui::DragValue::new(&mut r.frames).range(1..=1_000_000));
        ui.end_row();
        ui.label("spp");
        ui.add(egui::DragValue::new(&mut r.spp).range(1..=65536));
        ui.end_row();
    });
    ui.add(
        egui::Label::new(
            "Frames are rendered at the view's size and settings from the current camera (raykin record: resumable, \
             same files as the CLI).",
        )
        .wrap(),
    );
    if ui.button("Record").clicked() {
        actions.push(EditorAction::Record(Box::new(record_start(world, r))));
    }
}

/// What Record starts: the panel's `settings` with the world's clip, camera and render settings.
pub fn record_start(world: &mut World, settings: &RecordSettings) -> RecordStart {
    let clip = world
        .query::<&AnimationPlayer>()
        .iter(world)
        .next()
        .map(|p| p.clip);
    let scene_camera = match world.get_resource::<CameraRig>().map(|r| r.mode) {
        Some(CameraMode::Scene(i)) => Some(i),
        _ => None,
    };
    RecordStart {
        out_dir: settings.out_dir.clone().into(),
        clip,
        fps: settings.fps,
        start: settings.start,
        frames: settings.frames,
        spp: settings.spp,
        settings: world.resource::<RenderSettings>().clone(),
        camera: *world.resource::<CameraView>(),
        scene_camera,
    }
}

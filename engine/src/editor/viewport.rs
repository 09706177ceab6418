//! The image area: sets the render size from the space the panels leave, draws the tone-mapped image there
//! (a paint callback of the display pass), and turns mouse and keyboard input over it into camera movement
//! and picking.

use super::{EditorState, merge_camera_input, scene_tree};
use crate::camera::CameraInput;
use crate::render::gpu_scene::transform_box;
use crate::render::passes::display::ImageCallback;
use crate::render::{Accumulation, GpuScene, RenderSettings};
use crate::scene::{GlobalTransform, MeshInstance, SkinnedMesh};
use bevy_ecs::hierarchy::Children;
use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};

/// The render size for an image area of `area_px` pixels.
pub fn render_size(state: &EditorState, area_px: egui::Vec2) -> (u32, u32) {
    state.fixed_render_size.unwrap_or_else(|| {
        let s = state.render_scale.clamp(0.05, 1.0);
        (
            ((area_px.x * s).floor() as u32).max(1),
            ((area_px.y * s).floor() as u32).max(1),
        )
    })
}

/// Where an image of `image` pixels goes in `area` (pixels): centred, scaled by a whole factor when it fits
/// (pixel-exact), shrunk to fit when it does not; snapped to whole pixels.
pub fn image_rect(area: egui::Rect, image: (u32, u32)) -> egui::Rect {
    let (w, h) = (image.0.max(1) as f32, image.1.max(1) as f32);
    let fit = (area.width() / w).min(area.height() / h);
    let scale = if fit >= 1.0 { fit.floor() } else { fit };
    let size = egui::vec2((w * scale).round(), (h * scale).round());
    let min = (area.center() - size * 0.5).round();
    egui::Rect::from_min_size(min, size)
}

pub fn show(ui: &mut egui::Ui, world: &mut World, state: &mut EditorState) {
    let ppp = ui.ctx().pixels_per_point();
    let area = ui.available_rect_before_wrap();
    let area_px = egui::Rect::from_min_max(
        (area.min.to_vec2() * ppp).round().to_pos2(),
        (area.max.to_vec2() * ppp).round().to_pos2(),
    );
    let size = render_size(state, area_px.size());
    {
        let settings = world.resource::<RenderSettings>();
        if (settings.width, settings.height) != size {
            let mut settings = world.resource_mut::<RenderSettings>();
            (settings.width, settings.height) = size;
        }
    }
    let limit = (state.sample_limit > 0).then_some(state.sample_limit);
    if world.resource::<Accumulation>().sample_limit != limit {
        world.resource_mut::<Accumulation>().sample_limit = limit;
    }
    let rect_px = image_rect(area_px, size);
    state.image_rect_px = Some([
        rect_px.min.x,
        rect_px.min.y,
        rect_px.width(),
        rect_px.height(),
    ]);
    let rect = egui::Rect::from_min_max(
        (rect_px.min.to_vec2() / ppp).to_pos2(),
        (rect_px.max.to_vec2() / ppp).to_pos2(),
    );
    ui.painter().add(egui_wgpu::Callback::new_paint_callback(
        rect,
        ImageCallback {
            rect_px: [
                rect_px.min.x,
                rect_px.min.y,
                rect_px.width(),
                rect_px.height(),
            ],
        },
    ));
    let response = ui.interact(
        area,
        ui.scope_id().with("image area"),
        egui::Sense::click_and_drag(),
    );
    let mut input = CameraInput::default();
    if response.dragged_by(egui::PointerButton::Primary) {
        input.rotate = to_vec2(response.drag_delta() * ppp);
    }
    if response.dragged_by(egui::PointerButton::Secondary)
        || response.dragged_by(egui::PointerButton::Middle)
    {
        input.pan = to_vec2(response.drag_delta() * ppp);
    }
    if response.hovered() {
        input.scroll = ui.input(|i| i.smooth_scroll_delta.y) / 50.0;
    }
    if response.clicked()
        && let Some(pos) = response.interact_pointer_pos()
        && rect.contains(pos)
    {
        let local = (pos - rect.min) / rect.size();
        let (x, y) = (
            (local.x * size.0 as f32) as u32,
            (local.y * size.1 as f32) as u32,
        );
        if ui.input(|i| i.modifiers.command) {
            // Ctrl+click: focus the lens on the surface under the cursor.
            match crate::render::picking::depth_at(world, x, y) {
                Some(depth) => world.resource_mut::<RenderSettings>().lens.focus_distance = depth,
                None => state.report(
                    super::Severity::Info,
                    "nothing to focus on there: the ray leaves the scene",
                ),
            }
        } else {
            match crate::render::picking::pick_pixel(world, x, y) {
                Some(hit) => {
                    scene_tree::select(world, state, hit.entity);
                    state.selection.material = hit.material.or(state.selection.material);
                }
                None => state.selection = Default::default(),
            }
        }
    }
    // Keys move the camera unless a text field has the keyboard.
    if !ui.ctx().egui_wants_keyboard_input() {
        use egui::Key;
        ui.input(|i| {
            let axis = |plus: Key, minus: Key| {
                i.key_down(plus) as i32 as f32 - i.key_down(minus) as i32 as f32
            };
            input.movement = Vec3::new(
                axis(Key::D, Key::A),
                axis(Key::E, Key::Q),
                axis(Key::W, Key::S),
            );
            input.fast = i.modifiers.shift;
            input.dt = i.stable_dt.min(0.1);
            input.reset = i.key_pressed(Key::Home);
        });
        if ui.input(|i| i.key_pressed(egui::Key::F)) {
            input.frame = selection_bounds(world, state);
        }
    }
    if input != CameraInput::default() {
        merge_camera_input(world, input);
    }
    let hovering_files = ui.input(|i| !i.raw.hovered_files.is_empty());
    if hovering_files {
        ui.painter().text(
            area.center(),
            egui::Align2::CENTER_CENTER,
            "Drop a .gltf or .glb to open it",
            egui::FontId::proportional(18.0),
            egui::Color32::WHITE,
        );
    }
}

fn to_vec2(v: egui::Vec2) -> Vec2 {
    Vec2::new(v.x, v.y)
}

/// World bounds of the selected entity's meshes (and its descendants'), for framing.
pub fn selection_bounds(world: &World, state: &EditorState) -> Option<(Vec3, Vec3)> {
    bounds_below(world, state.selection.entity?)
}

fn bounds_below(world: &World, entity: Entity) -> Option<(Vec3, Vec3)> {
    let gpu_scene = world.get_resource::<GpuScene>()?;
    let mut lo = Vec3::MAX;
    let mut hi = Vec3::MIN;
    let mut stack = vec![entity];
    while let Some(e) = stack.pop() {
        if let (Some(mesh), Some(global)) = (
            world.get::<MeshInstance>(e),
            world.get::<GlobalTransform>(e),
        ) && let Some(slot) = gpu_scene.mesh_slots.get(mesh.mesh)
        {
            let (a, b) = slot
                .deformed_bounds
                .unwrap_or_else(|| slot.blas.root_bounds());
            let m = if world.get::<SkinnedMesh>(e).is_some() {
                glam::Mat4::IDENTITY
            } else {
                global.0
            };
            let (a, b) = transform_box(m, a, b);
            lo = lo.min(a);
            hi = hi.max(b);
        }
        if let Some(children) = world.get::<Children>(e) {
            stack.extend(children.iter());
        }
    }
    if lo.cmple(hi).all() {
        return Some((lo, hi));
    }
    // A node without meshes: a small box around its position.
    let p = world.get::<GlobalTransform>(entity)?.0.w_axis.truncate();
    Some((p - Vec3::splat(0.5), p + Vec3::splat(0.5)))
}

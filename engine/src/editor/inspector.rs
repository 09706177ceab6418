//! The selected entity's components: transform (editable), world position, mesh, skin, morph weights,
//! light (editable), camera.

use super::EditorState;
use super::scene_tree::entity_name;
use crate::camera::{CameraInput, CameraMode};
use crate::scene::{
    CameraComponent, GlobalTransform, MeshInstance, MorphWeights, SceneAssets, SceneNode,
    SkinnedMesh, Transform,
};
use bevy_ecs::prelude::*;
use glam::{EulerRot, Quat};

pub fn show(ui: &mut egui::Ui, world: &mut World, state: &mut EditorState) {
    let Some(entity) = state
        .selection
        .entity
        .filter(|&e| world.get_entity(e).is_ok())
    else {
        ui.label("Nothing selected: click the image or a node in the scene tree.");
        return;
    };
    let scene = world.resource::<SceneAssets>().0.clone();
    ui.label(egui::RichText::new(entity_name(world, entity)).strong());
    if let Some(mut t) = world.get::<Transform>(entity).copied() {
        let before = t;
        egui::Grid::new("transform").num_columns(4).show(ui, |ui| {
            ui.label("translation");
            for v in t.translation.as_mut() {
                ui.add(egui::DragValue::new(v).speed(0.01));
            }
            ui.end_row();
            ui.label("rotation (deg)");
            let (y, x, z) = t.rotation.to_euler(EulerRot::YXZ);
            let mut euler = [x.to_degrees(), y.to_degrees(), z.to_degrees()];
            let mut rotated = false;
            for v in &mut euler {
                rotated |= ui.add(egui::DragValue::new(v).speed(0.5)).changed();
            }
            if rotated {
                t.rotation = Quat::from_euler(
                    EulerRot::YXZ,
                    euler[1].to_radians(),
                    euler[0].to_radians(),
                    euler[2].to_radians(),
                );
            }
            ui.end_row();
            ui.label("scale");
            for v in t.scale.as_mut() {
                ui.add(egui::DragValue::new(v).speed(0.01));
            }
            ui.end_row();
        });
        if t != before
            && let Some(mut current) = world.get_mut::<Transform>(entity)
        {
            *current = t;
        }
    }
    if let Some(g) = world.get::<GlobalTransform>(entity) {
        let p = g.0.w_axis;
        ui.label(format!("world position {:.3}, {:.3}, {:.3}", p.x, p.y, p.z));
    }
    if let Some(mesh) = world.get::<MeshInstance>(entity).copied()
        && let Some(data) = scene.meshes.get(mesh.mesh)
    {
        ui.label(format!(
            "mesh `{}`: {} triangles, {} vertices",
            data.name,
            data.triangles.len(),
            data.vertex_count()
        ));
        ui.horizontal_wrapped(|ui| {
            ui.label("materials:");
            let mut used: Vec<u32> = data.primitives.iter().map(|p| p.material).collect();
            used.dedup();
            for m in used {
                let name = scene
                    .materials
                    .get(m as usize)
                    .map_or("default".to_string(), |m| m.name.clone());
                if (m as usize) < scene.materials.len()
                    && ui
                        .selectable_label(state.selection.material == Some(m as usize), name)
                        .clicked()
                {
                    state.selection.material = Some(m as usize);
                }
            }
        });
    }
    if let Some(skin) = world.get::<SkinnedMesh>(entity)
        && let Some(data) = scene.skins.get(skin.skin)
    {
        ui.label(format!(
            "skin `{}`: {} joints",
            data.name,
            data.joints.len()
        ));
    }
    if let Some(mut weights) = world.get::<MorphWeights>(entity).cloned() {
        let before = weights.clone();
        ui.label("morph weights");
        for (i, w) in weights.0.iter_mut().enumerate() {
            ui.add(egui::Slider::new(w, 0.0..=1.0).text(format!("target {i}")));
        }
        if weights != before
            && let Some(mut current) = world.get_mut::<MorphWeights>(entity)
        {
            *current = weights;
        }
    }
    super::lights_panel::light_inspector(ui, world, entity);
    if let Some(camera) = world.get::<CameraComponent>(entity).copied() {
        ui.label(format!(
            "camera: vertical fov {:.1} deg",
            camera.yfov.to_degrees()
        ));
        // Scene cameras are numbered in node order (as `CameraMode::Scene` counts them).
        let node = world.get::<SceneNode>(entity).map_or(0, |n| n.node);
        let index = scene.nodes[..node.min(scene.nodes.len())]
            .iter()
            .filter(|n| n.camera.is_some())
            .count();
        if ui.button("Look through this camera").clicked() {
            super::merge_camera_input(
                world,
                CameraInput {
                    set_mode: Some(CameraMode::Scene(index)),
                    ..Default::default()
                },
            );
        }
    }
}

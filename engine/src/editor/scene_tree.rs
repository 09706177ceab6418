//! The scene tree: every spawned scene copy and its node hierarchy; clicking a node selects it.

use super::EditorState;
use crate::scene::{SceneAssets, SceneNode, SceneRoot};
use bevy_ecs::hierarchy::Children;
use bevy_ecs::prelude::*;

/// Children shown per node before the list is cut (crowds have thousands of nodes).
const MAX_CHILDREN_SHOWN: usize = 200;

/// The display name of an entity: its glTF node name, else its kind and index.
pub fn entity_name(world: &World, entity: Entity) -> String {
    let scene = &world.resource::<SceneAssets>().0;
    if let Some(node) = world.get::<SceneNode>(entity) {
        let name = scene.nodes.get(node.node).map_or("", |n| n.name.as_str());
        return if name.is_empty() {
            format!("node {}", node.node)
        } else {
            name.to_string()
        };
    }
    if world.get::<SceneRoot>(entity).is_some() {
        return "scene".into();
    }
    format!("{entity}")
}

pub fn show(ui: &mut egui::Ui, world: &mut World, state: &mut EditorState) {
    let roots: Vec<Entity> = world
        .query_filtered::<Entity, With<SceneRoot>>()
        .iter(world)
        .collect();
    if roots.len() > 1 {
        ui.label(format!("{} scene copies", roots.len()));
    }
    egui::ScrollArea::vertical()
        .id_salt("scene tree")
        .max_height(220.0)
        .show(ui, |ui| {
            for root in roots.into_iter().take(MAX_CHILDREN_SHOWN) {
                node_ui(ui, world, state, root);
            }
        });
}

fn node_ui(ui: &mut egui::Ui, world: &World, state: &mut EditorState, entity: Entity) {
    let name = entity_name(world, entity);
    let selected = state.selection.entity == Some(entity);
    let children: Vec<Entity> = world
        .get::<Children>(entity)
        .map(|c| c.iter().collect())
        .unwrap_or_default();
    if children.is_empty() {
        if ui.selectable_label(selected, name).clicked() {
            select(world, state, entity);
        }
        return;
    }
    let id = ui.make_persistent_id(entity);
    egui::collapsing_header::CollapsingState::load_with_default_open(ui.ctx(), id, false)
        .show_header(ui, |ui| {
            if ui.selectable_label(selected, name).clicked() {
                select(world, state, entity);
            }
        })
        .body(|ui| {
            for &child in children.iter().take(MAX_CHILDREN_SHOWN) {
                node_ui(ui, world, state, child);
            }
            if children.len() > MAX_CHILDREN_SHOWN {
                ui.label(format!("... {} more", children.len() - MAX_CHILDREN_SHOWN));
            }
        });
}

/// Selects `entity` and, when it draws a mesh with one material, that material.
pub fn select(world: &World, state: &mut EditorState, entity: Entity) {
    state.selection.entity = Some(entity);
    let scene = &world.resource::<SceneAssets>().0;
    if let Some(mesh) = world.get::<crate::scene::MeshInstance>(entity)
        && let Some(data) = scene.meshes.get(mesh.mesh)
        && let Some(first) = data.primitives.first()
        && (first.material as usize) < scene.materials.len()
    {
        state.selection.material = Some(first.material as usize);
    }
}

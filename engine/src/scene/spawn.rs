//! The ECS side of a scene: one entity per glTF node, and transform propagation.

use super::{SceneAsset, SceneAssets};
use crate::FrameSet;
use bevy_app::{App, Plugin, Update};
use bevy_ecs::prelude::*;
use glam::{Mat4, Quat, Vec3};

/// Local transform of a node (translation, rotation, scale), written by animation and the editor.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    pub translation: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Self {
            translation: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
        }
    }
}

impl Transform {
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

impl From<super::NodeTransform> for Transform {
    fn from(t: super::NodeTransform) -> Self {
        Self {
            translation: t.translation,
            rotation: t.rotation,
            scale: t.scale,
        }
    }
}

/// World matrix, derived from [`Transform`]s each frame.
#[derive(Component, Clone, Copy, Debug, PartialEq, Default)]
pub struct GlobalTransform(pub Mat4);

/// The glTF node an entity came from, and the spawned copy of the scene it belongs to.
#[derive(Component, Clone, Copy, Debug)]
pub struct SceneNode {
    pub node: usize,
    pub root: Entity,
}

/// Root entity of one spawned copy of a scene (crowds spawn many).
#[derive(Component, Clone, Copy, Debug, Default)]
pub struct SceneRoot;

/// A node that draws a mesh of [`SceneAssets`].
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeshInstance {
    pub mesh: usize,
}

/// A mesh node with a glTF skin: its deformed vertices come out in world space (the joint matrices place
/// them), so its instance transform is the identity.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
pub struct SkinnedMesh {
    pub skin: usize,
}

/// Current morph-target weights of a mesh node (node.weights, else mesh.weights, else zeros; animated).
#[derive(Component, Clone, Debug, PartialEq, Default)]
pub struct MorphWeights(pub Vec<f32>);

/// On a scene root: the entity of every glTF node of that spawned copy, by node index.
#[derive(Component, Clone, Debug, Default)]
pub struct SceneNodes(pub Vec<Entity>);

/// A node that carries a glTF perspective camera.
#[derive(Component, Clone, Copy, Debug)]
pub struct CameraComponent {
    pub camera: usize,
    pub yfov: f32,
}

/// Spawns one copy of `scene` under a new root entity placed at `root_transform`.
/// Returns the root and, per glTF node, its entity.
pub fn spawn_scene(
    world: &mut World,
    scene: &SceneAsset,
    root_transform: Transform,
) -> (Entity, Vec<Entity>) {
    let root = world
        .spawn((SceneRoot, root_transform, GlobalTransform::default()))
        .id();
    // Nodes of other glTF scenes get an entity (animations may target them) but draw nothing.
    let shown = scene.displayed_nodes();
    let entities: Vec<Entity> = scene
        .nodes
        .iter()
        .enumerate()
        .map(|(i, node)| {
            let mut e = world.spawn((
                SceneNode { node: i, root },
                Transform::from(node.transform),
                GlobalTransform::default(),
            ));
            if !shown[i] {
                return e.id();
            }
            if let Some(mesh) = node.mesh {
                e.insert(MeshInstance { mesh });
                let data = &scene.meshes[mesh];
                if let Some(skin) = node
                    .skin
                    .filter(|&s| s < scene.skins.len() && data.skin_weights.is_some())
                {
                    e.insert(SkinnedMesh { skin });
                }
                if !data.morph_targets.is_empty() {
                    let mut w = node
                        .morph_weights
                        .clone()
                        .unwrap_or_else(|| data.default_morph_weights.clone());
                    w.resize(data.morph_targets.len(), 0.0);
                    e.insert(MorphWeights(w));
                }
            }
            if let Some(light) = node.light.and_then(|l| scene.lights.get(l)) {
                e.insert(super::LightSource(light.clone()));
            }
            if let Some(camera) = node.camera {
                e.insert(CameraComponent {
                    camera,
                    yfov: scene.cameras[camera].yfov,
                });
            }
            e.id()
        })
        .collect();
    for (i, node) in scene.nodes.iter().enumerate() {
        let parent = node.parent.map_or(root, |p| entities[p]);
        // Nodes outside the displayed scene stay unparented and are not drawn.
        if node.parent.is_some() || scene.roots.contains(&i) {
            world.entity_mut(entities[i]).insert(ChildOf(parent));
        }
    }
    world.entity_mut(root).insert(SceneNodes(entities.clone()));
    (root, entities)
}

/// Recomputes every [`GlobalTransform`] from the roots down.
pub fn propagate_transforms(
    roots: Query<Entity, (With<Transform>, Without<ChildOf>)>,
    mut nodes: Query<(&Transform, &mut GlobalTransform, Option<&Children>)>,
) {
    let mut stack: Vec<(Entity, Mat4)> = roots.iter().map(|e| (e, Mat4::IDENTITY)).collect();
    while let Some((entity, parent)) = stack.pop() {
        let Ok((transform, mut global, children)) = nodes.get_mut(entity) else {
            continue;
        };
        let world = parent * transform.matrix();
        if global.0 != world {
            global.0 = world;
        }
        if let Some(children) = children {
            stack.extend(children.iter().map(|c| (c, world)));
        }
    }
}

/// Holds the loaded scene and keeps world transforms current.
pub struct ScenePlugin {
    pub scene: std::sync::Arc<SceneAsset>,
}

impl Plugin for ScenePlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(SceneAssets(self.scene.clone()))
            .insert_resource(super::Materials::from_asset(&self.scene))
            .insert_resource(super::ActiveVariant(self.scene.active_variant));
        spawn_scene(app.world_mut(), &self.scene, Transform::default());
        app.add_systems(Update, propagate_transforms.in_set(FrameSet::Transform));
    }
}

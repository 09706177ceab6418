//! The scene's materials as editable ECS data. They start as the file's values ([`SceneAsset::materials`],
//! which stays immutable); the editor writes here, and the render plugin re-uploads the materials that differ
//! from what the GPU holds.

use super::{Material, SceneAsset};
use bevy_ecs::prelude::Resource;

/// One entry per material of the loaded scene, in file order (triangles refer to them by index).
#[derive(Resource, Clone, Debug, PartialEq)]
pub struct Materials(pub Vec<Material>);

impl Materials {
    pub fn from_asset(scene: &SceneAsset) -> Self {
        Self(scene.materials.clone())
    }

    /// Index of the material called `name`, or `name` read as an index.
    pub fn find(&self, name_or_index: &str) -> Option<usize> {
        self.0
            .iter()
            .position(|m| m.name == name_or_index)
            .or_else(|| {
                name_or_index
                    .parse::<usize>()
                    .ok()
                    .filter(|&i| i < self.0.len())
            })
    }

    /// Materials whose values differ from the file's.
    pub fn edited(&self, scene: &SceneAsset) -> Vec<usize> {
        (0..self.0.len())
            .filter(|&i| scene.materials.get(i) != Some(&self.0[i]))
            .collect()
    }
}

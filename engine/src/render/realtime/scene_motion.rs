//! Keeps the scene's previous-frame data (`gpu_scene::motion::SceneMotion`) current while the real-time path
//! runs: allocated when the mode says so (before this frame's deformation, so that the deform backends keep
//! the previous positions from the first frame on), and each frame the instances' previous placements, their
//! stable object ids and the light list's keys.

use crate::gpu::GpuContext;
use crate::render::gpu_scene::GpuScene;
use crate::render::gpu_scene::InstanceMap;
use crate::render::layout::{GpuMotionInstance, LIGHT_TRIANGLE, NONE};
use crate::render::settings::{RenderMode, RenderSettings};
use crate::scene::SceneAssets;
use bevy_ecs::prelude::*;
use std::collections::HashMap;

/// Stable ids of the entities behind GPU instances (dense, never reused), and where each was placed last frame.
#[derive(Resource, Default)]
pub struct MotionObjects {
    ids: HashMap<Entity, u32>,
    last_world: HashMap<Entity, [[f32; 4]; 3]>,
}

impl MotionObjects {
    /// The entity behind a stable object id.
    pub fn entity(&self, object: u32) -> Option<Entity> {
        self.ids
            .iter()
            .find(|(_, id)| **id == object)
            .map(|(e, _)| *e)
    }

    fn id(&mut self, entity: Entity) -> u32 {
        let next = self.ids.len() as u32;
        *self.ids.entry(entity).or_insert(next)
    }
}

/// Allocates the previous-frame data while the mode is real-time, frees it otherwise.
pub fn sync_scene_motion(
    ctx: Res<GpuContext>,
    assets: Res<SceneAssets>,
    settings: Res<RenderSettings>,
    mut scene: ResMut<GpuScene>,
) {
    match settings.mode {
        RenderMode::Realtime => scene.enable_motion(&ctx, &assets.0),
        RenderMode::Accumulate => {
            if scene.motion.is_some() {
                scene.disable_motion();
            }
        }
    }
}

/// Uploads each instance's previous placement and object id (in this frame's instance order) and the light
/// list's keys (after the top-level BVH and the instances were uploaded).
pub fn update_scene_motion(
    ctx: Res<GpuContext>,
    map: Res<InstanceMap>,
    mut objects: ResMut<MotionObjects>,
    mut scene: ResMut<GpuScene>,
) {
    if scene.motion.is_none() {
        return;
    }
    let mut instances = Vec::with_capacity(map.entities.len());
    for (&entity, inst) in map.entities.iter().zip(scene.uploaded_instances()) {
        if entity == Entity::PLACEHOLDER {
            // The merged static tree: never a hit of its own, never an object.
            instances.push(GpuMotionInstance {
                prev_world_from_object: inst.world_from_object,
                object: NONE,
                _pad: [0; 3],
            });
            continue;
        }
        let prev = objects.last_world.get(&entity).copied();
        instances.push(GpuMotionInstance {
            prev_world_from_object: prev.unwrap_or(inst.world_from_object),
            object: objects.id(entity),
            _pad: [0; 3],
        });
    }
    objects.last_world = map
        .entities
        .iter()
        .zip(scene.uploaded_instances())
        .filter(|(e, _)| **e != Entity::PLACEHOLDER)
        .map(|(&e, inst)| (e, inst.world_from_object))
        .collect();
    // Keys that follow a light from frame to frame while the list is rebuilt: an emissive triangle by its
    // object and slot, any other light by its kind and rank among the lights of that kind.
    let mut rank_of_kind = HashMap::<u32, u32>::new();
    let lights: Vec<(u32, u32)> = scene
        .light_list()
        .iter()
        .map(|l| {
            if l.kind == LIGHT_TRIANGLE {
                let object = instances
                    .get(l.index_a as usize)
                    .map_or(u32::MAX, |i| i.object);
                (object, l.index_b)
            } else {
                let rank = rank_of_kind.entry(l.kind).or_default();
                *rank += 1;
                (u32::MAX - 1 - l.kind, *rank - 1)
            }
        })
        .collect();
    let motion = scene.motion.as_mut().expect("checked above");
    motion.write_instances(&ctx, &instances);
    motion.write_lights(&ctx, lights);
}

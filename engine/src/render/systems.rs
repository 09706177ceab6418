//! The render plugin's systems before the frame: the CPU backend's refit of deformed meshes, the top-level
//! structure over this frame's placements, edited materials and the material variant shown.

use super::accumulation::Accumulation;
use super::gpu_scene::{GpuScene, InstanceInput};
use crate::animation::{DeformedElsewhere, DeformedMeshes};
use crate::bvh::MeshBvh;
use crate::bvh::refit::BvhStats;
use crate::gpu::GpuContext;
use crate::render::layout::NONE;
use crate::scene::{
    ActiveVariant, GlobalTransform, Materials, MeshInstance, SceneAssets, SceneNode, SkinnedMesh,
};
use bevy_ecs::prelude::*;

/// Deformed geometry moved this frame (set by whichever backend deformed it): the top-level BVH must be rebuilt
/// over the new bounds. Read and cleared by [`update_instances`].
#[derive(Resource, Default)]
pub struct GeometryChanged(pub bool);

pub use super::gpu_scene::InstanceMap;

/// What [`update_instances`] reads of a mesh instance: placement, mesh, skin, and the glTF node (by which the
/// merged static instances are recognised).
type PlacedMesh = (
    Entity,
    &'static GlobalTransform,
    &'static MeshInstance,
    Option<&'static SkinnedMesh>,
    Option<&'static SceneNode>,
);

/// Collects mesh instances; rebuilds the TLAS and re-uploads instances when any placement or deformed mesh
/// changed, and restarts accumulation.
#[allow(clippy::too_many_arguments)]
pub fn update_instances(
    ctx: Res<GpuContext>,
    assets: Res<SceneAssets>,
    mut scene: ResMut<GpuScene>,
    mut map: ResMut<InstanceMap>,
    mut geometry: ResMut<GeometryChanged>,
    mut accumulation: ResMut<Accumulation>,
    mut stats: ResMut<BvhStats>,
    instances: Query<PlacedMesh>,
) {
    let start = std::time::Instant::now();
    stats.last_tlas_seconds = 0.0;
    // Skinned vertices are already in world space (the joint matrices place them).
    let mut placed: Vec<(InstanceInput, Entity)> = instances
        .iter()
        .map(|(e, g, m, skinned, node)| {
            let world = if skinned.is_some() {
                glam::Mat4::IDENTITY
            } else {
                g.0
            };
            let input = InstanceInput {
                world,
                mesh: m.mesh as u32,
                node: node.map_or(NONE, |n| n.node as u32),
            };
            (input, e)
        })
        .collect();
    // Query order is not stable across archetype changes; sort for a deterministic TLAS.
    placed.sort_by(|(a, _), (b, _)| {
        a.mesh.cmp(&b.mesh).then_with(|| {
            a.world
                .to_cols_array()
                .partial_cmp(&b.world.to_cols_array())
                .unwrap_or(std::cmp::Ordering::Equal)
        })
    });
    let (inputs, entities): (Vec<InstanceInput>, Vec<Entity>) = placed.into_iter().unzip();
    let moved = std::mem::take(&mut geometry.0);
    if inputs == map.last_inputs && !moved && !scene.merge_needs_check() {
        return;
    }
    if let Err(e) = scene.update_instances(&ctx, &assets.0, &inputs) {
        tracing::error!("top-level BVH: {e}");
    }
    // The merged static tree's pseudo-instance is no entity (its hits become its members').
    map.entities = scene
        .instance_order
        .iter()
        .map(|&i| {
            entities
                .get(i as usize)
                .copied()
                .unwrap_or(Entity::PLACEHOLDER)
        })
        .collect();
    map.last_inputs = inputs;
    accumulation.restart();
    stats.last_tlas_seconds = start.elapsed().as_secs_f64();
}

/// CPU backend: uploads this frame's deformed meshes (only their vertex ranges), refits their BLAS, and rebuilds
/// the worst ones past the SAH-ratio threshold (at most `max_rebuilds_per_frame`). Any change sets
/// [`GeometryChanged`].
#[allow(clippy::too_many_arguments)]
pub fn refit_deformed(
    ctx: Res<GpuContext>,
    assets: Res<SceneAssets>,
    deformed: Res<DeformedMeshes>,
    elsewhere: Res<DeformedElsewhere>,
    mut stats: ResMut<BvhStats>,
    mut scene: ResMut<GpuScene>,
    mut geometry: ResMut<GeometryChanged>,
) {
    let asset = &assets.0;
    stats.ensure_len(asset.meshes.len());
    let start = std::time::Instant::now();
    let (ratios, upload_seconds) = if deformed.changed.is_empty() {
        (Vec::new(), 0.0)
    } else {
        keep_previous_positions(&ctx, &mut scene, &deformed);
        scene.apply_deformations(&ctx, asset, &deformed, stats.policy)
    };
    for (m, ratio) in ratios {
        stats.sah_ratio[m] = ratio;
        stats.refits += 1;
        geometry.0 = true;
    }
    stats.last_upload_seconds = upload_seconds;
    stats.last_refit_seconds = start.elapsed().as_secs_f64() - upload_seconds;
    let start = std::time::Instant::now();
    // Meshes the GPU deforms are rebuilt by the GPU deformer, from their GPU positions.
    let cpu_owned = |m: usize| !elsewhere.0.get(m).copied().unwrap_or(false);
    for m in stats.due(cpu_owned) {
        match scene.rebuild_mesh(&ctx, asset, m) {
            Ok(()) => {
                stats.sah_ratio[m] = scene.mesh_slots[m]
                    .blas
                    .binary()
                    .map_or(1.0, MeshBvh::sah_ratio);
                stats.mesh_rebuilds[m] += 1;
                stats.rebuilds += 1;
                geometry.0 = true;
            }
            Err(e) => {
                tracing::error!(
                    "mesh `{}`: BVH rebuild: {e}; keeping the refit tree",
                    asset.meshes[m].name
                );
                stats.sah_ratio[m] = 1.0;
            }
        }
    }
    stats.last_rebuild_seconds = start.elapsed().as_secs_f64();
}

/// Uploads edited materials (only those that differ from the GPU's copy), restarts accumulation, and tells
/// the real-time path which materials changed (their pixels' history is stale).
pub fn upload_materials(
    ctx: Res<GpuContext>,
    assets: Res<SceneAssets>,
    materials: Res<Materials>,
    mut scene: ResMut<GpuScene>,
    mut accumulation: ResMut<Accumulation>,
    mut realtime: ResMut<super::realtime::Realtime>,
) {
    if !materials.is_changed() {
        return;
    }
    let edited = scene.update_materials(&ctx, &assets.0, &materials.0);
    if !edited.is_empty() {
        accumulation.restart();
        realtime.state.edited_materials.extend(edited);
    }
}

/// Shows the KHR_materials_variants variant [`ActiveVariant`] names: rewrites only the triangles' material
/// words (no BVH is touched), and restarts accumulation when the image changes.
pub fn upload_variant(
    ctx: Res<GpuContext>,
    assets: Res<SceneAssets>,
    variant: Res<ActiveVariant>,
    mut scene: ResMut<GpuScene>,
    mut accumulation: ResMut<Accumulation>,
    mut realtime: ResMut<super::realtime::Realtime>,
) {
    if variant.0 == scene.variant {
        return;
    }
    let changed = scene.select_variant(&ctx, &assets.0, variant.0);
    if !changed.is_empty() {
        accumulation.restart();
        realtime.state.edited_materials.extend(changed);
    }
}

/// CPU backend, real-time path on: keeps the positions the deformed meshes had before this frame's writes
/// replace them. The copy goes in a submission of its own, ahead of the queued writes, which land at the
/// start of the next one.
fn keep_previous_positions(
    ctx: &GpuContext,
    scene: &mut GpuScene,
    deformed: &crate::animation::DeformedMeshes,
) {
    if scene.motion.is_none() {
        return;
    }
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    for &m in &deformed.changed {
        if deformed.meshes.get(m).is_some_and(Option::is_some) {
            scene.keep_previous_positions(&mut encoder, m);
        }
    }
    ctx.queue.submit([encoder.finish()]);
}

/// The environment setting the GPU's environment map was made from.
#[derive(Resource)]
pub struct UploadedEnvironment(pub super::Environment);

/// Keeps the light list current: the environment when its setting changed (a map that cannot be read becomes
/// a black environment, with the error logged), the punctual lights from their nodes (only when one moved or
/// was edited), and the emissive triangles `update_instances` and `upload_materials` rebuilt. Uploads once
/// and restarts accumulation when anything changed.
pub fn update_lights(
    ctx: Res<GpuContext>,
    settings: Res<super::RenderSettings>,
    mut uploaded: ResMut<UploadedEnvironment>,
    mut scene: ResMut<GpuScene>,
    mut accumulation: ResMut<Accumulation>,
    lights: Query<(Entity, &GlobalTransform, &crate::scene::LightSource)>,
) {
    if uploaded.0 != settings.environment {
        uploaded.0 = settings.environment.clone();
        match super::environment::bake(&settings.environment, scene.binding_limit) {
            Ok(baked) => {
                for note in &baked.notes {
                    tracing::warn!("{note}");
                }
                scene.set_environment(&ctx, Some(&baked));
            }
            Err(e) => {
                tracing::error!("{e}; the environment is black");
                scene.set_environment(&ctx, None);
            }
        }
    }
    let mut placed: Vec<(Entity, glam::Mat4, crate::scene::PunctualLight)> = lights
        .iter()
        .map(|(e, g, l)| (e, g.0, l.0.clone()))
        .collect();
    // Query order is not stable across archetype changes.
    placed.sort_by_key(|(e, _, _)| *e);
    let placed: Vec<(glam::Mat4, crate::scene::PunctualLight)> =
        placed.into_iter().map(|(_, m, l)| (m, l)).collect();
    scene.set_punctual_lights(&placed);
    if scene.upload_lights(&ctx) {
        accumulation.restart();
    }
}

//! Picking: which entity, mesh and material a pixel shows. A one-ray GPU pass (`passes/pick`) traces the
//! clicked pixel's centre through the last traced frame's camera, buffers and traversal, so a pick selects
//! exactly what is on screen: GPU-deformed poses, compressed wide BVHs and alpha-masked cut-outs included, where
//! a CPU ray cast would see stale trees. It costs nothing until a click (an earlier design wrote a per-pixel hit
//! AOV at every accumulation restart: a ray per pixel per frame while an animation plays).

use super::gpu_scene::GpuScene;
use super::gpu_scene::InstanceMap;
use super::passes::OnFirstUse;
use super::passes::pick::PickPass;
use super::scene_bindings::SceneBindings;
use super::view::ViewTargets;
use crate::gpu::GpuContext;
use crate::scene::{MeshInstance, SceneAssets};
use bevy_ecs::prelude::*;

/// What the ray through a pixel centre hit first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PickHit {
    pub entity: Entity,
    pub mesh: usize,
    /// Triangle index in the mesh (file order).
    pub triangle: usize,
    /// Index into the scene's materials; `None` for glTF's default material.
    pub material: Option<usize>,
    /// Weights of the triangle's second and third vertices at the hit.
    pub barycentrics: [f32; 2],
    /// Distance from the camera along the pixel centre's ray.
    pub distance: f32,
}

/// The hit through pixel (`x`, `y`) of the current image (pixels from the top-left); `None` where the ray
/// left the scene or outside the image. Blocks for a 16-byte readback.
pub fn pick_pixel(world: &World, x: u32, y: u32) -> Option<PickHit> {
    let ctx = world.get_resource::<GpuContext>()?;
    let scene = &world.get_resource::<SceneAssets>()?.0;
    let gpu_scene = world.get_resource::<GpuScene>()?;
    let bindings = world.get_resource::<SceneBindings>()?;
    let pass = world
        .get_resource::<OnFirstUse<PickPass>>()?
        .get_or_init(|| PickPass::new(ctx, &bindings.layout));
    let view = world.get_resource::<ViewTargets>()?;
    let (hit, distance) = pass.pick(ctx, &bindings.fresh(ctx, gpu_scene), view, x, y)?;
    let entity = *world
        .get_resource::<InstanceMap>()?
        .entities
        .get(hit.instance? as usize)?;
    let mesh = world.get::<MeshInstance>(entity)?.mesh;
    let slot = gpu_scene.mesh_slots.get(mesh)?;
    let local = hit.triangle.checked_sub(slot.gpu.triangle_offset)? as usize;
    let triangle = *slot.blas.order().get(local)? as usize;
    // The material shown: that of the variant the GPU holds.
    let material = *scene
        .meshes
        .get(mesh)?
        .triangle_materials_under(gpu_scene.variant)
        .get(triangle)? as usize;
    Some(PickHit {
        entity,
        mesh,
        triangle,
        material: (material < scene.materials.len()).then_some(material),
        barycentrics: hit.barycentrics,
        distance,
    })
}

/// Camera depth (distance along the view axis) of the surface through pixel (`x`, `y`)'s centre: the focus
/// distance that makes it sharp. `None` where the ray leaves the scene.
pub fn depth_at(world: &World, x: u32, y: u32) -> Option<f32> {
    let hit = pick_pixel(world, x, y)?;
    let camera = world.get_resource::<crate::camera::CameraView>()?;
    let view = world.get_resource::<ViewTargets>()?;
    let (_, dir) = camera.ray_through(x as f32 + 0.5, y as f32 + 0.5, view.width, view.height);
    Some(hit.distance * dir.dot(camera.forward()))
}

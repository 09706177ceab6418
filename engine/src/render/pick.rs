//! Picking: which entity, mesh and material a pixel shows. A ray cast on the CPU through the same BVHs and
//! current (deformed) positions the GPU traces, so a click selects what is on screen, also mid-animation.

use super::Renderer;
use crate::camera::CameraView;
use crate::scene::{GlobalTransform, MeshInstance, SceneAssets, SkinnedMesh};
use bevy_ecs::prelude::*;
use glam::{Mat4, Vec3};

/// What a picking ray hit first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PickHit {
    pub entity: Entity,
    pub mesh: usize,
    /// Triangle index in the mesh (file order).
    pub triangle: usize,
    /// Index into the scene's materials; `None` for glTF's default material.
    pub material: Option<usize>,
    /// Distance along the (unit) ray.
    pub distance: f32,
    pub position: Vec3,
}

/// Casts the ray through pixel (`x`, `y`) (image pixels from the top-left, fractional allowed) of a
/// `width` x `height` view from the world's [`CameraView`].
pub fn pick_pixel(world: &mut World, x: f32, y: f32, width: u32, height: u32) -> Option<PickHit> {
    let view = *world.get_resource::<CameraView>()?;
    let (origin, dir) = view.ray_through(x, y, width, height);
    pick_ray(world, origin, dir)
}

/// The nearest mesh-instance hit along a world-space ray (unit direction); both triangle faces count.
pub fn pick_ray(world: &mut World, origin: Vec3, dir: Vec3) -> Option<PickHit> {
    let scene = world.get_resource::<SceneAssets>()?.0.clone();
    let mut instances = world.query::<(
        Entity,
        &GlobalTransform,
        &MeshInstance,
        Option<&SkinnedMesh>,
    )>();
    let candidates: Vec<(Entity, Mat4, usize)> = instances
        .iter(world)
        .map(|(e, g, m, skinned)| {
            // Skinned vertices are already in world space (as for the GPU instances).
            (
                e,
                if skinned.is_some() {
                    Mat4::IDENTITY
                } else {
                    g.0
                },
                m.mesh,
            )
        })
        .collect();
    let renderer = world.get_resource::<Renderer>()?;
    let mut best: Option<PickHit> = None;
    for (entity, world_from_object, mesh) in candidates {
        let (Some(slot), Some(data)) =
            (renderer.scene.mesh_slots.get(mesh), scene.meshes.get(mesh))
        else {
            continue;
        };
        let object_from_world = world_from_object.inverse();
        if !object_from_world.is_finite() {
            continue;
        }
        let o = object_from_world.transform_point3(origin);
        // Not normalised: t along it equals world distance along the unit world ray.
        let d = object_from_world.transform_vector3(dir);
        let positions = slot.positions.as_deref().unwrap_or(&data.positions);
        let t_max = best.map_or(f32::INFINITY, |b| b.distance);
        let mut nearest_slot = None;
        let t = slot
            .bvh
            .flat
            .closest_hit(o, d, t_max, |first, count, t_max| {
                let mut found = None;
                let mut limit = t_max;
                for s in first..first + count {
                    let [a, b, c] = slot.gpu_triangles[s as usize].map(|v| positions[v as usize]);
                    if let Some(t) = ray_triangle(o, d, a, b, c).filter(|&t| t < limit) {
                        limit = t;
                        found = Some(t);
                        nearest_slot = Some(s as usize);
                    }
                }
                found
            });
        if let (Some(t), Some(s)) = (t, nearest_slot) {
            let triangle = slot.bvh.flat.order[s] as usize;
            let material = data.triangle_materials[triangle] as usize;
            best = Some(PickHit {
                entity,
                mesh,
                triangle,
                material: (material < scene.materials.len()).then_some(material),
                distance: t,
                position: origin + dir * t,
            });
        }
    }
    best
}

/// Moeller-Trumbore, both faces; the hit distance in units of `dir`.
pub fn ray_triangle(o: Vec3, d: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<f32> {
    let e1 = b - a;
    let e2 = c - a;
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0 && t.is_finite()).then_some(t)
}

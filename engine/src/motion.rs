//! Screen-space motion vectors: where the surface seen through each pixel centre was one frame earlier.
//!
//! The kernel records the primary hit through each pixel centre (instance, triangle, barycentrics; see
//! [`crate::render::PrimaryHit`]). Here, on the CPU, the same barycentric point is placed on the same
//! triangle in the current pose and in a previous pose (a CPU-only copy of the scene, [`PreviousPose`]:
//! animation, transforms, skinning and morphing, no GPU), and both are projected with their frame's camera.
//!
//! Convention (documented in docs/RECORDING.md): motion = previous screen position - current screen position,
//! in pixels, +x right, +y down (image rows), so `previous_pixel = pixel + motion`. Rays that leave the scene
//! see the environment at infinity: their motion comes from the camera's rotation alone. Output per pixel is
//! `[dx, dy, status]` with status [`STATUS_SURFACE`], [`STATUS_ENVIRONMENT`] or [`STATUS_INVALID`] (the point
//! was behind the previous camera; dx = dy = 0).

use crate::camera::{CameraChoice, CameraView, resolve_camera};
use crate::headless::HeadlessApp;
use crate::render::PrimaryHit;
use crate::scene::SkinnedMesh;
use crate::scene::{GlobalTransform, MeshInstance, SceneAsset, SceneNode, SceneNodes, SceneRoot};
use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::sync::Arc;

pub const STATUS_SURFACE: f32 = 1.0;
pub const STATUS_ENVIRONMENT: f32 = 0.0;
pub const STATUS_INVALID: f32 = -1.0;

/// Where a camera sees points: the kernel's pinhole model (pixel centres at i + 0.5).
#[derive(Clone, Copy, Debug)]
pub struct Projection {
    pub view: CameraView,
    pub width: u32,
    pub height: u32,
}

impl Projection {
    fn project_camera_space(&self, q: Vec3) -> Option<Vec2> {
        if q.z >= -1e-6 {
            return None;
        }
        let tan = (self.view.yfov * 0.5).tan();
        let aspect = self.width as f32 / self.height.max(1) as f32;
        let ndc = Vec2::new(q.x / (-q.z * tan * aspect), q.y / (-q.z * tan));
        Some(Vec2::new(
            (ndc.x + 1.0) * 0.5 * self.width as f32,
            (1.0 - ndc.y) * 0.5 * self.height as f32,
        ))
    }

    /// Pixel coordinates of a world point; `None` behind the camera.
    pub fn point(&self, p: Vec3) -> Option<Vec2> {
        let q = self.view.world_from_camera.inverse().transform_point3(p);
        self.project_camera_space(q)
    }

    /// Pixel coordinates of a direction at infinity; `None` behind the camera.
    pub fn direction(&self, d: Vec3) -> Option<Vec2> {
        let q = self.view.world_from_camera.inverse().transform_vector3(d);
        self.project_camera_space(q)
    }

    /// World direction of the ray through pixel coordinates `xy`.
    pub fn ray_direction(&self, xy: Vec2) -> Vec3 {
        let tan = (self.view.yfov * 0.5).tan();
        let aspect = self.width as f32 / self.height.max(1) as f32;
        let ndc = Vec2::new(
            xy.x / self.width as f32 * 2.0 - 1.0,
            1.0 - xy.y / self.height as f32 * 2.0,
        );
        let d = Vec3::new(ndc.x * tan * aspect, ndc.y * tan, -1.0);
        self.view
            .world_from_camera
            .transform_vector3(d)
            .normalize_or_zero()
    }
}

/// World-space corners of mesh `mesh`'s triangle (vertex indices `verts`) on node entity `entity`, as posed
/// in `world`: skinned meshes from their world-space deformed positions, morphed ones from their deformed
/// object positions, static ones from the rest positions, placed by the node's world matrix.
fn world_triangle(
    world: &World,
    scene: &SceneAsset,
    entity: Entity,
    mesh: usize,
    verts: [u32; 3],
) -> Option<[Vec3; 3]> {
    let deformed = world
        .get_resource::<crate::animation::DeformedMeshes>()
        .and_then(|d| d.meshes.get(mesh)?.as_ref());
    let skinned = world.get::<SkinnedMesh>(entity).is_some();
    let node_world = world.get::<GlobalTransform>(entity)?.0;
    let positions = deformed.map_or(&scene.meshes[mesh].positions, |d| &d.positions);
    let corner = |v: u32| -> Option<Vec3> {
        let p = *positions.get(v as usize)?;
        Some(if skinned && deformed.is_some() {
            p
        } else {
            node_world.transform_point3(p)
        })
    };
    Some([corner(verts[0])?, corner(verts[1])?, corner(verts[2])?])
}

fn barycentric_point(corners: [Vec3; 3], b: [f32; 2]) -> Vec3 {
    corners[0] * (1.0 - b[0] - b[1]) + corners[1] * b[0] + corners[2] * b[1]
}

/// A CPU-only copy of the scene (animation, transforms, skinning, morphing) posed at another time than the
/// renderer's, with the camera as seen in that pose.
pub struct PreviousPose {
    app: bevy_app::App,
    scene: Arc<SceneAsset>,
    nodes: Vec<Entity>,
    pub projection: Projection,
}

impl PreviousPose {
    pub fn new(scene: Arc<SceneAsset>, width: u32, height: u32) -> Self {
        let mut app = crate::animation::cpu_app(scene.clone());
        let world = app.world_mut();
        let nodes = world
            .query_filtered::<&SceneNodes, With<SceneRoot>>()
            .iter(world)
            .next()
            .map(|n| n.0.clone())
            .unwrap_or_default();
        let projection = Projection {
            view: CameraView::framing((Vec3::splat(-1.0), Vec3::ONE), 1.0, 1.0),
            width,
            height,
        };
        Self {
            app,
            scene,
            nodes,
            projection,
        }
    }

    /// Poses the copy at `seconds` into `clip` (`None`: rest pose) and resolves `camera` in that pose.
    pub fn pose(
        &mut self,
        clip: Option<usize>,
        seconds: f32,
        camera: &CameraChoice,
    ) -> Result<(), String> {
        if let Some(clip) = clip {
            crate::animation::hold_at(self.app.world_mut(), clip, seconds);
        }
        self.app.update();
        let aspect = self.projection.width as f32 / self.projection.height.max(1) as f32;
        self.projection.view = resolve_camera(self.app.world_mut(), &self.scene, camera, aspect)
            .map_err(|e| e.to_string())?;
        Ok(())
    }
}

/// Motion vectors `[dx, dy, status]` per pixel for the renderer's current frame (primary hits recorded with
/// [`HeadlessApp::set_hit_aov`]) against `previous`, computed in parallel over pixels. Empty when no hits were
/// recorded.
pub fn motion_vectors(app: &HeadlessApp, previous: &PreviousPose) -> Vec<[f32; 3]> {
    let hits = app.primary_hits();
    let scene = app.scene();
    let frames = two_frames(app, previous, &scene);
    hits.par_iter()
        .enumerate()
        .map(
            |(pixel, hit)| match frames.pixel_motion(pixel as u32, hit) {
                Some((m, status)) if m.is_finite() => [m.x, m.y, status],
                _ => [0.0, 0.0, STATUS_INVALID],
            },
        )
        .collect()
}

/// Where the surface point of `hit` (any point of a triangle, not only a pixel centre's) is on the renderer's
/// screen now and where it was in `previous`'s pose, in pixels; `None` behind a camera. The CPU reference the
/// real-time path's GPU motion vectors are checked against (tests/realtime.rs).
pub fn surface_screen_positions(
    app: &HeadlessApp,
    previous: &PreviousPose,
    hit: &PrimaryHit,
) -> Option<(Vec2, Vec2)> {
    let scene = app.scene();
    two_frames(app, previous, &scene).positions(hit)
}

fn two_frames<'a>(
    app: &'a HeadlessApp,
    previous: &'a PreviousPose,
    scene: &'a SceneAsset,
) -> TwoFrames<'a> {
    let world = app.app.world();
    let view = app.view();
    TwoFrames {
        now: world,
        before: previous.app.world(),
        nodes_before: &previous.nodes,
        gpu_scene: app.gpu_scene(),
        instances: world.resource::<crate::render::gpu_scene::InstanceMap>(),
        scene,
        projection_now: Projection {
            view: app.camera(),
            width: view.width,
            height: view.height,
        },
        projection_before: previous.projection,
    }
}

/// The current frame (the renderer's world and GPU scene) and the previous pose, read-only.
struct TwoFrames<'a> {
    now: &'a World,
    before: &'a World,
    nodes_before: &'a [Entity],
    gpu_scene: &'a crate::render::GpuScene,
    instances: &'a crate::render::gpu_scene::InstanceMap,
    scene: &'a SceneAsset,
    projection_now: Projection,
    projection_before: Projection,
}

impl TwoFrames<'_> {
    fn pixel_motion(&self, pixel: u32, hit: &PrimaryHit) -> Option<(Vec2, f32)> {
        let width = self.projection_now.width;
        let centre = Vec2::new((pixel % width) as f32 + 0.5, (pixel / width) as f32 + 0.5);
        if hit.instance.is_none() {
            // A still camera sees a still environment: exactly 0, not a rounding residue.
            if self.projection_before.view == self.projection_now.view {
                return Some((Vec2::ZERO, STATUS_ENVIRONMENT));
            }
            let d = self.projection_now.ray_direction(centre);
            let before = self.projection_before.direction(d)?;
            return Some((before - centre, STATUS_ENVIRONMENT));
        }
        let (now, before) = self.positions(hit)?;
        Some((before - now, STATUS_SURFACE))
    }

    fn positions(&self, hit: &PrimaryHit) -> Option<(Vec2, Vec2)> {
        let instance = hit.instance?;
        let entity = *self.instances.entities.get(instance as usize)?;
        let mesh = self.now.get::<MeshInstance>(entity)?.mesh;
        let node = self.now.get::<SceneNode>(entity)?.node;
        let slot = self.gpu_scene.mesh_slots.get(mesh)?;
        let local = hit.triangle.checked_sub(slot.gpu.triangle_offset)? as usize;
        let verts = *slot.gpu_triangles.get(local)?;
        let now = barycentric_point(
            world_triangle(self.now, self.scene, entity, mesh, verts)?,
            hit.barycentrics,
        );
        let entity_before = *self.nodes_before.get(node)?;
        let before = barycentric_point(
            world_triangle(self.before, self.scene, entity_before, mesh, verts)?,
            hit.barycentrics,
        );
        Some((
            self.projection_now.point(now)?,
            self.projection_before.point(before)?,
        ))
    }
}

//! The view the path tracer renders from: a glTF camera node, a framing of the scene bounds, or an explicit
//! look-at given on the command line; [`controller`] moves it interactively (orbit, fly, scene cameras).

pub mod controller;

pub use controller::{CameraControllerPlugin, CameraInput, CameraMode, CameraRig};

use crate::scene::{CameraComponent, GlobalTransform, SceneAsset};
use bevy_ecs::prelude::*;
use glam::{Mat4, Vec3};

/// A pinhole camera in world space (glTF convention: looks down its local -Z, +Y up).
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct CameraView {
    pub world_from_camera: Mat4,
    /// Vertical field of view, radians.
    pub yfov: f32,
}

impl CameraView {
    pub fn look_at(eye: Vec3, target: Vec3, up: Vec3, yfov: f32) -> Self {
        let forward = (target - eye).normalize_or(Vec3::NEG_Z);
        let up = if forward.cross(up).length_squared() < 1e-8 {
            Vec3::Z
        } else {
            up
        };
        // Columns: camera +X (right), +Y (up), +Z (backwards, glTF cameras look down -Z), position.
        let right = forward.cross(up).normalize();
        let true_up = right.cross(forward);
        Self {
            world_from_camera: Mat4::from_cols(
                right.extend(0.0),
                true_up.extend(0.0),
                (-forward).extend(0.0),
                eye.extend(1.0),
            ),
            yfov,
        }
    }

    /// Looks at the centre of `bounds` from +Z (glTF's "front"), far enough back that the bounding sphere fits.
    pub fn framing(bounds: (Vec3, Vec3), yfov: f32, aspect: f32) -> Self {
        let (lo, hi) = bounds;
        let center = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1e-3);
        // The sphere must fit both the vertical and the horizontal field of view.
        let half = (yfov * 0.5).min(((yfov * 0.5).tan() * aspect.max(1e-3)).atan());
        let distance = radius / half.sin().max(1e-3);
        Self::look_at(
            center + Vec3::new(0.0, radius * 0.15, distance),
            center,
            Vec3::Y,
            yfov,
        )
    }

    pub fn position(&self) -> Vec3 {
        self.world_from_camera.w_axis.truncate()
    }

    /// Unit direction the camera looks along (its -Z).
    pub fn forward(&self) -> Vec3 {
        (-self.world_from_camera.z_axis.truncate()).normalize_or(Vec3::NEG_Z)
    }

    /// The ray through image point (`x`, `y`) (pixels from the top-left; +0.5 is a pixel centre) of a
    /// `width` x `height` image: the same mapping the path tracer's camera rays use. Unit direction.
    pub fn ray_through(&self, x: f32, y: f32, width: u32, height: u32) -> (Vec3, Vec3) {
        let (w, h) = (width.max(1) as f32, height.max(1) as f32);
        let ndc_x = x / w * 2.0 - 1.0;
        let ndc_y = 1.0 - y / h * 2.0;
        let tan = (self.yfov * 0.5).tan();
        let d = Vec3::new(ndc_x * tan * w / h, ndc_y * tan, -1.0);
        let dir = self
            .world_from_camera
            .transform_vector3(d)
            .normalize_or(Vec3::NEG_Z);
        (self.position(), dir)
    }
}

/// Which camera a render uses.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum CameraChoice {
    /// The scene's first perspective camera, else a framing of its bounds.
    #[default]
    Auto,
    /// The i-th camera node in the scene (glTF node order).
    Index(usize),
    LookAt {
        eye: Vec3,
        target: Vec3,
        yfov: f32,
    },
}

#[derive(Debug, thiserror::Error)]
#[error("camera {requested} does not exist: the scene has {available} camera(s)")]
pub struct NoSuchCamera {
    pub requested: usize,
    pub available: usize,
}

/// The scene's glTF camera views in node order, from (node, world matrix, yfov) of each camera node.
pub fn scene_camera_views(cameras: impl Iterator<Item = (usize, Mat4, f32)>) -> Vec<CameraView> {
    let mut cameras: Vec<(usize, Mat4, f32)> = cameras.collect();
    cameras.sort_by_key(|c| c.0);
    cameras
        .into_iter()
        .map(|(_, m, yfov)| {
            // Camera nodes may carry scale: keep only rotation and translation.
            let (_, r, t) = m.to_scale_rotation_translation();
            CameraView {
                world_from_camera: Mat4::from_rotation_translation(r, t),
                yfov,
            }
        })
        .collect()
}

/// Resolves the choice against the ECS (camera node world transforms are current after propagation).
pub fn resolve_camera(
    world: &mut World,
    scene: &SceneAsset,
    choice: &CameraChoice,
    aspect: f32,
) -> Result<CameraView, NoSuchCamera> {
    let cameras = scene_camera_views(
        world
            .query::<(&crate::scene::SceneNode, &CameraComponent, &GlobalTransform)>()
            .iter(world)
            .map(|(n, c, g)| (n.node, g.0, c.yfov)),
    );
    Ok(match choice {
        CameraChoice::LookAt { eye, target, yfov } => {
            CameraView::look_at(*eye, *target, Vec3::Y, *yfov)
        }
        CameraChoice::Index(i) => *cameras.get(*i).ok_or(NoSuchCamera {
            requested: *i,
            available: cameras.len(),
        })?,
        CameraChoice::Auto => match cameras.first() {
            Some(view) => *view,
            None => {
                let bounds = scene
                    .rest_bounds()
                    .unwrap_or((Vec3::splat(-1.0), Vec3::ONE));
                CameraView::framing(bounds, 45f32.to_radians(), aspect)
            }
        },
    })
}

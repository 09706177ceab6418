//! The view the path tracer renders from: a glTF camera node, a framing of the scene bounds, or an explicit
//! look-at given on the command line.

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

/// Resolves the choice against the ECS (camera node world transforms are current after propagation).
pub fn resolve_camera(
    world: &mut World,
    scene: &SceneAsset,
    choice: &CameraChoice,
    aspect: f32,
) -> Result<CameraView, NoSuchCamera> {
    let mut cameras: Vec<(usize, Mat4, f32)> = world
        .query::<(&crate::scene::SceneNode, &CameraComponent, &GlobalTransform)>()
        .iter(world)
        .map(|(n, c, g)| (n.node, g.0, c.yfov))
        .collect();
    cameras.sort_by_key(|c| c.0);
    let rigid = |m: Mat4| {
        // Camera nodes may carry scale: keep only rotation and translation.
        let (_, r, t) = m.to_scale_rotation_translation();
        Mat4::from_rotation_translation(r, t)
    };
    Ok(match choice {
        CameraChoice::LookAt { eye, target, yfov } => {
            CameraView::look_at(*eye, *target, Vec3::Y, *yfov)
        }
        CameraChoice::Index(i) => {
            let (_, m, yfov) = *cameras.get(*i).ok_or(NoSuchCamera {
                requested: *i,
                available: cameras.len(),
            })?;
            CameraView {
                world_from_camera: rigid(m),
                yfov,
            }
        }
        CameraChoice::Auto => match cameras.first() {
            Some(&(_, m, yfov)) => CameraView {
                world_from_camera: rigid(m),
                yfov,
            },
            None => {
                let bounds = scene
                    .rest_bounds()
                    .unwrap_or((Vec3::splat(-1.0), Vec3::ONE));
                CameraView::framing(bounds, 45f32.to_radians(), aspect)
            }
        },
    })
}

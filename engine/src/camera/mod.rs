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

/// The chosen camera cannot be used: it does not exist, or its node's world transform is singular (a scale of
/// 0 has no orientation to look along). The message names the scene and the cameras it has.
#[derive(Debug, thiserror::Error)]
#[error("{scene}: {problem}")]
pub struct NoSuchCamera {
    pub scene: String,
    pub problem: String,
}

/// "the scene has 2 camera(s): 0 (node 3 `Camera`), ..." for messages; `cameras` as (node, world, yfov).
fn camera_listing(scene: &SceneAsset, cameras: &[(usize, Mat4, f32)]) -> String {
    if cameras.is_empty() {
        return "the scene has no cameras (use --look-from/--look-at, or leave --camera out to frame it)".into();
    }
    let list: Vec<String> = cameras
        .iter()
        .enumerate()
        .map(|(i, (node, _, _))| {
            let name = scene.nodes.get(*node).map_or("", |n| n.name.as_str());
            format!("{i} (node {node} `{name}`)")
        })
        .collect();
    format!(
        "the scene has {} camera(s): {}",
        cameras.len(),
        list.join(", ")
    )
}

/// Picks camera `index` (`None`: the first) among `cameras` and checks its transform can orient a view.
fn pick_camera(
    scene: &SceneAsset,
    mut cameras: Vec<(usize, Mat4, f32)>,
    index: Option<usize>,
) -> Result<Option<CameraView>, NoSuchCamera> {
    cameras.sort_by_key(|c| c.0);
    let fail = |problem: String| NoSuchCamera {
        scene: scene.source.clone(),
        problem,
    };
    let chosen = match index {
        Some(i) => Some(cameras.get(i).ok_or_else(|| {
            fail(format!(
                "camera {i} does not exist: {}",
                camera_listing(scene, &cameras)
            ))
        })?),
        None => cameras.first(),
    };
    let Some(&(node, world, yfov)) = chosen else {
        return Ok(None);
    };
    view_from_node(world, yfov).map(Some).ok_or_else(|| {
        let position = cameras.iter().position(|c| c.0 == node).unwrap_or(0);
        fail(format!(
            "camera {position} (node {node} `{}`) cannot be used: its world transform is singular (a scale \
             of 0, or a matrix without an orientation); fix the file, or choose another view with --camera \
             I or --look-from/--look-at",
            scene.nodes.get(node).map_or("", |n| n.name.as_str())
        ))
    })
}

/// A camera node's view: rotation and translation of its world matrix (camera nodes may carry scale);
/// `None` when the matrix is singular or not finite.
fn view_from_node(world: Mat4, yfov: f32) -> Option<CameraView> {
    let det = world.determinant();
    if !(det.is_finite() && det != 0.0) {
        return None;
    }
    let (_, r, t) = world.to_scale_rotation_translation();
    (r.is_finite() && t.is_finite()).then(|| CameraView {
        world_from_camera: Mat4::from_rotation_translation(r.normalize(), t),
        yfov,
    })
}

/// Checks `choice` against the scene's cameras in the rest pose, before any GPU work: `--camera 99` or a
/// camera node of scale 0 fail at once, naming the file and its cameras.
pub fn check_camera_choice(scene: &SceneAsset, choice: &CameraChoice) -> Result<(), NoSuchCamera> {
    let index = match choice {
        CameraChoice::LookAt { .. } => return Ok(()),
        CameraChoice::Index(i) => Some(*i),
        CameraChoice::Auto => None,
    };
    let world = scene.rest_world_matrices();
    let shown = scene.displayed_nodes();
    let cameras = (0..scene.nodes.len())
        .filter(|&n| shown[n])
        .filter_map(|n| {
            let camera = scene.cameras.get(scene.nodes[n].camera?)?;
            Some((n, world[n], camera.yfov))
        })
        .collect();
    pick_camera(scene, cameras, index).map(|_| ())
}

/// The scene's glTF camera views in node order, from (node, world matrix, yfov) of each camera node.
pub fn scene_camera_views(cameras: impl Iterator<Item = (usize, Mat4, f32)>) -> Vec<CameraView> {
    let mut cameras: Vec<(usize, Mat4, f32)> = cameras.collect();
    cameras.sort_by_key(|c| c.0);
    cameras
        .into_iter()
        .map(|(_, m, yfov)| {
            // A singular node (the loader warns of it) looks down -Z from where it is, rather than a NaN view.
            view_from_node(m, yfov).unwrap_or(CameraView {
                world_from_camera: Mat4::from_translation(
                    Some(m.w_axis.truncate())
                        .filter(|t| t.is_finite())
                        .unwrap_or(Vec3::ZERO),
                ),
                yfov,
            })
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
    if let CameraChoice::LookAt { eye, target, yfov } = choice {
        return Ok(CameraView::look_at(*eye, *target, Vec3::Y, *yfov));
    }
    let cameras = world
        .query::<(&crate::scene::SceneNode, &CameraComponent, &GlobalTransform)>()
        .iter(world)
        .map(|(n, c, g)| (n.node, g.0, c.yfov))
        .collect();
    let index = match choice {
        CameraChoice::Index(i) => Some(*i),
        _ => None,
    };
    Ok(match pick_camera(scene, cameras, index)? {
        Some(view) => view,
        None => {
            let bounds = scene
                .rest_bounds()
                .unwrap_or((Vec3::splat(-1.0), Vec3::ONE));
            CameraView::framing(bounds, 45f32.to_radians(), aspect)
        }
    })
}

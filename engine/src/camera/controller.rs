//! Interactive cameras: orbit (around a target), fly (WASD/QE + mouse look) and the scene's own glTF cameras.
//! The viewer fills [`CameraInput`] from the mouse and keyboard each frame; [`drive_camera`] turns it into the
//! [`CameraView`] the path tracer renders (accumulation restarts only when the view really changed).

use super::{CameraView, scene_camera_views};
use crate::FrameSet;
use crate::scene::{CameraComponent, GlobalTransform, SceneNode};
use bevy_ecs::prelude::*;
use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum CameraMode {
    /// Turns around `target` at `distance`; drag rotates, right/middle drag pans, the wheel zooms.
    Orbit,
    /// Free flight: drag looks around, WASD/QE move, the wheel changes speed.
    Fly,
    /// The i-th glTF camera of the scene (node order), following its node when animated.
    Scene(usize),
}

/// One frame of camera input, filled by the viewer and consumed by [`drive_camera`].
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct CameraInput {
    /// Pixels dragged with the primary button.
    pub rotate: Vec2,
    /// Pixels dragged with the secondary or middle button.
    pub pan: Vec2,
    /// Wheel steps (positive: towards the scene / faster).
    pub scroll: f32,
    /// Held movement keys: x right (D - A), y up (E - Q), z forward (W - S).
    pub movement: Vec3,
    /// Shift held: move four times faster.
    pub fast: bool,
    /// Seconds since the last frame (movement speed is per second).
    pub dt: f32,
    /// Frame these world bounds (the selection): switches to orbit around them.
    pub frame: Option<(Vec3, Vec3)>,
    /// Back to the view the scene opened with.
    pub reset: bool,
    pub set_mode: Option<CameraMode>,
}

impl CameraInput {
    fn moves(&self) -> bool {
        self.rotate != Vec2::ZERO
            || self.pan != Vec2::ZERO
            || self.scroll != 0.0
            || self.movement != Vec3::ZERO
    }
}

/// The interactive camera's state. Orbit and fly share the look direction (yaw, pitch), so switching between
/// them keeps the picture where it is.
#[derive(Resource, Clone, Debug, PartialEq)]
pub struct CameraRig {
    pub mode: CameraMode,
    pub target: Vec3,
    pub distance: f32,
    /// Radians about +Y; 0 looks down -Z.
    pub yaw: f32,
    /// Radians above the horizon.
    pub pitch: f32,
    /// Eye position in fly mode.
    pub position: Vec3,
    pub yfov: f32,
    /// World units per second for WASD/QE.
    pub move_speed: f32,
    /// Radians per dragged pixel.
    pub look_sensitivity: f32,
    home: (CameraMode, CameraView),
}

const MAX_PITCH: f32 = 89.0 * std::f32::consts::PI / 180.0;

fn direction(yaw: f32, pitch: f32) -> Vec3 {
    Vec3::new(
        -yaw.sin() * pitch.cos(),
        pitch.sin(),
        -yaw.cos() * pitch.cos(),
    )
}

impl CameraRig {
    /// Starts from `view` in `mode`; `extent` (the scene's size) scales the initial orbit distance and speed.
    pub fn new(view: CameraView, mode: CameraMode, extent: f32) -> Self {
        let extent = if extent.is_finite() && extent > 0.0 {
            extent
        } else {
            1.0
        };
        let mut rig = Self {
            mode,
            target: Vec3::ZERO,
            distance: extent,
            yaw: 0.0,
            pitch: 0.0,
            position: Vec3::ZERO,
            yfov: view.yfov,
            move_speed: extent * 0.5,
            look_sensitivity: 0.005,
            home: (mode, view),
        };
        rig.set_from_view(&view);
        rig
    }

    /// Orbit/fly state that reproduces `view` (the target sits `distance` ahead).
    pub fn set_from_view(&mut self, view: &CameraView) {
        let f = view.forward();
        self.pitch = f.y.clamp(-1.0, 1.0).asin().clamp(-MAX_PITCH, MAX_PITCH);
        self.yaw = (-f.x).atan2(-f.z);
        self.position = view.position();
        self.target = self.position + f * self.distance;
        self.yfov = view.yfov;
    }

    pub fn forward(&self) -> Vec3 {
        direction(self.yaw, self.pitch)
    }

    fn right(&self) -> Vec3 {
        self.forward().cross(Vec3::Y).normalize_or(Vec3::X)
    }

    /// The view of orbit or fly mode (scene cameras come from their nodes).
    pub fn free_view(&self) -> CameraView {
        let f = self.forward();
        let eye = match self.mode {
            CameraMode::Orbit => self.target - f * self.distance,
            _ => self.position,
        };
        CameraView::look_at(eye, eye + f, Vec3::Y, self.yfov)
    }

    /// Orbit around the bounds' centre, far enough that their bounding sphere fills the view.
    pub fn frame_bounds(&mut self, lo: Vec3, hi: Vec3) {
        let radius = ((hi - lo).length() * 0.5).max(1e-3);
        self.mode = CameraMode::Orbit;
        self.target = (lo + hi) * 0.5;
        self.distance = radius / (self.yfov * 0.5).sin().max(1e-3);
        self.position = self.target - self.forward() * self.distance;
    }

    /// Applies one frame of input; `current` is the view on screen (to leave a scene camera smoothly).
    pub fn apply(&mut self, input: &CameraInput, current: &CameraView) {
        if input.reset {
            let (mode, view) = self.home;
            self.mode = mode;
            self.set_from_view(&view);
        }
        if let Some(mode) = input.set_mode {
            if matches!(self.mode, CameraMode::Scene(_)) && !matches!(mode, CameraMode::Scene(_)) {
                self.set_from_view(current);
            }
            if mode == CameraMode::Orbit {
                self.target = self.position + self.forward() * self.distance;
            }
            self.mode = mode;
        }
        if let Some((lo, hi)) = input.frame {
            self.frame_bounds(lo, hi);
        }
        if !input.moves() {
            return;
        }
        // Moving away from a scene camera continues from where it looks, in orbit mode.
        if let CameraMode::Scene(_) = self.mode {
            self.set_from_view(current);
            self.mode = CameraMode::Orbit;
        }
        self.yaw = (self.yaw - input.rotate.x * self.look_sensitivity + std::f32::consts::PI)
            .rem_euclid(std::f32::consts::TAU)
            - std::f32::consts::PI;
        self.pitch =
            (self.pitch - input.rotate.y * self.look_sensitivity).clamp(-MAX_PITCH, MAX_PITCH);
        let (f, r) = (self.forward(), self.right());
        let up = r.cross(f);
        let speed = self.move_speed * if input.fast { 4.0 } else { 1.0 };
        let step = (r * input.movement.x + up * input.movement.y + f * input.movement.z)
            * speed
            * input.dt.max(0.0);
        match self.mode {
            CameraMode::Orbit => {
                let pan_scale = self.distance * 0.002;
                self.target += step + (-r * input.pan.x + up * input.pan.y) * pan_scale;
                self.distance = (self.distance * 0.9f32.powf(input.scroll)).max(1e-4);
                self.position = self.target - f * self.distance;
            }
            CameraMode::Fly | CameraMode::Scene(_) => {
                let pan_scale = self.move_speed * 0.004;
                self.position += step + (-r * input.pan.x + up * input.pan.y) * pan_scale;
                self.move_speed = (self.move_speed * 1.2f32.powf(input.scroll)).max(1e-4);
                self.target = self.position + f * self.distance;
            }
        }
    }
}

/// Applies [`CameraInput`] to the [`CameraRig`] and writes the resulting [`CameraView`] (only when it
/// changed, so an idle camera keeps accumulating). Runs after transform propagation, so an animated scene
/// camera is followed in the same frame.
pub fn drive_camera(
    mut rig: ResMut<CameraRig>,
    mut input: ResMut<CameraInput>,
    cameras: Query<(&SceneNode, &CameraComponent, &GlobalTransform)>,
    mut view: ResMut<CameraView>,
) {
    let input = std::mem::take(&mut *input);
    let current = *view;
    rig.apply(&input, &current);
    let next = match rig.mode {
        CameraMode::Scene(i) => {
            let scene_views =
                scene_camera_views(cameras.iter().map(|(n, c, g)| (n.node, g.0, c.yfov)));
            match scene_views.get(i) {
                Some(v) => *v,
                None => {
                    // The camera is gone (another scene was loaded): fall back to orbiting.
                    rig.mode = CameraMode::Orbit;
                    rig.free_view()
                }
            }
        }
        _ => rig.free_view(),
    };
    if next != current {
        *view = next;
    }
}

/// Drives [`CameraView`] from a [`CameraRig`] resource (inserted by the viewer) each frame.
pub struct CameraControllerPlugin;

impl bevy_app::Plugin for CameraControllerPlugin {
    fn build(&self, app: &mut bevy_app::App) {
        app.init_resource::<CameraInput>().add_systems(
            bevy_app::Update,
            drive_camera
                .in_set(FrameSet::Transform)
                .after(crate::scene::propagate_transforms)
                .run_if(resource_exists::<CameraRig>),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rig() -> CameraRig {
        let view = CameraView::look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 0.8);
        CameraRig::new(view, CameraMode::Orbit, 5.0)
    }

    #[test]
    fn the_initial_view_is_reproduced() {
        let r = rig();
        let v = r.free_view();
        assert!((v.position() - Vec3::new(0.0, 0.0, 5.0)).length() < 1e-4);
        assert!((v.forward() - Vec3::NEG_Z).length() < 1e-4);
        assert!((r.target - Vec3::ZERO).length() < 1e-4, "{:?}", r.target);
    }

    #[test]
    fn orbiting_keeps_the_distance_and_looks_at_the_target() {
        let mut r = rig();
        let view = r.free_view();
        r.apply(
            &CameraInput {
                rotate: Vec2::new(120.0, -40.0),
                ..Default::default()
            },
            &view,
        );
        let v = r.free_view();
        assert!((v.position().distance(r.target) - 5.0).abs() < 1e-3);
        let to_target = (r.target - v.position()).normalize();
        assert!(to_target.dot(v.forward()) > 0.9999);
        assert!(v.position().x.abs() > 0.5, "the eye moved sideways");
    }

    #[test]
    fn flying_forward_moves_along_the_view() {
        let mut r = rig();
        r.mode = CameraMode::Fly;
        let view = r.free_view();
        r.apply(
            &CameraInput {
                movement: Vec3::Z,
                dt: 1.0,
                ..Default::default()
            },
            &view,
        );
        let moved = r.free_view().position() - view.position();
        assert!(
            (moved - Vec3::NEG_Z * r.move_speed).length() < 1e-4,
            "{moved:?}"
        );
    }

    #[test]
    fn framing_fits_the_bounding_sphere() {
        let mut r = rig();
        r.frame_bounds(Vec3::splat(9.0), Vec3::splat(11.0));
        let v = r.free_view();
        let radius = 3f32.sqrt();
        let d = v.position().distance(Vec3::splat(10.0));
        assert!((radius / d - (r.yfov * 0.5).sin()).abs() < 1e-4);
        assert_eq!(r.mode, CameraMode::Orbit);
    }

    #[test]
    fn reset_returns_home() {
        let mut r = rig();
        let home = r.free_view();
        r.apply(
            &CameraInput {
                rotate: Vec2::new(300.0, 80.0),
                scroll: 3.0,
                ..Default::default()
            },
            &home,
        );
        let moved = r.free_view();
        assert!(moved.position().distance(home.position()) > 1.0);
        r.apply(
            &CameraInput {
                reset: true,
                ..Default::default()
            },
            &moved,
        );
        assert!(r.free_view().position().distance(home.position()) < 1e-3);
    }
}

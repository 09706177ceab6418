//! Keyframe sampling of glTF animation channels (STEP, LINEAR with slerp, CUBICSPLINE), animation players,
//! and CPU skinning and morphing ([`deform`]).

mod crowd;
mod deform;
mod interior;
mod seed_interior;

pub use crowd::{CrowdScene, crowd_scene};
pub use interior::{InteriorScene, interior_scene};
pub use seed_interior::{SeedInterior, seed_interior_scene};

pub use deform::{
    DeformedElsewhere, DeformedMesh, DeformedMeshes, MeshPose, MeshPoses, deform_mesh,
    deform_meshes, joint_matrices, pose_meshes,
};

use crate::FrameSet;
use crate::scene::{
    AnimationChannel, ChannelValues, Interpolation, MorphWeights, SceneAssets, SceneNode,
    SceneNodes, Transform,
};
use bevy_ecs::prelude::*;
use glam::{Quat, Vec3};

/// A sampled channel value.
#[derive(Clone, Debug, PartialEq)]
pub enum Sampled {
    Translation(Vec3),
    Rotation(Quat),
    Scale(Vec3),
    Weights(Vec<f32>),
}

/// Where `t` falls: keyframe index `i` and the fraction towards `i + 1` (clamped to the first/last key).
fn locate(times: &[f32], t: f32) -> (usize, f32, f32) {
    let last = times.len() - 1;
    if t <= times[0] || last == 0 {
        return (0, 0.0, 0.0);
    }
    if t >= times[last] {
        return (last, 0.0, 0.0);
    }
    let i = times.partition_point(|&k| k <= t) - 1;
    let dt = times[i + 1] - times[i];
    (i, (t - times[i]) / dt, dt)
}

/// Cubic Hermite spline between keys i and i+1; `get(k)` gives (in-tangent, value, out-tangent) of key k.
fn hermite<T>(s: f32, dt: f32, p0: T, m0: T, p1: T, m1: T) -> T
where
    T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    let (s2, s3) = (s * s, s * s * s);
    p0 * (2.0 * s3 - 3.0 * s2 + 1.0)
        + m0 * ((s3 - 2.0 * s2 + s) * dt)
        + p1 * (-2.0 * s3 + 3.0 * s2)
        + m1 * ((s3 - s2) * dt)
}

fn sample_vec3(interp: Interpolation, times: &[f32], v: &[Vec3], t: f32) -> Vec3 {
    let (i, s, dt) = locate(times, t);
    match interp {
        Interpolation::CubicSpline => {
            if s == 0.0 {
                return v[3 * i + 1];
            }
            hermite(
                s,
                dt,
                v[3 * i + 1],
                v[3 * i + 2],
                v[3 * (i + 1) + 1],
                v[3 * (i + 1)],
            )
        }
        Interpolation::Step => v[i],
        Interpolation::Linear => {
            if s == 0.0 {
                v[i]
            } else {
                v[i].lerp(v[i + 1], s)
            }
        }
    }
}

fn sample_quat(interp: Interpolation, times: &[f32], v: &[Quat], t: f32) -> Quat {
    let (i, s, dt) = locate(times, t);
    let q = match interp {
        Interpolation::CubicSpline => {
            if s == 0.0 {
                v[3 * i + 1]
            } else {
                let [a, b, c, d] = [
                    v[3 * i + 1],
                    v[3 * i + 2],
                    v[3 * (i + 1) + 1],
                    v[3 * (i + 1)],
                ]
                .map(glam::Vec4::from);
                Quat::from_vec4(hermite(s, dt, a, b, c, d))
            }
        }
        Interpolation::Step => v[i],
        Interpolation::Linear => {
            if s == 0.0 {
                v[i]
            } else {
                slerp_shortest(v[i], v[i + 1], s)
            }
        }
    };
    let len = q.length();
    if len > 0.0 && len.is_finite() {
        q / len
    } else {
        Quat::IDENTITY
    }
}

/// Spherical interpolation along the shorter arc (glTF: "slerp"), exact for nearly parallel keys too.
pub fn slerp_shortest(a: Quat, b: Quat, s: f32) -> Quat {
    let mut b = b;
    let mut d = a.dot(b);
    if d < 0.0 {
        b = -b;
        d = -d;
    }
    if d > 0.9995 {
        return a.lerp(b, s).normalize();
    }
    let theta = d.clamp(-1.0, 1.0).acos();
    let sin = theta.sin();
    a * (((1.0 - s) * theta).sin() / sin) + b * ((s * theta).sin() / sin)
}

fn sample_weights(
    interp: Interpolation,
    times: &[f32],
    v: &[f32],
    count: usize,
    t: f32,
) -> Vec<f32> {
    let (i, s, dt) = locate(times, t);
    let key = |k: usize, part: usize| -> &[f32] {
        let stride = if interp == Interpolation::CubicSpline {
            3
        } else {
            1
        };
        let start = (k * stride + part) * count;
        &v[start..start + count]
    };
    match interp {
        Interpolation::Step => key(i, 0).to_vec(),
        Interpolation::Linear => {
            if s == 0.0 {
                return key(i, 0).to_vec();
            }
            key(i, 0)
                .iter()
                .zip(key(i + 1, 0))
                .map(|(a, b)| a + (b - a) * s)
                .collect()
        }
        Interpolation::CubicSpline => {
            if s == 0.0 {
                return key(i, 1).to_vec();
            }
            (0..count)
                .map(|w| {
                    hermite(
                        s,
                        dt,
                        key(i, 1)[w],
                        key(i, 2)[w],
                        key(i + 1, 1)[w],
                        key(i + 1, 0)[w],
                    )
                })
                .collect()
        }
    }
}

/// The channel's value at `t` seconds; `t` is clamped to the channel's keyframe range.
pub fn sample_channel(c: &AnimationChannel, t: f32) -> Sampled {
    match &c.values {
        ChannelValues::Translation(v) => {
            Sampled::Translation(sample_vec3(c.interpolation, &c.times, v, t))
        }
        ChannelValues::Scale(v) => Sampled::Scale(sample_vec3(c.interpolation, &c.times, v, t)),
        ChannelValues::Rotation(v) => {
            Sampled::Rotation(sample_quat(c.interpolation, &c.times, v, t))
        }
        ChannelValues::Weights { values, count } => {
            Sampled::Weights(sample_weights(c.interpolation, &c.times, values, *count, t))
        }
    }
}

/// Explicit time: every frame advances playing players by `delta` seconds (no wall clock), so the same
/// frame count always gives the same pose.
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct FrameClock {
    /// Seconds per frame (default 1/60).
    pub delta: f32,
    /// Frames run so far.
    pub frame: u64,
}

impl Default for FrameClock {
    fn default() -> Self {
        Self {
            delta: 1.0 / 60.0,
            frame: 0,
        }
    }
}

/// What a player does at the end of its clip.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PlayMode {
    /// Wraps to the start.
    #[default]
    Loop,
    /// Holds the last pose and stops playing.
    Once,
    /// Plays forwards then backwards.
    PingPong,
}

/// Plays one clip of the scene on the copy of the scene it sits in. Put it on a scene root entity, or on
/// any node entity (a crowd puts one on each copy's group node); several players run at once.
/// The pose of a frame is the clip at `time` as the frame starts; playing players then advance by
/// `speed` x [`FrameClock::delta`].
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct AnimationPlayer {
    /// Index into [`crate::scene::SceneAsset::animations`].
    pub clip: usize,
    pub time: f32,
    pub speed: f32,
    pub mode: PlayMode,
    pub playing: bool,
}

impl AnimationPlayer {
    /// Plays `clip` in a loop from 0 at normal speed.
    pub fn new(clip: usize) -> Self {
        Self {
            clip,
            time: 0.0,
            speed: 1.0,
            mode: PlayMode::Loop,
            playing: true,
        }
    }

    /// Holds `clip` at `time` seconds (times outside the clip clamp to its ends).
    pub fn paused_at(clip: usize, time: f32) -> Self {
        Self {
            clip,
            time,
            speed: 1.0,
            mode: PlayMode::Once,
            playing: false,
        }
    }

    /// The clip-local sampling time for a clip of `duration` seconds.
    pub fn local_time(&self, duration: f32) -> f32 {
        if !self.time.is_finite() {
            return 0.0;
        }
        if duration <= 0.0 {
            return self.time.max(0.0);
        }
        match self.mode {
            PlayMode::Once => self.time.clamp(0.0, duration),
            PlayMode::Loop => self.time.rem_euclid(duration),
            PlayMode::PingPong => {
                let t = self.time.rem_euclid(2.0 * duration);
                if t > duration { 2.0 * duration - t } else { t }
            }
        }
    }

    fn advance(&mut self, dt: f32, duration: f32) {
        if !self.playing {
            return;
        }
        self.time += dt * self.speed;
        match self.mode {
            PlayMode::Once if self.time >= duration || self.time <= 0.0 => {
                self.time = self.time.clamp(0.0, duration);
                self.playing = false;
            }
            // Keep the stored time small so f32 precision does not drift over long runs.
            PlayMode::Loop if duration > 0.0 => self.time = self.time.rem_euclid(duration),
            PlayMode::PingPong if duration > 0.0 => {
                self.time = self.time.rem_euclid(2.0 * duration)
            }
            _ => {}
        }
    }
}

/// Resolves `--animation NAME|INDEX` to a clip index; the error lists the clips.
pub fn find_clip(scene: &crate::scene::SceneAsset, name_or_index: &str) -> Result<usize, String> {
    let list = || {
        scene
            .animations
            .iter()
            .enumerate()
            .map(|(i, a)| format!("{i}: `{}` ({:.3} s)", a.name, a.duration))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if scene.animations.is_empty() {
        return Err(format!("{} has no animations", scene.source));
    }
    if let Some(i) = scene
        .animations
        .iter()
        .position(|a| a.name == name_or_index)
    {
        return Ok(i);
    }
    match name_or_index.parse::<usize>() {
        Ok(i) if i < scene.animations.len() => Ok(i),
        _ => Err(format!(
            "{}: no animation `{name_or_index}`; the clips are {}",
            scene.source,
            list()
        )),
    }
}

/// Holds every spawned scene copy at `seconds` into `clip` (a paused player on each scene root): the next
/// animation pass poses exactly that time, whatever ran before.
pub fn hold_at(world: &mut World, clip: usize, seconds: f32) {
    let roots: Vec<Entity> = world
        .query_filtered::<Entity, With<crate::scene::SceneRoot>>()
        .iter(world)
        .collect();
    for root in roots {
        world
            .entity_mut(root)
            .insert(AnimationPlayer::paused_at(clip, seconds));
    }
}

/// Adds `(node, player)` pairs to a spawned scene copy whose root is `root` (see [`crowd_scene`]).
pub fn attach_players(world: &mut World, root: Entity, players: &[(usize, AnimationPlayer)]) {
    let Some(nodes) = world.get::<SceneNodes>(root).map(|n| n.0.clone()) else {
        return;
    };
    for (node, player) in players {
        if let Some(&e) = nodes.get(*node) {
            world.entity_mut(e).insert(*player);
        }
    }
}

/// Samples every player's clip and writes node [`Transform`]s and [`MorphWeights`], then advances time.
pub fn animate(
    mut clock: ResMut<FrameClock>,
    assets: Res<SceneAssets>,
    mut players: Query<(Entity, &mut AnimationPlayer, Option<&SceneNode>)>,
    roots: Query<&SceneNodes>,
    mut targets: Query<(&mut Transform, Option<&mut MorphWeights>)>,
) {
    let scene = &assets.0;
    for (entity, mut player, node) in &mut players {
        let Some(clip) = scene.animations.get(player.clip) else {
            continue;
        };
        let root = node.map_or(entity, |n| n.root);
        let Ok(nodes) = roots.get(root) else { continue };
        let t = player.local_time(clip.duration);
        for channel in &clip.channels {
            let Some(&target) = nodes.0.get(channel.node) else {
                continue;
            };
            let Ok((mut transform, weights)) = targets.get_mut(target) else {
                continue;
            };
            match sample_channel(channel, t) {
                Sampled::Translation(v) => transform.translation = v,
                Sampled::Rotation(q) => transform.rotation = q,
                Sampled::Scale(v) => transform.scale = v,
                Sampled::Weights(w) => {
                    if let Some(mut weights) = weights {
                        let n = weights.0.len();
                        weights
                            .0
                            .iter_mut()
                            .zip(w.iter().chain(std::iter::repeat(&0.0)).take(n))
                            .for_each(|(a, b)| *a = *b);
                    }
                }
            }
        }
        player.advance(clock.delta, clip.duration);
    }
    clock.frame += 1;
}

/// Animation players (Animate set); poses and CPU skinning/morphing (Deform set).
pub struct AnimationPlugin;

impl bevy_app::Plugin for AnimationPlugin {
    fn build(&self, app: &mut bevy_app::App) {
        use bevy_ecs::schedule::IntoScheduleConfigs;
        app.init_resource::<FrameClock>()
            .init_resource::<DeformedMeshes>()
            .init_resource::<MeshPoses>()
            .init_resource::<DeformedElsewhere>()
            .add_systems(
                bevy_app::Update,
                (
                    animate.in_set(FrameSet::Animate),
                    (pose_meshes, deform_meshes)
                        .chain()
                        .in_set(FrameSet::Deform),
                ),
            );
    }
}

/// A world with the scene spawned and the CPU frame systems (animation, transforms, deformation) but no
/// GPU: tests and benches pose scenes with it.
pub fn cpu_app(scene: std::sync::Arc<crate::scene::SceneAsset>) -> bevy_app::App {
    let mut app = bevy_app::App::new();
    crate::configure_frame_schedule(&mut app);
    app.add_plugins(crate::scene::ScenePlugin { scene })
        .add_plugins(AnimationPlugin);
    app
}

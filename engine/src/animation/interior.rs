//! The animated interior bench scene: characters walking inside the Cornell box, lit only by emitters
//! ([`crate::scene::compose`] of the box, CesiumMan, the Fox and a lamp), with the players that animate it.

use super::AnimationPlayer;
use crate::scene::compose::compose;
use crate::scene::{
    AnimationChannel, AnimationClip, ChannelValues, Interpolation, LoadOptions, Material,
    NodeTransform, SceneAsset, SceneError, load_gltf, procedural,
};
use glam::{Quat, Vec3, Vec4};
use std::path::Path;
use std::sync::Arc;

/// The animated interior bench scene: [`interior_scene`]'s scene, its players, and the lamp a bench can switch
/// on (its material starts without emission).
pub struct InteriorScene {
    pub scene: SceneAsset,
    pub players: Vec<(usize, AnimationPlayer)>,
    /// Material of the wall lamp: set its emission to switch it on.
    pub lamp_material: usize,
    /// The lamp's emitted radiance when on.
    pub lamp_radiance: Vec3,
}

/// An animated interior lit only by emitters: the Cornell box (its ceiling light) with CesiumMan walking
/// across the front left and the Fox walking to and fro at the back right, both moved along their paths by
/// clips on their group nodes (rigid motion) while their own clips skin them; and a small lamp on the back
/// wall, off. The box's classic camera frames it (`raykin bench --scene interior`). `shared_assets` holds
/// `CornellBox/`, `CesiumMan/` and `Fox/`.
pub fn interior_scene(shared_assets: impl AsRef<Path>) -> Result<InteriorScene, SceneError> {
    use std::f32::consts::{FRAC_PI_2, PI};
    let dir = shared_assets.as_ref();
    let options = LoadOptions::default();
    let cornell = Arc::new(load_gltf(dir.join("CornellBox/CornellBox.glb"), &options)?);
    let man = Arc::new(load_gltf(
        dir.join("CesiumMan/glTF-Binary/CesiumMan.glb"),
        &options,
    )?);
    let fox = Arc::new(load_gltf(dir.join("Fox/glTF-Binary/Fox.glb"), &options)?);
    let lamp_radiance = Vec3::new(10.0, 8.0, 6.0);
    let lamp = Arc::new(procedural::scene_from_meshes(
        "lamp",
        vec![(procedural::ground_quad(90.0, 0), NodeTransform::default())],
        vec![Material {
            name: "lamp".into(),
            base_color: Vec4::new(0.8, 0.8, 0.8, 1.0),
            metallic: 0.0,
            roughness: 0.9,
            emissive: Vec3::ZERO,
            ..Default::default()
        }],
    ));
    // Box interior: x -556..0, y 0..549, z -559..0; the tall block near (-368, -351), the short one near
    // (-185, -169). CesiumMan is 1.5 units tall (x180: 270), the Fox 79 (x1.2: 95).
    let parts = vec![
        (cornell, NodeTransform::default()),
        (
            man.clone(),
            NodeTransform {
                translation: Vec3::new(-500.0, 0.0, -110.0),
                rotation: Quat::IDENTITY,
                scale: Vec3::splat(180.0),
            },
        ),
        (
            fox.clone(),
            NodeTransform {
                translation: Vec3::new(-110.0, 0.0, -520.0),
                rotation: Quat::IDENTITY,
                scale: Vec3::splat(1.2),
            },
        ),
        (
            lamp,
            NodeTransform {
                translation: Vec3::new(-120.0, 330.0, -557.0),
                rotation: Quat::from_rotation_x(FRAC_PI_2),
                scale: Vec3::ONE,
            },
        ),
    ];
    let (mut scene, copies) = compose("interior (Cornell box, CesiumMan, Fox)", &parts);
    // Paths: the man walks along +x and back, the fox along +z and back, each turning at the ends.
    let path_clip = |node: usize, from: Vec3, to: Vec3, seconds: f32, facing: [Quat; 2]| {
        let times = vec![0.0, seconds, seconds, 2.0 * seconds];
        AnimationClip {
            name: format!("path of node {node}"),
            channels: vec![
                AnimationChannel {
                    node,
                    interpolation: Interpolation::Linear,
                    times: vec![0.0, seconds, 2.0 * seconds],
                    values: ChannelValues::Translation(vec![from, to, from]),
                },
                AnimationChannel {
                    node,
                    interpolation: Interpolation::Step,
                    times,
                    values: ChannelValues::Rotation(vec![
                        facing[0], facing[0], facing[1], facing[1],
                    ]),
                },
            ],
            duration: 2.0 * seconds,
        }
    };
    let (man_copy, fox_copy) = (&copies[1], &copies[2]);
    let man_path = scene.animations.len();
    scene.animations.push(path_clip(
        man_copy.group_node,
        Vec3::new(-510.0, 0.0, -110.0),
        Vec3::new(-290.0, 0.0, -110.0),
        4.0,
        [
            Quat::from_rotation_y(FRAC_PI_2),
            Quat::from_rotation_y(-FRAC_PI_2),
        ],
    ));
    let fox_path = scene.animations.len();
    scene.animations.push(path_clip(
        fox_copy.group_node,
        Vec3::new(-110.0, 0.0, -530.0),
        Vec3::new(-110.0, 0.0, -300.0),
        3.0,
        [Quat::IDENTITY, Quat::from_rotation_y(PI)],
    ));
    // One player per entity: the paths on the group nodes, the walk cycles on each copy's first node.
    let mut players = vec![
        (man_copy.group_node, AnimationPlayer::new(man_path)),
        (fox_copy.group_node, AnimationPlayer::new(fox_path)),
    ];
    if man_copy.clip_count > 0 {
        players.push((
            man_copy.group_node + 1,
            AnimationPlayer::new(man_copy.first_clip),
        ));
    }
    if fox_copy.clip_count > 1 {
        // The Fox's clip 1 is its walk.
        players.push((
            fox_copy.group_node + 1,
            AnimationPlayer::new(fox_copy.first_clip + 1),
        ));
    }
    let lamp_material = scene
        .materials
        .iter()
        .position(|m| m.name == "lamp")
        .unwrap_or(scene.materials.len().saturating_sub(1));
    Ok(InteriorScene {
        scene,
        players,
        lamp_material,
        lamp_radiance,
    })
}

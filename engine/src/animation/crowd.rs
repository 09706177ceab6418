//! The crowd benchmark scene: copies of animated characters composed into one scene
//! ([`crate::scene::compose`]), each with the player that animates it.

use super::AnimationPlayer;
use crate::scene::compose::{ComposedCopy, compose};
use crate::scene::{
    LoadOptions, Material, NodeTransform, SceneAsset, SceneError, load_gltf, procedural,
};
use glam::{Quat, Vec3, Vec4};
use std::path::Path;
use std::sync::Arc;

/// A composed scene plus the animation players to attach to its copies' group nodes.
pub struct CrowdScene {
    pub scene: SceneAsset,
    pub copies: Vec<ComposedCopy>,
    /// (group node, player): spawn with [`super::attach_players`].
    pub players: Vec<(usize, AnimationPlayer)>,
}

/// The crowd benchmark: 64 CesiumMan (8x8 grid) and 32 Fox (8x4 grid) on a ground quad, each playing its
/// clip 0 (Fox: clips 0..3 in turn) looped from a staggered start time. `shared_assets` is the folder that
/// holds `CesiumMan/` and `Fox/` (`../shared/assets` from the repository root).
pub fn crowd_scene(shared_assets: impl AsRef<Path>) -> Result<CrowdScene, SceneError> {
    let dir = shared_assets.as_ref();
    let options = LoadOptions::default();
    let man = Arc::new(load_gltf(
        dir.join("CesiumMan/glTF-Binary/CesiumMan.glb"),
        &options,
    )?);
    let fox = Arc::new(load_gltf(dir.join("Fox/glTF-Binary/Fox.glb"), &options)?);
    let ground = Arc::new(procedural::scene_from_meshes(
        "ground",
        vec![(procedural::ground_quad(40.0, 0), NodeTransform::default())],
        vec![Material {
            base_color: Vec4::new(0.6, 0.6, 0.6, 1.0),
            metallic: 0.0,
            roughness: 0.8,
            ..Default::default()
        }],
    ));
    let mut parts = vec![(ground, NodeTransform::default())];
    let mut starts = Vec::new();
    for i in 0..64 {
        let (x, z) = ((i % 8) as f32 * 1.6 - 5.6, (i / 8) as f32 * 1.6 - 8.0);
        parts.push((
            man.clone(),
            NodeTransform {
                translation: Vec3::new(x, 0.0, z),
                ..Default::default()
            },
        ));
        starts.push((0usize, i as f32 * 0.097));
    }
    for i in 0..32 {
        let (x, z) = ((i % 8) as f32 * 1.6 - 5.6, (i / 8) as f32 * 1.6 + 5.0);
        let placement = NodeTransform {
            translation: Vec3::new(x, 0.0, z),
            rotation: Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
            scale: Vec3::splat(0.012),
        };
        parts.push((fox.clone(), placement));
        starts.push(((i % 3) as usize, i as f32 * 0.131));
    }
    let (scene, copies) = compose("crowd (64 CesiumMan + 32 Fox)", &parts);
    let players = copies[1..]
        .iter()
        .zip(starts)
        .filter(|(c, _)| c.clip_count > 0)
        .map(|(c, (clip, t))| {
            let clip = c.first_clip + clip.min(c.clip_count - 1);
            let mut p = AnimationPlayer::new(clip);
            p.time = t;
            (c.group_node, p)
        })
        .collect();
    Ok(CrowdScene {
        scene,
        copies,
        players,
    })
}

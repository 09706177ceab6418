//! Scene composition: deformable meshes get one node each, and N placed copies of scenes merge into one
//! [`SceneAsset`] (a crowd), sharing static meshes and duplicating deformable ones.

use super::*;
use crate::animation::AnimationPlayer;
use std::path::Path;

/// Gives every deformable mesh (skin or morph targets) used by several nodes its own copy, so that each
/// node instance deforms, refits and uploads its own vertices and BVH. Static meshes stay shared.
/// Also reports skin data problems (out-of-range joints, all-zero weights) as warnings; see
/// [`crate::animation::deform_mesh`] for the fallbacks.
pub fn unshare_deformable_meshes(scene: &mut SceneAsset) {
    let mut used = vec![false; scene.meshes.len()];
    for n in 0..scene.nodes.len() {
        let Some(m) = scene.nodes[n].mesh else {
            continue;
        };
        if m >= scene.meshes.len() || !scene.meshes[m].is_deformable() {
            continue;
        }
        if used[m] {
            let copy = scene.meshes[m].clone();
            scene.nodes[n].mesh = Some(scene.meshes.len());
            scene.meshes.push(copy);
            used.push(true);
        } else {
            used[m] = true;
        }
    }
    let mut warnings = Vec::new();
    for (n, node) in scene.nodes.iter().enumerate() {
        let (Some(m), Some(s)) = (node.mesh, node.skin) else {
            continue;
        };
        let Some(skin) = scene.skins.get(s) else {
            continue;
        };
        let Some(w) = &scene.meshes[m].skin_weights else {
            warnings.push(format!(
                "node {n}: has skin {s} but its mesh has no JOINTS_0/WEIGHTS_0; drawn unskinned"
            ));
            continue;
        };
        let sets = w.sets.max(1) as usize;
        let (mut bad_joint, mut zero) = (0usize, 0usize);
        for v in 0..w.joints.len() / sets {
            let mut sum = 0.0;
            for i in v * sets..(v + 1) * sets {
                for k in 0..4 {
                    if w.weights[i][k] > 0.0 {
                        if (w.joints[i][k] as usize) < skin.joints.len() {
                            sum += w.weights[i][k];
                        } else {
                            bad_joint += 1;
                        }
                    }
                }
            }
            if sum <= 0.0 {
                zero += 1;
            }
        }
        if bad_joint > 0 {
            warnings.push(format!(
                "node {n}: {bad_joint} skin influences name joints outside skin {s} ({} joints); those influences are ignored",
                skin.joints.len()
            ));
        }
        if zero > 0 {
            warnings.push(format!(
                "node {n}: {zero} vertices have no usable skin weight; they follow the node rigidly"
            ));
        }
    }
    scene.warnings.extend(warnings);
}

/// One placed copy inside a composed scene.
#[derive(Clone, Debug)]
pub struct ComposedCopy {
    /// The group node that places the copy (its children are the copy's root nodes).
    pub group_node: usize,
    /// The copy's clips are `first_clip..first_clip + clip_count` of the composed scene.
    pub first_clip: usize,
    pub clip_count: usize,
}

/// Merges placed copies of scenes into one. Materials, textures, images and static meshes are shared
/// between copies of the same asset (`Arc` identity); deformable meshes, nodes, skins and clips are copied
/// (clips re-targeted to the copy's nodes). Each copy hangs under a new group node carrying its placement.
pub fn compose(
    name: &str,
    parts: &[(Arc<SceneAsset>, NodeTransform)],
) -> (SceneAsset, Vec<ComposedCopy>) {
    let mut out = SceneAsset {
        source: name.into(),
        ..Default::default()
    };
    let mut copies = Vec::new();
    // Per distinct asset: material offset, texture offset, and shared mesh indices.
    let mut seen: Vec<(*const SceneAsset, u32, Vec<Option<usize>>)> = Vec::new();
    for (asset, placement) in parts {
        let key = Arc::as_ptr(asset);
        let idx = match seen.iter().position(|s| s.0 == key) {
            Some(i) => i,
            None => {
                let material_offset = out.materials.len() as u32;
                let texture_offset = out.textures.len() as u32;
                let image_offset = out.images.len() as u32;
                out.images.extend(asset.images.iter().cloned());
                out.textures.extend(asset.textures.iter().map(|t| Texture {
                    image: t.image + image_offset,
                    ..*t
                }));
                let shift = |t: Option<TextureRef>| {
                    t.map(|t| TextureRef {
                        texture: t.texture + texture_offset,
                        ..t
                    })
                };
                out.materials
                    .extend(asset.materials.iter().map(|m| Material {
                        base_color_texture: shift(m.base_color_texture),
                        metallic_roughness_texture: shift(m.metallic_roughness_texture),
                        normal_texture: shift(m.normal_texture),
                        emissive_texture: shift(m.emissive_texture),
                        ..m.clone()
                    }));
                seen.push((key, material_offset, vec![None; asset.meshes.len()]));
                seen.len() - 1
            }
        };
        let material_offset = seen[idx].1;
        // The glTF default material (index == materials.len()) maps to the composed scene's default, which
        // the renderer appends after all materials: remap it to an explicit copy instead.
        let default_slot = asset.materials.len() as u32;
        let mut mesh_map = Vec::with_capacity(asset.meshes.len());
        for (m, mesh) in asset.meshes.iter().enumerate() {
            if !mesh.is_deformable()
                && let Some(shared) = seen[idx].2[m]
            {
                mesh_map.push(shared);
                continue;
            }
            let mut copy = mesh.clone();
            let remap = |mat: u32| {
                if mat >= default_slot {
                    u32::MAX
                } else {
                    mat + material_offset
                }
            };
            copy.triangle_materials
                .iter_mut()
                .for_each(|t| *t = remap(*t));
            copy.primitives
                .iter_mut()
                .for_each(|p| p.material = remap(p.material));
            let index = out.meshes.len();
            out.meshes.push(copy);
            if !mesh.is_deformable() {
                seen[idx].2[m] = Some(index);
            }
            mesh_map.push(index);
        }
        let node_offset = out.nodes.len() + 1;
        let skin_offset = out.skins.len();
        let camera_offset = out.cameras.len();
        let group = out.nodes.len();
        out.nodes.push(NodeData {
            name: format!("{} #{}", asset.source, copies.len()),
            children: asset.roots.iter().map(|r| r + node_offset).collect(),
            transform: *placement,
            ..Default::default()
        });
        out.roots.push(group);
        for node in &asset.nodes {
            out.nodes.push(NodeData {
                parent: Some(node.parent.map_or(group, |p| p + node_offset)),
                children: node.children.iter().map(|c| c + node_offset).collect(),
                mesh: node.mesh.map(|m| mesh_map[m]),
                camera: node.camera.map(|c| c + camera_offset),
                skin: node.skin.map(|s| s + skin_offset),
                ..node.clone()
            });
        }
        // Nodes outside the copy's displayed scene are not parented to the group.
        for (i, node) in asset.nodes.iter().enumerate() {
            if node.parent.is_none() && !asset.roots.contains(&i) {
                out.nodes[i + node_offset].parent = None;
            }
        }
        out.cameras.extend(asset.cameras.iter().copied());
        out.skins.extend(asset.skins.iter().map(|s| SkinData {
            joints: s.joints.iter().map(|j| j + node_offset).collect(),
            skeleton: s.skeleton.map(|j| j + node_offset),
            ..s.clone()
        }));
        let first_clip = out.animations.len();
        out.animations.extend(asset.animations.iter().map(|a| {
            AnimationClip {
                channels: a
                    .channels
                    .iter()
                    .map(|c| AnimationChannel {
                        node: c.node + node_offset,
                        ..c.clone()
                    })
                    .collect(),
                ..a.clone()
            }
        }));
        out.warnings.extend(
            asset
                .warnings
                .iter()
                .map(|w| format!("{}: {w}", asset.source)),
        );
        copies.push(ComposedCopy {
            group_node: group,
            first_clip,
            clip_count: asset.animations.len(),
        });
    }
    // Meshes that used a glTF default material get the composed scene's default (appended last).
    let default_material = out.materials.len() as u32;
    for mesh in &mut out.meshes {
        mesh.triangle_materials
            .iter_mut()
            .filter(|t| **t == u32::MAX)
            .for_each(|t| *t = default_material);
        mesh.primitives
            .iter_mut()
            .filter(|p| p.material == u32::MAX)
            .for_each(|p| p.material = default_material);
    }
    (out, copies)
}

/// A composed scene plus the animation players to attach to its copies' group nodes.
pub struct CrowdScene {
    pub scene: SceneAsset,
    pub copies: Vec<ComposedCopy>,
    /// (group node, player): spawn with [`crate::animation::attach_players`].
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

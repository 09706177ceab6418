//! Scene composition: deformable meshes get one node each, and N placed copies of scenes merge into one
//! [`SceneAsset`] (a crowd), sharing static meshes and duplicating deformable ones.

use super::*;

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
                out.materials.extend(asset.materials.iter().map(|m| {
                    let mut m = m.clone();
                    for slot in m.texture_slots_mut().into_iter().flatten() {
                        slot.texture += texture_offset;
                    }
                    m
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
            // A composed scene has no variants: the copies keep the materials selected when loading.
            copy.primitive_variants.clear();
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
        let light_offset = out.lights.len();
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
                light: node.light.map(|l| l + light_offset),
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
        out.lights.extend(asset.lights.iter().cloned());
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

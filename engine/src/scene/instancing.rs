//! EXT_mesh_gpu_instancing: one node draws its mesh many times, each copy placed by per-instance
//! TRANSLATION / ROTATION / SCALE accessors in the node's space.
//!
//! raykin gives every instance its own node (and so its own ECS entity with `Transform`, `GlobalTransform` and
//! `MeshInstance`): the renderer's instance list, the top-level BVH, picking and the editor's scene tree all
//! see instances like any other placement, and all of them share the one mesh and its one BLAS. The
//! instanced node keeps its own transform and children; its mesh moves to synthetic child nodes named
//! `<node> instance <i>`, appended after the file's nodes (indices >= the file's node count), whose local
//! transforms are the instance transforms, so world = node's world x instance TRS, as the extension says.

use super::accessor::read_vectors;
use super::{NodeData, NodeTransform};
use glam::{Quat, Vec3};

pub(super) const EXTENSION: &str = "EXT_mesh_gpu_instancing";

/// A node's instance transforms and, when some were dropped, a note saying how many.
pub(super) type Instances = (Vec<NodeTransform>, Option<String>);

/// Reads a node's instance transforms. `Ok(None)` when the node has no instancing extension; instances with
/// non-finite values are dropped and counted in the returned note.
pub(super) fn read(
    node: &gltf::Node,
    document: &gltf::Document,
    buffers: &[Vec<u8>],
) -> Result<Option<Instances>, String> {
    let Some(extension) = node.extension_value(EXTENSION) else {
        return Ok(None);
    };
    let attributes = extension
        .get("attributes")
        .and_then(serde_json::Value::as_object)
        .ok_or("EXT_mesh_gpu_instancing has no attributes")?;
    let accessor = |name: &str| -> Result<Option<gltf::Accessor>, String> {
        let Some(index) = attributes.get(name) else {
            return Ok(None);
        };
        let index = index
            .as_u64()
            .ok_or_else(|| format!("instance attribute {name} is not an accessor index"))?
            as usize;
        document.accessors().nth(index).map(Some).ok_or_else(|| {
            format!("instance attribute {name} names accessor {index}, which does not exist")
        })
    };
    let translations = accessor("TRANSLATION")?
        .map(|a| read_vectors::<3>(&a, buffers, "instance TRANSLATION"))
        .transpose()?;
    let rotations = accessor("ROTATION")?
        .map(|a| read_vectors::<4>(&a, buffers, "instance ROTATION"))
        .transpose()?;
    let scales = accessor("SCALE")?
        .map(|a| read_vectors::<3>(&a, buffers, "instance SCALE"))
        .transpose()?;
    let counts: Vec<usize> = [
        translations.as_ref().map(Vec::len),
        rotations.as_ref().map(Vec::len),
        scales.as_ref().map(Vec::len),
    ]
    .into_iter()
    .flatten()
    .collect();
    let Some(&count) = counts.first() else {
        return Err("EXT_mesh_gpu_instancing has none of TRANSLATION, ROTATION, SCALE".into());
    };
    if counts.iter().any(|&c| c != count) {
        return Err(format!(
            "EXT_mesh_gpu_instancing accessors have different counts ({counts:?})"
        ));
    }
    let mut instances = Vec::with_capacity(count);
    let mut dropped = 0;
    for i in 0..count {
        let t = translations
            .as_ref()
            .map_or(Vec3::ZERO, |v| Vec3::from(v[i]));
        let r = rotations
            .as_ref()
            .map_or(Quat::IDENTITY, |v| Quat::from_array(v[i]));
        let s = scales.as_ref().map_or(Vec3::ONE, |v| Vec3::from(v[i]));
        if !(t.is_finite() && r.is_finite() && s.is_finite()) || r.length_squared() == 0.0 {
            dropped += 1;
            continue;
        }
        instances.push(NodeTransform {
            translation: t,
            rotation: r.normalize(),
            scale: s,
        });
    }
    let note = (dropped > 0).then(|| {
        format!("{dropped} instances with non-finite or zero-rotation transforms dropped")
    });
    Ok(Some((instances, note)))
}

/// Moves each instanced node's mesh onto one child node per instance (see the module comment).
pub(super) fn expand(nodes: &mut Vec<NodeData>, instanced: Vec<(usize, Vec<NodeTransform>)>) {
    for (node, transforms) in instanced {
        let Some(mesh) = nodes[node].mesh.take() else {
            continue;
        };
        let base = nodes[node].clone();
        for (i, transform) in transforms.into_iter().enumerate() {
            let child = nodes.len();
            nodes.push(NodeData {
                name: format!("{} instance {i}", base.name),
                parent: Some(node),
                children: Vec::new(),
                transform,
                mesh: Some(mesh),
                camera: None,
                light: None,
                skin: base.skin,
                morph_weights: base.morph_weights.clone(),
            });
            nodes[node].children.push(child);
        }
    }
}

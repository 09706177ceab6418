//! CPU skinning and morphing (FrameSet::Deform).
//!
//! Morph deltas apply first (positions, normals, tangents), then linear-blend skinning with the joint
//! matrices `global(joint) x inverseBindMatrix`. Normals use the inverse transpose of each vertex's blended
//! matrix, tangents the blended matrix. Skinned vertices come out in world space (the skinned node's own
//! transform is ignored, as glTF requires); morph-only meshes stay in object space.
//!
//! Fallbacks for bad skin data (never a panic or a NaN): influences that name a joint outside the skin are
//! ignored; weights are renormalised to sum to 1 over all JOINTS_n/WEIGHTS_n sets; a vertex with no usable
//! weight follows the skinned node's world transform rigidly; a non-finite result falls back the same way.

use crate::scene::{
    GlobalTransform, MeshData, MeshInstance, MorphWeights, SceneAsset, SceneAssets, SceneNode,
    SceneNodes, SkinnedMesh,
};
use bevy_ecs::prelude::*;
use glam::{Mat3, Mat4, Vec3, Vec4};
use rayon::prelude::*;

/// Deformed vertex attributes of one mesh (world space when skinned, object space otherwise).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DeformedMesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub tangents: Option<Vec<Vec4>>,
    /// The inputs that produced it (joint matrices and weights), to skip unchanged poses.
    pose_key: Vec<f32>,
}

/// Current deformation of every deformable mesh (each belongs to exactly one node instance, see
/// [`crate::scene::unshare_deformable_meshes`]), and which changed this frame.
#[derive(Resource, Default, Debug)]
pub struct DeformedMeshes {
    pub meshes: Vec<Option<DeformedMesh>>,
    /// Meshes deformed this frame (read by the BVH refit in the same frame).
    pub changed: Vec<usize>,
    /// CPU time of the last frame's deformation, and the vertices it processed.
    pub last_seconds: f64,
    pub last_vertices: usize,
}

/// `global(joint_j) x inverseBindMatrix_j` for each joint of `skin`, from node world matrices by node index.
pub fn joint_matrices(
    scene: &SceneAsset,
    skin: usize,
    global: impl Fn(usize) -> Option<Mat4>,
) -> Vec<Mat4> {
    let skin = &scene.skins[skin];
    skin.joints
        .iter()
        .zip(&skin.inverse_bind_matrices)
        .map(|(&j, ibm)| global(j).unwrap_or(Mat4::IDENTITY) * *ibm)
        .collect()
}

/// Maps normals through `m`: its inverse transpose up to a positive scale (the result is normalised), which
/// is the cofactor matrix times the determinant's sign; no division, so it is cheap per vertex.
fn normal_matrix(m: &Mat3) -> Mat3 {
    let det = m.determinant();
    if det.abs() > 1e-20 && det.is_finite() {
        let cofactor = Mat3::from_cols(
            m.y_axis.cross(m.z_axis),
            m.z_axis.cross(m.x_axis),
            m.x_axis.cross(m.y_axis),
        );
        cofactor * det.signum()
    } else {
        *m
    }
}

/// Morphs then skins `mesh`. `skin`: the joint matrices and the node's world matrix (the fallback for
/// vertices without usable weights); `None` for a morph-only mesh.
pub fn deform_mesh(
    mesh: &MeshData,
    skin: Option<(&[Mat4], Mat4)>,
    weights: &[f32],
) -> DeformedMesh {
    let mut positions = mesh.positions.clone();
    let mut normals = mesh.normals.clone();
    let mut tangents = mesh.tangents.clone();
    for (target, &w) in mesh.morph_targets.iter().zip(weights) {
        if w == 0.0 || !w.is_finite() {
            continue;
        }
        positions
            .iter_mut()
            .zip(&target.positions)
            .for_each(|(p, d)| *p += *d * w);
        if let (Some(n), Some(d)) = (&mut normals, &target.normals) {
            n.iter_mut().zip(d).for_each(|(n, d)| *n += *d * w);
        }
        if let (Some(t), Some(d)) = (&mut tangents, &target.tangents) {
            t.iter_mut()
                .zip(d)
                .for_each(|(t, d)| *t += (*d * w).extend(0.0));
        }
    }
    if let (Some((joints, node_world)), Some(sw)) = (skin, &mesh.skin_weights) {
        let sets = sw.sets.max(1) as usize;
        for v in 0..positions.len() {
            let mut m = Mat4::ZERO;
            let mut sum = 0.0f32;
            for i in v * sets..((v + 1) * sets).min(sw.joints.len()) {
                for k in 0..4 {
                    let w = sw.weights[i][k];
                    let j = sw.joints[i][k] as usize;
                    if w > 0.0 && j < joints.len() {
                        m += joints[j] * w;
                        sum += w;
                    }
                }
            }
            let m = if sum > 0.0 && sum.is_finite() {
                m * (1.0 / sum)
            } else {
                node_world
            };
            let rest = positions[v];
            let mut p = m.transform_point3(rest);
            let mut m3 = Mat3::from_mat4(m);
            if !p.is_finite() {
                p = node_world.transform_point3(rest);
                m3 = Mat3::from_mat4(node_world);
            }
            positions[v] = p;
            if let Some(n) = &mut normals {
                n[v] = (normal_matrix(&m3) * n[v]).normalize_or_zero();
            }
            if let Some(t) = &mut tangents {
                let w = if t[v].w < 0.0 { -1.0 } else { 1.0 };
                t[v] = (m3 * t[v].truncate()).normalize_or_zero().extend(w);
            }
        }
    } else {
        if let Some(n) = &mut normals {
            n.iter_mut().for_each(|n| *n = n.normalize_or_zero());
        }
        if let Some(t) = &mut tangents {
            t.iter_mut().for_each(|t| {
                *t = t
                    .truncate()
                    .normalize_or_zero()
                    .extend(if t.w < 0.0 { -1.0 } else { 1.0 })
            });
        }
    }
    // Morph deltas from a file can be huge or NaN-producing; never hand a non-finite vertex to the BVH.
    for (p, r) in positions.iter_mut().zip(&mesh.positions) {
        if !p.is_finite() {
            *p = *r;
        }
    }
    DeformedMesh {
        positions,
        normals,
        tangents,
        pose_key: Vec::new(),
    }
}

/// What the deform system reads of a mesh node.
type DeformInputs = (
    &'static MeshInstance,
    &'static SceneNode,
    &'static GlobalTransform,
    Option<&'static SkinnedMesh>,
    Option<&'static MorphWeights>,
);

/// Deforms every deformable mesh whose joints or morph weights changed since its last deformation.
pub fn deform_meshes(
    assets: Res<SceneAssets>,
    mut out: ResMut<DeformedMeshes>,
    meshes: Query<DeformInputs>,
    roots: Query<&SceneNodes>,
    globals: Query<&GlobalTransform>,
) {
    let start = std::time::Instant::now();
    let scene = &assets.0;
    // Consumers (the BVH refit) read this frame's list in a later set of the same frame.
    out.changed.clear();
    if out.meshes.len() < scene.meshes.len() {
        out.meshes.resize(scene.meshes.len(), None);
    }
    // Gather each changed mesh's inputs serially (cheap, borrows the ECS), then deform them in parallel:
    // every deformable mesh belongs to one instance, so the jobs are independent.
    struct Job<'a> {
        mesh: usize,
        data: &'a MeshData,
        skin: Option<(Vec<Mat4>, Mat4)>,
        weights: &'a [f32],
        key: Vec<f32>,
    }
    let mut jobs: Vec<Job> = Vec::new();
    for (instance, node, world, skinned, weights) in &meshes {
        let Some(mesh) = scene.meshes.get(instance.mesh) else {
            continue;
        };
        if !mesh.is_deformable() {
            continue;
        }
        let joints = skinned.and_then(|s| {
            let nodes = roots.get(node.root).ok()?;
            Some(joint_matrices(scene, s.skin, |j| {
                nodes
                    .0
                    .get(j)
                    .and_then(|&e| globals.get(e).ok())
                    .map(|g| g.0)
            }))
        });
        let weights: &[f32] = weights.map_or(&[][..], |w| w.0.as_slice());
        let mut key: Vec<f32> =
            Vec::with_capacity(joints.as_ref().map_or(0, |j| j.len() * 16 + 16) + weights.len());
        if let Some(j) = &joints {
            key.extend(j.iter().flat_map(|m| m.to_cols_array()));
            key.extend(world.0.to_cols_array());
        }
        key.extend_from_slice(weights);
        if out.meshes[instance.mesh]
            .as_ref()
            .is_some_and(|d| d.pose_key == key)
        {
            continue;
        }
        jobs.push(Job {
            mesh: instance.mesh,
            data: mesh,
            skin: joints.map(|j| (j, world.0)),
            weights,
            key,
        });
    }
    let results: Vec<(usize, DeformedMesh)> = jobs
        .into_par_iter()
        .map(|job| {
            let skin = job.skin.as_ref().map(|(j, w)| (j.as_slice(), *w));
            let mut d = deform_mesh(job.data, skin, job.weights);
            d.pose_key = job.key;
            (job.mesh, d)
        })
        .collect();
    let mut vertices = 0;
    for (mesh, d) in results {
        vertices += d.positions.len();
        out.meshes[mesh] = Some(d);
        out.changed.push(mesh);
    }
    out.last_seconds = start.elapsed().as_secs_f64();
    out.last_vertices = vertices;
}

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

/// The inputs of one deformable mesh's deformation: what the CPU and the GPU deformer both consume.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshPose {
    /// `global(joint) x inverseBindMatrix` per joint, and the skinned node's world matrix (the fallback for
    /// vertices without usable weights); `None` for a morph-only mesh.
    pub skin: Option<(Vec<Mat4>, Mat4)>,
    pub weights: Vec<f32>,
}

/// The current pose of every deformable mesh (by mesh index) and the meshes whose pose changed this
/// frame: the one place that decides what needs deforming, on either backend.
#[derive(Resource, Default, Debug)]
pub struct MeshPoses {
    pub poses: Vec<Option<MeshPose>>,
    pub changed: Vec<usize>,
}

impl MeshPoses {
    /// Forgets every pose, so the next frame deforms every deformable mesh (a backend switch).
    pub fn invalidate(&mut self) {
        self.poses.iter_mut().for_each(|p| *p = None);
    }
}

/// By mesh index: meshes another deformer handles (the GPU pass, `gpu_deform`); the CPU skips them.
#[derive(Resource, Default, Debug, Clone, PartialEq)]
pub struct DeformedElsewhere(pub Vec<bool>);

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
    }
}

/// What the pose system reads of a mesh node.
type PoseInputs = (
    &'static MeshInstance,
    &'static SceneNode,
    &'static GlobalTransform,
    Option<&'static SkinnedMesh>,
    Option<&'static MorphWeights>,
);

/// Joint matrices and morph weights of every deformable mesh; lists the meshes whose pose changed.
pub fn pose_meshes(
    assets: Res<SceneAssets>,
    mut poses: ResMut<MeshPoses>,
    meshes: Query<PoseInputs>,
    roots: Query<&SceneNodes>,
    globals: Query<&GlobalTransform>,
) {
    let scene = &assets.0;
    let poses = &mut *poses;
    // Consumers (the deformers, the BVH refit) read this frame's list later in the same frame.
    poses.changed.clear();
    if poses.poses.len() < scene.meshes.len() {
        poses.poses.resize(scene.meshes.len(), None);
    }
    for (instance, node, world, skinned, weights) in &meshes {
        let Some(mesh) = scene.meshes.get(instance.mesh) else {
            continue;
        };
        if !mesh.is_deformable() {
            continue;
        }
        let skin = skinned.and_then(|s| {
            let nodes = roots.get(node.root).ok()?;
            let joints = joint_matrices(scene, s.skin, |j| {
                nodes
                    .0
                    .get(j)
                    .and_then(|&e| globals.get(e).ok())
                    .map(|g| g.0)
            });
            Some((joints, world.0))
        });
        let pose = MeshPose {
            skin,
            weights: weights.map_or_else(Vec::new, |w| w.0.clone()),
        };
        let slot = &mut poses.poses[instance.mesh];
        if slot.as_ref() != Some(&pose) {
            *slot = Some(pose);
            poses.changed.push(instance.mesh);
        }
    }
}

/// Deforms on the CPU every mesh whose pose changed (except those deformed elsewhere), in parallel over
/// meshes: every deformable mesh belongs to one node instance, so the jobs are independent.
pub fn deform_meshes(
    assets: Res<SceneAssets>,
    poses: Res<MeshPoses>,
    elsewhere: Res<DeformedElsewhere>,
    mut out: ResMut<DeformedMeshes>,
) {
    let start = std::time::Instant::now();
    let scene = &assets.0;
    out.changed.clear();
    if out.meshes.len() < scene.meshes.len() {
        out.meshes.resize(scene.meshes.len(), None);
    }
    let jobs: Vec<(usize, &MeshPose)> = poses
        .changed
        .iter()
        .filter(|&&m| !elsewhere.0.get(m).copied().unwrap_or(false))
        .filter_map(|&m| Some((m, poses.poses[m].as_ref()?)))
        .collect();
    let results: Vec<(usize, DeformedMesh)> = jobs
        .into_par_iter()
        .map(|(m, pose)| {
            let skin = pose.skin.as_ref().map(|(j, w)| (j.as_slice(), *w));
            (m, deform_mesh(&scene.meshes[m], skin, &pose.weights))
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

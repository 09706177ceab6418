//! The static inputs of the GPU deform pass, packed once at upload and only for the meshes it deforms:
//! rest positions, normals and tangents (f32, as the CPU reference reads them), skin influences (joints as
//! u16 pairs + f32 weights, per influence set) and morph-target deltas. Per frame only joint matrices and
//! morph weights go up (see [`super::GpuDeformer`]).

use crate::render::layout::{DEFORM_GROUP, GpuMesh, NONE};
use crate::scene::MeshData;
use bytemuck::{Pod, Zeroable};

/// `render/passes/deform/deform.wgsl` `DeformMesh`: offsets in 32-bit words (`NONE` = absent).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeformMeshGpu {
    pub vertex_count: u32,
    pub first_group: u32,
    pub rest_position: u32,
    pub rest_normal: u32,
    pub rest_tangent: u32,
    pub influences: u32,
    pub influence_sets: u32,
    pub morph_targets: u32,
    pub morph_deltas: u32,
    pub morph_stride: u32,
    pub morph_normal: u32,
    pub morph_tangent: u32,
    pub out_position: u32,
    pub out_normal: u32,
    pub out_tangent: u32,
    /// First matrix of this mesh in the per-frame matrix buffer: its joints, then the node's world matrix.
    pub joint_base: u32,
    pub joint_count: u32,
    pub weight_base: u32,
    pub _pad: [u32; 2],
}

/// One mesh the GPU deforms: its index in the scene, where its outputs live, and its skin's joint count
/// (`None`: not skinned on this node, morph targets only).
#[derive(Clone, Copy, Debug)]
pub struct DeformTarget<'a> {
    pub mesh: &'a MeshData,
    pub out: GpuMesh,
    pub joints: Option<usize>,
}

/// Everything `render/passes/deform/deform.wgsl` reads that does not change per frame.
#[derive(Debug, Default)]
pub struct DeformInputs {
    pub words: Vec<u32>,
    pub meshes: Vec<DeformMeshGpu>,
    /// Workgroups of one dispatch over every mesh.
    pub groups: u32,
    /// Entries of the per-frame matrix and weight buffers.
    pub matrix_count: u32,
    pub weight_count: u32,
}

fn push_vec3s<'a>(words: &mut Vec<u32>, v: impl IntoIterator<Item = &'a glam::Vec3>) {
    words.extend(v.into_iter().flat_map(|p| p.to_array().map(f32::to_bits)));
}

impl DeformInputs {
    pub fn pack(targets: &[DeformTarget]) -> Self {
        let mut out = DeformInputs::default();
        let words = &mut out.words;
        for t in targets {
            let mesh = t.mesh;
            let n = mesh.positions.len();
            let mut d = DeformMeshGpu {
                vertex_count: n as u32,
                first_group: out.groups,
                rest_position: words.len() as u32,
                rest_normal: NONE,
                rest_tangent: NONE,
                influences: NONE,
                influence_sets: 0,
                morph_targets: mesh.morph_targets.len() as u32,
                morph_deltas: NONE,
                morph_stride: 0,
                morph_normal: NONE,
                morph_tangent: NONE,
                out_position: t.out.position_offset,
                out_normal: t.out.normal_offset,
                out_tangent: t.out.tangent_offset,
                joint_base: out.matrix_count,
                joint_count: 0,
                weight_base: out.weight_count,
                _pad: [0; 2],
            };
            push_vec3s(words, &mesh.positions);
            if let Some(normals) = &mesh.normals {
                d.rest_normal = words.len() as u32;
                push_vec3s(words, normals);
            }
            if let Some(tangents) = &mesh.tangents {
                d.rest_tangent = words.len() as u32;
                words.extend(tangents.iter().flat_map(|t| t.to_array().map(f32::to_bits)));
            }
            if let (Some(sw), Some(joints)) = (&mesh.skin_weights, t.joints) {
                let sets = sw.sets.max(1) as usize;
                d.influences = words.len() as u32;
                d.influence_sets = sets as u32;
                d.joint_count = joints as u32;
                for i in 0..n * sets {
                    // Missing sets (a short accessor) read as no influence, as the CPU loop bound does.
                    let (j, w) = match (sw.joints.get(i), sw.weights.get(i)) {
                        (Some(j), Some(w)) => (*j, *w),
                        _ => ([0; 4], [0.0; 4]),
                    };
                    words.push(j[0] as u32 | (j[1] as u32) << 16);
                    words.push(j[2] as u32 | (j[3] as u32) << 16);
                    words.extend(w.map(f32::to_bits));
                }
                out.matrix_count += joints as u32 + 1;
            }
            if !mesh.morph_targets.is_empty() {
                // Normal/tangent deltas only when the mesh has that attribute and some target moves it;
                // targets without them store zeros (adding zero is exact).
                let normals = mesh.normals.is_some()
                    && mesh.morph_targets.iter().any(|t| t.normals.is_some());
                let tangents = mesh.tangents.is_some()
                    && mesh.morph_targets.iter().any(|t| t.tangents.is_some());
                let block = 3 * n as u32;
                d.morph_deltas = words.len() as u32;
                d.morph_normal = if normals { block } else { NONE };
                d.morph_tangent = if tangents {
                    block * (1 + normals as u32)
                } else {
                    NONE
                };
                d.morph_stride = block * (1 + normals as u32 + tangents as u32);
                let zeros = vec![glam::Vec3::ZERO; n];
                for target in &mesh.morph_targets {
                    let part =
                        |v: &Option<Vec<glam::Vec3>>| v.as_deref().unwrap_or(&zeros).to_vec();
                    let mut positions = target.positions.clone();
                    positions.resize(n, glam::Vec3::ZERO);
                    push_vec3s(words, &positions);
                    for (on, deltas) in [
                        (normals, part(&target.normals)),
                        (tangents, part(&target.tangents)),
                    ] {
                        if on {
                            let mut deltas = deltas;
                            deltas.resize(n, glam::Vec3::ZERO);
                            push_vec3s(words, &deltas);
                        }
                    }
                }
                out.weight_count += mesh.morph_targets.len() as u32;
            }
            out.groups += (n as u32).div_ceil(DEFORM_GROUP);
            out.meshes.push(d);
        }
        out
    }

    pub fn bytes(&self) -> u64 {
        self.words.len() as u64 * 4
    }
}

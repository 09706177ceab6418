// GPU morphing + linear-blend skinning, written straight into each deformable mesh's vertex-pool range
// (engine/src/gpu_deform). It mirrors the CPU reference (engine/src/animation/deform.rs) operation for
// operation, so the two agree to float rounding: morph deltas first, then the blended joint matrix
// `sum(w * joint) / sum(w)`, normals by its cofactor matrix (inverse transpose up to scale), tangents by its
// 3x3 part, the node-rigid fallback for vertices without usable weights, and the rest position for anything
// non-finite. Outputs use the vertex pool's encodings (f32 positions, octahedral snorm16 normals/tangents).


// Static description of one GPU-deformed mesh (engine/src/gpu_deform/inputs.rs, `DeformMeshGpu`). Offsets
// are in 32-bit words of `deform_data` (inputs) or `vertex_pool` (outputs); NONE = absent.
struct DeformMesh {
    vertex_count: u32, first_group: u32, rest_position: u32, rest_normal: u32,
    rest_tangent: u32, influences: u32, influence_sets: u32, morph_targets: u32,
    morph_deltas: u32, morph_stride: u32, morph_normal: u32, morph_tangent: u32,
    out_position: u32, out_normal: u32, out_tangent: u32, joint_base: u32,
    joint_count: u32, weight_base: u32, _p0: u32, _p1: u32,
}

struct DeformParams { mesh_count: u32, groups_x: u32, _p0: u32, _p1: u32 }

@group(0) @binding(0) var<storage, read> deform_data: array<u32>;
@group(0) @binding(1) var<storage, read> deform_meshes: array<DeformMesh>;
// Per mesh: its joints' `global x inverseBind`, then the skinned node's world matrix.
@group(0) @binding(2) var<storage, read> matrices: array<mat4x4<f32>>;
@group(0) @binding(3) var<storage, read> morph_weights: array<f32>;
// Bit 0: the mesh's pose changed this frame (deform it); bit 1: refit only (shaders/refit.wgsl).
@group(0) @binding(4) var<storage, read> mesh_flags: array<u32>;
@group(0) @binding(5) var<storage, read_write> vertex_pool: array<u32>;
@group(0) @binding(6) var<uniform> params: DeformParams;

fn all_finite(v: vec3<f32>) -> bool {
    return is_finite(v.x) && is_finite(v.y) && is_finite(v.z);
}

fn data_vec3(o: u32) -> vec3<f32> {
    return vec3<f32>(bitcast<f32>(deform_data[o]), bitcast<f32>(deform_data[o + 1u]), bitcast<f32>(deform_data[o + 2u]));
}

// glam's normalize_or_zero: scale by the reciprocal length when it is finite and positive.
fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let r = 1.0 / length(v);
    if is_finite(r) && r > 0.0 { return v * r; }
    return vec3<f32>(0.0);
}

// Inverse transpose up to a positive scale: the cofactor matrix times the determinant's sign.
fn normal_matrix(m: mat3x3<f32>) -> mat3x3<f32> {
    let det = dot(m[2], cross(m[0], m[1]));
    if abs(det) > 1e-20 && is_finite(det) {
        return mat3x3<f32>(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1])) * signum(det);
    }
    return m;
}

fn upper3(m: mat4x4<f32>) -> mat3x3<f32> {
    return mat3x3<f32>(m[0].xyz, m[1].xyz, m[2].xyz);
}

@compute @workgroup_size(DEFORM_GROUP)
fn deform(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    // Each mesh starts on a workgroup boundary: the group index finds the mesh (uniform per workgroup).
    let group = wg.x + wg.y * params.groups_x;
    var lo = 0u;
    var hi = params.mesh_count - 1u;
    while lo < hi {
        let mid = (lo + hi + 1u) / 2u;
        if deform_meshes[mid].first_group <= group { lo = mid; } else { hi = mid - 1u; }
    }
    if (mesh_flags[lo] & 1u) == 0u { return; }
    let m = deform_meshes[lo];
    let v = (group - m.first_group) * DEFORM_GROUP + lane;
    if v >= m.vertex_count { return; }

    let rest = data_vec3(m.rest_position + 3u * v);
    var p = rest;
    var n = vec3<f32>(0.0);
    var t = vec3<f32>(0.0);
    var handedness = 1.0;
    if m.rest_normal != NONE { n = data_vec3(m.rest_normal + 3u * v); }
    if m.rest_tangent != NONE {
        t = data_vec3(m.rest_tangent + 4u * v);
        handedness = select(1.0, -1.0, bitcast<f32>(deform_data[m.rest_tangent + 4u * v + 3u]) < 0.0);
    }
    for (var k = 0u; k < m.morph_targets; k++) {
        let w = morph_weights[m.weight_base + k];
        if w == 0.0 || !is_finite(w) { continue; }
        let base = m.morph_deltas + k * m.morph_stride;
        p += data_vec3(base + 3u * v) * w;
        if m.morph_normal != NONE { n += data_vec3(base + m.morph_normal + 3u * v) * w; }
        if m.morph_tangent != NONE { t += data_vec3(base + m.morph_tangent + 3u * v) * w; }
    }

    if m.influences != NONE {
        let node_world = matrices[m.joint_base + m.joint_count];
        var blended = mat4x4<f32>(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
        var sum = 0.0;
        for (var s = 0u; s < m.influence_sets; s++) {
            // Per influence set: joints as 2 x u16 pairs, then 4 f32 weights.
            let o = m.influences + (v * m.influence_sets + s) * 6u;
            let joints = vec4<u32>(deform_data[o] & 0xffffu, deform_data[o] >> 16u, deform_data[o + 1u] & 0xffffu, deform_data[o + 1u] >> 16u);
            for (var k = 0u; k < 4u; k++) {
                let w = bitcast<f32>(deform_data[o + 2u + k]);
                if w > 0.0 && joints[k] < m.joint_count {
                    blended += matrices[m.joint_base + joints[k]] * w;
                    sum += w;
                }
            }
        }
        var skin = node_world;
        if sum > 0.0 && is_finite(sum) { skin = blended * (1.0 / sum); }
        var q = (skin * vec4<f32>(p, 1.0)).xyz;
        var m3 = upper3(skin);
        if !all_finite(q) {
            q = (node_world * vec4<f32>(p, 1.0)).xyz;
            m3 = upper3(node_world);
        }
        p = q;
        n = normalize_or_zero(normal_matrix(m3) * n);
        t = normalize_or_zero(m3 * t);
    } else {
        n = normalize_or_zero(n);
        t = normalize_or_zero(t);
    }
    // Never hand a non-finite vertex to the BVH.
    if !all_finite(p) { p = rest; }

    vertex_pool[m.out_position + POSITION_WORDS * v] = bitcast<u32>(p.x);
    vertex_pool[m.out_position + POSITION_WORDS * v + 1u] = bitcast<u32>(p.y);
    vertex_pool[m.out_position + POSITION_WORDS * v + 2u] = bitcast<u32>(p.z);
    if m.out_normal != NONE { vertex_pool[m.out_normal + v] = oct_encode(n); }
    if m.out_tangent != NONE {
        vertex_pool[m.out_tangent + 2u * v] = oct_encode(t);
        vertex_pool[m.out_tangent + 2u * v + 1u] = bitcast<u32>(handedness);
    }
}

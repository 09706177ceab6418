// GPU refit of the BLASes of GPU-deformed meshes, then each refit tree's SAH cost (the rebuild guard).
// One workgroup per mesh sweeps its child-pair nodes level by level, deepest level first (engine/src/
// gpu_deform/levels.rs orders them), with a barrier between levels: a node's inner child was refit in an
// earlier level, its leaf children read the deformed triangles. Same min/max as the CPU refit
// (engine/src/bvh/mod.rs `FlatBvh::refit`), so both give identical boxes from identical positions. The SAH
// cost matches `FlatBvh::sah_cost` (traversal and intersection cost 1, relative to the root's area).

const MIN_POSITIVE: f32 = 1.17549435e-38;

// engine/src/gpu_deform/mod.rs `RefitMeshGpu`.
struct RefitMesh {
    blas_root: u32, triangle_offset: u32, position_offset: u32, node_count: u32,
    order_offset: u32, level_offset: u32, levels: u32, _pad: u32,
}

@group(0) @binding(0) var<storage, read_write> blas_nodes: array<BvhNode>;
@group(0) @binding(1) var<storage, read> triangles: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> vertex_pool: array<u32>;
@group(0) @binding(3) var<storage, read> refit_meshes: array<RefitMesh>;
// Per mesh, its node indices (relative to its BLAS root) sorted by depth, deepest first.
@group(0) @binding(4) var<storage, read> level_order: array<u32>;
// Per mesh, `levels + 1` offsets into its slice of `level_order`.
@group(0) @binding(5) var<storage, read> level_starts: array<u32>;
@group(0) @binding(6) var<storage, read> mesh_flags: array<u32>;
@group(0) @binding(7) var<storage, read_write> sah_cost: array<f32>;

var<workgroup> partial: array<f32, REFIT_GROUP>;

fn position(m: RefitMesh, v: u32) -> vec3<f32> {
    let o = m.position_offset + POSITION_WORDS * v;
    return vec3<f32>(bitcast<f32>(vertex_pool[o]), bitcast<f32>(vertex_pool[o + 1u]), bitcast<f32>(vertex_pool[o + 2u]));
}

fn is_empty(c: BvhChild) -> bool {
    return c.count == 0u && c.index == NONE;
}

fn refit_child(m: RefitMesh, c: BvhChild) -> BvhChild {
    if is_empty(c) { return c; }
    var out = c;
    if c.count > 0u {
        var lo = vec3<f32>(3.4028235e38);
        var hi = vec3<f32>(-3.4028235e38);
        for (var i = 0u; i < c.count; i++) {
            let tri = triangles[m.triangle_offset + c.index + i];
            let a = position(m, tri.x);
            let b = position(m, tri.y);
            let d = position(m, tri.z);
            lo = min(lo, min(min(a, b), d));
            hi = max(hi, max(max(a, b), d));
        }
        out.min = lo;
        out.max = hi;
    } else {
        let child = blas_nodes[m.blas_root + c.index];
        out.min = min(child.a.min, child.b.min);
        out.max = max(child.a.max, child.b.max);
    }
    return out;
}

fn half_area(c: BvhChild) -> f32 {
    if is_empty(c) { return 0.0; }
    let d = max(c.max - c.min, vec3<f32>(0.0));
    return d.x * d.y + d.y * d.z + d.z * d.x;
}

fn union_half_area(a: BvhChild, b: BvhChild) -> f32 {
    if is_empty(b) { return half_area(a); }
    let d = max(max(a.max, b.max) - min(a.min, b.min), vec3<f32>(0.0));
    return d.x * d.y + d.y * d.z + d.z * d.x;
}

fn node_cost(n: BvhNode) -> f32 {
    var cost = union_half_area(n.a, n.b);
    if n.a.count > 0u { cost += half_area(n.a) * f32(n.a.count); }
    if n.b.count > 0u { cost += half_area(n.b) * f32(n.b.count); }
    return cost;
}

@compute @workgroup_size(REFIT_GROUP)
fn refit(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let mesh = wg.x + wg.y * 65535u;
    if mesh >= arrayLength(&refit_meshes) || mesh_flags[mesh] == 0u { return; }
    let m = refit_meshes[mesh];
    for (var level = 0u; level < m.levels; level++) {
        let start = level_starts[m.level_offset + level];
        let end = level_starts[m.level_offset + level + 1u];
        for (var i = start + lane; i < end; i += REFIT_GROUP) {
            let node = m.blas_root + level_order[m.order_offset + i];
            var n = blas_nodes[node];
            n.a = refit_child(m, n.a);
            n.b = refit_child(m, n.b);
            blas_nodes[node] = n;
        }
        // The next (shallower) level reads the boxes this one wrote.
        storageBarrier();
    }

    var cost = 0.0;
    for (var i = lane; i < m.node_count; i += REFIT_GROUP) {
        cost += node_cost(blas_nodes[m.blas_root + i]);
    }
    partial[lane] = cost;
    workgroupBarrier();
    for (var stride = REFIT_GROUP / 2u; stride > 0u; stride /= 2u) {
        if lane < stride { partial[lane] += partial[lane + stride]; }
        workgroupBarrier();
    }
    if lane == 0u {
        let root = blas_nodes[m.blas_root];
        sah_cost[mesh] = partial[0] / max(union_half_area(root.a, root.b), MIN_POSITIVE);
    }
}

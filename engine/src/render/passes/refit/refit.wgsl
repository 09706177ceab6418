// GPU refit of the BLASes of GPU-deformed meshes, then each refit tree's SAH cost (the rebuild guard).
// One workgroup per mesh sweeps its child-pair nodes level by level, deepest level first (engine/src/
// gpu_deform/levels.rs orders them), with a barrier between levels: a node's inner child was refit in an
// earlier level, its leaf children read the deformed triangles. Same min/max as the CPU refit
// (engine/src/bvh/mod.rs `FlatBvh::refit`), so both give identical boxes from identical positions. The SAH
// cost matches `FlatBvh::sah_cost` (traversal and intersection cost 1, relative to the root's area).
// Then `refit_wide` re-quantises the wide trees collapsed from those BVH2s (engine/src/bvh/wide_refit.rs,
// whose `RefitWideBvh::refit` it mirrors operation for operation).

const MIN_POSITIVE: f32 = 1.17549435e-38;

// engine/src/gpu_deform/mod.rs `RefitMeshGpu`.
struct RefitMesh {
    blas_root: u32, triangle_offset: u32, position_offset: u32, node_count: u32,
    order_offset: u32, level_offset: u32, levels: u32, wide_root: u32,
    wide_count: u32, source_offset: u32, _pad0: u32, _pad1: u32,
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
// The wide trees' nodes (obvhs `CwBvhNode`, 20 words each) and, per wide node, the BVH2 node it stands for.
@group(0) @binding(8) var<storage, read_write> wide_nodes: array<u32>;
@group(0) @binding(9) var<storage, read> wide_sources: array<u32>;

var<workgroup> partial: array<f32, REFIT_GROUP>;

fn position(m: RefitMesh, v: u32) -> vec3<f32> {
    let o = m.position_offset + POSITION_WORDS * v;
    return vec3<f32>(bitcast<f32>(vertex_pool[o]), bitcast<f32>(vertex_pool[o + 1u]), bitcast<f32>(vertex_pool[o + 2u]));
}

fn is_empty(c: BvhChild) -> bool {
    return c.count == 0u && c.index == NONE;
}

struct Box { lo: vec3<f32>, hi: vec3<f32> }

// The box of `count` triangles from slot `first` of the mesh's triangle range.
fn triangles_box(m: RefitMesh, first: u32, count: u32) -> Box {
    var b = Box(vec3<f32>(3.4028235e38), vec3<f32>(-3.4028235e38));
    for (var i = 0u; i < count; i++) {
        let tri = triangles[m.triangle_offset + first + i];
        let p0 = position(m, tri.x);
        let p1 = position(m, tri.y);
        let p2 = position(m, tri.z);
        b.lo = min(b.lo, min(min(p0, p1), p2));
        b.hi = max(b.hi, max(max(p0, p1), p2));
    }
    return b;
}

// The box of an inner BVH2 node: the union of its two children (inner nodes always have both).
fn inner_node_box(m: RefitMesh, node: u32) -> Box {
    let n = blas_nodes[m.blas_root + node];
    return Box(min(n.a.min, n.b.min), max(n.a.max, n.b.max));
}

fn refit_child(m: RefitMesh, c: BvhChild) -> BvhChild {
    if is_empty(c) { return c; }
    var out = c;
    var b: Box;
    if c.count > 0u {
        b = triangles_box(m, c.index, c.count);
    } else {
        b = inner_node_box(m, c.index);
    }
    out.min = b.lo;
    out.max = b.hi;
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

const WIDE_NODE_WORDS: u32 = 20u;
const CELLS: f32 = 255.0;

// `cell_exponent` in wide_refit.rs: the biased exponent of the smallest power of two c with 255 c >= extent.
fn cell_exponent(extent: f32) -> u32 {
    let bits = bitcast<u32>(extent * (1.0 / CELLS));
    var e = (bits >> 23u) + select(0u, 1u, (bits & 0x7fffffu) != 0u);
    if bitcast<f32>(min(e, 254u) << 23u) * CELLS < extent { e += 1u; }
    return clamp(e, 1u, 253u);
}

// Byte `slot` of an eight-byte array held in two words.
fn slot_byte(words: vec2<u32>, slot: u32) -> u32 {
    return (words[slot / 4u] >> ((slot % 4u) * 8u)) & 0xffu;
}

// Sets byte `slot` of the two-word plane array starting at word `at` of the node.
fn put_plane(planes: ptr<function, array<u32, 12>>, at: u32, slot: u32, q: f32) {
    (*planes)[at + slot / 4u] |= u32(q) << ((slot % 4u) * 8u);
}

@compute @workgroup_size(REFIT_GROUP)
fn refit_wide(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let mesh = wg.x + wg.y * 65535u;
    if mesh >= arrayLength(&refit_meshes) || mesh_flags[mesh] == 0u { return; }
    let m = refit_meshes[mesh];
    if m.wide_root == NONE { return; }
    for (var i = lane; i < m.wide_count; i += REFIT_GROUP) {
        let base = (m.wide_root + i) * WIDE_NODE_WORDS;
        let imask = wide_nodes[base + 3u] >> 24u;
        let child_base = wide_nodes[base + 4u];
        let primitive_base = wide_nodes[base + 5u];
        let metas = vec2<u32>(wide_nodes[base + 6u], wide_nodes[base + 7u]);
        var boxes: array<Box, 8>;
        var union_lo = vec3<f32>(3.4028235e38);
        var union_hi = vec3<f32>(-3.4028235e38);
        var inner = 0u;
        for (var slot = 0u; slot < 8u; slot++) {
            let slot_meta = slot_byte(metas, slot);
            if slot_meta == 0u { continue; }
            var b: Box;
            if (imask & (1u << slot)) != 0u {
                // An inner slot: its BVH2 node's two children, refit by `refit` before this dispatch.
                b = inner_node_box(m, wide_sources[m.source_offset + child_base + inner]);
                inner++;
            } else {
                b = triangles_box(m, primitive_base + (slot_meta & 0x1fu), countOneBits(slot_meta >> 5u));
            }
            boxes[slot] = b;
            union_lo = min(union_lo, b.lo);
            union_hi = max(union_hi, b.hi);
        }
        if union_lo.x > union_hi.x { continue; }
        let extent = max(union_hi - union_lo, vec3<f32>(1e-20));
        let e = vec3<u32>(cell_exponent(extent.x), cell_exponent(extent.y), cell_exponent(extent.z));
        let inverse = bitcast<vec3<f32>>((vec3<u32>(254u) - e) << vec3<u32>(23u));
        // Planes: min x, max x, min y, max y, min z, max z, two words (eight bytes) each.
        var planes: array<u32, 12>;
        for (var slot = 0u; slot < 8u; slot++) {
            if slot_byte(metas, slot) == 0u { continue; }
            let q_lo = clamp(floor((boxes[slot].lo - union_lo) * inverse), vec3<f32>(0.0), vec3<f32>(CELLS));
            let q_hi = clamp(ceil((boxes[slot].hi - union_lo) * inverse), vec3<f32>(0.0), vec3<f32>(CELLS));
            put_plane(&planes, 0u, slot, q_lo.x);
            put_plane(&planes, 2u, slot, q_hi.x);
            put_plane(&planes, 4u, slot, q_lo.y);
            put_plane(&planes, 6u, slot, q_hi.y);
            put_plane(&planes, 8u, slot, q_lo.z);
            put_plane(&planes, 10u, slot, q_hi.z);
        }
        wide_nodes[base] = bitcast<u32>(union_lo.x);
        wide_nodes[base + 1u] = bitcast<u32>(union_lo.y);
        wide_nodes[base + 2u] = bitcast<u32>(union_lo.z);
        wide_nodes[base + 3u] = e.x | (e.y << 8u) | (e.z << 16u) | (imask << 24u);
        for (var w = 0u; w < 12u; w++) {
            wide_nodes[base + 8u + w] = planes[w];
        }
    }
}

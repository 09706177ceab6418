// Two-level BVH traversal: a top-level BVH over instances, a bottom-level BVH per mesh, both in the
// child-pair BVH2 layout (engine/src/bvh/mod.rs). Stack-based and iterative: no recursion on the GPU.

const MISS: f32 = 3.0e38;
const STACK_SIZE: u32 = 64u;

struct Ray { origin: vec3<f32>, dir: vec3<f32> }

struct Hit {
    t: f32,
    instance: u32,
    // Slot in `triangles` (mesh offset included).
    triangle: u32,
    bary: vec2<f32>,
}

fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    let eps = 1e-20;
    let s = select(vec3<f32>(1.0), vec3<f32>(-1.0), d < vec3<f32>(0.0));
    return 1.0 / select(d, s * eps, abs(d) < vec3<f32>(eps));
}

// Entry distance of the ray into a child box, or MISS.
fn hit_child(c: BvhChild, o: vec3<f32>, inv_d: vec3<f32>, t_max: f32) -> f32 {
    let t0 = (c.min - o) * inv_d;
    let t1 = (c.max - o) * inv_d;
    let lo = min(t0, t1);
    let hi = max(t0, t1);
    let t_enter = max(max(lo.x, lo.y), max(lo.z, 0.0));
    let t_exit = min(min(hi.x, hi.y), min(hi.z, t_max));
    return select(MISS, t_enter, t_enter <= t_exit);
}

// Moeller-Trumbore, both faces. Returns (t, u, v); t = MISS when there is no hit in (0, t_max).
fn hit_triangle(o: vec3<f32>, d: vec3<f32>, p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>, t_max: f32) -> vec3<f32> {
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let pv = cross(d, e2);
    let det = dot(e1, pv);
    if det == 0.0 { return vec3<f32>(MISS, 0.0, 0.0); }
    let inv = 1.0 / det;
    let tv = o - p0;
    let u = dot(tv, pv) * inv;
    let qv = cross(tv, e1);
    let v = dot(d, qv) * inv;
    let t = dot(e2, qv) * inv;
    if u < 0.0 || v < 0.0 || u + v > 1.0 || t <= 0.0 || t >= t_max { return vec3<f32>(MISS, 0.0, 0.0); }
    return vec3<f32>(t, u, v);
}

// Alpha-mask cut-out: false when the hit point's base-colour alpha is below the material's cutoff.
fn alpha_passes(mesh: Mesh, tri: vec4<u32>, bary: vec2<f32>) -> bool {
    let m = materials[tri.w];
    if (m.flags & MATERIAL_ALPHA_MASK) == 0u { return true; }
    var alpha = m.base_color.a;
    if m.base_color_texture != NONE {
        let set_offset = select(mesh.uv0_offset, mesh.uv1_offset, (m.base_color_texture >> 24u) == 1u);
        if set_offset != NONE {
            let w = vec3<f32>(1.0 - bary.x - bary.y, bary.x, bary.y);
            let uv = pool_vec2(set_offset + 2u * tri.x) * w.x + pool_vec2(set_offset + 2u * tri.y) * w.y + pool_vec2(set_offset + 2u * tri.z) * w.z;
            alpha *= sample_texture(m.base_color_texture, uv).a;
        }
    }
    if mesh.color_offset != NONE {
        let w = vec3<f32>(1.0 - bary.x - bary.y, bary.x, bary.y);
        alpha *= unpack4x8unorm(vertex_pool[mesh.color_offset + tri.x]).a * w.x
            + unpack4x8unorm(vertex_pool[mesh.color_offset + tri.y]).a * w.y
            + unpack4x8unorm(vertex_pool[mesh.color_offset + tri.z]).a * w.z;
    }
    return alpha >= m.alpha_cutoff;
}

// Intersects one triangle slot; true when it became the closest hit.
fn hit_slot(mesh: Mesh, instance: u32, slot: u32, o: vec3<f32>, d: vec3<f32>, hit: ptr<function, Hit>) -> bool {
    let tri = triangles[slot];
    let r = hit_triangle(o, d, vertex_position(mesh, tri.x), vertex_position(mesh, tri.y), vertex_position(mesh, tri.z), (*hit).t);
    if r.x < MISS && alpha_passes(mesh, tri, r.yz) {
        (*hit).t = r.x;
        (*hit).instance = instance;
        (*hit).triangle = slot;
        (*hit).bary = r.yz;
        return true;
    }
    return false;
}

// Intersects the triangles of one leaf; returns true if the closest hit moved.
fn hit_leaf(mesh: Mesh, instance: u32, first: u32, count: u32, o: vec3<f32>, d: vec3<f32>, hit: ptr<function, Hit>) -> bool {
    var found = false;
    for (var i = 0u; i < count; i++) {
        found = hit_slot(mesh, instance, mesh.triangle_offset + first + i, o, d, hit) || found;
    }
    return found;
}

// Closest hit within the instance's mesh (or any hit, for shadow rays), in whichever layout the mesh's BLAS
// has. Object-space ray: t stays comparable with world space because the direction is transformed, not
// renormalised.
fn trace_blas(instance: u32, ray_world: Ray, hit: ptr<function, Hit>, any_hit: bool) -> bool {
    let inst = instances[instance];
    let mesh = meshes[inst.mesh];
    let o = transform_point(inst.object_from_world, ray_world.origin);
    let d = transform_vector(inst.object_from_world, ray_world.dir);
    if (mesh.blas_root & WIDE_BLAS) != 0u {
        return trace_blas_wide(mesh, instance, o, d, hit, any_hit);
    }
    return trace_blas_binary(mesh, instance, o, d, hit, any_hit);
}

fn trace_blas_binary(mesh: Mesh, instance: u32, o: vec3<f32>, d: vec3<f32>, hit: ptr<function, Hit>, any_hit: bool) -> bool {
    let inv_d = safe_inverse(d);
    var stack: array<u32, STACK_SIZE>;
    var sp = 0u;
    var node = mesh.blas_root;
    var found = false;
    loop {
        let n = blas_nodes[node];
        let ta = hit_child(n.a, o, inv_d, (*hit).t);
        let tb = hit_child(n.b, o, inv_d, (*hit).t);
        if n.a.count > 0u && ta < MISS {
            found = hit_leaf(mesh, instance, n.a.index, n.a.count, o, d, hit) || found;
            if found && any_hit { return true; }
        }
        if n.b.count > 0u && tb < MISS && tb < (*hit).t {
            found = hit_leaf(mesh, instance, n.b.index, n.b.count, o, d, hit) || found;
            if found && any_hit { return true; }
        }
        let go_a = n.a.count == 0u && ta < (*hit).t;
        let go_b = n.b.count == 0u && tb < (*hit).t;
        if go_a && go_b {
            let a_first = ta <= tb;
            if sp < STACK_SIZE {
                stack[sp] = mesh.blas_root + select(n.a.index, n.b.index, a_first);
                sp++;
            }
            node = mesh.blas_root + select(n.b.index, n.a.index, a_first);
        } else if go_a {
            node = mesh.blas_root + n.a.index;
        } else if go_b {
            node = mesh.blas_root + n.b.index;
        } else {
            if sp == 0u { break; }
            sp--;
            node = stack[sp];
        }
    }
    return found;
}

// ---- compressed wide BVH (Ylitie et al. 2017) ----

// One entry per tree level; the build refuses deeper trees (engine/src/bvh/wide.rs, MAX_WIDE_DEPTH).
const WIDE_STACK_SIZE: u32 = 32u;

// The ray against a wide node's 8 quantised child boxes. Returns the node's hit mask: for each inner child hit,
// bit 24 + (slot ^ ray octant), so that taking the highest bit first visits near children first (the build
// ordered the slots per octant); for each leaf hit, its triangles' bits (unary count << offset) in bits 0..23.
fn intersect_wide(n: WideNode, o: vec3<f32>, inv_d: vec3<f32>, oct_inv4: u32, t_max: f32) -> u32 {
    let e = vec3<u32>(n.w0.w & 0xffu, (n.w0.w >> 8u) & 0xffu, (n.w0.w >> 16u) & 0xffu);
    // Plane q of the grid sits at origin + q * 2^(e - 127): fold that into the ray instead of the boxes.
    let scale = bitcast<vec3<f32>>(e << vec3<u32>(23u)) * inv_d;
    let origin = (bitcast<vec3<f32>>(n.w0.xyz) - o) * inv_d;
    let negative = inv_d < vec3<f32>(0.0);
    var mask = 0u;
    for (var half = 0u; half < 2u; half++) {
        let upper = half == 1u;
        let meta4 = select(n.w1.z, n.w1.w, upper);
        // Inner children have meta 0b001_11xxx: both bits 3 and 4 set, which leaves never have.
        let inner4 = (meta4 & (meta4 << 1u)) & 0x10101010u;
        let bit_index4 = (meta4 ^ (oct_inv4 & ((inner4 >> 4u) * 0xffu))) & 0x1f1f1f1fu;
        let child_bits4 = (meta4 >> 5u) & 0x07070707u;
        let lo = vec3<u32>(select(n.w2.x, n.w2.y, upper), select(n.w3.x, n.w3.y, upper), select(n.w4.x, n.w4.y, upper));
        let hi = vec3<u32>(select(n.w2.z, n.w2.w, upper), select(n.w3.z, n.w3.w, upper), select(n.w4.z, n.w4.w, upper));
        // The near plane of each axis is the min plane for a positive direction, the max plane otherwise.
        let near = select(lo, hi, negative);
        let far = select(hi, lo, negative);
        for (var j = 0u; j < 4u; j++) {
            let shift = j * 8u;
            let t_near = vec3<f32>((near >> vec3<u32>(shift)) & vec3<u32>(0xffu)) * scale + origin;
            let t_far = vec3<f32>((far >> vec3<u32>(shift)) & vec3<u32>(0xffu)) * scale + origin;
            let t_enter = max(max(t_near.x, t_near.y), max(t_near.z, 0.0));
            let t_exit = min(min(t_far.x, t_far.y), min(t_far.z, t_max));
            if t_enter <= t_exit {
                mask |= ((child_bits4 >> shift) & 0xffu) << ((bit_index4 >> shift) & 0xffu);
            }
        }
    }
    return mask;
}

fn trace_blas_wide(mesh: Mesh, instance: u32, o: vec3<f32>, d: vec3<f32>, hit: ptr<function, Hit>, any_hit: bool) -> bool {
    let inv_d = safe_inverse(d);
    let oct_inv4 = select(0u, 0x04040404u, inv_d.x >= 0.0)
        | select(0u, 0x02020202u, inv_d.y >= 0.0)
        | select(0u, 0x01010101u, inv_d.z >= 0.0);
    var stack: array<vec2<u32>, WIDE_STACK_SIZE>;
    var sp = 0u;
    // A node group: (first child node, inner-child hit bits 24..31 | the parent's inner-child mask in bits 0..7).
    // The root starts as the one hit child of a group with an empty mask, so its index resolves to the base.
    let root = mesh.blas_root & ~WIDE_BLAS;
    var group = vec2<u32>(root, 0x80000000u);
    var found = false;
    loop {
        var tri_base = 0u;
        var tri_bits = 0u;
        if group.y > 0x00ffffffu {
            let bit = firstLeadingBit(group.y);
            group.y &= ~(1u << bit);
            let slot = (bit - 24u) ^ (oct_inv4 & 0xffu);
            // Inner children are stored contiguously in slot order: count the inner slots before this one.
            let child = group.x + countOneBits(group.y & 0xffu & ((1u << slot) - 1u));
            if group.y > 0x00ffffffu && sp < WIDE_STACK_SIZE {
                stack[sp] = group;
                sp++;
            }
            let n = wide_nodes[child];
            let mask = intersect_wide(n, o, inv_d, oct_inv4, (*hit).t);
            // Child indices are relative to the mesh's first node.
            group = vec2<u32>(root + n.w1.x, (mask & 0xff000000u) | (n.w0.w >> 24u));
            tri_base = n.w1.y;
            tri_bits = mask & 0x00ffffffu;
        }
        while tri_bits != 0u {
            let k = firstTrailingBit(tri_bits);
            tri_bits &= tri_bits - 1u;
            if hit_slot(mesh, instance, mesh.triangle_offset + tri_base + k, o, d, hit) {
                found = true;
                if any_hit { return true; }
            }
        }
        if group.y <= 0x00ffffffu {
            if sp == 0u { break; }
            sp--;
            group = stack[sp];
        }
    }
    return found;
}

fn trace(ray: Ray, t_max: f32, any_hit: bool) -> Hit {
    var hit = Hit(t_max, NONE, 0u, vec2<f32>(0.0));
    let inv_d = safe_inverse(ray.dir);
    var stack: array<u32, 32>;
    var sp = 0u;
    var node = 0u;
    loop {
        let n = tlas_nodes[node];
        let ta = hit_child(n.a, ray.origin, inv_d, hit.t);
        let tb = hit_child(n.b, ray.origin, inv_d, hit.t);
        if n.a.count > 0u && ta < MISS {
            for (var i = 0u; i < n.a.count; i++) {
                if trace_blas(n.a.index + i, ray, &hit, any_hit) && any_hit { return hit; }
            }
        }
        if n.b.count > 0u && tb < hit.t {
            for (var i = 0u; i < n.b.count; i++) {
                if trace_blas(n.b.index + i, ray, &hit, any_hit) && any_hit { return hit; }
            }
        }
        let go_a = n.a.count == 0u && ta < hit.t;
        let go_b = n.b.count == 0u && tb < hit.t;
        if go_a && go_b {
            let a_first = ta <= tb;
            if sp < 32u {
                stack[sp] = select(n.a.index, n.b.index, a_first);
                sp++;
            }
            node = select(n.b.index, n.a.index, a_first);
        } else if go_a {
            node = n.a.index;
        } else if go_b {
            node = n.b.index;
        } else {
            if sp == 0u { break; }
            sp--;
            node = stack[sp];
        }
    }
    return hit;
}

// Bottom-level traversal of a compressed 8-wide BVH (Ylitie et al. 2017; obvhs `CwBvhNode`, engine/src/bvh/wide.rs)
// for static meshes: node groups and octant-ordered hit masks. WIDE_STACK_SIZE is one entry per tree level (the
// build refuses deeper trees).

// The wide traversal's node-group stack, private for the reason of tlas.wgsl's `tlas_stack` (one zero-fill per
// invocation, not per instance visited).
var<private> wide_stack: array<vec2<u32>, WIDE_STACK_SIZE>;

// The ray's octant, inverted, in each byte: `intersect_wide` and `take_wide_child` order the slots by it.
fn wide_octant_inverse4(inv_d: vec3<f32>) -> u32 {
    return select(0u, 0x04040404u, inv_d.x >= 0.0)
        | select(0u, 0x02020202u, inv_d.y >= 0.0)
        | select(0u, 0x01010101u, inv_d.z >= 0.0);
}

// The node of a group's next inner child to visit (the nearest left by the ray's octant), taken out of the group.
// A group is (first child node, inner-child hit bits 24..31 | the parent's inner-child mask in bits 0..7); inner
// children are stored contiguously in slot order, so the child's node counts the inner slots before its own.
fn take_wide_child(group: ptr<function, vec2<u32>>, oct_inv4: u32) -> u32 {
    let bit = firstLeadingBit((*group).y);
    (*group).y &= ~(1u << bit);
    let slot = (bit - 24u) ^ (oct_inv4 & 0xffu);
    return (*group).x + countOneBits((*group).y & 0xffu & ((1u << slot) - 1u));
}

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
    let oct_inv4 = wide_octant_inverse4(inv_d);
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
            let child = take_wide_child(&group, oct_inv4);
            if group.y > 0x00ffffffu && sp < WIDE_STACK_SIZE {
                wide_stack[sp] = group;
                sp++;
            }
            let n = read_wide_node(child);
            count_work(WORK_WIDE_NODE);
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
            group = wide_stack[sp];
        }
    }
    return found;
}


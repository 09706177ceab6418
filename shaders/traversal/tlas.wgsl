// Two-level traversal: the top-level BVH2 over instances (rebuilt on the CPU when placements change), then each
// instance's mesh in its own BLAS layout. TLAS_STACK_SIZE is the deepest tree the CPU build accepts, so no push
// is ever dropped.

// The top level's traversal stack. Module-scope (private) rather than a local of `trace`: WGSL zero-fills a
// local array at every call, which lavapipe pays per ray (64 entries: 17% of the Cornell box's trace time on this
// 2-core machine, docs/BENCHMARKS.md "Traversal stacks zero-filled once per invocation"); a private array is
// filled once per invocation. Entries are always written before they are read.
var<private> tlas_stack: array<u32, TLAS_STACK_SIZE>;

// The BLAS layouts the top level's leaves use (BLAS_LAYOUT_* bits): the trace kernels set them
// (engine/src/render/material_lobes.rs `KernelNeeds`) and the other layout's traversal compiles away; CPU adapters
// would run its loop for every instance visited otherwise.
override BLAS_LAYOUTS: u32 = BLAS_LAYOUTS_ALL;

// Closest hit within the instance's mesh (or any hit, for shadow rays), in whichever layout the mesh's BLAS
// has. Object-space ray: t stays comparable with world space because the direction is transformed, not
// renormalised.
fn trace_blas(instance: u32, ray_world: Ray, hit: ptr<function, Hit>, any_hit: bool) -> bool {
    let inst = read_instance(instance);
    let mesh = read_mesh(inst.mesh);
    let o = transform_point(inst.object_from_world, ray_world.origin);
    let d = transform_vector(inst.object_from_world, ray_world.dir);
    let wide_only = (BLAS_LAYOUTS & BLAS_LAYOUT_BINARY) == 0u;
    if wide_only || ((BLAS_LAYOUTS & BLAS_LAYOUT_WIDE) != 0u && (mesh.blas_root & WIDE_BLAS) != 0u) {
        return trace_blas_wide(mesh, instance, o, d, hit, any_hit);
    }
    return trace_blas_binary(mesh, instance, o, d, hit, any_hit);
}

// A hit on the merged static tree as the member instance and its mesh's own triangle slot: all that shading,
// the light list and picking know. Once per ray, outside the traversal loops.
fn member_hit(hit: Hit) -> Hit {
    if hit.instance == NONE { return hit; }
    let origins = read_instance(hit.instance).merged_origins;
    if origins == NONE { return hit; }
    let pair = read_triangle(origins + (hit.triangle >> 1u));
    let origin = select(pair.xy, pair.zw, (hit.triangle & 1u) == 1u);
    var member = hit;
    member.instance = origin.x;
    member.triangle = origin.y;
    return member;
}

// The instance the top level's one leaf holds, where it holds one (a static scene merged into one tree): the
// trace kernels set it (engine/src/render/material_lobes.rs `KernelNeeds`) and traversal starts there, the
// top-level loop compiled away; NONE keeps the loop.
override SOLE_INSTANCE: u32 = NONE;

// The top level as a compressed wide tree (engine/src/bvh/tlas.rs), which the waves' kernels traverse where the
// scene holds one: its first 16-byte word in the top level's buffer (after the BVH2), or NONE for the BVH2. The
// waves' extend is bound by dependent node fetches, and a ray visits a third as many wide nodes; the megakernel
// keeps the BVH2, which visits nearer instances first (docs/BENCHMARKS.md, "The top level as a wide tree").
override WIDE_TOP_LEVEL: u32 = NONE;

// The wide top level's node-group stack (module scope for the reason `tlas_stack` is), one entry per level.
var<private> wide_tlas_stack: array<vec2<u32>, WIDE_TLAS_STACK_SIZE>;

fn read_wide_tlas_node(i: u32) -> WideNode {
    let t = WIDE_TOP_LEVEL + 5u * i;
    return WideNode(read_tlas_word(t), read_tlas_word(t + 1u), read_tlas_word(t + 2u), read_tlas_word(t + 3u),
        read_tlas_word(t + 4u));
}

// The instance in 32-bit word `i` of the top level's buffer (a wide leaf slot's).
fn read_tlas_slot(i: u32) -> u32 {
    return read_tlas_word(i >> 2u)[i & 3u];
}

fn trace_wide_top_level(ray: Ray, t_max: f32, any_hit: bool) -> Hit {
    var hit = Hit(t_max, NONE, 0u, vec2<f32>(0.0));
    let inv_d = safe_inverse(ray.dir);
    let oct_inv4 = wide_octant_inverse4(inv_d);
    var sp = 0u;
    // A node group, as in cwbvh.wgsl `trace_blas_wide`: the root is the one hit child of a group with an empty mask.
    var group = vec2<u32>(0u, 0x80000000u);
    loop {
        var first_slot = 0u;
        var leaf_bits = 0u;
        if group.y > 0x00ffffffu {
            let child = take_wide_child(&group, oct_inv4);
            if group.y > 0x00ffffffu && sp < WIDE_TLAS_STACK_SIZE {
                wide_tlas_stack[sp] = group;
                sp++;
            }
            let n = read_wide_tlas_node(child);
            count_work(WORK_TLAS_NODE);
            let mask = intersect_wide(n, ray.origin, inv_d, oct_inv4, hit.t);
            group = vec2<u32>(n.w1.x, (mask & 0xff000000u) | (n.w0.w >> 24u));
            // The node's leaf slots name their instances from this word on (the CPU moved it past the nodes).
            first_slot = n.w1.y;
            leaf_bits = mask & 0x00ffffffu;
        }
        // Every instance hit through one call site: the compiled kernel holds a copy of the BLAS traversal per
        // call (drivers inline every function).
        while leaf_bits != 0u {
            let k = firstTrailingBit(leaf_bits);
            leaf_bits &= leaf_bits - 1u;
            if trace_blas(read_tlas_slot(first_slot + k), ray, &hit, any_hit) && any_hit { return member_hit(hit); }
        }
        if group.y <= 0x00ffffffu {
            if sp == 0u { break; }
            sp--;
            group = wide_tlas_stack[sp];
        }
    }
    return member_hit(hit);
}

fn trace(ray: Ray, t_max: f32, any_hit: bool) -> Hit {
    var hit = Hit(t_max, NONE, 0u, vec2<f32>(0.0));
    if SOLE_INSTANCE != NONE {
        trace_blas(SOLE_INSTANCE, ray, &hit, any_hit);
        return member_hit(hit);
    }
    if WIDE_TOP_LEVEL != NONE {
        return trace_wide_top_level(ray, t_max, any_hit);
    }
    let inv_d = safe_inverse(ray.dir);
    var sp = 0u;
    var node = 0u;
    loop {
        let n = read_tlas_node(node);
        count_work(WORK_TLAS_NODE);
        let ta = hit_child(n.a, ray.origin, inv_d, hit.t);
        let tb = hit_child(n.b, ray.origin, inv_d, hit.t);
        // Both leaf children's instances through one call site: the compiled kernel holds a copy of the BLAS
        // traversal per call (drivers inline every function), and CPU drivers spend seconds compiling each copy.
        // Child a is tested against the distance at node entry, b against the closest hit after a's instances.
        // (A loop over the two children around a loop over each one's instances computed wrong hits on lavapipe.)
        let count_a = select(0u, n.a.count, ta < MISS);
        let total = count_a + n.b.count;
        for (var k = 0u; k < total; k++) {
            var instance = n.a.index + k;
            if k >= count_a {
                if k == count_a && !(tb < hit.t) { break; }
                instance = n.b.index + (k - count_a);
            }
            if trace_blas(instance, ray, &hit, any_hit) && any_hit { return member_hit(hit); }
        }
        let go_a = n.a.count == 0u && ta < hit.t;
        let go_b = n.b.count == 0u && tb < hit.t;
        if go_a && go_b {
            let a_first = ta <= tb;
            if sp < TLAS_STACK_SIZE {
                tlas_stack[sp] = select(n.a.index, n.b.index, a_first);
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
            node = tlas_stack[sp];
        }
    }
    return member_hit(hit);
}

// Traversal as a resumable state machine, one node a step, for kernels that give an invocation whose ray ended a
// new ray inside the traversal loop (Aila and Laine 2009, "Understanding the Efficiency of Ray Traversal on GPUs":
// persistent threads that replace terminated rays). In a kernel that traces one ray an invocation, a warp runs as
// long as its longest ray while its finished lanes idle; here every lane takes a node step in each iteration of
// one loop, and a lane whose ray ended starts its next one there. The steps visit the nodes, instances and
// triangles in the order `trace` (tlas.wgsl) does, so the hit is the same hit.
// Only for the layouts the waves' extend traverses: the wide top level (`WIDE_TOP_LEVEL`) or one merged tree
// (`SOLE_INSTANCE`) above wide meshes (BLAS_LAYOUTS without the BVH2); the kernel checks `refill_supported`.

// The ray in world space and the closest hit so far (`t` bounds the traversal).
var<private> refill_origin: vec3<f32>;
var<private> refill_dir: vec3<f32>;
var<private> refill_inv_d: vec3<f32>;
var<private> refill_octant: u32;
var<private> refill_any_hit: bool;
var<private> refill_hit: Hit;
// The top level: its node group and stack depth (the stack is tlas.wgsl's `wide_tlas_stack`), and the instances
// of the last top-level node's leaf slots still to enter (first slot word, hit bits).
var<private> refill_top_group: vec2<u32>;
var<private> refill_top_sp: u32;
var<private> refill_leaf_first: u32;
var<private> refill_leaf_bits: u32;
// The instance being traversed, if any: its mesh, the ray in its object space, its node group and stack depth
// (the stack is cwbvh.wgsl's `wide_stack`).
var<private> refill_in_mesh: bool;
var<private> refill_instance: u32;
var<private> refill_mesh: Mesh;
var<private> refill_object_origin: vec3<f32>;
var<private> refill_object_dir: vec3<f32>;
var<private> refill_object_inv_d: vec3<f32>;
var<private> refill_object_octant: u32;
var<private> refill_mesh_group: vec2<u32>;
var<private> refill_mesh_sp: u32;

// Whether the kernel's scene shape is one these steps traverse.
fn refill_supported() -> bool {
    return (SOLE_INSTANCE != NONE || WIDE_TOP_LEVEL != NONE) && (BLAS_LAYOUTS & BLAS_LAYOUT_BINARY) == 0u;
}

// Enters `instance`: the ray into its object space, the traversal at its mesh's root.
fn refill_enter(instance: u32) {
    let inst = read_instance(instance);
    refill_instance = instance;
    refill_mesh = read_mesh(inst.mesh);
    refill_object_origin = transform_point(inst.object_from_world, refill_origin);
    refill_object_dir = transform_vector(inst.object_from_world, refill_dir);
    refill_object_inv_d = safe_inverse(refill_object_dir);
    refill_object_octant = wide_octant_inverse4(refill_object_inv_d);
    // The root as the one hit child of a group with an empty mask (cwbvh.wgsl `trace_blas_wide`).
    refill_mesh_group = vec2<u32>(refill_mesh.blas_root & ~WIDE_BLAS, 0x80000000u);
    refill_mesh_sp = 0u;
    refill_in_mesh = true;
}

// Starts a ray: nothing hit closer than t_max; any hit ends it where `any_hit`.
fn refill_start(ray: Ray, t_max: f32, any_hit: bool) {
    refill_origin = ray.origin;
    refill_dir = ray.dir;
    refill_inv_d = safe_inverse(ray.dir);
    refill_octant = wide_octant_inverse4(refill_inv_d);
    refill_any_hit = any_hit;
    refill_hit = Hit(t_max, NONE, 0u, vec2<f32>(0.0));
    refill_top_sp = 0u;
    refill_leaf_bits = 0u;
    refill_in_mesh = false;
    if SOLE_INSTANCE != NONE {
        // No top level: the merged tree is all there is.
        refill_top_group = vec2<u32>(0u, 0u);
        refill_enter(SOLE_INSTANCE);
    } else {
        refill_top_group = vec2<u32>(0u, 0x80000000u);
    }
}

// The ray's hit once `refill_step` said it ended (tlas.wgsl `member_hit`: a member of a merged tree by name).
fn refill_result() -> Hit {
    return member_hit(refill_hit);
}

// One step: the next node of the mesh being traversed, or of the top level, with what its leaves hold (a mesh
// node's triangles are tested in the same step; a top-level node's instances are entered one a step). Returns
// true when the ray has ended (nothing left to visit, or any hit of a shadow ray).
fn refill_step() -> bool {
    // Where the last step left an empty group: the mesh's stack, else back to the top level.
    if refill_in_mesh && refill_mesh_group.y <= 0x00ffffffu {
        if refill_mesh_sp > 0u {
            refill_mesh_sp--;
            refill_mesh_group = wide_stack[refill_mesh_sp];
        } else {
            refill_in_mesh = false;
        }
    }
    if !refill_in_mesh {
        if refill_leaf_bits != 0u {
            let k = firstTrailingBit(refill_leaf_bits);
            refill_leaf_bits &= refill_leaf_bits - 1u;
            refill_enter(read_tlas_slot(refill_leaf_first + k));
        } else if refill_top_group.y <= 0x00ffffffu {
            if refill_top_sp == 0u { return true; }
            refill_top_sp--;
            refill_top_group = wide_tlas_stack[refill_top_sp];
        }
    }
    // One wide node, of the mesh or of the top level: one call of the box tests for both.
    var n: WideNode;
    var o = refill_origin;
    var inv_d = refill_inv_d;
    var octant = refill_octant;
    // (take_wide_child takes a function-space pointer: the groups are module-scope.)
    var group: vec2<u32>;
    if refill_in_mesh {
        group = refill_mesh_group;
        n = read_wide_node(take_wide_child(&group, refill_object_octant));
        if group.y > 0x00ffffffu && refill_mesh_sp < WIDE_STACK_SIZE {
            wide_stack[refill_mesh_sp] = group;
            refill_mesh_sp++;
        }
        o = refill_object_origin;
        inv_d = refill_object_inv_d;
        octant = refill_object_octant;
    } else {
        group = refill_top_group;
        n = read_wide_tlas_node(take_wide_child(&group, refill_octant));
        if group.y > 0x00ffffffu && refill_top_sp < WIDE_TLAS_STACK_SIZE {
            wide_tlas_stack[refill_top_sp] = group;
            refill_top_sp++;
        }
    }
    let mask = intersect_wide(n, o, inv_d, octant, refill_hit.t);
    let next = vec2<u32>(n.w1.x, (mask & 0xff000000u) | (n.w0.w >> 24u));
    if !refill_in_mesh {
        refill_top_group = next;
        refill_leaf_first = n.w1.y;
        refill_leaf_bits = mask & 0x00ffffffu;
        return false;
    }
    // Child indices are relative to the mesh's first node.
    let root = refill_mesh.blas_root & ~WIDE_BLAS;
    refill_mesh_group = vec2<u32>(root + next.x, next.y);
    var tri_bits = mask & 0x00ffffffu;
    var hit = refill_hit;
    var found = false;
    while tri_bits != 0u {
        let k = firstTrailingBit(tri_bits);
        tri_bits &= tri_bits - 1u;
        let slot = refill_mesh.triangle_offset + n.w1.y + k;
        if hit_slot(refill_mesh, refill_instance, slot, refill_object_origin, refill_object_dir, &hit) {
            found = true;
            if refill_any_hit { break; }
        }
    }
    refill_hit = hit;
    return found && refill_any_hit;
}

// Bottom-level traversal of a child-pair BVH2 (deformable meshes, and static ones with `--static-bvh binary`):
// each node holds two child boxes (engine/src/bvh/mod.rs). Stack-based and iterative: no recursion on the GPU.

// The BVH2 traversal stack, private for the reason of tlas.wgsl's `tlas_stack` (one zero-fill per invocation,
// not per instance visited).
var<private> blas_stack: array<u32, BLAS_STACK_SIZE>;

// Intersects the triangles of one leaf; returns true if the closest hit moved.
fn hit_leaf(mesh: Mesh, instance: u32, first: u32, count: u32, o: vec3<f32>, d: vec3<f32>, hit: ptr<function, Hit>) -> bool {
    var found = false;
    for (var i = 0u; i < count; i++) {
        found = hit_slot(mesh, instance, mesh.triangle_offset + first + i, o, d, hit) || found;
    }
    return found;
}

fn trace_blas_binary(mesh: Mesh, instance: u32, o: vec3<f32>, d: vec3<f32>, hit: ptr<function, Hit>, any_hit: bool) -> bool {
    let inv_d = safe_inverse(d);
    var sp = 0u;
    var node = mesh.blas_root;
    var found = false;
    loop {
        let n = read_blas_node(node);
        count_work(WORK_BVH2_NODE);
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
            if sp < BLAS_STACK_SIZE {
                blas_stack[sp] = mesh.blas_root + select(n.a.index, n.b.index, a_first);
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
            node = blas_stack[sp];
        }
    }
    return found;
}


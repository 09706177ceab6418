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

// Intersects the triangles of one leaf; returns true if the closest hit moved.
fn hit_leaf(mesh: Mesh, instance: u32, first: u32, count: u32, o: vec3<f32>, d: vec3<f32>, hit: ptr<function, Hit>) -> bool {
    var found = false;
    for (var i = 0u; i < count; i++) {
        let slot = mesh.triangle_offset + first + i;
        let tri = triangles[slot];
        let r = hit_triangle(o, d, vertex_position(mesh, tri.x), vertex_position(mesh, tri.y), vertex_position(mesh, tri.z), (*hit).t);
        if r.x < MISS && alpha_passes(mesh, tri, r.yz) {
            (*hit).t = r.x;
            (*hit).instance = instance;
            (*hit).triangle = slot;
            (*hit).bary = r.yz;
            found = true;
        }
    }
    return found;
}

// Closest hit within the instance's mesh (or any hit, for shadow rays). Object-space ray: t stays comparable
// with world space because the direction is transformed, not renormalised.
fn trace_blas(instance: u32, ray_world: Ray, hit: ptr<function, Hit>, any_hit: bool) -> bool {
    let inst = instances[instance];
    let mesh = meshes[inst.mesh];
    let o = transform_point(inst.object_from_world, ray_world.origin);
    let d = transform_vector(inst.object_from_world, ray_world.dir);
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

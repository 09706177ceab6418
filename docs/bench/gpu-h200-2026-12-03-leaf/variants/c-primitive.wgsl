// A ray against one triangle slot of an instance's mesh: the closest-hit update every BLAS layout shares,
// with the alpha-mask test.

// The object-space vertices of the mesh's triangle `local` (its slot less the mesh's first): one contiguous
// 48-byte fetch from `leaf_triangles` where the mesh has them, else the vertex indices and then three vertex
// fetches that wait on them.
fn slot_positions(mesh: Mesh, local: u32) -> array<vec3<f32>, 3> {
    let i = 3u * (mesh.leaf_triangles + local);
    return array<vec3<f32>, 3>(leaf_triangles[i].xyz, leaf_triangles[i + 1u].xyz, leaf_triangles[i + 2u].xyz);
}

// Intersects one triangle slot; true when it became the closest hit. The indices and material are read only
// for a candidate hit (the alpha test).
fn hit_slot(mesh: Mesh, instance: u32, slot: u32, o: vec3<f32>, d: vec3<f32>, hit: ptr<function, Hit>) -> bool {
    let p = slot_positions(mesh, slot - mesh.triangle_offset);
    let r = hit_triangle(o, d, p[0], p[1], p[2], (*hit).t);
    if r.x < MISS && alpha_passes(mesh, triangles[slot], r.yz) {
        (*hit).t = r.x;
        (*hit).instance = instance;
        (*hit).triangle = slot;
        (*hit).bary = r.yz;
        return true;
    }
    return false;
}

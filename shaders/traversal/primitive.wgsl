// A ray against one triangle slot of an instance's mesh: the closest-hit update every BLAS layout shares,
// with the alpha-mask test.

// Intersects one triangle slot; true when it became the closest hit.
fn hit_slot(mesh: Mesh, instance: u32, slot: u32, o: vec3<f32>, d: vec3<f32>, hit: ptr<function, Hit>) -> bool {
    count_work(WORK_TRIANGLE);
    let tri = read_triangle(slot);
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

// Vertex attributes in the vertex pool: f32 positions and UVs, octahedral snorm16 normals and tangents,
// unorm8x4 colours (engine/src/render/gpu_scene/packing.rs writes them).

fn vertex_position(mesh: Mesh, v: u32) -> vec3<f32> {
    return read_pool_position(mesh.position_offset + POSITION_WORDS * v);
}

fn interpolate_uv(offset: u32, tri: vec4<u32>, w: vec3<f32>) -> vec2<f32> {
    return read_pool_vec2(offset + 2u * tri.x) * w.x + read_pool_vec2(offset + 2u * tri.y) * w.y + read_pool_vec2(offset + 2u * tri.z) * w.z;
}

// The UV set a texture slot reads (TEXCOORD index in bit 24 of the slot); (0, 0) when the mesh lacks it.
fn texture_uv(texture: u32, mesh: Mesh, tri: vec4<u32>, w: vec3<f32>) -> vec2<f32> {
    let offset = select(mesh.uv0_offset, mesh.uv1_offset, (texture >> 24u) == 1u);
    if offset == NONE { return vec2<f32>(0.0); }
    return interpolate_uv(offset, tri, w);
}

// The triangle slot's vertices in world space.
fn world_triangle(instance: u32, slot: u32) -> array<vec3<f32>, 3> {
    let inst = read_instance(instance);
    let mesh = read_mesh(inst.mesh);
    let tri = read_triangle(slot);
    return array<vec3<f32>, 3>(
        transform_point(inst.world_from_object, vertex_position(mesh, tri.x)),
        transform_point(inst.world_from_object, vertex_position(mesh, tri.y)),
        transform_point(inst.world_from_object, vertex_position(mesh, tri.z)));
}

// Interpolated COLOR_0 (opaque white when the mesh has none is the caller's default: check color_offset).
fn vertex_color(mesh: Mesh, tri: vec4<u32>, w: vec3<f32>) -> vec4<f32> {
    return unpack4x8unorm(read_pool_word(mesh.color_offset + tri.x)) * w.x
        + unpack4x8unorm(read_pool_word(mesh.color_offset + tri.y)) * w.y
        + unpack4x8unorm(read_pool_word(mesh.color_offset + tri.z)) * w.z;
}

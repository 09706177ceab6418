// Where the scene was one frame earlier (engine/src/render/gpu_scene/motion.rs `SceneMotion`): each instance's
// previous placement and stable object id, the previous positions of meshes deformed this frame, the current
// instance of each object, and how last frame's light indices map to this frame's. Group 2 of the real-time
// kernels that look back in time.

struct MotionInstance {
    // Rows of the previous world-from-object matrix.
    prev_world_from_object: mat3x4<f32>,
    // Stable across frames, unlike the instance index (instances are in top-level BVH leaf order).
    object: u32, _p0: u32, _p1: u32, _p2: u32,
}

@group(2) @binding(0) var<storage, read> motion_instances: array<MotionInstance>;
// Object id -> this frame's instance index (NONE: the object is gone).
@group(2) @binding(1) var<storage, read> object_instances: array<u32>;
// Previous positions (POSITION_WORDS f32 each: the vertex pool's words, copied) of the meshes deformed this
// frame, at `mesh_motion[mesh]` words.
@group(2) @binding(2) var<storage, read> prev_positions: array<f32>;
// Per mesh: word offset of its previous positions, NONE when its vertices did not move this frame.
@group(2) @binding(3) var<storage, read> mesh_motion: array<u32>;
// Last frame's light index -> this frame's (NONE: gone); read only with RT_LIGHTS_REMAPPED.
@group(2) @binding(4) var<storage, read> light_remap: array<u32>;

fn instance_of_object(object: u32) -> u32 {
    if object >= arrayLength(&object_instances) { return NONE; }
    return object_instances[object];
}

fn previous_vertex(mesh_index: u32, mesh: Mesh, v: u32) -> vec3<f32> {
    let offset = mesh_motion[mesh_index];
    if offset == NONE { return vertex_position(mesh, v); }
    let o = offset + POSITION_WORDS * v;
    return vec3<f32>(prev_positions[o], prev_positions[o + 1u], prev_positions[o + 2u]);
}

// Where the point at barycentrics `bary` of triangle `slot` on `instance` was in the previous frame.
fn previous_world_position(instance: u32, slot: u32, bary: vec2<f32>) -> vec3<f32> {
    let mesh_index = read_instance(instance).mesh;
    let mesh = read_mesh(mesh_index);
    let tri = read_triangle(slot);
    let w = vec3<f32>(1.0 - bary.x - bary.y, bary.x, bary.y);
    let p = previous_vertex(mesh_index, mesh, tri.x) * w.x + previous_vertex(mesh_index, mesh, tri.y) * w.y
        + previous_vertex(mesh_index, mesh, tri.z) * w.z;
    return transform_point(motion_instances[instance].prev_world_from_object, p);
}

// This frame's index of a light a reservoir picked last frame.
fn current_light(previous: u32) -> u32 {
    if previous == NONE || !realtime_flag(RT_LIGHTS_REMAPPED) { return previous; }
    if previous >= arrayLength(&light_remap) { return NONE; }
    return light_remap[previous];
}

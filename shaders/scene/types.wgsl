// The scene's GPU structs, byte for byte the Rust structs of engine/src/render/layout.rs (the naga test checks
// every size and field offset). Constants such as NONE and WIDE_BLAS come from the generated `constants` module.

struct BvhChild { min: vec3<f32>, index: u32, max: vec3<f32>, count: u32 }
struct BvhNode { a: BvhChild, b: BvhChild }
// w0: origin of the quantisation grid (xyz, f32 bits), exponents e.x | e.y << 8 | e.z << 16 | inner-child mask << 24
// w1: first child node, first triangle slot, child meta bytes 0-3, 4-7
// w2..w4: quantised child planes per axis: min bytes 0-3, min 4-7, max 0-3, max 4-7 (x, y, z)
struct WideNode { w0: vec4<u32>, w1: vec4<u32>, w2: vec4<u32>, w3: vec4<u32>, w4: vec4<u32> }

struct Instance {
    world_from_object: mat3x4<f32>, // rows
    object_from_world: mat3x4<f32>,
    mesh: u32,
    // This instance's emissive triangles in the light list: lights[first_light .. first_light + light_count],
    // sorted by triangle slot.
    first_light: u32, light_count: u32,
    // NONE, except on the merged static tree's pseudo-instance: its (member instance, member triangle slot) pairs
    // in `triangles`, two per entry: slot s's in entry merged_origins + s / 2, half s % 2
    // (engine/src/render/gpu_scene/static_merge.rs).
    merged_origins: u32,
}

struct Mesh {
    blas_root: u32, triangle_offset: u32, position_offset: u32, normal_offset: u32,
    tangent_offset: u32, uv0_offset: u32, uv1_offset: u32, color_offset: u32,
}

struct Material {
    base_color: vec4<f32>,
    emissive: vec3<f32>, metallic: f32,
    roughness: f32, alpha_cutoff: f32, normal_scale: f32, flags: u32,
    base_color_texture: u32, metallic_roughness_texture: u32, normal_texture: u32, emissive_texture: u32,
    specular_f0: vec3<f32>, specular_weight: f32,
    attenuation: vec3<f32>, refraction_ior: f32,
    transmission: f32, transmission_texture: u32, specular_texture: u32, specular_color_texture: u32,
    clearcoat: f32, clearcoat_roughness: f32, clearcoat_texture: u32, clearcoat_roughness_texture: u32,
    sheen_color: vec3<f32>, sheen_roughness: f32,
    clearcoat_normal_texture: u32, clearcoat_normal_scale: f32, sheen_color_texture: u32, sheen_roughness_texture: u32,
}

struct TextureInfo { offset: u32, width: u32, height: u32, flags: u32, uv_u: vec4<f32>, uv_v: vec4<f32> }

// One light of any kind (engine/src/render/layout.rs `GpuLight` documents each field per kind).
struct Light {
    kind: u32, index_a: u32, index_b: u32, flags: u32,
    position: vec3<f32>, range: f32,
    direction: vec3<f32>, cos_outer: f32,
    radiance: vec3<f32>, cos_inner: f32,
}

// A node of the light sampler's tree (engine/src/render/gpu_scene/light_tree.rs `GpuLightTreeNode`).
struct LightTreeNode {
    lo: vec3<f32>, phi: f32,
    hi: vec3<f32>, cos_theta_o: f32,
    w: vec3<f32>, cos_theta_e: f32,
    child_or_light: u32, flags: u32, _p0: u32, _p1: u32,
}

// The scene as every ray-tracing kernel reads it: group 0, read only (engine/src/render/scene_bindings.rs).

// The top level in 16-byte words: its BVH2 (4 words a node), then where the waves asked for one its wide tree
// (engine/src/bvh/tlas.rs: 5 words a node, then a word per leaf slot).
@group(0) @binding(0) var<storage, read> tlas_nodes: array<vec4<u32>>;
@group(0) @binding(1) var<storage, read> blas_nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read> instances: array<Instance>;
@group(0) @binding(3) var<storage, read> meshes: array<Mesh>;
@group(0) @binding(4) var<storage, read> triangles: array<vec4<u32>>; // 3 vertex indices + material
@group(0) @binding(5) var<storage, read> vertex_pool: array<u32>;
@group(0) @binding(6) var<storage, read> materials: array<Material>;
@group(0) @binding(7) var<storage, read> texels: array<u32>;
@group(0) @binding(8) var<storage, read> texture_infos: array<TextureInfo>;
// Every light (engine/src/render/gpu_scene/lights.rs): emissive triangles first, then punctual lights, then
// the lights at infinity (frame.infinite_light_first ..).
@group(0) @binding(9) var<storage, read> lights: array<Light>;
// Compressed 8-wide BVH nodes of static meshes (obvhs `CwBvhNode`, 80 bytes: engine/src/bvh/wide.rs).
@group(0) @binding(10) var<storage, read> wide_nodes: array<WideNode>;
// The light sampler's cumulative probabilities, one per light (the last is 1).
@group(0) @binding(11) var<storage, read> light_cdf: array<f32>;
// The environment map (lights/environment.wgsl): RGB texels, then per-row conditional CDFs, then the marginal.
@group(0) @binding(12) var<storage, read> environment_map: array<f32>;
// The light sampler's tree over the lights at finite distance (lights/light_tree.wgsl).
@group(0) @binding(13) var<storage, read> light_tree: array<LightTreeNode>;

// Every read of the scene goes through these functions. On CPU adapters the composer replaces this module with
// scene/bindings_texels.wgsl, which reads the same bytes from textures: lavapipe turns each storage-buffer load
// into a loop over the SIMD lanes, several times slower than a texel fetch (docs/BENCHMARKS.md).
fn read_tlas_word(i: u32) -> vec4<u32> { return tlas_nodes[i]; }
fn tlas_child(lo: vec4<u32>, hi: vec4<u32>) -> BvhChild {
    return BvhChild(bitcast<vec3<f32>>(lo.xyz), lo.w, bitcast<vec3<f32>>(hi.xyz), hi.w);
}
fn read_tlas_node(i: u32) -> BvhNode {
    let t = 4u * i;
    return BvhNode(tlas_child(tlas_nodes[t], tlas_nodes[t + 1u]), tlas_child(tlas_nodes[t + 2u], tlas_nodes[t + 3u]));
}
fn read_blas_node(i: u32) -> BvhNode { return blas_nodes[i]; }
fn read_instance(i: u32) -> Instance { return instances[i]; }
fn read_mesh(i: u32) -> Mesh { return meshes[i]; }
fn read_triangle(i: u32) -> vec4<u32> { return triangles[i]; }
fn read_pool_word(i: u32) -> u32 { return vertex_pool[i]; }
fn read_pool_vec2(i: u32) -> vec2<f32> {
    return vec2<f32>(bitcast<f32>(vertex_pool[i]), bitcast<f32>(vertex_pool[i + 1u]));
}
// A vertex position (word i, a multiple of POSITION_WORDS).
fn read_pool_position(i: u32) -> vec3<f32> {
    return bitcast<vec3<f32>>(vec3<u32>(vertex_pool[i], vertex_pool[i + 1u], vertex_pool[i + 2u]));
}
fn read_material(i: u32) -> Material { return materials[i]; }
fn read_texel(i: u32) -> u32 { return texels[i]; }
fn read_texture_info(i: u32) -> TextureInfo { return texture_infos[i]; }
fn read_light(i: u32) -> Light { return lights[i]; }
fn read_wide_node(i: u32) -> WideNode { return wide_nodes[i]; }
fn read_light_cdf(i: u32) -> f32 { return light_cdf[i]; }
fn read_environment(i: u32) -> f32 { return environment_map[i]; }
// The texel whose ENVIRONMENT_TEXEL_WORDS words start at i: rgb.
fn read_environment_texel(i: u32) -> vec3<f32> {
    return vec3<f32>(environment_map[i], environment_map[i + 1u], environment_map[i + 2u]);
}
fn read_light_tree_node(i: u32) -> LightTreeNode { return light_tree[i]; }

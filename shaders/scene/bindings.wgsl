// The scene as every ray-tracing kernel reads it: group 0, read only (engine/src/render/scene_bindings.rs).

@group(0) @binding(0) var<storage, read> tlas_nodes: array<BvhNode>;
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

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
@group(0) @binding(9) var<storage, read> emitters: array<Emitter>;
// Compressed 8-wide BVH nodes of static meshes (obvhs `CwBvhNode`, 80 bytes: engine/src/bvh/wide.rs).
@group(0) @binding(10) var<storage, read> wide_nodes: array<WideNode>;

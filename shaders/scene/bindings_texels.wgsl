// The scene as kernels read it on CPU adapters: scene/bindings.wgsl's buffers, byte for byte, as read-only
// rgba32uint storage textures at the same bindings, in rows of 2^SCENE_TEXEL_ROW_LOG2 16-byte texels
// (engine/src/render/scene_texels.rs copies each buffer into its texture). The composer puts this module in
// place of scene/bindings.wgsl there (engine/src/gpu/mod.rs `scene_in_textures`): lavapipe compiles each
// storage-buffer load into a loop over its SIMD lanes with a bounds check per word, and a texel load into
// straight-line vector code (storage textures: no mip level to look up per lane, unlike sampled ones;
// docs/BENCHMARKS.md). The read_* functions return what scene/bindings.wgsl's return.

@group(0) @binding(0) var tlas_nodes: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(1) var blas_nodes: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(2) var instances: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(3) var meshes: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(4) var triangles: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(5) var vertex_pool: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(6) var materials: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(7) var texels: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(8) var texture_infos: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(9) var lights: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(10) var wide_nodes: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(11) var light_cdf: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(12) var environment_map: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(13) var light_tree: texture_storage_2d<rgba32uint, read>;

// Where texel i of a buffer is.
fn scene_texel_at(i: u32) -> vec2<u32> {
    return vec2<u32>(i & ((1u << SCENE_TEXEL_ROW_LOG2) - 1u), i >> SCENE_TEXEL_ROW_LOG2);
}

// Word j (0..7) of two consecutive texels.
fn word_of_pair(a: vec4<u32>, b: vec4<u32>, j: u32) -> u32 {
    return select(a[j & 3u], b[j & 3u], j >= 4u);
}

// Three consecutive words from word i of a word array: the two texels they can span, read unconditionally
// (a branch would not save the second fetch: lanes take both sides).
fn words3(first: vec4<u32>, second: vec4<u32>, i: u32) -> vec3<u32> {
    let k = i & 3u;
    return vec3<u32>(word_of_pair(first, second, k), word_of_pair(first, second, k + 1u), word_of_pair(first, second, k + 2u));
}

fn bvh_child(lo: vec4<u32>, hi: vec4<u32>) -> BvhChild {
    return BvhChild(bitcast<vec3<f32>>(lo.xyz), lo.w, bitcast<vec3<f32>>(hi.xyz), hi.w);
}

fn read_tlas_node(i: u32) -> BvhNode {
    let t = 4u * i;
    return BvhNode(
        bvh_child(textureLoad(tlas_nodes, scene_texel_at(t)), textureLoad(tlas_nodes, scene_texel_at(t + 1u))),
        bvh_child(textureLoad(tlas_nodes, scene_texel_at(t + 2u)), textureLoad(tlas_nodes, scene_texel_at(t + 3u))));
}

fn read_blas_node(i: u32) -> BvhNode {
    let t = 4u * i;
    return BvhNode(
        bvh_child(textureLoad(blas_nodes, scene_texel_at(t)), textureLoad(blas_nodes, scene_texel_at(t + 1u))),
        bvh_child(textureLoad(blas_nodes, scene_texel_at(t + 2u)), textureLoad(blas_nodes, scene_texel_at(t + 3u))));
}

fn read_instance(i: u32) -> Instance {
    let t = 7u * i;
    let w = mat3x4<f32>(
        bitcast<vec4<f32>>(textureLoad(instances, scene_texel_at(t))),
        bitcast<vec4<f32>>(textureLoad(instances, scene_texel_at(t + 1u))),
        bitcast<vec4<f32>>(textureLoad(instances, scene_texel_at(t + 2u))));
    let o = mat3x4<f32>(
        bitcast<vec4<f32>>(textureLoad(instances, scene_texel_at(t + 3u))),
        bitcast<vec4<f32>>(textureLoad(instances, scene_texel_at(t + 4u))),
        bitcast<vec4<f32>>(textureLoad(instances, scene_texel_at(t + 5u))));
    let m = textureLoad(instances, scene_texel_at(t + 6u));
    return Instance(w, o, m.x, m.y, m.z, m.w);
}

fn read_mesh(i: u32) -> Mesh {
    let a = textureLoad(meshes, scene_texel_at(2u * i));
    let b = textureLoad(meshes, scene_texel_at(2u * i + 1u));
    return Mesh(a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w);
}

fn read_triangle(i: u32) -> vec4<u32> {
    return textureLoad(triangles, scene_texel_at(i));
}

fn read_pool_word(i: u32) -> u32 {
    return textureLoad(vertex_pool, scene_texel_at(i >> 2u))[i & 3u];
}

fn read_pool_vec2(i: u32) -> vec2<f32> {
    let a = textureLoad(vertex_pool, scene_texel_at(i >> 2u));
    let b = textureLoad(vertex_pool, scene_texel_at((i >> 2u) + 1u));
    let k = i & 3u;
    return bitcast<vec2<f32>>(vec2<u32>(word_of_pair(a, b, k), word_of_pair(a, b, k + 1u)));
}

fn read_pool_vec3(i: u32) -> vec3<f32> {
    let a = textureLoad(vertex_pool, scene_texel_at(i >> 2u));
    let b = textureLoad(vertex_pool, scene_texel_at((i >> 2u) + 1u));
    return bitcast<vec3<f32>>(words3(a, b, i));
}

fn read_material(i: u32) -> Material {
    let t = 10u * i;
    let t0 = textureLoad(materials, scene_texel_at(t));
    let t1 = textureLoad(materials, scene_texel_at(t + 1u));
    let t2 = textureLoad(materials, scene_texel_at(t + 2u));
    let t3 = textureLoad(materials, scene_texel_at(t + 3u));
    let t4 = textureLoad(materials, scene_texel_at(t + 4u));
    let t5 = textureLoad(materials, scene_texel_at(t + 5u));
    let t6 = textureLoad(materials, scene_texel_at(t + 6u));
    let t7 = textureLoad(materials, scene_texel_at(t + 7u));
    let t8 = textureLoad(materials, scene_texel_at(t + 8u));
    let t9 = textureLoad(materials, scene_texel_at(t + 9u));
    return Material(
        bitcast<vec4<f32>>(t0),
        bitcast<vec3<f32>>(t1.xyz), bitcast<f32>(t1.w),
        bitcast<f32>(t2.x), bitcast<f32>(t2.y), bitcast<f32>(t2.z), t2.w,
        t3.x, t3.y, t3.z, t3.w,
        bitcast<vec3<f32>>(t4.xyz), bitcast<f32>(t4.w),
        bitcast<vec3<f32>>(t5.xyz), bitcast<f32>(t5.w),
        bitcast<f32>(t6.x), t6.y, t6.z, t6.w,
        bitcast<f32>(t7.x), bitcast<f32>(t7.y), t7.z, t7.w,
        bitcast<vec3<f32>>(t8.xyz), bitcast<f32>(t8.w),
        t9.x, bitcast<f32>(t9.y), t9.z, t9.w);
}

fn read_texel(i: u32) -> u32 {
    return textureLoad(texels, scene_texel_at(i >> 2u))[i & 3u];
}

fn read_texture_info(i: u32) -> TextureInfo {
    let t = 3u * i;
    let a = textureLoad(texture_infos, scene_texel_at(t));
    return TextureInfo(a.x, a.y, a.z, a.w,
        bitcast<vec4<f32>>(textureLoad(texture_infos, scene_texel_at(t + 1u))),
        bitcast<vec4<f32>>(textureLoad(texture_infos, scene_texel_at(t + 2u))));
}

fn read_light(i: u32) -> Light {
    let t = 4u * i;
    let a = textureLoad(lights, scene_texel_at(t));
    let p = textureLoad(lights, scene_texel_at(t + 1u));
    let d = textureLoad(lights, scene_texel_at(t + 2u));
    let r = textureLoad(lights, scene_texel_at(t + 3u));
    return Light(a.x, a.y, a.z, a.w,
        bitcast<vec3<f32>>(p.xyz), bitcast<f32>(p.w),
        bitcast<vec3<f32>>(d.xyz), bitcast<f32>(d.w),
        bitcast<vec3<f32>>(r.xyz), bitcast<f32>(r.w));
}

fn read_wide_node(i: u32) -> WideNode {
    let t = 5u * i;
    return WideNode(
        textureLoad(wide_nodes, scene_texel_at(t)),
        textureLoad(wide_nodes, scene_texel_at(t + 1u)),
        textureLoad(wide_nodes, scene_texel_at(t + 2u)),
        textureLoad(wide_nodes, scene_texel_at(t + 3u)),
        textureLoad(wide_nodes, scene_texel_at(t + 4u)));
}

fn read_light_cdf(i: u32) -> f32 {
    return bitcast<f32>(textureLoad(light_cdf, scene_texel_at(i >> 2u))[i & 3u]);
}

fn read_environment(i: u32) -> f32 {
    return bitcast<f32>(textureLoad(environment_map, scene_texel_at(i >> 2u))[i & 3u]);
}

fn read_environment3(i: u32) -> vec3<f32> {
    let a = textureLoad(environment_map, scene_texel_at(i >> 2u));
    let b = textureLoad(environment_map, scene_texel_at((i >> 2u) + 1u));
    return bitcast<vec3<f32>>(words3(a, b, i));
}

fn read_light_tree_node(i: u32) -> LightTreeNode {
    let t = 4u * i;
    let lo = textureLoad(light_tree, scene_texel_at(t));
    let hi = textureLoad(light_tree, scene_texel_at(t + 1u));
    let w = textureLoad(light_tree, scene_texel_at(t + 2u));
    let c = textureLoad(light_tree, scene_texel_at(t + 3u));
    return LightTreeNode(
        bitcast<vec3<f32>>(lo.xyz), bitcast<f32>(lo.w),
        bitcast<vec3<f32>>(hi.xyz), bitcast<f32>(hi.w),
        bitcast<vec3<f32>>(w.xyz), bitcast<f32>(w.w),
        c.x, c.y, c.z, c.w);
}

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

// Texel i of a buffer's texture.
fn scene_texel(buffer: texture_storage_2d<rgba32uint, read>, i: u32) -> vec4<u32> {
    return textureLoad(buffer, vec2<u32>(i & ((1u << SCENE_TEXEL_ROW_LOG2) - 1u), i >> SCENE_TEXEL_ROW_LOG2));
}

// Word i of a buffer of words.
fn scene_word(buffer: texture_storage_2d<rgba32uint, read>, i: u32) -> u32 {
    return scene_texel(buffer, i >> 2u)[i & 3u];
}

fn bvh_child(lo: vec4<u32>, hi: vec4<u32>) -> BvhChild {
    return BvhChild(bitcast<vec3<f32>>(lo.xyz), lo.w, bitcast<vec3<f32>>(hi.xyz), hi.w);
}

// A child-pair BVH node (4 texels) of either tree.
fn scene_bvh_node(buffer: texture_storage_2d<rgba32uint, read>, i: u32) -> BvhNode {
    let t = 4u * i;
    return BvhNode(
        bvh_child(scene_texel(buffer, t), scene_texel(buffer, t + 1u)),
        bvh_child(scene_texel(buffer, t + 2u), scene_texel(buffer, t + 3u)));
}

fn read_tlas_node(i: u32) -> BvhNode { return scene_bvh_node(tlas_nodes, i); }
fn read_tlas_word(i: u32) -> vec4<u32> { return scene_texel(tlas_nodes, i); }
fn read_blas_node(i: u32) -> BvhNode { return scene_bvh_node(blas_nodes, i); }

fn read_instance(i: u32) -> Instance {
    let t = 7u * i;
    let w = mat3x4<f32>(
        bitcast<vec4<f32>>(scene_texel(instances, t)),
        bitcast<vec4<f32>>(scene_texel(instances, t + 1u)),
        bitcast<vec4<f32>>(scene_texel(instances, t + 2u)));
    let o = mat3x4<f32>(
        bitcast<vec4<f32>>(scene_texel(instances, t + 3u)),
        bitcast<vec4<f32>>(scene_texel(instances, t + 4u)),
        bitcast<vec4<f32>>(scene_texel(instances, t + 5u)));
    let m = scene_texel(instances, t + 6u);
    return Instance(w, o, m.x, m.y, m.z, m.w);
}

fn read_mesh(i: u32) -> Mesh {
    let a = scene_texel(meshes, 2u * i);
    let b = scene_texel(meshes, 2u * i + 1u);
    return Mesh(a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w);
}

fn read_triangle(i: u32) -> vec4<u32> {
    return scene_texel(triangles, i);
}

fn read_pool_word(i: u32) -> u32 {
    return scene_word(vertex_pool, i);
}

// A UV pair (word i, even: packing.rs starts every UV set on an even word), one texel.
fn read_pool_vec2(i: u32) -> vec2<f32> {
    let t = scene_texel(vertex_pool, i >> 2u);
    return bitcast<vec2<f32>>(select(t.xy, t.zw, (i & 2u) != 0u));
}

// A vertex position (word i, a multiple of POSITION_WORDS = 4): one texel.
fn read_pool_position(i: u32) -> vec3<f32> {
    return bitcast<vec3<f32>>(scene_texel(vertex_pool, i >> 2u).xyz);
}

fn read_material(i: u32) -> Material {
    let t = 10u * i;
    let t0 = scene_texel(materials, t);
    let t1 = scene_texel(materials, t + 1u);
    let t2 = scene_texel(materials, t + 2u);
    let t3 = scene_texel(materials, t + 3u);
    let t4 = scene_texel(materials, t + 4u);
    let t5 = scene_texel(materials, t + 5u);
    let t6 = scene_texel(materials, t + 6u);
    let t7 = scene_texel(materials, t + 7u);
    let t8 = scene_texel(materials, t + 8u);
    let t9 = scene_texel(materials, t + 9u);
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
    return scene_word(texels, i);
}

fn read_texture_info(i: u32) -> TextureInfo {
    let t = 3u * i;
    let a = scene_texel(texture_infos, t);
    return TextureInfo(a.x, a.y, a.z, a.w,
        bitcast<vec4<f32>>(scene_texel(texture_infos, t + 1u)),
        bitcast<vec4<f32>>(scene_texel(texture_infos, t + 2u)));
}

fn read_light(i: u32) -> Light {
    let t = 4u * i;
    let a = scene_texel(lights, t);
    let p = scene_texel(lights, t + 1u);
    let d = scene_texel(lights, t + 2u);
    let r = scene_texel(lights, t + 3u);
    return Light(a.x, a.y, a.z, a.w,
        bitcast<vec3<f32>>(p.xyz), bitcast<f32>(p.w),
        bitcast<vec3<f32>>(d.xyz), bitcast<f32>(d.w),
        bitcast<vec3<f32>>(r.xyz), bitcast<f32>(r.w));
}

fn read_wide_node(i: u32) -> WideNode {
    let t = 5u * i;
    return WideNode(
        scene_texel(wide_nodes, t),
        scene_texel(wide_nodes, t + 1u),
        scene_texel(wide_nodes, t + 2u),
        scene_texel(wide_nodes, t + 3u),
        scene_texel(wide_nodes, t + 4u));
}

fn read_light_cdf(i: u32) -> f32 {
    return bitcast<f32>(scene_word(light_cdf, i));
}

fn read_environment(i: u32) -> f32 {
    return bitcast<f32>(scene_word(environment_map, i));
}

// The texel whose ENVIRONMENT_TEXEL_WORDS (= 4) words start at i: rgb, one texel load.
fn read_environment_texel(i: u32) -> vec3<f32> {
    return bitcast<vec3<f32>>(scene_texel(environment_map, i >> 2u).xyz);
}

fn read_light_tree_node(i: u32) -> LightTreeNode {
    let t = 4u * i;
    let lo = scene_texel(light_tree, t);
    let hi = scene_texel(light_tree, t + 1u);
    let w = scene_texel(light_tree, t + 2u);
    let c = scene_texel(light_tree, t + 3u);
    return LightTreeNode(
        bitcast<vec3<f32>>(lo.xyz), bitcast<f32>(lo.w),
        bitcast<vec3<f32>>(hi.xyz), bitcast<f32>(hi.w),
        bitcast<vec3<f32>>(w.xyz), bitcast<f32>(w.w),
        c.x, c.y, c.z, c.w);
}

// Shared declarations of the path tracer: GPU structs (mirrors engine/src/render/layout.rs), bindings, RNG.

const PI: f32 = 3.14159265358979;
const INV_PI: f32 = 0.318309886183791;
const NONE: u32 = 0xffffffffu;
const INVALID_OCT: u32 = 0x80008000u;
const MATERIAL_DOUBLE_SIDED: u32 = 1u;
const MATERIAL_ALPHA_MASK: u32 = 2u;
const MATERIAL_ALPHA_BLEND: u32 = 4u;
const FRAME_NEE: u32 = 1u;
// Write the primary-hit AOV (the recorder's motion vectors need it; off otherwise).
const FRAME_HIT_AOV: u32 = 2u;
// Accumulate the denoiser's moments (skipped when nothing will denoise this accumulation: about 5% of a frame).
const FRAME_MOMENTS: u32 = 4u;

struct BvhChild { min: vec3<f32>, index: u32, max: vec3<f32>, count: u32 }
struct BvhNode { a: BvhChild, b: BvhChild }
// w0: origin of the quantisation grid (xyz, f32 bits), exponents e.x | e.y << 8 | e.z << 16 | inner-child mask << 24
// w1: first child node, first triangle slot, child meta bytes 0-3, 4-7
// w2..w4: quantised child planes per axis: min bytes 0-3, min 4-7, max 0-3, max 4-7 (x, y, z)
struct WideNode { w0: vec4<u32>, w1: vec4<u32>, w2: vec4<u32>, w3: vec4<u32>, w4: vec4<u32> }
// Set in Mesh.blas_root when the root indexes `wide_nodes`.
const WIDE_BLAS: u32 = 0x80000000u;

struct Instance {
    world_from_object: mat3x4<f32>, // rows
    object_from_world: mat3x4<f32>,
    mesh: u32, _p0: u32, _p1: u32, _p2: u32,
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
}

struct TextureInfo { offset: u32, width: u32, height: u32, flags: u32 }

struct Emitter { instance: u32, triangle: u32, cdf: f32, pmf: f32 }

struct Frame {
    world_from_camera: mat4x4<f32>,
    env_color: vec3<f32>, tan_half_fov: f32,
    width: u32, height: u32, sample_base: u32, spp: u32,
    max_depth: u32, seed: u32, env_mode: u32, rr_depth: u32,
    emitter_count: u32, flags: u32, emitter_total_power: f32, _pad: u32,
}

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
@group(0) @binding(10) var<uniform> frame: Frame;
// Compressed 8-wide BVH nodes of static meshes (obvhs `CwBvhNode`, 80 bytes: engine/src/bvh/wide.rs).
@group(0) @binding(11) var<storage, read> wide_nodes: array<WideNode>;

// ---- random numbers: a PCG stream per (pixel, sample, seed) ----
struct Rng { state: u32 }

fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn rng_new(pixel: u32, sample_index: u32, seed: u32) -> Rng {
    return Rng(pcg_hash(pixel ^ pcg_hash(sample_index ^ pcg_hash(seed + 0x9e3779b9u))));
}

fn rand(rng: ptr<function, Rng>) -> f32 {
    (*rng).state = (*rng).state * 747796405u + 2891336453u;
    let s = (*rng).state;
    let word = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    // 24 random bits: uniform in [0, 1).
    return f32(((word >> 22u) ^ word) >> 8u) * (1.0 / 16777216.0);
}

// ---- vertex pool decoding ----
fn pool_vec3(offset: u32) -> vec3<f32> {
    return vec3<f32>(bitcast<f32>(vertex_pool[offset]), bitcast<f32>(vertex_pool[offset + 1u]), bitcast<f32>(vertex_pool[offset + 2u]));
}
fn pool_vec2(offset: u32) -> vec2<f32> {
    return vec2<f32>(bitcast<f32>(vertex_pool[offset]), bitcast<f32>(vertex_pool[offset + 1u]));
}
fn oct_decode(word: u32) -> vec3<f32> {
    let e = unpack2x16snorm(word);
    var n = vec3<f32>(e.x, e.y, 1.0 - abs(e.x) - abs(e.y));
    let t = max(-n.z, 0.0);
    n.x += select(t, -t, n.x >= 0.0);
    n.y += select(t, -t, n.y >= 0.0);
    return normalize(n);
}

fn vertex_position(mesh: Mesh, v: u32) -> vec3<f32> {
    return pool_vec3(mesh.position_offset + 3u * v);
}

fn transform_point(m: mat3x4<f32>, p: vec3<f32>) -> vec3<f32> {
    let h = vec4<f32>(p, 1.0);
    return vec3<f32>(dot(m[0], h), dot(m[1], h), dot(m[2], h));
}
fn transform_vector(m: mat3x4<f32>, v: vec3<f32>) -> vec3<f32> {
    let h = vec4<f32>(v, 0.0);
    return vec3<f32>(dot(m[0], h), dot(m[1], h), dot(m[2], h));
}
// Normals transform by the inverse transpose: columns of object_from_world's 3x3.
fn transform_normal(object_from_world: mat3x4<f32>, n: vec3<f32>) -> vec3<f32> {
    return object_from_world[0].xyz * n.x + object_from_world[1].xyz * n.y + object_from_world[2].xyz * n.z;
}

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// Offsets a ray origin off a surface by a few ULPs along the geometric normal, scaled to the coordinates'
// magnitude (Waechter & Binder, Ray Tracing Gems ch. 6): no self-intersection at large coordinates or grazing
// angles, and no visible gap near the origin.
fn offset_ray_origin(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let int_scale = 256.0;
    let float_scale = 1.0 / 65536.0;
    let origin = 1.0 / 32.0;
    let of_i = vec3<i32>(int_scale * n);
    let p_i = vec3<f32>(
        bitcast<f32>(bitcast<i32>(p.x) + select(of_i.x, -of_i.x, p.x < 0.0)),
        bitcast<f32>(bitcast<i32>(p.y) + select(of_i.y, -of_i.y, p.y < 0.0)),
        bitcast<f32>(bitcast<i32>(p.z) + select(of_i.z, -of_i.z, p.z < 0.0)));
    return vec3<f32>(
        select(p_i.x, p.x + float_scale * n.x, abs(p.x) < origin),
        select(p_i.y, p.y + float_scale * n.y, abs(p.y) < origin),
        select(p_i.z, p.z + float_scale * n.z, abs(p.z) < origin));
}

// ---- textures: RGBA8 texels in one storage buffer, filtered here (no binding arrays needed) ----
fn wrap_coord(i: i32, size: i32, mode: u32) -> i32 {
    if mode == 2u { return clamp(i, 0, size - 1); }
    if mode == 1u {
        let period = 2 * size;
        var m = i % period;
        if m < 0 { m += period; }
        return select(m, period - 1 - m, m >= size);
    }
    var m = i % size;
    if m < 0 { m += size; }
    return m;
}

fn texel(info: TextureInfo, x: i32, y: i32) -> vec4<f32> {
    let wx = wrap_coord(x, i32(info.width), info.flags & 3u);
    let wy = wrap_coord(y, i32(info.height), (info.flags >> 2u) & 3u);
    return unpack4x8unorm(texels[info.offset + u32(wy) * info.width + u32(wx)]);
}

fn sample_texture(texture: u32, uv: vec2<f32>) -> vec4<f32> {
    let info = texture_infos[texture & 0xffffffu];
    let size = vec2<f32>(f32(info.width), f32(info.height));
    let st = uv * size - 0.5;
    if (info.flags & 16u) != 0u {
        let p = vec2<i32>(floor(st + 0.5));
        return texel(info, p.x, p.y);
    }
    let base = floor(st);
    let f = st - base;
    let p = vec2<i32>(base);
    let a = mix(texel(info, p.x, p.y), texel(info, p.x + 1, p.y), f.x);
    let b = mix(texel(info, p.x, p.y + 1), texel(info, p.x + 1, p.y + 1), f.x);
    return mix(a, b, f.y);
}

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    return select(pow((c + 0.055) / 1.055, vec3<f32>(2.4)), c / 12.92, c <= vec3<f32>(0.04045));
}

// Direction of the camera ray through `offset` (in pixels, 0..1 each way) of pixel `gid`.
fn camera_ray_dir(gid: vec2<u32>, offset: vec2<f32>) -> vec3<f32> {
    let aspect = f32(frame.width) / f32(frame.height);
    let ndc = vec2<f32>(
        (f32(gid.x) + offset.x) / f32(frame.width) * 2.0 - 1.0,
        1.0 - (f32(gid.y) + offset.y) / f32(frame.height) * 2.0);
    let d_cam = vec3<f32>(ndc.x * frame.tan_half_fov * aspect, ndc.y * frame.tan_half_fov, -1.0);
    return normalize((frame.world_from_camera * vec4<f32>(d_cam, 0.0)).xyz);
}

// Textures: every image as RGBA8 texels in one storage buffer, filtered here (no binding arrays, so it runs on
// lavapipe): bilinear or nearest, with glTF's wrap modes.

// The core texture slots (CORE_TEXTURE_*) some material of the scene uses (engine/src/render/material_lobes.rs
// `MaterialNeeds`): lookups of the other slots compile away. On lavapipe a lookup behind a material's `if` runs at
// every hit whether or not the material has that texture (its `if`s mask SIMD lanes, they never skip code): the
// Cornell box, which has no texture, took 0.57x the time without them (docs/BENCHMARKS.md, "Kernels without the
// texture slots no material uses"). Kernels that do not set it look up every slot.
override CORE_TEXTURES: u32 = CORE_TEXTURES_ALL;

fn scene_uses_texture(slot: u32) -> bool {
    return (CORE_TEXTURES & slot) != 0u;
}

// i wrapped into 0 .. size - 1 by the sampler's mode (0 repeat, 1 mirrored repeat, 2 clamp). The remainders are
// taken in f32 (exact for |i| < 2^24, with the quotient's rounding corrected): an integer remainder by a
// non-constant is a scalar division per SIMD lane on lavapipe, which runs this code for every hit whether or not
// a texture is read (its `if`s only mask lanes): 15% of the Cornell box's time, which has no texture
// (docs/BENCHMARKS.md, "Texture wraps in floats").
fn wrap_coord(i: i32, size: i32, mode: u32) -> i32 {
    if mode == 2u { return clamp(i, 0, size - 1); }
    let x = f32(i);
    let n = f32(size);
    let period = select(n, 2.0 * n, mode == 1u);
    var m = x - period * floor(x / period);
    m = select(m, m + period, m < 0.0);
    m = select(m, m - period, m >= period);
    m = select(m, period - 1.0 - m, m >= n);
    return clamp(i32(m), 0, size - 1);
}

fn texel(info: TextureInfo, x: i32, y: i32) -> vec4<f32> {
    let wx = wrap_coord(x, i32(info.width), info.flags & 3u);
    let wy = wrap_coord(y, i32(info.height), (info.flags >> 2u) & 3u);
    return unpack4x8unorm(read_texel(info.offset + u32(wy) * info.width + u32(wx)));
}

fn sample_texture(texture: u32, uv_in: vec2<f32>) -> vec4<f32> {
    let info = read_texture_info(texture & 0xffffffu);
    var uv = uv_in;
    if (info.flags & TEXTURE_TRANSFORMED) != 0u {
        let h = vec3<f32>(uv_in, 1.0);
        uv = vec2<f32>(dot(info.uv_u.xyz, h), dot(info.uv_v.xyz, h));
    }
    let size = vec2<f32>(f32(info.width), f32(info.height));
    let st = uv * size - 0.5;
    if (info.flags & TEXTURE_NEAREST) != 0u {
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

// A tangent-space normal sampled through a rotating KHR_texture_transform, turned back into the mesh's tangent
// frame: the texture's u axis runs along the frame's (cos, -sin) (the rotation applies to UVs whose v axis
// points down the image, the bitangent up), as three.js and Filament do.
fn untransform_tangent_normal(texture: u32, xy: vec2<f32>) -> vec2<f32> {
    let info = read_texture_info(texture & 0xffffffu);
    if (info.flags & TEXTURE_TRANSFORMED) == 0u { return xy; }
    let c = info.uv_u.w;
    let s = info.uv_v.w;
    return vec2<f32>(c * xy.x + s * xy.y, -s * xy.x + c * xy.y);
}

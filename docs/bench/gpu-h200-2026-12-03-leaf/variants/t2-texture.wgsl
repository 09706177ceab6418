// Textures: every image as RGBA8 texels in one storage buffer, filtered here (no binding arrays, so it runs on
// lavapipe): bilinear or nearest, with glTF's wrap modes.

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

// Texel coordinates i and i + 1 under a wrap mode, with one integer division instead of two (the bilinear
// footprint's two columns or rows).
fn wrap_pair(i: i32, size: i32, mode: u32) -> vec2<i32> {
    if mode == 2u { return clamp(vec2<i32>(i, i + 1), vec2<i32>(0), vec2<i32>(size - 1)); }
    let period = select(size, 2 * size, mode == 1u);
    var m = i % period;
    if m < 0 { m += period; }
    let next = select(m + 1, 0, m + 1 == period);
    let pair = vec2<i32>(m, next);
    if mode == 1u {
        return select(pair, vec2<i32>(period - 1) - pair, pair >= vec2<i32>(size));
    }
    return pair;
}

fn texel_at(info: TextureInfo, x: i32, y: i32) -> vec4<f32> {
    return unpack4x8unorm(texels[info.offset + u32(y) * info.width + u32(x)]);
}

fn sample_texture(texture: u32, uv_in: vec2<f32>) -> vec4<f32> {
    let info = texture_infos[texture & 0xffffffu];
    var uv = uv_in;
    if (info.flags & TEXTURE_TRANSFORMED) != 0u {
        let h = vec3<f32>(uv_in, 1.0);
        uv = vec2<f32>(dot(info.uv_u.xyz, h), dot(info.uv_v.xyz, h));
    }
    let size = vec2<f32>(f32(info.width), f32(info.height));
    let st = uv * size - 0.5;
    let nearest = (info.flags & TEXTURE_NEAREST) != 0u;
    // Nearest: the texel under st + 0.5 (the first of the pair); bilinear: the 2x2 footprint from floor(st).
    let base = select(floor(st), floor(st + 0.5), nearest);
    let p = vec2<i32>(base);
    let xs = wrap_pair(p.x, i32(info.width), info.flags & 3u);
    let ys = wrap_pair(p.y, i32(info.height), (info.flags >> 2u) & 3u);
    if nearest {
        return texel_at(info, xs.x, ys.x);
    }
    let f = st - base;
    let a = mix(texel_at(info, xs.x, ys.x), texel_at(info, xs.y, ys.x), f.x);
    let b = mix(texel_at(info, xs.x, ys.y), texel_at(info, xs.y, ys.y), f.x);
    return mix(a, b, f.y);
}

// A tangent-space normal sampled through a rotating KHR_texture_transform, turned back into the mesh's tangent
// frame: the texture's u axis runs along the frame's (cos, -sin) (the rotation applies to UVs whose v axis
// points down the image, the bitangent up), as three.js and Filament do.
fn untransform_tangent_normal(texture: u32, xy: vec2<f32>) -> vec2<f32> {
    let info = texture_infos[texture & 0xffffffu];
    if (info.flags & TEXTURE_TRANSFORMED) == 0u { return xy; }
    let c = info.uv_u.w;
    let s = info.uv_v.w;
    return vec2<f32>(c * xy.x + s * xy.y, -s * xy.x + c * xy.y);
}

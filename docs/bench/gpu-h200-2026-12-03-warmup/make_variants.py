# Makes the kernel variants of run5.sh from the repository's shaders (run at aee5f83, from the repository root):
# ab-shaders/noaov (the path without AOVs), ab-shaders/wrap and ab-shaders/nearest (texture lookups).
import os
for d in ['ab-shaders/noaov/integrator', 'ab-shaders/wrap/scene', 'ab-shaders/nearest/scene']:
    os.makedirs(d, exist_ok=True)
src=open('shaders/integrator/path.wgsl').read()
s=src
reps=[('''            if (aov & AOV_FOLLOWING) != 0u {
                result.albedo = vec3<f32>(0.0);
                result.normal = vec3<f32>(0.0);
            }''',''),
('''            if depth == 0u { result.unscattered += escaped; }''',''),
('''        if depth == 0u && !result.hit {
            result.hit = true;
            result.albedo = s.bsdf.base_color;
            result.normal = s.n;
            result.depth = hit.t * dot(ray.dir, forward);
            aov = AOV_OPEN;
        } else if (aov & AOV_FOLLOWING) != 0u {
            result.albedo *= s.bsdf.base_color;
            result.normal = s.n;
            aov = (aov & ~AOV_FOLLOWING) | AOV_OPEN;
        }''','''        if depth == 0u && !result.hit {
            result.hit = true;
        }'''),
('''            if depth == 0u { result.unscattered += throughput * s.emission * weight; }''',''),
('''        if (aov & AOV_OPEN) != 0u && path_alive && (bs.flags & BSDF_GLOSSY) != 0u && aov_is_mirror(s.bsdf)
            && aov < AOV_MAX_MIRRORS * AOV_MIRROR_COUNT {
            // The reflectance so far: 1 at the first mirror; at a later one, what reached it (its base colour
            // divided back out).
            let so_far = result.albedo / max(s.bsdf.base_color, vec3<f32>(1e-4));
            result.albedo = select(vec3<f32>(1.0), so_far, aov >= AOV_MIRROR_COUNT) * aov_mirror_tint(wo, s.bsdf);
            aov = aov + AOV_MIRROR_COUNT + AOV_FOLLOWING;
        }''','')]
for a,b in reps:
    assert a in s, a[:60]
    s=s.replace(a,b)
open('ab-shaders/noaov/integrator/path.wgsl','w').write(s)

t=open('shaders/scene/texture.wgsl').read()
# `wrap`: a texel fetch without wrapping, and the bilinear lookup wrapping each of its two columns and rows once.
fetch = """fn texel_at(info: TextureInfo, x: i32, y: i32) -> vec4<f32> {
    return unpack4x8unorm(texels[info.offset + u32(y) * info.width + u32(x)]);
}

"""
bilinear_before = t[t.index('    let a = mix(texel(info, p.x, p.y)'):t.index('// A tangent-space normal')]
bilinear_after = """    // Each coordinate wrapped once: the four texels share two columns and two rows.
    let w = i32(info.width);
    let h = i32(info.height);
    let x0 = wrap_coord(p.x, w, info.flags & 3u);
    let x1 = wrap_coord(p.x + 1, w, info.flags & 3u);
    let y0 = wrap_coord(p.y, h, (info.flags >> 2u) & 3u);
    let y1 = wrap_coord(p.y + 1, h, (info.flags >> 2u) & 3u);
    let a = mix(texel_at(info, x0, y0), texel_at(info, x1, y0), f.x);
    let b = mix(texel_at(info, x0, y1), texel_at(info, x1, y1), f.x);
    return mix(a, b, f.y);
}

"""
wrap = (t.replace('fn texel(', fetch + 'fn texel(', 1)
        .replace('return unpack4x8unorm(texels[info.offset + u32(wy) * info.width + u32(wx)]);',
                 'return texel_at(info, wx, wy);', 1)
        .replace(bilinear_before, bilinear_after, 1))
open('ab-shaders/wrap/scene/texture.wgsl','w').write(wrap)
near=t.replace('''    if (info.flags & TEXTURE_NEAREST) != 0u {''','''    if true {''')
open('ab-shaders/nearest/scene/texture.wgsl','w').write(near)

// Display transform: accumulated linear radiance -> exposure -> tone curve -> sRGB, packed RGBA8.
// Also shows the AOVs (albedo, normal, depth) for inspection.

struct Params {
    width: u32,
    height: u32,
    // 0 ACES (Hill's fit), 1 AgX-like (Reinhard on luminance), 2 clamp
    tonemapper: u32,
    // 0 colour, 1 albedo, 2 normal, 3 depth
    view: u32,
    exposure_scale: f32,
    depth_scale: f32,
    _p0: u32,
    _p1: u32,
}

@group(0) @binding(0) var<storage, read> accum: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> aov_albedo_depth: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> aov_normal: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> out_rgba8: array<u32>;
@group(0) @binding(4) var<uniform> params: Params;

// ACES filmic fit (Stephen Hill): sRGB -> ACES AP1-ish, RRT+ODT fit, back to sRGB.
fn aces_fitted(c: vec3<f32>) -> vec3<f32> {
    let input = mat3x3<f32>(
        vec3<f32>(0.59719, 0.07600, 0.02840),
        vec3<f32>(0.35458, 0.90834, 0.13383),
        vec3<f32>(0.04823, 0.01566, 0.83777));
    let output = mat3x3<f32>(
        vec3<f32>(1.60475, -0.10208, -0.00327),
        vec3<f32>(-0.53108, 1.10813, -0.07276),
        vec3<f32>(-0.07367, -0.00605, 1.07602));
    let v = input * c;
    let a = v * (v + 0.0245786) - 0.000090537;
    let b = v * (0.983729 * v + 0.4329510) + 0.238081;
    return clamp(output * (a / b), vec3<f32>(0.0), vec3<f32>(1.0));
}

fn reinhard_luminance(c: vec3<f32>) -> vec3<f32> {
    let l = luminance(c);
    return clamp(c / (1.0 + l), vec3<f32>(0.0), vec3<f32>(1.0));
}

// Branch-free on purpose: the same selection written as nested if/else made lavapipe (Mesa 22.3.6, LLVM 15) grow
// its resident memory by ~200 KB on every dispatch of more than a few workgroups, which the viewer does each
// frame (docs/VIEWER.md, "Memory over long runs"). The extra reads and ALU are negligible next to the trace.
@compute @workgroup_size(8, 8)
fn tonemap(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height { return; }
    let i = gid.y * params.width + gid.x;
    let a = accum[i];
    let samples = max(a.w, 1.0);
    let c = max(a.rgb / samples, vec3<f32>(0.0)) * params.exposure_scale;
    var tone = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
    tone = select(tone, reinhard_luminance(c), params.tonemapper == 1u);
    tone = select(tone, aces_fitted(c), params.tonemapper == 0u);
    let colour = linear_to_srgb(tone);
    let ad = aov_albedo_depth[i];
    let albedo = linear_to_srgb(clamp(ad.rgb / samples, vec3<f32>(0.0), vec3<f32>(1.0)));
    let nh = aov_normal[i];
    let has_normal = nh.w > 0.0 && dot(nh.xyz, nh.xyz) > 0.0;
    let normal = select(vec3<f32>(0.0), normalize(select(vec3<f32>(1.0), nh.xyz, has_normal)) * 0.5 + 0.5, has_normal);
    // Mean camera depth over the samples that hit (0 where none did).
    let depth = select(0.0, ad.w / max(nh.w, 1e-30), nh.w > 0.0);
    var display = colour;
    display = select(display, albedo, params.view == 1u);
    display = select(display, normal, params.view == 2u);
    display = select(display, vec3<f32>(exp(-depth * params.depth_scale)), params.view == 3u);
    out_rgba8[i] = pack4x8unorm(vec4<f32>(display, 1.0));
}

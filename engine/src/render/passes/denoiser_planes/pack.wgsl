// An external denoiser's inputs (Open Image Denoise's) from the accumulation, written in GPU memory it shares:
// per pixel the mean radiance, less its unscattered part where split.wgsl's `pixel_split` says so (that part is
// exact and unpack.wgsl adds it back), first-hit albedo and first-hit normal (each sum over the samples
// divided by the sample count, as oidn::inputs does on the host), sanitised as oidn::filter does (NaN -> 0;
// radiance in [0, max_radiance], albedo in [0, 1], normal in [-1, 1]) and stored as tightly packed float3
// planes, the layout of OIDN's FLOAT3 images.

struct Params {
    width: u32,
    height: u32,
    // Radiance above this is clamped: OIDN's HDR transfer must not overflow to infinity.
    max_radiance: f32,
    _pad: u32,
}

@group(0) @binding(0) var<storage, read> accum: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> albedo_depth: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> normal_hits: array<vec4<f32>>;
// rgb: unscattered radiance summed over the samples.
@group(0) @binding(3) var<storage, read> moments: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> color_plane: array<f32>;
@group(0) @binding(5) var<storage, read_write> albedo_plane: array<f32>;
@group(0) @binding(6) var<storage, read_write> normal_plane: array<f32>;
@group(0) @binding(7) var<uniform> params: Params;

@compute @workgroup_size(8, 8)
fn pack(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height { return; }
    let i = gid.y * params.width + gid.x;
    let sum = accum[i];
    let n = max(sum.w, 1.0);
    var mean = sum.rgb / n;
    if pixel_split(gid.x, gid.y) == SPLIT_SCATTERED { mean = max(mean - moments[i].rgb / n, vec3<f32>(0.0)); }
    let color = sanitised3(mean, 0.0, params.max_radiance);
    let albedo = sanitised3(albedo_depth[i].rgb / n, 0.0, 1.0);
    let normal = sanitised3(normal_hits[i].rgb / n, -1.0, 1.0);
    for (var c = 0u; c < 3u; c++) {
        color_plane[3u * i + c] = color[c];
        albedo_plane[3u * i + c] = albedo[c];
        normal_plane[3u * i + c] = normal[c];
    }
}

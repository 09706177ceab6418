// An external denoiser's output (Open Image Denoise's packed float3 image, in GPU memory it shares) plus the
// exact unscattered radiance pack.wgsl left out, into the accumulation's layout with a sample count of 1, which
// the display's tone mapper reads unchanged. Pixels split.wgsl keeps show the colour plane (their mean), as does a
// pixel the denoiser returned non-finite; negative channels become 0 (as oidn::filter::repair does on the host).

struct Params {
    width: u32,
    height: u32,
    // Radiance above this is clamped (as in pack.wgsl).
    max_radiance: f32,
    _pad: u32,
}

@group(0) @binding(0) var<storage, read> output_plane: array<f32>;
@group(0) @binding(1) var<storage, read> color_plane: array<f32>;
@group(0) @binding(2) var<storage, read> accum: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> normal_hits: array<vec4<f32>>;
// rgb: unscattered radiance summed over the samples.
@group(0) @binding(4) var<storage, read> moments: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> shown: array<vec4<f32>>;
@group(0) @binding(6) var<uniform> params: Params;

@compute @workgroup_size(8, 8)
fn unpack(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height { return; }
    let i = gid.y * params.width + gid.x;
    let denoised = vec3<f32>(output_plane[3u * i], output_plane[3u * i + 1u], output_plane[3u * i + 2u]);
    let noisy = vec3<f32>(color_plane[3u * i], color_plane[3u * i + 1u], color_plane[3u * i + 2u]);
    let split = pixel_split(gid.x, gid.y);
    let use_denoised = split != SPLIT_KEPT && is_finite(denoised.x) && is_finite(denoised.y) && is_finite(denoised.z);
    var unscattered = vec3<f32>(0.0);
    if split == SPLIT_SCATTERED {
        unscattered = sanitised3(moments[i].rgb / max(accum[i].w, 1.0), 0.0, params.max_radiance);
    }
    shown[i] = vec4<f32>(select(noisy, max(denoised, vec3<f32>(0.0)), use_denoised) + unscattered, 1.0);
}

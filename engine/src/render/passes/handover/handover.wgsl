// The hand-over from the real-time image to plain accumulation once nothing moves: the last real-time frame
// (held) and the accumulation's display image, mixed with the accumulation's weight growing with its samples.
// Both inputs are in the accumulation's layout (sums and a count); the output is a mean (count 1).

struct Params {
    width: u32,
    height: u32,
    // Weight of the accumulation, 0..1.
    weight: f32,
    _pad: u32,
}

@group(0) @binding(0) var<storage, read> realtime_image: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> accumulated: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> blended: array<vec4<f32>>;
@group(0) @binding(3) var<uniform> params: Params;

fn mean(v: vec4<f32>) -> vec3<f32> {
    return v.rgb / max(v.w, 1.0);
}

@compute @workgroup_size(8, 8)
fn blend(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height { return; }
    let i = gid.y * params.width + gid.x;
    blended[i] = vec4<f32>(mix(mean(realtime_image[i]), mean(accumulated[i]), params.weight), 1.0);
}

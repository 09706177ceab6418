// Random numbers by dimension (pbrt-v4's `Sampler::Get1D/Get2D`): the value of dimension `d` of sample `s` in
// pixel `p` is a hash of (p, s, seed, d) (Jarzynski & Olano 2020, `pcg4d`), so a kernel that draws a new
// dimension, or skips one on some paths, never shifts any other decision. The integrator assigns dimensions
// (integrator/path.wgsl); the camera takes 0..3.

struct Sampler {
    pixel: u32,
    index: u32,
    seed: u32,
}

fn sampler_start(pixel: u32, sample_index: u32, seed: u32) -> Sampler {
    return Sampler(pixel, sample_index, seed);
}

// Four well-mixed 32-bit words from four (Jarzynski & Olano, "Hash Functions for GPU Rendering", JCGT 2020).
fn pcg4d(input: vec4<u32>) -> vec4<u32> {
    var v = input * 1664525u + 1013904223u;
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    v ^= v >> vec4<u32>(16u);
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    return v;
}

// 24 random bits: uniform in [0, 1).
fn unit_float(word: u32) -> f32 {
    return f32(word >> 8u) * (1.0 / 16777216.0);
}

fn get_1d(s: Sampler, dimension: u32) -> f32 {
    return unit_float(pcg4d(vec4<u32>(s.pixel, s.index, s.seed, dimension)).x);
}

// Dimensions `dimension` and `dimension + 1`.
fn get_2d(s: Sampler, dimension: u32) -> vec2<f32> {
    let h = pcg4d(vec4<u32>(s.pixel, s.index, s.seed, dimension));
    return vec2<f32>(unit_float(h.x), unit_float(h.y));
}

// (A/B variant: the independent sampler of 68fb315 under the names d12e333's kernels call.)
fn get_2d_independent(s: Sampler, dimension: u32) -> vec2<f32> {
    return get_2d(s, dimension);
}

// Random numbers by dimension (pbrt-v4's `Sampler::Get1D/Get2D`): the value of dimension `d` of sample `s` in
// pixel `p` depends only on (p, s, seed, d), so a kernel that draws a new dimension, or skips one on some paths,
// never shifts any other decision. The integrator assigns dimensions (integrator/path.wgsl); the camera takes
// 0..3.
//
// The values are Sobol' points padded by dimension (pbrt-v4's `PaddedSobolSampler`): each `get_2d` is the first
// two Sobol' dimensions of the sample's index, each `get_1d` the first, so a pixel's first 2^k samples are
// stratified in every elementary interval of each pair (a (0,k,2)-net) and converge faster than independent
// numbers on what is smooth. Independence between dimensions comes from the padding: every call shuffles the
// sample index by its own nested uniform scramble (the hashed Owen scramble of Burley 2020, "Practical Hash-based
// Owen Scrambling", JCGT 9(4)), seeded by a hash of (p, seed, d), which permutes each aligned block of 2^k indices
// among themselves and so keeps the nets. The values themselves are randomised by a digital shift (an xor with
// the same hash: pbrt-v4's `PermuteDigits` in base 2), which keeps the nets too: an Owen scramble of the values
// measured the same error at 1-1024 spp and cost the Cornell box 3.4% more trace time on the H200
// (docs/BENCHMARKS.md). The pixel's hash decorrelates neighbouring pixels.

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

// A random bijection of u32 in which every bit depends only on itself and the bits below it (an addition and
// xors with products by even constants; Burley's constants): applied to bit-reversed values it is a nested
// uniform (Owen) scramble, where each bit is flipped by a hash of the bits above it.
fn owen_hash(x: u32, seed: u32) -> u32 {
    var v = x + seed;
    v ^= v * 0x6c50b47cu;
    v ^= v * 0xb82f1e52u;
    v ^= v * 0xc7afe638u;
    v ^= v * 0x8d22f6e6u;
    return v;
}

// The sample index shuffled within every aligned block of 2^k indices, for all k at once (a nested uniform
// scramble of the index's bits, most significant first).
fn shuffled_index(index: u32, seed: u32) -> u32 {
    return reverseBits(owen_hash(reverseBits(index), seed));
}

// Sobol' dimension 1 of `index`, bit-reversed (bit 31 - i of the returned word is the 2^-(i+1) digit). Its
// direction numbers are Pascal's triangle mod 2: the index's bit b contributes to digit i exactly when the bits
// of i are a subset of those of b (Lucas), so digit i is the xor of the index bits at every superset of i: a
// superset-xor transform over the five bits of a bit position, five shifts in all.
fn sobol_1_reversed(index: u32) -> u32 {
    var v = index;
    v ^= (v >> 1u) & 0x55555555u;
    v ^= (v >> 2u) & 0x33333333u;
    v ^= (v >> 4u) & 0x0f0f0f0fu;
    v ^= (v >> 8u) & 0x00ff00ffu;
    v ^= (v >> 16u) & 0x0000ffffu;
    return v;
}

// Salts keep a 1D and a 2D draw at the same dimension apart.
const SAMPLER_SALT_1D: u32 = 0x1d1d1d1du;
const SAMPLER_SALT_2D: u32 = 0x2d2d2d2du;

fn get_1d(s: Sampler, dimension: u32) -> f32 {
    let h = pcg4d(vec4<u32>(s.pixel, s.seed, dimension, SAMPLER_SALT_1D));
    let i = shuffled_index(s.index, h.x);
    // Sobol' dimension 0 is the bit-reversed index (van der Corput), digitally shifted.
    return unit_float(reverseBits(i) ^ h.y);
}

// Dimensions `dimension` and `dimension + 1`.
fn get_2d(s: Sampler, dimension: u32) -> vec2<f32> {
    let h = pcg4d(vec4<u32>(s.pixel, s.seed, dimension, SAMPLER_SALT_2D));
    let i = shuffled_index(s.index, h.x);
    let x = reverseBits(i) ^ h.y;
    let y = reverseBits(sobol_1_reversed(i)) ^ h.z;
    return vec2<f32>(unit_float(x), unit_float(y));
}

// Dimensions `dimension` and `dimension + 1` as independent uniform numbers, a hash of (p, s, seed, d), not
// stratified over the pixel's samples: the camera's film position. Stratified, it makes a pixel's first-hit
// normal and depth converge within a few samples to the blend of both sides of an edge, which blunts the
// denoisers' edge-stopping guides (the a-trous filter kept 0.70 of the Cornell box's edge contrast at 4 spp
// instead of 1.00), and in the real-time path it alternates consecutive frames' jitter across an edge, which
// fails history validation.
fn get_2d_independent(s: Sampler, dimension: u32) -> vec2<f32> {
    let h = pcg4d(vec4<u32>(s.pixel, s.index, s.seed, dimension));
    return vec2<f32>(unit_float(h.x), unit_float(h.y));
}

// ReSTIR reservoirs (Bitterli et al. 2020; the generalised RIS of Lin et al. 2022): one light sample y (a
// light index and the 2D point `u` that light's `sample_li` maps to a point on it), its unbiased contribution
// weight W and a confidence weight M. Samples live in the lights' primary sample space, which every pixel
// shares, so reusing a neighbour's sample is the identity shift with Jacobian 1: only target functions change.

struct Reservoir {
    light: u32,
    u: vec2<f32>,
    // Unbiased contribution weight: light contribution x W estimates the direct light.
    w: f32,
    // Confidence: how many frames' worth of candidates it summarises.
    m: f32,
}

fn empty_reservoir() -> Reservoir {
    return Reservoir(NONE, vec2<f32>(0.0), 0.0, 0.0);
}

// `u` as stored (unorm16 each): quantise before evaluating a new candidate, so that every later evaluation of
// the stored sample sees exactly the point its weight was computed for.
fn quantise_u(u: vec2<f32>) -> vec2<f32> {
    return unpack2x16unorm(pack2x16unorm(u));
}

fn pack_reservoir(r: Reservoir) -> vec4<u32> {
    return vec4<u32>(r.light, pack2x16unorm(r.u), bitcast<u32>(r.w), bitcast<u32>(r.m));
}

// A stored reservoir; one whose weights are not finite and non-negative reads as empty (never propagates).
// A reservoir without a sample keeps its confidence: the technique that drew nothing still takes its share of
// the MIS weights.
fn unpack_reservoir(v: vec4<u32>) -> Reservoir {
    let w = bitcast<f32>(v.z);
    let m = bitcast<f32>(v.w);
    if !is_finite(w) || !is_finite(m) || w < 0.0 || m < 0.0 { return empty_reservoir(); }
    if v.x == NONE { return Reservoir(NONE, vec2<f32>(0.0), 0.0, m); }
    return Reservoir(v.x, unpack2x16unorm(v.y), w, m);
}

// Weighted reservoir sampling over a stream of candidates: keeps one with probability proportional to its
// resampling weight, and the target function's value there (to form W at the end).
struct Resampler {
    light: u32,
    u: vec2<f32>,
    weight_sum: f32,
    // Target function of the kept sample at the pixel that resamples.
    target_value: f32,
    // Its light contribution there (what shading multiplies by W).
    contribution: vec3<f32>,
    // Whether the kept sample is known to be visible from the pixel.
    visible: bool,
}

fn empty_resampler() -> Resampler {
    return Resampler(NONE, vec2<f32>(0.0), 0.0, 0.0, vec3<f32>(0.0), false);
}

// Offers a candidate with resampling weight `weight`; `xi` uniform in [0, 1).
fn resampler_offer(s: ptr<function, Resampler>, light: u32, u: vec2<f32>, weight: f32, target_value: f32,
    contribution: vec3<f32>, visible: bool, xi: f32) {
    if !(weight > 0.0) || !is_finite(weight) { return; }
    (*s).weight_sum += weight;
    if xi * (*s).weight_sum < weight {
        (*s).light = light;
        (*s).u = u;
        (*s).target_value = target_value;
        (*s).contribution = contribution;
        (*s).visible = visible;
    }
}

// The reservoir the stream leaves: W = weight sum / target value of the kept sample.
fn resampler_finish(s: Resampler, m: f32) -> Reservoir {
    if s.light == NONE || !(s.target_value > 0.0) { return Reservoir(NONE, vec2<f32>(0.0), 0.0, m); }
    let w = s.weight_sum / s.target_value;
    if !is_finite(w) { return Reservoir(NONE, vec2<f32>(0.0), 0.0, m); }
    return Reservoir(s.light, s.u, w, m);
}

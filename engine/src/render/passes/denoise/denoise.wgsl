// Display-side denoiser: an edge-avoiding a-trous wavelet filter (Dammertz et al. 2010) in the SVGF style
// (Schied et al. 2017) over the accumulated image. The scattered part of the radiance is divided by the
// first-hit reflectance (so textures never blur), filtered with weights that stop at normal, depth and
// colour edges (the colour scale comes from a variance estimate), and multiplied back; radiance that
// reached the camera unscattered (emitters and the environment seen directly) is exact and added back
// unfiltered. docs/ACCURACY.md has the measurements behind each choice.
//
// Passes (one module, one bind group layout, ping-pong buffers `illum_in` -> `illum_out`):
//   prepare:  per pixel: demodulated illumination, the second moment of its luminance, and the guide
//             (normal, inverse depth and its screen-space gradient);
//   variance: the variance of the pixel mean, from the pixel's surface neighbourhood;
//   atrous:   one 5x5 B3-spline iteration with taps `step` pixels apart; the last one remodulates.

struct Params {
    width: u32,
    height: u32,
    // Tap spacing of this a-trous iteration: 1, 2, 4, ...
    step: u32,
    // 1 on the last iteration: write the remodulated radiance into `denoised`.
    last: u32,
    sigma_luminance: f32,
    sigma_normal: f32,
    sigma_depth: f32,
    _pad: u32,
}

// The path tracer's accumulation (read only): radiance sum + sample count, first-hit albedo sum + depth
// sum, first-hit normal sum + hit count, unscattered radiance sum + sum of luminance(scattered)^2.
@group(0) @binding(0) var<storage, read> accum: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> aov_albedo_depth: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> aov_normal: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> moments: array<vec4<f32>>;
// x: octahedral normal (bits), y: inverse camera depth 1/z (< 0: nothing hit), zw: its change per pixel in
// x and y. 1/z, not z, is affine in screen space over a plane, so a tangent plane predicts it exactly.
@group(0) @binding(4) var<storage, read_write> guide: array<vec4<f32>>;
// rgb: demodulated illumination; w: luminance second moment (prepare) or variance of the mean (after).
@group(0) @binding(5) var<storage, read> illum_in: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> illum_out: array<vec4<f32>>;
// The result, in the accumulation's layout (rgb sum, count 1) so the tone mapper reads it unchanged.
@group(0) @binding(7) var<storage, read_write> denoised: array<vec4<f32>>;
@group(0) @binding(8) var<uniform> params: Params;

const DIELECTRIC_F0: f32 = 0.04;
// Darker albedo than this is treated as this: demodulation must not divide by zero, and remodulation uses
// the same value, so a pixel the filter leaves alone comes back exactly.
const ALBEDO_FLOOR: f32 = 1e-3;
// Bound on any filtered value: 25 taps of it still fit an f32, so no sum overflows to infinity.
const VALUE_CAP: f32 = 1e30;
// Below this many samples the per-pixel variance is too unreliable (0 at 1 spp): estimate it spatially.
const MIN_PIXEL_SAMPLES: f32 = 4.0;
const SPATIAL_RADIUS: i32 = 3;

// Non-finite (NaN or infinite) values become `fallback`; finite ones are clamped to [0, VALUE_CAP].
fn sane(v: f32, fallback: f32) -> f32 {
    return select(fallback, min(max(v, 0.0), VALUE_CAP), abs(v) <= 3.0e38);
}
fn sane3(v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(sane(v.x, 0.0), sane(v.y, 0.0), sane(v.z, 0.0));
}

fn oct_wrap(v: vec2<f32>) -> vec2<f32> {
    return (1.0 - abs(v.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), v >= vec2<f32>(0.0));
}
fn encode_normal(n: vec3<f32>) -> u32 {
    let p = n / max(abs(n.x) + abs(n.y) + abs(n.z), 1e-20);
    return pack2x16snorm(select(oct_wrap(p.xy), p.xy, p.z >= 0.0));
}
fn decode_normal(word: u32) -> vec3<f32> {
    let e = unpack2x16snorm(word);
    let z = 1.0 - abs(e.x) - abs(e.y);
    let xy = select(oct_wrap(e), e, z >= 0.0);
    return normalize(vec3<f32>(xy, z));
}

fn index(p: vec2<i32>) -> u32 {
    return u32(p.y) * params.width + u32(p.x);
}
fn inside(p: vec2<i32>) -> bool {
    return p.x >= 0 && p.y >= 0 && p.x < i32(params.width) && p.y < i32(params.height);
}

fn samples_at(i: u32) -> f32 {
    return max(accum[i].w, 1.0);
}

// The reflectance to divide out: the first hit's base colour, plus the share of reflection that base colour
// does not tint (dielectric Fresnel, F0 = 0.04 in glTF). Dividing by base colour alone would make a dark
// texel's illumination look brighter than a light one's (its specular part is not darker), and filtering
// across them would then move energy to the light texels (+5% on a 7:1 checker, measured). Misses count as
// 0, so a partly covered pixel demodulates only its covered share.
fn demodulation_albedo(i: u32) -> vec3<f32> {
    let n = samples_at(i);
    let base = sane3(aov_albedo_depth[i].rgb / n);
    let coverage = min(sane(aov_normal[i].w / n, 0.0), 1.0);
    return max(base * (1.0 - DIELECTRIC_F0) + DIELECTRIC_F0 * coverage, vec3<f32>(ALBEDO_FLOOR));
}

fn unscattered(i: u32) -> vec3<f32> {
    return sane3(moments[i].rgb / samples_at(i));
}

// Inverse of the mean camera depth of the samples that hit, or -1 where none did.
fn inverse_depth(p: vec2<i32>) -> f32 {
    let i = index(p);
    let hits = aov_normal[i].w;
    let z = aov_albedo_depth[i].w / hits;
    if hits <= 0.0 || !(z > 0.0) { return -1.0; }
    return sane(1.0 / z, -1.0);
}

// Inverse-depth change per pixel along `axis`: the one-sided difference of smaller magnitude, so a pixel
// next to a silhouette takes its slope from its own surface.
fn depth_slope(p: vec2<i32>, z: f32, axis: vec2<i32>) -> f32 {
    var slope = 0.0;
    var found = false;
    for (var s = -1; s <= 1; s += 2) {
        let q = p + axis * s;
        if !inside(q) { continue; }
        let zq = inverse_depth(q);
        if zq < 0.0 { continue; }
        let d = (zq - z) * f32(s);
        if !found || abs(d) < abs(slope) { slope = d; found = true; }
    }
    return slope;
}

@compute @workgroup_size(8, 8)
fn prepare(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height { return; }
    let p = vec2<i32>(gid.xy);
    let i = index(p);
    let n = samples_at(i);
    let scattered = max(sane3(accum[i].rgb / n) - unscattered(i), vec3<f32>(0.0));
    let illum = min(scattered / demodulation_albedo(i), vec3<f32>(VALUE_CAP));
    // The moment was gathered on luminance(scattered); rescale it to the illumination's luminance.
    let l_scattered = luminance(scattered);
    let l_illum = luminance(illum);
    let to_illum = select(0.0, l_illum / l_scattered, l_scattered > 0.0);
    let m2 = sane(moments[i].w / n * to_illum * to_illum, VALUE_CAP);
    illum_out[i] = vec4<f32>(illum, m2);

    let z = inverse_depth(p);
    let nh = aov_normal[i];
    var g = vec4<f32>(0.0, -1.0, 0.0, 0.0);
    if z >= 0.0 && dot(nh.xyz, nh.xyz) > 0.0 {
        g = vec4<f32>(bitcast<f32>(encode_normal(nh.xyz)), z,
            depth_slope(p, z, vec2<i32>(1, 0)), depth_slope(p, z, vec2<i32>(0, 1)));
    }
    guide[i] = g;
}

// Depth and normal agreement of pixel q with centre pixel p (1: same surface, 0: different).
fn geometry_weight(gp: vec4<f32>, np: vec3<f32>, gq: vec4<f32>, offset: vec2<f32>) -> f32 {
    if gq.y < 0.0 { return 0.0; }
    let nq = decode_normal(bitcast<u32>(gq.x));
    let w_normal = pow(max(dot(np, nq), 0.0), params.sigma_normal);
    // Distance from the centre's tangent plane (in inverse depth), against the change the plane predicts
    // over that offset: surfaces continue, silhouettes do not.
    let predicted = dot(gp.zw, offset);
    let off_plane = abs(gq.y - (gp.y + predicted));
    let scale = params.sigma_depth * abs(predicted) + 1e-3 * gp.y + 1e-6;
    return w_normal * exp(-off_plane / scale);
}

@compute @workgroup_size(8, 8)
fn variance(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height { return; }
    let p = vec2<i32>(gid.xy);
    let i = index(p);
    let c = illum_in[i];
    let n = samples_at(i);
    var var_mean: f32;
    let gp = guide[i];
    if gp.y < 0.0 {
        // Nothing was hit: no scattered light to filter.
        var_mean = 0.0;
    } else {
        // Estimates from the pixels of the same surface nearby (7x7, normal and depth weights): one
        // pixel's few samples rarely contain the tail of the distribution, and an underestimated variance
        // makes the luminance test reject the bright samples that carry the mean.
        let np = decode_normal(bitcast<u32>(gp.x));
        var sum_w = 0.0;
        var sum_m1 = 0.0;
        var sum_m2 = 0.0;
        var sum_var = 0.0;
        for (var dy = -SPATIAL_RADIUS; dy <= SPATIAL_RADIUS; dy++) {
            for (var dx = -SPATIAL_RADIUS; dx <= SPATIAL_RADIUS; dx++) {
                let q = p + vec2<i32>(dx, dy);
                if !inside(q) { continue; }
                let j = index(q);
                let w = select(geometry_weight(gp, np, guide[j], vec2<f32>(f32(dx), f32(dy))), 1.0, j == i);
                let cq = illum_in[j];
                let lq = luminance(cq.rgb);
                sum_w += w;
                sum_m1 += w * lq;
                sum_m2 += w * cq.w;
                sum_var += w * max(cq.w - lq * lq, 0.0);
            }
        }
        if n >= MIN_PIXEL_SAMPLES {
            // Per-sample variance m2 - m1^2: the mean over the neighbourhood, or the pixel's own where that
            // is larger (a firefly then accepts its neighbours and fades instead of staying a dot); made
            // unbiased (x n / (n - 1)) and divided by n for the variance of the pixel's mean.
            let own = max(c.w - luminance(c.rgb) * luminance(c.rgb), 0.0);
            var_mean = max(sum_var / sum_w, own) / (n - 1.0);
        } else {
            // Too few samples per pixel: the spread of the pixels' values themselves.
            let mean = sum_m1 / sum_w;
            var_mean = max(sum_m2 / sum_w - mean * mean, 0.0) / n;
        }
    }
    illum_out[i] = vec4<f32>(c.rgb, sane(var_mean, VALUE_CAP));
}

// The centre's variance blurred by a 3x3 Gaussian over pixels that hit something: one pixel's estimate is
// itself noisy.
fn blurred_variance(p: vec2<i32>) -> f32 {
    var sum = 0.0;
    var sum_w = 0.0;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let q = p + vec2<i32>(dx, dy);
            if !inside(q) || guide[index(q)].y < 0.0 { continue; }
            let w = select(0.5, 1.0, dx == 0) * select(0.5, 1.0, dy == 0);
            sum += w * illum_in[index(q)].w;
            sum_w += w;
        }
    }
    return select(0.0, sum / sum_w, sum_w > 0.0);
}

// B3-spline taps 1/16, 1/4, 3/8, 1/4, 1/16 at offsets -2..2.
fn b3(d: i32) -> f32 {
    return select(select(0.0625, 0.25, abs(d) == 1), 0.375, d == 0);
}

@compute @workgroup_size(8, 8)
fn atrous(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height { return; }
    let p = vec2<i32>(gid.xy);
    let i = index(p);
    let c = illum_in[i];
    let gp = guide[i];
    var result = c;
    if gp.y >= 0.0 {
        let np = decode_normal(bitcast<u32>(gp.x));
        let lp = luminance(c.rgb);
        // SVGF's test, scaled by the centre's (blurred) variance only. Counting the neighbour's too
        // (var_p + var_q, the variance of the difference) conserves energy around fireflies but spreads
        // them into blotches: measured worse (docs/ACCURACY.md).
        let l_scale = params.sigma_luminance * sqrt(blurred_variance(p)) + 1e-10;
        var sum_w = b3(0) * b3(0);
        var sum_c = sum_w * c.rgb;
        var sum_v = sum_w * sum_w * c.w;
        for (var dy = -2; dy <= 2; dy++) {
            for (var dx = -2; dx <= 2; dx++) {
                if dx == 0 && dy == 0 { continue; }
                let offset = vec2<i32>(dx, dy) * i32(params.step);
                let q = p + offset;
                if !inside(q) { continue; }
                let j = index(q);
                let cq = illum_in[j];
                let w_geometry = geometry_weight(gp, np, guide[j], vec2<f32>(offset));
                // Luminance of the per-channel differences, not the difference of luminances: on a
                // saturated albedo (the red wall) most of the illumination's luminance comes from channels
                // the surface barely reflects, and a hue change of the red light would pass unseen.
                let w_luminance = exp(-luminance(abs(c.rgb - cq.rgb)) / l_scale);
                let w = b3(dx) * b3(dy) * w_geometry * w_luminance;
                sum_w += w;
                sum_c += w * cq.rgb;
                sum_v += w * w * cq.w;
            }
        }
        // Variance of a weighted mean: sum w^2 var / (sum w)^2.
        result = vec4<f32>(sane3(sum_c / sum_w), sane(sum_v / (sum_w * sum_w), VALUE_CAP));
    }
    illum_out[i] = result;
    if params.last == 1u {
        let radiance = result.rgb * demodulation_albedo(i) + unscattered(i);
        denoised[i] = vec4<f32>(sane3(radiance), 1.0);
    }
}

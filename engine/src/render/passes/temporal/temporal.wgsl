// The temporal pass (SVGF's temporal accumulation, Schied et al. 2017): each pixel's history is fetched where
// its surface was last frame (the G-buffer's motion vector), from the bilinear taps around that point that
// saw the same surface (same object and material, the depth the point had then, a similar normal), or failing
// those from the 3x3 pixels around it; the tap weights are renormalised. The history length grows by one per
// frame up to a cap; the temporal gradient (gradient.wgsl) shortens it where lighting changed (A-SVGF's
// lambda), and a disoccluded pixel starts from its own sample. The new sample is blended in with weight
// 1 / length: a plain mean until the cap, then an exponential moving average.
//
// The history is written in the accumulation's layout (sums over `length` samples), so the spatial filter
// (passes/denoise) reads it as it reads an accumulation: mean radiance, unscattered radiance, first-hit
// reflectance and coverage, and the second moment of scattered luminance (its temporal variance). A sample
// that is not finite never enters: the pixel keeps its history for that frame.

@group(1) @binding(2) var<storage, read> gbuffer: array<GSurface>;
@group(1) @binding(3) var<storage, read> gbuffer_prev: array<GSurface>;
@group(1) @binding(4) var<storage, read> samples: array<RealtimeSample>;
// Filtered gradients per stratum of the previous frame (a 16-byte stub while gradients are off).
@group(1) @binding(5) var<storage, read> gradients: array<vec4<f32>>;
// Materials edited since last frame: bit m of word m / 32 (pixels showing them start afresh).
@group(1) @binding(6) var<storage, read> edited_materials: array<u32>;
// Last frame's history and this frame's, in the accumulation's layout.
@group(1) @binding(7) var<storage, read> prev_accum: array<vec4<f32>>;
@group(1) @binding(8) var<storage, read> prev_albedo_depth: array<vec4<f32>>;
@group(1) @binding(9) var<storage, read> prev_normal_hits: array<vec4<f32>>;
@group(1) @binding(10) var<storage, read> prev_moments: array<vec4<f32>>;
@group(1) @binding(11) var<storage, read_write> accum: array<vec4<f32>>;
@group(1) @binding(12) var<storage, read_write> albedo_depth: array<vec4<f32>>;
@group(1) @binding(13) var<storage, read_write> normal_hits: array<vec4<f32>>;
@group(1) @binding(14) var<storage, read_write> moments: array<vec4<f32>>;

const VALUE_CAP: f32 = 1e30;

// Means over a pixel's history.
struct History {
    radiance: vec3<f32>,
    unscattered: vec3<f32>,
    albedo: vec3<f32>,
    coverage: f32,
    // Mean of luminance(scattered)^2.
    m2: f32,
    length: f32,
}

fn no_history() -> History {
    return History(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), 0.0, 0.0, 0.0);
}

fn finite_history(h: History) -> bool {
    return finite3(h.radiance) && finite3(h.unscattered) && finite3(h.albedo) && is_finite(h.coverage)
        && is_finite(h.m2) && is_finite(h.length);
}

fn read_history(i: u32) -> History {
    let a = prev_accum[i];
    let n = a.w;
    if !(n > 0.0) || !is_finite(n) { return no_history(); }
    let m = prev_moments[i];
    let h = History(a.rgb / n, m.rgb / n, prev_albedo_depth[i].rgb / n, prev_normal_hits[i].w / n, m.w / n, n);
    if !finite_history(h) { return no_history(); }
    return h;
}

fn add_history(sum: ptr<function, History>, h: History, w: f32) {
    (*sum).radiance += w * h.radiance;
    (*sum).unscattered += w * h.unscattered;
    (*sum).albedo += w * h.albedo;
    (*sum).coverage += w * h.coverage;
    (*sum).m2 += w * h.m2;
    (*sum).length += w * h.length;
}

fn scale_history(h: History, s: f32) -> History {
    return History(h.radiance * s, h.unscattered * s, h.albedo * s, h.coverage * s, h.m2 * s, h.length * s);
}

fn material_edited(m: u32) -> bool {
    if m == NONE || !realtime_flag(RT_MATERIALS_EDITED) { return false; }
    let word = m / 32u;
    return word < arrayLength(&edited_materials) && (edited_materials[word] & (1u << (m % 32u))) != 0u;
}

// Tap `q` of the previous frame saw the surface this pixel sees now.
fn same_surface(g: GSurface, q: GSurface) -> bool {
    if !gsurface_hit(g) || !gsurface_hit(q) { return gsurface_hit(g) == gsurface_hit(q); }
    if g.object != q.object || g.material != q.material || g.prev_depth <= 0.0 { return false; }
    let ng = oct_decode(g.geometric);
    if dot(ng, oct_decode(q.geometric)) < realtime.normal_tolerance { return false; }
    // The depth a neighbouring pixel of the same plane may differ by grows with obliquity: a pixel's
    // footprint over the cosine to the view direction.
    let view = normalize(realtime.prev_camera_origin - g.position);
    let cos_view = max(abs(dot(ng, view)), 0.05);
    let footprint = g.prev_depth * 2.0 * realtime.prev_tan_half_fov / f32(frame.height);
    let tolerance = realtime.depth_tolerance * g.prev_depth + 2.0 * footprint * sqrt(1.0 - cos_view * cos_view) / cos_view;
    return abs(q.depth - g.prev_depth) <= tolerance;
}

fn inside(p: vec2<i32>) -> bool {
    return p.x >= 0 && p.y >= 0 && p.x < i32(frame.width) && p.y < i32(frame.height);
}

fn index_of(p: vec2<i32>) -> u32 {
    return u32(p.y) * frame.width + u32(p.x);
}

// The history at continuous position `at` of the previous frame, from taps that saw this surface.
fn reproject(g: GSurface, at: vec2<f32>) -> History {
    let base = at - 0.5;
    let i0 = vec2<i32>(floor(base));
    let f = base - floor(base);
    var sum = no_history();
    var sum_w = 0.0;
    for (var k = 0; k < 4; k++) {
        let o = vec2<i32>(k & 1, k >> 1u);
        let q = i0 + o;
        if !inside(q) { continue; }
        let j = index_of(q);
        if !same_surface(g, gbuffer_prev[j]) { continue; }
        let h = read_history(j);
        if h.length <= 0.0 { continue; }
        let w = select(1.0 - f.x, f.x, o.x == 1) * select(1.0 - f.y, f.y, o.y == 1);
        add_history(&sum, h, w);
        sum_w += w;
    }
    if sum_w > 1e-3 { return scale_history(sum, 1.0 / sum_w); }
    // Thin geometry and silhouettes: any of the 3x3 pixels around the point that saw this surface.
    sum = no_history();
    sum_w = 0.0;
    let centre = vec2<i32>(floor(at));
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let q = centre + vec2<i32>(dx, dy);
            if !inside(q) { continue; }
            let j = index_of(q);
            if !same_surface(g, gbuffer_prev[j]) { continue; }
            let h = read_history(j);
            if h.length <= 0.0 { continue; }
            add_history(&sum, h, 1.0);
            sum_w += 1.0;
        }
    }
    if sum_w > 0.0 { return scale_history(sum, 1.0 / sum_w); }
    return no_history();
}

// How much of the history the temporal gradient says is stale (0: none, 1: all), looked up in the previous
// frame's strata at `at`.
fn staleness(at: vec2<f32>) -> f32 {
    let s = at / f32(GRADIENT_STRATUM) - 0.5;
    let i0 = vec2<i32>(floor(s));
    let f = s - floor(s);
    var delta = 0.0;
    var scale = 0.0;
    var sum_w = 0.0;
    for (var k = 0; k < 4; k++) {
        let o = vec2<i32>(k & 1, k >> 1u);
        let q = clamp(i0 + o, vec2<i32>(0), vec2<i32>(i32(realtime.strata_width) - 1, i32(realtime.strata_height) - 1));
        let v = gradients[u32(q.y) * realtime.strata_width + u32(q.x)];
        let w = select(1.0 - f.x, f.x, o.x == 1) * select(1.0 - f.y, f.y, o.y == 1) * v.z;
        delta += w * v.x;
        scale += w * v.y;
        sum_w += w;
    }
    if sum_w <= 0.0 || scale <= 0.0 { return 0.0; }
    let lambda = abs(delta) / scale;
    return select(0.0, clamp(lambda, 0.0, 1.0), is_finite(lambda));
}

fn sane(v: f32) -> f32 {
    return select(0.0, min(max(v, 0.0), VALUE_CAP), is_finite(v));
}

fn sane3(v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(sane(v.x), sane(v.y), sane(v.z));
}

@compute @workgroup_size(8, 8)
fn accumulate(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height { return; }
    let i = gid.y * frame.width + gid.x;
    let g = gbuffer[i];
    let sample = samples[i];
    var h = no_history();
    let at = vec2<f32>(gid.xy) + 0.5 + g.motion;
    if realtime_flag(RT_TEMPORAL) && realtime_flag(RT_HISTORY) && !material_edited(g.material) {
        h = reproject(g, at);
        if realtime_flag(RT_GRADIENTS) && h.length > 0.0 {
            h.length *= 1.0 - staleness(at);
        }
    }
    var length = h.length;
    if sample.valid != 0u {
        length = min(h.length + 1.0, max(realtime.history_cap, 1.0));
        let alpha = 1.0 / length;
        let hit = gsurface_hit(g);
        let albedo = select(vec3<f32>(0.0), unpack_bsdf(g.bsdf).base_color, hit);
        // Capped so that a firefly's square cannot overflow (as the trace pass's moments).
        let l = min(max(luminance(sample.radiance - sample.unscattered), 0.0), 1e15);
        h.radiance = mix(h.radiance, sample.radiance, alpha);
        h.unscattered = mix(h.unscattered, sample.unscattered, alpha);
        h.albedo = mix(h.albedo, albedo, alpha);
        h.coverage = mix(h.coverage, select(0.0, 1.0, hit), alpha);
        h.m2 = mix(h.m2, l * l, alpha);
    }
    // A history shortened below one sample by a gradient, with no new sample, still counts as one.
    let n = select(0.0, max(sane(length), 1.0), length > 0.0 && is_finite(length));
    let hits = sane(h.coverage * n);
    let decoded = oct_decode(g.normal);
    let normal = select(vec3<f32>(0.0), decoded, gsurface_hit(g) && finite3(decoded));
    accum[i] = vec4<f32>(sane3(h.radiance * n), n);
    albedo_depth[i] = vec4<f32>(sane3(h.albedo * n), sane(max(g.depth, 0.0) * hits));
    normal_hits[i] = vec4<f32>(normal * hits, hits);
    moments[i] = vec4<f32>(sane3(h.unscattered * n), sane(h.m2 * n));
}

// Temporal gradients (A-SVGF, Schied et al. 2018), backward variant: for each gradient stratum of the previous
// frame, the surface point its chosen pixel saw is found again in this frame (same object, triangle and
// barycentrics, wherever they moved) and shaded again with that pixel's random numbers from last frame. Where
// nothing about the lighting changed the two estimates agree (exactly, on diffuse surfaces); the difference,
// relative to the larger, says how much of the history is stale. The sparse gradients are then filtered across
// strata (a-trous, stopped at depth and normal edges of the sources), and the temporal pass looks them up
// where each pixel's history comes from. Unlike A-SVGF's forward projection, no sample of the current frame is
// moved: the re-shading is an extra path at one pixel in nine.
//   shade:  per stratum: (luminance difference, larger luminance, 1) or zeros where there is no gradient;
//   filter: one 3x3 a-trous iteration, taps `step` strata apart.

struct FilterStep {
    step: u32,
    _p0: u32,
    _p1: u32,
    _p2: u32,
}

@group(1) @binding(2) var<storage, read> gbuffer_prev: array<GSurface>;
@group(1) @binding(3) var<storage, read> gradient_estimates: array<f32>;
@group(1) @binding(4) var<storage, read> gradients_in: array<vec4<f32>>;
@group(1) @binding(5) var<storage, read_write> gradients_out: array<vec4<f32>>;
@group(1) @binding(6) var<storage, read_write> ray_counter: array<atomic<u32>>;
@group(3) @binding(0) var<uniform> filter_step: FilterStep;

var<workgroup> workgroup_rays: atomic<u32>;

fn stratum_index(s: vec2<u32>) -> u32 {
    return s.y * realtime.strata_width + s.x;
}

fn in_strata(s: vec2<u32>) -> bool {
    return s.x < realtime.strata_width && s.y < realtime.strata_height;
}

// The previous frame's G-buffer at stratum `s`'s chosen pixel.
fn source_surface(s: vec2<u32>) -> GSurface {
    let p = gradient_source(s, frame.sample_base - 1u);
    return gbuffer_prev[p.y * frame.width + p.x];
}

@compute @workgroup_size(8, 8)
fn shade_gradients(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    rays_traced = 0u;
    if in_strata(gid.xy) {
        gradients_out[stratum_index(gid.xy)] = gradient_at(gid.xy);
    }
    atomicAdd(&workgroup_rays, rays_traced);
    workgroupBarrier();
    if lid == 0u {
        atomicAdd(&ray_counter[0], atomicLoad(&workgroup_rays));
    }
}

fn gradient_at(s: vec2<u32>) -> vec4<f32> {
    let before = gradient_estimates[stratum_index(s)];
    let previous = frame.sample_base - 1u;
    let source = gradient_source(s, previous);
    let g = gbuffer_prev[source.y * frame.width + source.x];
    if before < 0.0 || !gsurface_hit(g) { return vec4<f32>(0.0); }
    let instance = instance_of_object(g.object);
    if instance == NONE {
        // The object is gone: whatever lit it then, all of it changed.
        return vec4<f32>(-before, before, 1.0, 0.0);
    }
    let corners = world_triangle(instance, g.triangle);
    let p = corners[0] * (1.0 - g.bary.x - g.bary.y) + corners[1] * g.bary.x + corners[2] * g.bary.y;
    let origin = camera_origin();
    let to_p = p - origin;
    let t = length(to_p);
    if !(t > 0.0) { return vec4<f32>(0.0); }
    let ray = Ray(origin, to_p / t);
    let sampler = sampler_start(source.y * frame.width + source.x, previous, frame.seed);
    let now = luminance(gradient_estimate(ray, Hit(t, instance, g.triangle, g.bary), sampler,
        realtime_flag(RT_RESTIR)));
    if !is_finite(now) { return vec4<f32>(0.0); }
    return vec4<f32>(now - before, max(now, before), 1.0, 0.0);
}

// 1, 2, 1 over 4 each way.
fn tent(d: i32) -> f32 {
    return select(0.25, 0.5, d == 0);
}

@compute @workgroup_size(8, 8)
fn filter_gradients(@builtin(global_invocation_id) gid: vec3<u32>) {
    if !in_strata(gid.xy) { return; }
    let centre = source_surface(gid.xy);
    let nc = oct_decode(centre.geometric);
    var sum = vec2<f32>(0.0);
    var sum_w = 0.0;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let q = vec2<i32>(gid.xy) + vec2<i32>(dx, dy) * i32(filter_step.step);
            if any(q < vec2<i32>(0)) || !in_strata(vec2<u32>(q)) { continue; }
            let v = gradients_in[stratum_index(vec2<u32>(q))];
            if v.z <= 0.0 { continue; }
            var w = tent(dx) * tent(dy) * v.z;
            // Across a silhouette or a crease, lighting changes independently: stop there.
            if gsurface_hit(centre) && (dx != 0 || dy != 0) {
                let gq = source_surface(vec2<u32>(q));
                let same = gsurface_hit(gq) && abs(gq.depth - centre.depth) <= 0.1 * centre.depth
                    && dot(oct_decode(gq.geometric), nc) >= 0.8;
                w *= select(0.0, 1.0, same);
            }
            sum += w * v.xy;
            sum_w += w;
        }
    }
    gradients_out[stratum_index(gid.xy)] = select(vec4<f32>(0.0), vec4<f32>(sum / sum_w, min(sum_w, 1.0), 0.0),
        sum_w > 0.0);
}

// ReSTIR DI (Bitterli et al. 2020) in two dispatches over the G-buffer, for light-sampler lights (target.wgsl):
//   candidates: RIS over `restir_candidates` light samples with the unshadowed target, a shadow ray for the
//               kept one (visibility reuse: an occluded sample keeps its confidence but no weight), then
//               temporal reuse of last frame's reservoir where the motion vector lands on the same surface;
//   spatial:    reuse of `restir_neighbours` reservoirs from a disc around the pixel on similar surfaces, then
//               the pixel's direct light = contribution x W, and the reservoir kept for the next frame.
// Reuse combines reservoirs by generalised RIS with pairwise MIS and confidence weights (Lin et al. 2022;
// Wyman et al., "A gentle introduction to ReSTIR", 2023). With RT_RESTIR_UNBIASED the target functions in the
// MIS weights include visibility (a shadow ray per evaluation): every pixel's candidates are then exactly the
// samples visible from it, and the weights sum to one over the techniques that can produce a sample, so the
// estimate is unbiased on a static scene. Without it, the weights use the unshadowed target and the estimate
// darkens slightly near shadow edges (docs/ACCURACY.md measures both).

@group(1) @binding(2) var<storage, read> gbuffer: array<GSurface>;
@group(1) @binding(3) var<storage, read> gbuffer_prev: array<GSurface>;
// Last frame's final reservoirs (read by `candidates`); this frame's final ones (written by `spatial`).
@group(1) @binding(4) var<storage, read_write> reservoirs: array<vec4<u32>>;
// After candidates + temporal reuse.
@group(1) @binding(5) var<storage, read_write> reservoirs_temporal: array<vec4<u32>>;
// Direct light at each pixel's first hit (rgb).
@group(1) @binding(6) var<storage, read_write> direct_light: array<vec4<f32>>;
@group(1) @binding(7) var<storage, read_write> ray_counter: array<atomic<u32>>;

const MAX_NEIGHBOURS: u32 = 8u;
// Offsets within the ReSTIR dimension block (integrator/realtime.wgsl DIM_RESTIR).
const DIM_CANDIDATE_PICK: u32 = 0x100000u; // one per candidate
const DIM_TEMPORAL_PICK: u32 = 0x200000u;
const DIM_NEIGHBOUR: u32 = 0x300000u; // 2D per neighbour
const DIM_SPATIAL_PICK: u32 = 0x400000u; // one per neighbour + 1

var<workgroup> workgroup_rays: atomic<u32>;

fn pixel_index(p: vec2<u32>) -> u32 {
    return p.y * frame.width + p.x;
}

fn count_rays(lid: u32) {
    atomicAdd(&workgroup_rays, rays_traced);
    workgroupBarrier();
    if lid == 0u {
        atomicAdd(&ray_counter[0], atomicLoad(&workgroup_rays));
    }
}

// Target function of sample (light, u) at `sp`, with its visibility when `with_visibility` (one ray).
fn target_at(sp: ShadingPoint, light: u32, u: vec2<f32>, with_visibility: bool) -> f32 {
    if light == NONE { return 0.0; }
    let e = evaluate_light_sample(sp, light, u);
    let t = target_function(e);
    if t > 0.0 && with_visibility && !light_visible(e) { return 0.0; }
    return t;
}

// The two surfaces agree enough to share light samples (RTXDI's test: 10% depth, 25 degrees).
fn similar_surfaces(a: GSurface, b: GSurface) -> bool {
    if !gsurface_hit(a) || !gsurface_hit(b) { return false; }
    let na = oct_decode(a.normal);
    let nb = oct_decode(b.normal);
    return dot(na, nb) >= 0.906 && abs(a.depth - b.depth) <= 0.1 * a.depth;
}

@compute @workgroup_size(8, 8)
fn candidates(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    rays_traced = 0u;
    if gid.x < frame.width && gid.y < frame.height {
        let pixel = pixel_index(gid.xy);
        reservoirs_temporal[pixel] = pack_reservoir(candidates_at(gid.xy, pixel));
    }
    count_rays(lid);
}

fn candidates_at(gid: vec2<u32>, pixel: u32) -> Reservoir {
    let g = gbuffer[pixel];
    if !gsurface_hit(g) || light_count() == 0u { return empty_reservoir(); }
    let sampler = sampler_start(pixel, frame.sample_base, frame.seed);
    let sp = gsurface_shading_point(g, camera_origin());
    let unbiased = realtime_flag(RT_RESTIR_UNBIASED);

    // Resampled importance sampling of the light sampler's samples towards the unshadowed target.
    var ris = empty_resampler();
    let count = max(realtime.restir_candidates, 1u);
    for (var i = 0u; i < count; i++) {
        let choice = light_sampler_sample(get_1d(sampler, DIM_RESTIR + 3u * i));
        let u = quantise_u(get_2d(sampler, DIM_RESTIR + 3u * i + 1u));
        if choice.pmf <= 0.0 { continue; }
        let e = evaluate_light_sample(sp, choice.light, u);
        let t = target_function(e);
        resampler_offer(&ris, choice.light, u, t / (choice.pmf * f32(count)), t, e.value, false,
            get_1d(sampler, DIM_RESTIR + DIM_CANDIDATE_PICK + i));
    }
    var canonical = resampler_finish(ris, 1.0);
    // Visibility reuse: what is occluded here is not worth sharing. With unbiased MIS the canonical
    // technique must produce exactly the visible samples, so the test is not optional then.
    if canonical.light != NONE && (unbiased || realtime_flag(RT_RESTIR_VISIBILITY)) {
        let e = evaluate_light_sample(sp, canonical.light, canonical.u);
        if !light_visible(e) { canonical.w = 0.0; }
    }
    if !realtime_flag(RT_RESTIR_TEMPORAL) || !realtime_flag(RT_RESTIR_HISTORY) { return canonical; }

    // Temporal reuse: last frame's reservoir where this surface was.
    let before = vec2<f32>(gid) + 0.5 + g.motion;
    if any(before < vec2<f32>(0.0)) || any(before >= vec2<f32>(f32(frame.width), f32(frame.height))) {
        return canonical;
    }
    let q = pixel_index(vec2<u32>(before));
    let gq = gbuffer_prev[q];
    if !temporal_match(g, gq) { return canonical; }
    var previous = unpack_reservoir(reservoirs[q]);
    previous.light = current_light(previous.light);
    if previous.light == NONE { return canonical; }
    previous.m = min(previous.m, realtime.restir_max_confidence * canonical.m);
    let sq = gsurface_shading_point(gq, realtime.prev_camera_origin);
    return combine_pair(sp, canonical, previous, sq, unbiased, get_1d(sampler, DIM_RESTIR + DIM_TEMPORAL_PICK));
}

// The previous frame's surface under the motion vector is this one (same object, depth where it should be).
fn temporal_match(g: GSurface, gq: GSurface) -> bool {
    if !gsurface_hit(gq) || gq.object != g.object || g.prev_depth <= 0.0 { return false; }
    return abs(gq.depth - g.prev_depth) <= 0.1 * g.prev_depth
        && dot(oct_decode(g.geometric), oct_decode(gq.geometric)) >= 0.906;
}

// Generalised RIS over the canonical reservoir `c` (at `sp`) and one other, `n`, whose surface is `sn`:
// balance-heuristic MIS weights with confidences (the pairwise weights for one neighbour).
fn combine_pair(sp: ShadingPoint, c: Reservoir, n: Reservoir, sn: ShadingPoint, unbiased: bool, xi: f32) -> Reservoir {
    // Target functions of both samples at both surfaces. The canonical sample is visible here (or has no
    // weight). The other was visible at its own surface when it was kept, but in last frame's scene: once
    // something moved, its visibility there may differ in this frame's scene, where `tn_c` is tested. With
    // unbiased MIS both samples' targets at `sn` must be the same function, or the two weights of a sample
    // no longer sum to one and W drifts from frame to frame; so `tn_n` is tested as well (one more ray).
    let tc_c = target_at(sp, c.light, c.u, false);
    let tn_c = target_at(sn, c.light, c.u, unbiased);
    let tc_n = target_at(sp, n.light, n.u, unbiased);
    let tn_n = target_at(sn, n.light, n.u, unbiased);
    let mc = c.m * tc_c / max(c.m * tc_c + n.m * tn_c, 1e-30);
    let mn = n.m * tn_n / max(c.m * tc_n + n.m * tn_n, 1e-30);
    var s = empty_resampler();
    resampler_offer(&s, c.light, c.u, mc * tc_c * c.w, tc_c, vec3<f32>(0.0), true, 0.0);
    resampler_offer(&s, n.light, n.u, mn * tc_n * n.w, tc_n, vec3<f32>(0.0), unbiased, xi);
    return resampler_finish(s, c.m + n.m);
}

@compute @workgroup_size(8, 8)
fn spatial(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    rays_traced = 0u;
    if gid.x < frame.width && gid.y < frame.height {
        spatial_at(gid.xy, pixel_index(gid.xy));
    }
    count_rays(lid);
}

fn spatial_at(gid: vec2<u32>, pixel: u32) {
    let g = gbuffer[pixel];
    let c = unpack_reservoir(reservoirs_temporal[pixel]);
    if !gsurface_hit(g) || light_count() == 0u {
        reservoirs[pixel] = pack_reservoir(empty_reservoir());
        direct_light[pixel] = vec4<f32>(0.0);
        return;
    }
    let sampler = sampler_start(pixel, frame.sample_base, frame.seed);
    let sp = gsurface_shading_point(g, camera_origin());
    let unbiased = realtime_flag(RT_RESTIR_UNBIASED);

    // The neighbours on similar surfaces within the disc.
    var neighbours: array<u32, MAX_NEIGHBOURS>;
    var k = 0u;
    var m_sum = 0.0;
    if realtime_flag(RT_RESTIR_SPATIAL) {
        let wanted = min(realtime.restir_neighbours, MAX_NEIGHBOURS);
        for (var i = 0u; i < wanted; i++) {
            let u = get_2d(sampler, DIM_RESTIR + DIM_NEIGHBOUR + 2u * i);
            let r = realtime.restir_radius * sqrt(u.x);
            let phi = 2.0 * PI * u.y;
            let q = vec2<i32>(vec2<f32>(gid) + 0.5 + r * vec2<f32>(cos(phi), sin(phi)));
            if any(q < vec2<i32>(0)) || q.x >= i32(frame.width) || q.y >= i32(frame.height) { continue; }
            let j = pixel_index(vec2<u32>(q));
            if j == pixel || !similar_surfaces(g, gbuffer[j]) { continue; }
            let rj = unpack_reservoir(reservoirs_temporal[j]);
            if rj.m <= 0.0 { continue; }
            neighbours[k] = j;
            m_sum += rj.m;
            k++;
        }
    }

    // Pairwise MIS (Bitterli 2022, with confidences): pair j of the canonical technique (confidence c.m / k)
    // and neighbour j weighs in by its share of the total confidence; within a pair, the balance heuristic.
    var s = empty_resampler();
    let ec = evaluate_light_sample(sp, c.light, c.u);
    let tc_c = select(0.0, target_function(ec), c.light != NONE);
    var m_canonical = select(0.0, 1.0, k == 0u);
    let total = c.m + m_sum;
    let mc_share = c.m / max(f32(k), 1.0);
    for (var i = 0u; i < k; i++) {
        let j = neighbours[i];
        let gj = gbuffer[j];
        let rj = unpack_reservoir(reservoirs_temporal[j]);
        let sj = gsurface_shading_point(gj, camera_origin());
        let share = (mc_share + rj.m) / max(total, 1e-30);
        let tj_c = target_at(sj, c.light, c.u, unbiased);
        m_canonical += share * mc_share * tc_c / max(mc_share * tc_c + rj.m * tj_c, 1e-30);
        let tj_j = target_at(sj, rj.light, rj.u, false);
        let e = evaluate_light_sample(sp, rj.light, rj.u);
        var tc_j = target_function(e);
        if tc_j > 0.0 && unbiased && !light_visible(e) { tc_j = 0.0; }
        let mj = share * rj.m * tj_j / max(rj.m * tj_j + mc_share * tc_j, 1e-30);
        resampler_offer(&s, rj.light, rj.u, mj * tc_j * rj.w, tc_j, e.value, unbiased,
            get_1d(sampler, DIM_RESTIR + DIM_SPATIAL_PICK + i));
    }
    // The canonical sample is visible here or has no weight, when candidates were tested (unbiased MIS).
    resampler_offer(&s, c.light, c.u, m_canonical * tc_c * c.w, tc_c, ec.value, unbiased,
        get_1d(sampler, DIM_RESTIR + DIM_SPATIAL_PICK + MAX_NEIGHBOURS));
    var out = resampler_finish(s, min(total, realtime.restir_max_confidence));

    // Shade: contribution x W, with a shadow ray unless the kept sample is known to be visible.
    var direct = vec3<f32>(0.0);
    if out.light != NONE && out.w > 0.0 {
        var visible = s.visible;
        if !visible {
            let e = evaluate_light_sample(sp, out.light, out.u);
            visible = light_visible(e);
        }
        if visible {
            direct = s.contribution * out.w;
        } else {
            // Kept for its confidence, but what is occluded here is not shared next frame.
            out.w = 0.0;
        }
    }
    if !finite3(direct) {
        direct = vec3<f32>(0.0);
        out = empty_reservoir();
    }
    reservoirs[pixel] = pack_reservoir(out);
    direct_light[pixel] = vec4<f32>(direct, 1.0);
}

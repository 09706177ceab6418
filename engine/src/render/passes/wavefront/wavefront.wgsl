// The wavefront path tracer (Laine, Karras and Aila 2013, "Megakernels Considered Harmful"; Novak et al. 2010):
// the path loop of integrator/path.wgsl cut at its traversals into kernels over a queue of the paths still alive,
// so that a warp runs only paths at the same stage and deep bounces cost what their live paths cost, not what a
// warp's longest path costs. One path per pixel per wave (a wave = one sample of every pixel); its state lives in
// the arrays below, indexed by pixel, between the kernels. Per wave:
//   begin_wave, generate (camera rays, queued by 8x8 tiles so that a warp's camera rays are coherent), then per
//   bounce: extend (trace the queue's rays, passing through alpha-blended surfaces, and the shadow rays of the
//   bounce before), shade (emission, next-event estimation's shadow ray, BSDF sampling, Russian roulette: the
//   queue of the next bounce), advance (the next bounce's counts and dispatch sizes); a last extend for the last
//   shadow rays; finish (add each path's radiance to the accumulation). Dispatches that depend on the one before
//   each cost a pipeline drain, hence shadow rays traced with the next bounce's rays rather than on their own.
// Every decision draws the same sampler dimension as the megakernel's, so a path is the same path and the
// radiance the same sum in the same order (tests/engine/wavefront.rs). What the megakernel records only for the
// denoisers (first-hit AOVs, moments) and the real-time integrator's start are not here: the trace pass runs the
// megakernel where they are needed.

// The view's accumulation: rgb radiance sums, w samples.
@group(1) @binding(1) var<storage, read_write> accum: array<vec4<f32>>;
// Path state, one entry per pixel. The ray to trace: origin and `depth | pass_throughs << 16` (bits).
@group(1) @binding(2) var<storage, read_write> path_origin: array<vec4<f32>>;
// The ray's direction and the density with which the BSDF sampled it (0: a camera ray).
@group(1) @binding(3) var<storage, read_write> path_dir: array<vec4<f32>>;
// Throughput and the medium the ray travels in (bits; NONE in the open).
@group(1) @binding(4) var<storage, read_write> path_throughput: array<vec4<f32>>;
// Where the path last scattered (next-event estimation's point); w: the hit's second barycentric (extend -> shade).
@group(1) @binding(5) var<storage, read_write> path_vertex: array<vec4<f32>>;
// The geometric normal there.
@group(1) @binding(6) var<storage, read_write> path_normal: array<vec4<f32>>;
// The sample's radiance so far.
@group(1) @binding(7) var<storage, read_write> path_radiance: array<vec4<f32>>;
// What extend found: t (bits), instance (NONE: nothing), triangle slot, first barycentric (bits).
@group(1) @binding(8) var<storage, read_write> path_hit: array<vec4<u32>>;
// Two queues of path indices, [0, N) and [N, 2N): one read this bounce, the other filled for the next.
@group(1) @binding(9) var<storage, read_write> queues: array<u32>;
// Shadow rays in the order shade appended them: origin and t_max; direction and the path (bits); what the light
// adds when nothing blocks it.
@group(1) @binding(10) var<storage, read_write> shadow_origin: array<vec4<f32>>;
@group(1) @binding(11) var<storage, read_write> shadow_dir: array<vec4<f32>>;
@group(1) @binding(12) var<storage, read_write> shadow_light: array<vec4<f32>>;
// Counters (CONTROL_*), zeroed before the pass.
@group(1) @binding(13) var<storage, read_write> control: array<atomic<u32>, 16>;
// Indirect dispatch sizes, written by begin_wave and advance only (a buffer read as dispatch arguments cannot be
// bound to the kernels it sizes): [0..3) extend (live paths and shadow rays), [3..6) shade (live paths).
@group(2) @binding(0) var<storage, read_write> dispatch_args: array<u32, 8>;

// The queue read this bounce holds CONTROL_LIVE paths, from CONTROL_PARITY x N on.
const CONTROL_LIVE: u32 = 0u;
// Paths shade appended to the next bounce's queue.
const CONTROL_NEXT: u32 = 1u;
// Shadow rays shade appended this bounce, and those the shadow kernel traces.
const CONTROL_SHADOWS_APPENDED: u32 = 2u;
const CONTROL_SHADOWS: u32 = 3u;
const CONTROL_PARITY: u32 = 4u;
// This wave's sample, counted from frame.sample_base; and the next wave's.
const CONTROL_WAVE: u32 = 5u;
const CONTROL_NEXT_WAVE: u32 = 6u;
// Rays traced (camera, bounce and shadow), copied to the view's ray counter after the pass.
const CONTROL_RAYS: u32 = 7u;
// Camera rays queued by generate.
const CONTROL_GENERATED: u32 = 8u;

// Alpha-blended surfaces (stochastic coverage) are passed through in extend, so that a pass-through does not
// take a bounce of the wave; compiled in only for scenes with such materials.
override WAVE_PASS_THROUGHS: bool = true;

// Queue kernels run 128 paths a workgroup over a 2D grid of workgroups (65535 per side at most).
const QUEUE_GROUP: u32 = 128u;
const MAX_GROUPS_X: u32 = 32768u;

fn path_count() -> u32 {
    return frame.width * frame.height;
}

fn queue_index(group: vec3<u32>, groups: vec3<u32>, lid: u32) -> u32 {
    return (group.y * groups.x + group.x) * QUEUE_GROUP + lid;
}

var<workgroup> workgroup_rays: atomic<u32>;

// One global atomic per workgroup for the ray count.
fn count_rays(lid: u32) {
    atomicAdd(&workgroup_rays, rays_traced);
    workgroupBarrier();
    if lid == 0u {
        atomicAdd(&control[CONTROL_RAYS], atomicLoad(&workgroup_rays));
    }
}

fn write_dispatch(first: u32, items: u32) {
    let groups = (items + QUEUE_GROUP - 1u) / QUEUE_GROUP;
    let x = min(groups, MAX_GROUPS_X);
    dispatch_args[first] = x;
    dispatch_args[first + 1u] = select(0u, (groups + x - 1u) / max(x, 1u), groups > 0u);
    dispatch_args[first + 2u] = 1u;
}

@compute @workgroup_size(1)
fn begin_wave() {
    let wave = atomicLoad(&control[CONTROL_NEXT_WAVE]);
    atomicStore(&control[CONTROL_WAVE], wave);
    atomicStore(&control[CONTROL_NEXT_WAVE], wave + 1u);
    atomicStore(&control[CONTROL_LIVE], path_count());
    atomicStore(&control[CONTROL_NEXT], 0u);
    atomicStore(&control[CONTROL_GENERATED], 0u);
    atomicStore(&control[CONTROL_SHADOWS_APPENDED], 0u);
    atomicStore(&control[CONTROL_SHADOWS], 0u);
    atomicStore(&control[CONTROL_PARITY], 0u);
    write_dispatch(0u, path_count());
    write_dispatch(3u, path_count());
}

// After shade: the queue it filled becomes the one read, and its shadow rays are the ones to trace.
@compute @workgroup_size(1)
fn advance() {
    let live = atomicExchange(&control[CONTROL_NEXT], 0u);
    let shadows = atomicExchange(&control[CONTROL_SHADOWS_APPENDED], 0u);
    atomicStore(&control[CONTROL_LIVE], live);
    atomicStore(&control[CONTROL_SHADOWS], shadows);
    atomicStore(&control[CONTROL_PARITY], 1u - atomicLoad(&control[CONTROL_PARITY]));
    write_dispatch(0u, live + shadows);
    write_dispatch(3u, live);
}

fn wave_sampler(pixel: u32) -> Sampler {
    return sampler_start(pixel, frame.sample_base + atomicLoad(&control[CONTROL_WAVE]), frame.seed);
}

var<workgroup> workgroup_first: u32;

// Camera rays: every pixel's path starts. The first queue holds each 8x8 tile's pixels together.
@compute @workgroup_size(8, 8)
fn generate(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(workgroup_id) tile: vec3<u32>,
            @builtin(local_invocation_id) local: vec3<u32>) {
    let tile_size = min(vec2<u32>(8u), vec2<u32>(frame.width, frame.height) - tile.xy * 8u);
    if all(local.xy == vec2<u32>(0u)) {
        workgroup_first = atomicAdd(&control[CONTROL_GENERATED], tile_size.x * tile_size.y);
    }
    workgroupBarrier();
    if gid.x >= frame.width || gid.y >= frame.height { return; }
    let pixel = gid.y * frame.width + gid.x;
    let sample = camera_sample(gid.xy, pixel, frame.sample_base + atomicLoad(&control[CONTROL_WAVE]));
    path_origin[pixel] = vec4<f32>(sample.ray.origin, bitcast<f32>(0u));
    path_dir[pixel] = vec4<f32>(sample.ray.dir, 0.0);
    path_throughput[pixel] = vec4<f32>(1.0, 1.0, 1.0, bitcast<f32>(NONE));
    path_vertex[pixel] = vec4<f32>(sample.ray.origin, 0.0);
    path_normal[pixel] = vec4<f32>(0.0);
    path_radiance[pixel] = vec4<f32>(0.0);
    queues[workgroup_first + local.y * tile_size.x + local.x] = pixel;
}

fn live_path(i: u32) -> u32 {
    return queues[atomicLoad(&control[CONTROL_PARITY]) * path_count() + i];
}

// The queue's rays (threads [0, live)), then the shadow rays shade appended the bounce before ([live, live +
// shadows)): one dispatch for both.
@compute @workgroup_size(128)
fn extend(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
          @builtin(local_invocation_index) lid: u32) {
    rays_traced = 0u;
    let i = queue_index(group, groups, lid);
    let live = atomicLoad(&control[CONTROL_LIVE]);
    if i < live {
        extend_path(live_path(i));
    } else if i - live < atomicLoad(&control[CONTROL_SHADOWS]) {
        trace_shadow(i - live);
    }
    count_rays(lid);
}

// The path's ray to its next surface: one that lets the path through (alpha blending as stochastic coverage,
// with probability 1 - alpha, as trace_path_from decides it: the same sampler dimension, the same offset origin,
// the medium's attenuation over each segment) is passed and the ray traced on from behind it.
fn extend_path(path: u32) {
    var origin = path_origin[path];
    let dir = path_dir[path].xyz;
    var hit: Hit;
    var passed = false;
    var carried = path_throughput[path];
    loop {
        rays_traced++;
        hit = trace(Ray(origin.xyz, dir), MISS, false);
        if !WAVE_PASS_THROUGHS || hit.instance == NONE { break; }
        let state = bitcast<u32>(origin.w);
        let depth = state & 0xffffu;
        let pass_throughs = state >> 16u;
        if pass_throughs >= MAX_PASS_THROUGHS { break; }
        if (read_material(read_triangle(hit.triangle).w).flags & MATERIAL_ALPHA_BLEND) == 0u { break; }
        let s = resolve_hit(hit, Ray(origin.xyz, dir));
        let sampler = wave_sampler(path);
        if get_1d(sampler, DIM_PASS_THROUGH + depth * MAX_PASS_THROUGHS + pass_throughs) < s.alpha { break; }
        let medium = bitcast<u32>(carried.w);
        if medium != NONE { carried = vec4<f32>(carried.xyz * transmittance(medium, hit.t), carried.w); }
        origin = vec4<f32>(offset_ray_origin(s.p, -s.ng), bitcast<f32>(depth | ((pass_throughs + 1u) << 16u)));
        passed = true;
    }
    if passed {
        path_origin[path] = origin;
        path_throughput[path] = carried;
    }
    path_hit[path] = vec4<u32>(bitcast<u32>(hit.t), hit.instance, hit.triangle, bitcast<u32>(hit.bary.x));
    path_vertex[path].w = hit.bary.y;
}

fn trace_shadow(i: u32) {
    rays_traced++;
    let origin = shadow_origin[i];
    let dir = shadow_dir[i];
    let hit = trace(Ray(origin.xyz, dir.xyz), origin.w, true);
    if hit.instance == NONE {
        let path = bitcast<u32>(dir.w);
        path_radiance[path] += vec4<f32>(shadow_light[i].xyz, 0.0);
    }
}

var<workgroup> workgroup_next: atomic<u32>;
var<workgroup> workgroup_next_base: u32;
var<workgroup> workgroup_shadows: atomic<u32>;
var<workgroup> workgroup_shadows_base: u32;

// One bounce of trace_path_from's loop (integrator/path.wgsl) for a path whose ray extend traced: what it met,
// then the shadow ray and the next ray. The queues are filled by workgroup: one global atomic per queue and
// workgroup, each path at its workgroup's offset.
@compute @workgroup_size(128)
fn shade(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
         @builtin(local_invocation_index) lid: u32) {
    if lid == 0u {
        atomicStore(&workgroup_next, 0u);
        atomicStore(&workgroup_shadows, 0u);
    }
    workgroupBarrier();
    let i = queue_index(group, groups, lid);
    var step = BounceStep(false, false, DirectLight(Ray(vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0)), 0.0, vec3<f32>(0.0)));
    var path = 0u;
    if i < atomicLoad(&control[CONTROL_LIVE]) {
        path = live_path(i);
        step = shade_bounce(path);
    }
    var next_slot = 0u;
    var shadow_slot = 0u;
    if step.continues { next_slot = atomicAdd(&workgroup_next, 1u); }
    if step.shadow { shadow_slot = atomicAdd(&workgroup_shadows, 1u); }
    workgroupBarrier();
    if lid == 0u {
        workgroup_next_base = atomicAdd(&control[CONTROL_NEXT], atomicLoad(&workgroup_next));
        workgroup_shadows_base = atomicAdd(&control[CONTROL_SHADOWS_APPENDED], atomicLoad(&workgroup_shadows));
    }
    workgroupBarrier();
    if step.continues {
        let out = (1u - atomicLoad(&control[CONTROL_PARITY])) * path_count();
        queues[out + workgroup_next_base + next_slot] = path;
    }
    if step.shadow {
        let slot = workgroup_shadows_base + shadow_slot;
        shadow_origin[slot] = vec4<f32>(step.direct.ray.origin, step.direct.t_max);
        shadow_dir[slot] = vec4<f32>(step.direct.ray.dir, bitcast<f32>(path));
        shadow_light[slot] = vec4<f32>(step.direct.contribution, 0.0);
    }
}

struct BounceStep {
    continues: bool,
    shadow: bool,
    direct: DirectLight,
}

fn shade_bounce(path: u32) -> BounceStep {
    var step = BounceStep(false, false, DirectLight(Ray(vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0)), 0.0, vec3<f32>(0.0)));
    let origin = path_origin[path];
    let dir = path_dir[path];
    let state = bitcast<u32>(origin.w);
    let depth = state & 0xffffu;
    let pass_throughs = state >> 16u;
    var ray = Ray(origin.xyz, dir.xyz);
    let last_bsdf_pdf = dir.w;
    let carried = path_throughput[path];
    var throughput = carried.xyz;
    var medium = bitcast<u32>(carried.w);
    let vertex = path_vertex[path];
    let last_vertex = LightSampleContext(vertex.xyz, path_normal[path].xyz);
    let h = path_hit[path];
    let hit = Hit(bitcast<f32>(h.x), h.y, h.z, vec2<f32>(bitcast<f32>(h.w), vertex.w));
    let sampler = wave_sampler(path);
    let nee = (frame.flags & FRAME_NEE) != 0u && light_count() > 0u;
    var radiance = vec3<f32>(0.0);

    if medium != NONE { throughput *= transmittance(medium, hit.t); }
    if hit.instance == NONE {
        radiance += throughput * escaped_radiance(ray.dir, last_bsdf_pdf, nee);
        path_radiance[path] += vec4<f32>(radiance, 0.0);
        return step;
    }
    // extend passed the alpha-blended surfaces this path went through.
    let s = resolve_hit(hit, ray);
    if any(s.emission > vec3<f32>(0.0)) && emits_towards_viewer(s) {
        var weight = 1.0;
        if nee && last_bsdf_pdf > 0.0 {
            weight = power_heuristic(last_bsdf_pdf, direct_pdf_of_hit(hit, s.p, last_vertex, ray.dir));
        }
        radiance += throughput * s.emission * weight;
    }
    if radiance.x != 0.0 || radiance.y != 0.0 || radiance.z != 0.0 {
        path_radiance[path] += vec4<f32>(radiance, 0.0);
    }
    // An unlit surface scatters nothing.
    if MATERIAL_LOBES != 0u && (s.flags & MATERIAL_UNLIT) != 0u { return step; }
    if depth >= frame.max_depth { return step; }

    let dims = bounce_dimensions(depth);
    let tbn = basis(s.n);
    let wo = -ray.dir * tbn;
    if nee {
        step.direct = sample_direct(s, wo, tbn, sampler, dims, medium);
        step.direct.contribution *= throughput;
        step.shadow = any(step.direct.contribution != vec3<f32>(0.0));
    }
    let bs = bsdf_sample(wo, s.bsdf, get_1d(sampler, dims + DIM_LOBE), get_2d(sampler, dims + DIM_DIRECTION));
    let next_dir = tbn * bs.wi;
    // The direction must leave on the side its lobe says (integrator/path.wgsl).
    let transmitted = (bs.flags & BSDF_TRANSMISSION) != 0u;
    if !(bs.pdf > 0.0 && (dot(next_dir, s.ng) > 0.0) != transmitted) { return step; }
    throughput *= bs.weight;
    let next_depth = depth + 1u;
    if next_depth >= frame.rr_depth {
        let survive = min(max(throughput.x, max(throughput.y, throughput.z)), 0.95);
        if get_1d(sampler, dims + DIM_ROULETTE) >= survive { return step; }
        throughput /= survive;
    }
    if transmitted { medium = medium_after_transmission(s, medium); }
    let next_origin = offset_ray_origin(s.p, select(s.ng, -s.ng, transmitted));
    path_origin[path] = vec4<f32>(next_origin, bitcast<f32>(next_depth | (pass_throughs << 16u)));
    path_dir[path] = vec4<f32>(next_dir, bs.pdf);
    path_throughput[path] = vec4<f32>(throughput, bitcast<f32>(medium));
    path_vertex[path] = vec4<f32>(s.p, 0.0);
    path_normal[path] = vec4<f32>(s.ng, 0.0);
    step.continues = true;
    return step;
}

// Each path's sample into the accumulation (a non-finite sample adds nothing but counts, as in the megakernel).
@compute @workgroup_size(8, 8)
fn finish(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height { return; }
    let pixel = gid.y * frame.width + gid.x;
    let r = path_radiance[pixel].xyz;
    accum[pixel] += vec4<f32>(select(vec3<f32>(0.0), r, finite3(r)), 1.0);
}

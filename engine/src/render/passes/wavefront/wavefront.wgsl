// The wavefront path tracer (Laine, Karras and Aila 2013, "Megakernels Considered Harmful"): the path loop of
// integrator/path.wgsl cut at its traversals into kernels over a queue of the paths still alive, so that a warp
// runs only live paths and deep bounces cost what their live paths cost, not what a warp's longest path costs.
// A wave holds samples_per_wave() paths per pixel (a wave = that many samples of every pixel: several where the
// view has too few pixels to fill the GPU, `WavefrontPass::prepare` says how many); between kernels a path's
// state lives in the arrays below, indexed by path: path = sample in the wave x pixels + pixel. Per wave:
//   begin_wave; first_bounce (a megakernel for depth 0: camera ray, its surface shaded, the shadow ray and the
//   next ray queued; every path is alive there, so a queue would only add traffic); advance; then per bounce:
//   extend (the queue's rays, passing through alpha-blended surfaces, and the shadow rays of the bounce before),
//   shade (emission, next-event estimation's shadow ray, BSDF sampling, Russian roulette: the next queue),
//   advance (the next bounce's counts and dispatch sizes); a last extend for the last shadow rays; finish (each
//   pixel's paths' radiance into the accumulation).
// Every decision draws the same sampler dimension as the megakernel's and the radiance is summed in the same
// order, so a path is the same path (tests/engine/wavefront.rs). What the megakernel records for the denoisers
// (first-hit AOVs, moments) and the real-time integrator's start are not here: the trace pass runs the
// megakernel where they are needed.

// The view's accumulation: rgb radiance sums, w samples.
@group(1) @binding(1) var<storage, read_write> accum: array<vec4<f32>>;
// Path state, one entry per path. The ray to trace: origin and `depth | pass_throughs << 16` (bits).
@group(1) @binding(2) var<storage, read_write> path_origin: array<vec4<f32>>;
// The ray's direction and the density with which the BSDF sampled it.
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
// The counters (CONTROL_*, zeroed before the pass), then two queues of path indices, [0, N) and [N, 2N): one read
// this bounce, the other filled for the next. One binding for both, and the shadow rays one array of a struct,
// so that the sizing kernels, which bind the scene's group too (`WavefrontPass::new` says why), stay within the
// storage buffers a stage may bind (`MIN_STORAGE_BUFFERS_PER_STAGE`).
// With WAVE_SORT the entries go on with each queued ray's sort key, [2N, 3N), and the queue read this bounce in
// the keys' order, [3N, 4N); `sort` holds the counting sort's bins (see `sort_key`).
struct Queues {
    control: array<atomic<u32>, WAVE_CONTROL_WORDS>,
    sort: array<atomic<u32>, SORT_WORDS>,
    entries: array<u32>,
}
@group(1) @binding(9) var<storage, read_write> queues: Queues;
// Shadow rays in the order they were queued.
struct ShadowRay {
    // Origin and t_max.
    origin: vec4<f32>,
    // Direction and the path (bits).
    dir: vec4<f32>,
    // What the light adds when nothing blocks it.
    light: vec4<f32>,
}
@group(1) @binding(10) var<storage, read_write> shadow_rays: array<ShadowRay>;
// Indirect dispatch sizes, written by begin_wave and advance only (a buffer read as dispatch arguments cannot be
// bound to the kernels it sizes): [0..3) extend (live paths and shadow rays), [3..6) shade (live paths), [8..11)
// extend_refill (the same rays, at most WAVE_REFILL_GROUPS workgroups).
@group(2) @binding(0) var<storage, read_write> dispatch_args: array<u32, 12>;

// The queue read this bounce holds CONTROL_LIVE paths, from CONTROL_PARITY x N on.
const CONTROL_LIVE: u32 = 0u;
// Paths queued for the next bounce.
const CONTROL_NEXT: u32 = 1u;
// Shadow rays queued this bounce, and those extend traces.
const CONTROL_SHADOWS_QUEUED: u32 = 2u;
const CONTROL_SHADOWS: u32 = 3u;
const CONTROL_PARITY: u32 = 4u;
// This wave, counted from the dispatch's first; and the next.
const CONTROL_WAVE: u32 = 5u;
const CONTROL_NEXT_WAVE: u32 = 6u;
// Rays traced (camera, bounce and shadow), copied to the view's ray counter after the pass: WAVE_CONTROL_RAYS,
// from the shared constants.

// Alpha-blended surfaces (stochastic coverage) are passed through where the ray is traced, so that a
// pass-through does not take a bounce of the wave; compiled in only for scenes with such materials.
override WAVE_PASS_THROUGHS: bool = true;

// Ray sorting (Meister et al. 2020, "On Ray Reordering Techniques for Faster GPU Ray Tracing"): each bounce's
// queue is copied in the order of its rays' keys (where the ray starts, then which octant it points into), and
// extend traces it in that order, so that a warp's rays walk the same nodes and the caches hold them. Shade keeps
// the queue's own order, which follows the paths' (the state arrays are read in runs; in the keys' order every
// path's state was a scattered read: the first form, which sorted the queue itself, lost more in shade than
// extend gained, docs/BENCHMARKS.md). A counting sort over SORT_BINS keys: the shading kernels count the rays
// they queue per key (`sort` [0, SORT_BINS)) and keep each one's key; `sort_prefix` turns the counts into each
// key's first slot within its block of SORT_BLOCK keys ([SORT_BINS, 2 SORT_BINS)) and each block's total
// ([2 SORT_BINS, + SORT_BLOCKS)), zeroing the counts for the next bounce; `sort_scatter` copies each entry to its
// key's next slot. The sizes come from the generated constants (engine/src/render/layout.rs), which the pass
// sizes the buffer by. A pipeline constant, so that scenes which do not gain compile none of it.
override WAVE_SORT: bool = false;

// Extend with refill (`extend_refill`): the most workgroups its dispatch takes, each invocation tracing every
// stride-th ray; 0 where the pass does not run it (advance writes its size only then). Set on `advance`.
override WAVE_REFILL_GROUPS: u32 = 0u;

// Queue kernels run 128 paths a workgroup over a 2D grid of workgroups (65535 per side at most).
const QUEUE_GROUP: u32 = 128u;
const MAX_GROUPS_X: u32 = 32768u;

fn pixel_count() -> u32 {
    return frame.width * frame.height;
}

// The paths of a wave per pixel: the state arrays hold that many per pixel.
fn samples_per_wave() -> u32 {
    return arrayLength(&path_radiance) / pixel_count();
}

fn path_count() -> u32 {
    return arrayLength(&path_radiance);
}

// The first sample of this wave, counted from this dispatch's first.
fn wave_first_sample() -> u32 {
    return atomicLoad(&queues.control[CONTROL_WAVE]) * samples_per_wave();
}

// The samples this wave traces per pixel: samples_per_wave(), or fewer in the dispatch's last wave.
fn wave_samples() -> u32 {
    return min(samples_per_wave(), frame.spp - wave_first_sample());
}

fn queue_index(group: vec3<u32>, groups: vec3<u32>, lid: u32) -> u32 {
    return (group.y * groups.x + group.x) * QUEUE_GROUP + lid;
}

fn write_dispatch(first: u32, items: u32) {
    write_dispatch_groups(first, (items + QUEUE_GROUP - 1u) / QUEUE_GROUP);
}

fn write_dispatch_groups(first: u32, groups: u32) {
    let x = min(groups, MAX_GROUPS_X);
    dispatch_args[first] = x;
    dispatch_args[first + 1u] = select(0u, (groups + x - 1u) / max(x, 1u), groups > 0u);
    dispatch_args[first + 2u] = 1u;
}

@compute @workgroup_size(1)
fn begin_wave() {
    let wave = atomicLoad(&queues.control[CONTROL_NEXT_WAVE]);
    atomicStore(&queues.control[CONTROL_WAVE], wave);
    atomicStore(&queues.control[CONTROL_NEXT_WAVE], wave + 1u);
    atomicStore(&queues.control[CONTROL_LIVE], 0u);
    atomicStore(&queues.control[CONTROL_NEXT], 0u);
    atomicStore(&queues.control[CONTROL_SHADOWS_QUEUED], 0u);
    atomicStore(&queues.control[CONTROL_SHADOWS], 0u);
    atomicStore(&queues.control[CONTROL_PARITY], 0u);
}

// After a shading kernel: the queue it filled becomes the one read, and its shadow rays the ones to trace.
@compute @workgroup_size(1)
fn advance() {
    let live = atomicExchange(&queues.control[CONTROL_NEXT], 0u);
    let shadows = atomicExchange(&queues.control[CONTROL_SHADOWS_QUEUED], 0u);
    atomicStore(&queues.control[CONTROL_LIVE], live);
    atomicStore(&queues.control[CONTROL_SHADOWS], shadows);
    atomicStore(&queues.control[CONTROL_PARITY], 1u - atomicLoad(&queues.control[CONTROL_PARITY]));
    write_dispatch(0u, live + shadows);
    write_dispatch(3u, live);
    if WAVE_REFILL_GROUPS > 0u {
        write_dispatch_groups(8u, min((live + shadows + QUEUE_GROUP - 1u) / QUEUE_GROUP, WAVE_REFILL_GROUPS));
    }
}

// A live path's state (what trace_path_from keeps in registers across a bounce).
struct WavePath {
    ray: Ray,
    depth: u32,
    pass_throughs: u32,
    last_bsdf_pdf: f32,
    throughput: vec3<f32>,
    medium: u32,
    last_vertex: LightSampleContext,
}

fn load_path(path: u32) -> WavePath {
    let origin = path_origin[path];
    let dir = path_dir[path];
    let carried = path_throughput[path];
    let state = bitcast<u32>(origin.w);
    let vertex = LightSampleContext(path_vertex[path].xyz, path_normal[path].xyz);
    return WavePath(Ray(origin.xyz, dir.xyz), state & 0xffffu, state >> 16u, dir.w, carried.xyz,
        bitcast<u32>(carried.w), vertex);
}

// The ray's origin, depth and pass-throughs, and the throughput and medium: what a pass-through changes.
fn store_origin_and_throughput(path: u32, p: WavePath) {
    path_origin[path] = vec4<f32>(p.ray.origin, bitcast<f32>(p.depth | (p.pass_throughs << 16u)));
    path_throughput[path] = vec4<f32>(p.throughput, bitcast<f32>(p.medium));
}

fn store_path(path: u32, p: WavePath) {
    store_origin_and_throughput(path, p);
    path_dir[path] = vec4<f32>(p.ray.dir, p.last_bsdf_pdf);
    path_vertex[path] = vec4<f32>(p.last_vertex.p, 0.0);
    path_normal[path] = vec4<f32>(p.last_vertex.n, 0.0);
}

// The sample a path traces: the sampler's index of its pixel's sample.
fn path_sample(path: u32) -> u32 {
    return frame.sample_base + wave_first_sample() + path / pixel_count();
}

fn wave_sampler(path: u32) -> Sampler {
    return sampler_start(path % pixel_count(), path_sample(path), frame.seed);
}

// Whether the path's ray, which met `hit`, passes through it: alpha blending as stochastic coverage, with
// probability 1 - alpha, as trace_path_from decides it (the same sampler dimension, the same offset origin, the
// medium's attenuation over the segment). If so, `p` has the ray from behind the surface, the pass-through
// counted and the throughput attenuated.
fn pass_through(path: u32, p: ptr<function, WavePath>, hit: Hit) -> bool {
    if !hit_blends(hit) || (*p).pass_throughs >= MAX_PASS_THROUGHS { return false; }
    let s = resolve_hit(hit, (*p).ray);
    let u = get_1d(wave_sampler(path), DIM_PASS_THROUGH + (*p).depth * MAX_PASS_THROUGHS + (*p).pass_throughs);
    if u < s.alpha { return false; }
    if (*p).medium != NONE { (*p).throughput *= transmittance((*p).medium, hit.t); }
    (*p).ray.origin = offset_ray_origin(s.p, -s.ng);
    (*p).pass_throughs++;
    return true;
}

// Whether `hit` is on an alpha-blended surface a path may pass through (compiled out without WAVE_PASS_THROUGHS).
fn hit_blends(hit: Hit) -> bool {
    return WAVE_PASS_THROUGHS && hit.instance != NONE
        && (read_material(read_triangle(hit.triangle).w).flags & MATERIAL_ALPHA_BLEND) != 0u;
}

// One bounce of trace_path_from's loop (integrator/path.wgsl) from the surface (or the sky) the path's ray met:
// emission, next-event estimation's shadow ray, BSDF sampling and Russian roulette. The radiance goes to the
// path's sum; a path that goes on is stored for the next bounce.
struct BounceStep {
    continues: bool,
    shadow: bool,
    direct: DirectLight,
    // WAVE_SORT: the next ray's sort key.
    key: u32,
}

fn shade_bounce(path: u32, state: WavePath, hit: Hit) -> BounceStep {
    var step = no_step();
    var p = state;
    let nee = (frame.flags & FRAME_NEE) != 0u && light_count() > 0u;
    if p.medium != NONE { p.throughput *= transmittance(p.medium, hit.t); }
    if hit.instance == NONE {
        path_radiance[path] += vec4<f32>(p.throughput * escaped_radiance(p.ray.dir, p.last_bsdf_pdf, nee), 0.0);
        return step;
    }
    let s = resolve_hit(hit, p.ray);
    if any(s.emission > vec3<f32>(0.0)) && emits_towards_viewer(s) {
        var weight = 1.0;
        if nee && p.last_bsdf_pdf > 0.0 {
            weight = power_heuristic(p.last_bsdf_pdf, direct_pdf_of_hit(hit, s.p, p.last_vertex, p.ray.dir));
        }
        path_radiance[path] += vec4<f32>(p.throughput * s.emission * weight, 0.0);
    }
    // An unlit surface scatters nothing.
    if MATERIAL_LOBES != 0u && (s.flags & MATERIAL_UNLIT) != 0u { return step; }
    if p.depth >= frame.max_depth { return step; }

    let sampler = wave_sampler(path);
    let dims = bounce_dimensions(p.depth);
    let tbn = basis(s.n);
    let wo = -p.ray.dir * tbn;
    if nee {
        step.direct = sample_direct(s, wo, tbn, sampler, dims, p.medium);
        step.direct.contribution *= p.throughput;
        step.shadow = any(step.direct.contribution != vec3<f32>(0.0));
    }
    let bs = bsdf_sample(wo, s.bsdf, get_1d(sampler, dims + DIM_LOBE), get_2d(sampler, dims + DIM_DIRECTION));
    let dir = tbn * bs.wi;
    // The direction must leave on the side its lobe says (integrator/path.wgsl).
    let transmitted = (bs.flags & BSDF_TRANSMISSION) != 0u;
    if !(bs.pdf > 0.0 && (dot(dir, s.ng) > 0.0) != transmitted) { return step; }
    p.throughput *= bs.weight;
    p.last_bsdf_pdf = bs.pdf;
    p.depth++;
    if p.depth >= frame.rr_depth {
        let survive = min(max(p.throughput.x, max(p.throughput.y, p.throughput.z)), 0.95);
        if get_1d(sampler, dims + DIM_ROULETTE) >= survive { return step; }
        p.throughput /= survive;
    }
    p.ray = Ray(offset_ray_origin(s.p, select(s.ng, -s.ng, transmitted)), dir);
    if transmitted { p.medium = medium_after_transmission(s, p.medium); }
    p.last_vertex = LightSampleContext(s.p, s.ng);
    store_path(path, p);
    step.continues = true;
    if WAVE_SORT { step.key = sort_key(p.ray); }
    return step;
}

var<workgroup> workgroup_rays: atomic<u32>;
var<workgroup> workgroup_next: atomic<u32>;
var<workgroup> workgroup_next_base: u32;
var<workgroup> workgroup_shadows: atomic<u32>;
var<workgroup> workgroup_shadows_base: u32;

fn clear_workgroup_counts(lid: u32) {
    if lid == 0u {
        atomicStore(&workgroup_rays, 0u);
        atomicStore(&workgroup_next, 0u);
        atomicStore(&workgroup_shadows, 0u);
    }
    workgroupBarrier();
}

// Queues what a shading kernel's invocations produced, one global atomic per queue and workgroup (each
// invocation at its workgroup's offset), and adds the workgroup's rays to the count. Called by every
// invocation, in uniform control flow.
fn queue_step(step: BounceStep, path: u32, lid: u32) {
    var next_slot = 0u;
    var shadow_slot = 0u;
    if step.continues { next_slot = atomicAdd(&workgroup_next, 1u); }
    if step.shadow { shadow_slot = atomicAdd(&workgroup_shadows, 1u); }
    atomicAdd(&workgroup_rays, rays_traced);
    workgroupBarrier();
    if lid == 0u {
        workgroup_next_base = atomicAdd(&queues.control[CONTROL_NEXT], atomicLoad(&workgroup_next));
        workgroup_shadows_base = atomicAdd(&queues.control[CONTROL_SHADOWS_QUEUED], atomicLoad(&workgroup_shadows));
        atomicAdd(&queues.control[WAVE_CONTROL_RAYS], atomicLoad(&workgroup_rays));
    }
    workgroupBarrier();
    if step.continues {
        let out = (1u - atomicLoad(&queues.control[CONTROL_PARITY])) * path_count();
        queues.entries[out + workgroup_next_base + next_slot] = path;
        if WAVE_SORT {
            queues.entries[2u * path_count() + workgroup_next_base + next_slot] = step.key;
            atomicAdd(&queues.sort[step.key], 1u);
        }
    }
    if step.shadow {
        shadow_rays[workgroup_shadows_base + shadow_slot] = ShadowRay(
            vec4<f32>(step.direct.ray.origin, step.direct.t_max),
            vec4<f32>(step.direct.ray.dir, bitcast<f32>(path)),
            vec4<f32>(step.direct.contribution, 0.0));
    }
}

fn no_step() -> BounceStep {
    return BounceStep(false, false, no_direct_light(), 0u);
}

// Bits 0-3 of `v` at bits 0, 3, 6 and 9 (one axis of a Morton code).
fn spread_4_bits(v: u32) -> u32 {
    var x = v & 0xfu;
    x = (x | (x << 4u)) & 0xc3u;
    return (x | (x << 2u)) & 0x249u;
}

// A ray's sort key: the Morton code of its origin's cell in a 16^3 grid over the scene's box (the top level's
// root), then the octant of its direction. Any origin, NaN included, gets a key below SORT_BINS.
fn sort_key(ray: Ray) -> u32 {
    let root = read_tlas_node(0u);
    var lo = vec3<f32>(3.0e38);
    var hi = vec3<f32>(-3.0e38);
    for (var k = 0u; k < 2u; k++) {
        var c = root.a;
        if k == 1u { c = root.b; }
        if c.count != 0u || c.index != NONE {
            lo = min(lo, c.min);
            hi = max(hi, c.max);
        }
    }
    let cell = (ray.origin - lo) * (16.0 / max(hi - lo, vec3<f32>(1e-30)));
    let q = min(vec3<u32>(clamp(cell, vec3<f32>(0.0), vec3<f32>(15.0))), vec3<u32>(15u));
    let morton = spread_4_bits(q.x) | (spread_4_bits(q.y) << 1u) | (spread_4_bits(q.z) << 2u);
    let octant = u32(ray.dir.x < 0.0) | (u32(ray.dir.y < 0.0) << 1u) | (u32(ray.dir.z < 0.0) << 2u);
    return ((morton << 3u) | octant) & (SORT_BINS - 1u);
}

var<workgroup> sort_sums: array<u32, SORT_BLOCK>;

// In place over `sort_sums[0 .. n)` (n a power of two, every invocation of the workgroup calling, lid < n or not):
// each entry becomes the sum of itself and those before it.
fn inclusive_scan(lid: u32, n: u32) {
    workgroupBarrier();
    for (var offset = 1u; offset < SORT_BLOCK; offset <<= 1u) {
        var v = 0u;
        if lid < n {
            v = sort_sums[lid];
            if lid >= offset && offset < n { v += sort_sums[lid - offset]; }
        }
        workgroupBarrier();
        if lid < n { sort_sums[lid] = v; }
        workgroupBarrier();
    }
}

// The counts of block `group.x`'s keys into their first slots within the block, and the block's total; the
// counts zeroed.
@compute @workgroup_size(SORT_BLOCK)
fn sort_prefix(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let bin = group.x * SORT_BLOCK + lid;
    let count = atomicExchange(&queues.sort[bin], 0u);
    sort_sums[lid] = count;
    inclusive_scan(lid, SORT_BLOCK);
    atomicStore(&queues.sort[SORT_BINS + bin], sort_sums[lid] - count);
    if lid == SORT_BLOCK - 1u {
        atomicStore(&queues.sort[2u * SORT_BINS + group.x], sort_sums[lid]);
    }
}

// Each path of the queue read this bounce to its key's next slot (the blocks' totals summed before it) in the
// sorted copy, which extend reads.
@compute @workgroup_size(128)
fn sort_scatter(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                @builtin(local_invocation_index) lid: u32) {
    sort_sums[lid] = atomicLoad(&queues.sort[2u * SORT_BINS + lid]);
    inclusive_scan(lid, SORT_BLOCKS);
    let i = queue_index(group, groups, lid);
    if i < atomicLoad(&queues.control[CONTROL_LIVE]) {
        let n = path_count();
        let key = queues.entries[2u * n + i] & (SORT_BINS - 1u);
        let block = key / SORT_BLOCK;
        var slot = atomicAdd(&queues.sort[SORT_BINS + key], 1u);
        if block > 0u { slot += sort_sums[block - 1u]; }
        queues.entries[3u * n + min(slot, n - 1u)] = live_path(i);
    }
}

// Depth 0, per 8x8 tile and sample of the wave (z): the camera ray, what it meets, and the next ray and shadow ray
// queued (by tile, so the next queue's neighbours are neighbouring pixels).
@compute @workgroup_size(8, 8)
fn first_bounce(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    clear_workgroup_counts(lid);
    rays_traced = 0u;
    var step = no_step();
    let pixel = gid.y * frame.width + gid.x;
    let path = gid.z * pixel_count() + pixel;
    if gid.x < frame.width && gid.y < frame.height && gid.z < wave_samples() {
        let sample = camera_sample(gid.xy, pixel, path_sample(path));
        var p = WavePath(sample.ray, 0u, 0u, 0.0, vec3<f32>(1.0), NONE, LightSampleContext(sample.ray.origin, vec3<f32>(0.0)));
        var hit: Hit;
        loop {
            rays_traced++;
            hit = trace(p.ray, MISS, false);
            if !pass_through(path, &p, hit) { break; }
        }
        path_radiance[path] = vec4<f32>(0.0);
        step = shade_bounce(path, p, hit);
    }
    queue_step(step, path, lid);
}

fn live_path(i: u32) -> u32 {
    return queues.entries[atomicLoad(&queues.control[CONTROL_PARITY]) * path_count() + i];
}

// The path of extend's ray i (i < live): in the keys' order where the rays are sorted.
fn extended_path(i: u32) -> u32 {
    if WAVE_SORT { return queues.entries[3u * path_count() + i]; }
    return live_path(i);
}

// The queue's rays (invocations [0, live)), then the shadow rays queued the bounce before ([live, live +
// shadows)): one dispatch for both, and one call of the traversal (a second call site would inline it twice).
@compute @workgroup_size(128)
fn extend(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
          @builtin(local_invocation_index) lid: u32) {
    clear_workgroup_counts(lid);
    rays_traced = 0u;
    let i = queue_index(group, groups, lid);
    let live = atomicLoad(&queues.control[CONTROL_LIVE]);
    let is_path = i < live;
    let is_shadow = !is_path && i - live < atomicLoad(&queues.control[CONTROL_SHADOWS]);
    var path = 0u;
    var p: WavePath;
    var t_max = MISS;
    if is_path {
        path = extended_path(i);
        p = load_path(path);
    } else if is_shadow {
        let origin = shadow_rays[i - live].origin;
        let dir = shadow_rays[i - live].dir;
        p.ray = Ray(origin.xyz, dir.xyz);
        t_max = origin.w;
        path = bitcast<u32>(dir.w);
    }
    if is_path || is_shadow {
        let pass_throughs = p.pass_throughs;
        var hit: Hit;
        loop {
            rays_traced++;
            hit = trace(p.ray, t_max, is_shadow);
            if is_shadow || !pass_through(path, &p, hit) { break; }
        }
        if is_path && p.pass_throughs != pass_throughs { store_origin_and_throughput(path, p); }
        store_extended(i, live, path, hit);
    }
    count_workgroup_rays(lid);
}

// What extend's ray i (of `path`) found: a path's hit for shade, or a shadow ray's light where nothing blocked it.
fn store_extended(i: u32, live: u32, path: u32, hit: Hit) {
    if i < live {
        path_hit[path] = vec4<u32>(bitcast<u32>(hit.t), hit.instance, hit.triangle, bitcast<u32>(hit.bary.x));
        path_vertex[path].w = hit.bary.y;
    } else if hit.instance == NONE {
        path_radiance[path] += vec4<f32>(shadow_rays[i - live].light.xyz, 0.0);
    }
}

// Adds the workgroup's rays to the count (every invocation, in uniform control flow).
fn count_workgroup_rays(lid: u32) {
    atomicAdd(&workgroup_rays, rays_traced);
    workgroupBarrier();
    if lid == 0u {
        atomicAdd(&queues.control[WAVE_CONTROL_RAYS], atomicLoad(&workgroup_rays));
    }
}

// Extend's work with refill (traversal/refill.wgsl): a fixed grid of at most WAVE_REFILL_GROUPS workgroups
// whose invocations trace rays i, i + stride, ... (no atomics), each starting its next ray inside the traversal
// loop as soon as its last one ends, so that a warp's lanes stay busy until the rays run out instead of waiting
// for its longest ray. The same hits as `extend`, and the same pass-throughs of alpha-blended surfaces (each
// one's next segment started in the loop like a new ray); only where `refill_supported` (the pass checks).
@compute @workgroup_size(128)
fn extend_refill(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
                 @builtin(local_invocation_index) lid: u32) {
    clear_workgroup_counts(lid);
    rays_traced = 0u;
    let live = atomicLoad(&queues.control[CONTROL_LIVE]);
    let total = live + atomicLoad(&queues.control[CONTROL_SHADOWS]);
    let stride = groups.x * groups.y * QUEUE_GROUP;
    var i = queue_index(group, groups, lid);
    if i < total {
        var path = start_extended_ray(i, live);
        loop {
            if refill_step() {
                if end_extended_ray(i, live, path) { continue; }
                i += stride;
                if i >= total { break; }
                path = start_extended_ray(i, live);
            }
        }
    }
    count_workgroup_rays(lid);
}

// Starts ray i of extend_refill, a live path's ray (i < live) or else a shadow ray, which any hit ends. Returns
// its path.
fn start_extended_ray(i: u32, live: u32) -> u32 {
    rays_traced++;
    if i < live {
        let path = extended_path(i);
        refill_start(Ray(path_origin[path].xyz, path_dir[path].xyz), MISS, false);
        return path;
    }
    let shadow = shadow_rays[i - live];
    refill_start(Ray(shadow.origin.xyz, shadow.dir.xyz), shadow.origin.w, true);
    return bitcast<u32>(shadow.dir.w);
}

// What ray i found, stored as `extend` stores it; or, where a path's ray passes through an alpha-blended surface,
// the path's origin and throughput moved past it and the ray from there started (returns true: not ended).
fn end_extended_ray(i: u32, live: u32, path: u32) -> bool {
    let hit = refill_result();
    // The material's flag first: most hits are on surfaces that do not blend, and need no path state.
    if i < live && hit_blends(hit) {
        var p = load_path(path);
        if pass_through(path, &p, hit) {
            store_origin_and_throughput(path, p);
            rays_traced++;
            refill_start(p.ray, MISS, false);
            return true;
        }
    }
    store_extended(i, live, path, hit);
    return false;
}

// Depth 1 on: what extend found, shaded.
@compute @workgroup_size(128)
fn shade(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
         @builtin(local_invocation_index) lid: u32) {
    clear_workgroup_counts(lid);
    rays_traced = 0u;
    let i = queue_index(group, groups, lid);
    var step = no_step();
    var path = 0u;
    if i < atomicLoad(&queues.control[CONTROL_LIVE]) {
        path = live_path(i);
        let h = path_hit[path];
        let hit = Hit(bitcast<f32>(h.x), h.y, h.z, vec2<f32>(bitcast<f32>(h.w), path_vertex[path].w));
        step = shade_bounce(path, load_path(path), hit);
    }
    queue_step(step, path, lid);
}

// Each pixel's samples of the wave into the accumulation, in sample order (a non-finite sample adds nothing but
// counts, as in the megakernel).
@compute @workgroup_size(8, 8)
fn finish(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height { return; }
    let pixel = gid.y * frame.width + gid.x;
    let samples = wave_samples();
    var sum = vec3<f32>(0.0);
    for (var j = 0u; j < samples; j++) {
        let r = path_radiance[j * pixel_count() + pixel].xyz;
        sum += select(vec3<f32>(0.0), r, finite3(r));
    }
    accum[pixel] += vec4<f32>(sum, f32(samples));
}

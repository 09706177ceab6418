// The path integrator (pbrt-v4 `PathIntegrator`): unidirectional path tracing with next-event estimation on the
// lights, combined with BSDF sampling by multiple importance sampling (power heuristic), and Russian roulette.
// `max_depth` = surface interactions after the camera ray. It only calls the library: traversal (`trace`),
// `resolve_hit`, the BSDF, the light sampler and lights, the environment and the sampler. The kernel counts
// rays in `rays_traced`.

var<private> rays_traced: u32;

// Whether paths record the denoisers' inputs (`PathResult`'s first-hit albedo, normal and depth, and the light
// no surface scattered). The trace pass compiles them out where nothing reads them (renders without a
// denoiser): their state is live across every traversal of the path, and cost 3-9% of the H200's trace time
// (docs/BENCHMARKS.md). The real-time kernels keep the default.
override PATH_AOVS: bool = true;

// Path regeneration (Novak et al. 2010), on CPU adapters: the trace pass runs all of a pixel's samples in one path
// loop and starts the next sample's camera ray as soon as a path ends, instead of each SIMD lane waiting at the end
// of the sample loop for the longest path of its eight (lavapipe runs invocations as masked 8-lane vector code).
// The trace pass sets `regeneration` before its one call; the sums of the samples are left there. Off, the code
// below folds away and the loop is the one-path loop GPUs run (there the carried state cost occupancy:
// docs/BENCHMARKS.md, "Clocks after idle, and path regeneration").
override PATH_REGENERATION: bool = false;

// What the trace pass adds to a pixel over its samples.
struct PixelSums {
    radiance: vec3<f32>,
    // rgb: first-hit albedo, w: camera-space depth (samples that hit a surface).
    albedo_depth: vec4<f32>,
    // xyz: first-hit shading normal, w: samples that hit a surface.
    normal_hits: vec4<f32>,
    // rgb: unscattered radiance, w: luminance(scattered radiance)^2.
    unscattered_m2: vec4<f32>,
}

// `sums` with the path's sample added.
fn add_sample(sums: PixelSums, r: PathResult) -> PixelSums {
    var out = sums;
    // A non-finite sample would poison the pixel forever; it is dropped (it should never happen).
    if finite3(r.radiance) {
        out.radiance += r.radiance;
        if PATH_AOVS {
            // Capped so that a firefly's square cannot overflow the sum.
            let l = min(max(luminance(r.radiance - r.unscattered), 0.0), 1e15);
            out.unscattered_m2 += vec4<f32>(r.unscattered, l * l);
        }
    }
    if PATH_AOVS && r.hit {
        out.albedo_depth += vec4<f32>(r.albedo, r.depth);
        out.normal_hits += vec4<f32>(r.normal, 1.0);
    }
    return out;
}

// The pixel whose samples a regenerating path loop runs: samples sample_base + next .. sample_base + end - 1 are
// still to start; `sums` holds the finished ones.
struct Regeneration {
    pixel_xy: vec2<u32>,
    pixel: u32,
    next: u32,
    end: u32,
    sums: PixelSums,
}

var<private> regeneration: Regeneration;

// Sample `index` of the pixel at `pixel_xy` (flat index `pixel`): its sampler and camera ray through a uniform
// point in the pixel (box filter).
struct CameraSample {
    sampler: Sampler,
    ray: Ray,
}

fn camera_sample(pixel_xy: vec2<u32>, pixel: u32, index: u32) -> CameraSample {
    let sampler = sampler_start(pixel, index, frame.seed);
    // The film position is stratified over the pixel's samples (anti-aliasing converges faster), except where
    // the denoisers read the first-hit AOVs: their guides and variance estimates are tuned for independent
    // positions (sampler.wgsl, get_2d_independent).
    var u_film: vec2<f32>;
    if PATH_AOVS {
        u_film = get_2d_independent(sampler, DIM_FILM);
    } else {
        u_film = get_2d(sampler, DIM_FILM);
    }
    return CameraSample(sampler, generate_ray(pixel_xy, u_film, get_2d(sampler, DIM_LENS)));
}

// Sample dimensions (sampler.wgsl): the camera's, then a fixed block per bounce, so every decision of a path
// has its own dimension whatever the path did before.
const DIM_FILM: u32 = 0u; // 2D
const DIM_LENS: u32 = 2u; // 2D
const DIM_FIRST_BOUNCE: u32 = 4u;
const DIMS_PER_BOUNCE: u32 = 8u;
// Offsets within a bounce's block.
const DIM_LIGHT_CHOICE: u32 = 0u;
const DIM_LIGHT_POINT: u32 = 1u; // 2D
const DIM_LOBE: u32 = 3u;
const DIM_DIRECTION: u32 = 4u; // 2D
const DIM_ROULETTE: u32 = 6u;
// Alpha-blend pass-throughs, one dimension each, apart from the bounces' blocks: two transparent surfaces met at
// the same depth must not share a number.
const DIM_PASS_THROUGH: u32 = 0x40000000u;
const MAX_PASS_THROUGHS: u32 = 16u;

fn bounce_dimensions(depth: u32) -> u32 {
    return DIM_FIRST_BOUNCE + depth * DIMS_PER_BOUNCE;
}

// A shadow ray to test and what the light adds when nothing blocks it.
struct DirectLight {
    ray: Ray,
    t_max: f32,
    // Unoccluded contribution: f x cos x Li x MIS weight / pdf; zero when there is nothing to test.
    contribution: vec3<f32>,
}

// Nothing to test: a shadow ray that adds nothing.
fn no_direct_light() -> DirectLight {
    return DirectLight(Ray(vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0)), 0.0, vec3<f32>(0.0));
}

// Next-event estimation at `s`: one light picked by the light sampler, one sample on it, weighed against BSDF
// sampling (delta lights take no weight). The shadow ray is returned, not traced, so that the path loop traces
// every ray at one call site (a smaller kernel).
// `medium` is the volume the path is in; a shadow ray through a refracting surface crosses into the one behind
// it, and its light is attenuated over its length.
fn sample_direct(s: SurfaceInteraction, wo: vec3<f32>, tbn: mat3x3<f32>, sampler: Sampler, dims: u32, medium: u32) -> DirectLight {
    let none = no_direct_light();
    let ctx = LightSampleContext(s.p, s.ng);
    let choice = light_sampler_sample_at(ctx, get_1d(sampler, dims + DIM_LIGHT_CHOICE));
    if choice.pmf <= 0.0 { return none; }
    let ls = light_sample_li(choice.light, ctx, get_2d(sampler, dims + DIM_LIGHT_POINT), true);
    if ls.pdf <= 0.0 || choice.pmf <= 0.0 { return none; }
    // Light from behind the surface counts only through a transmitting lobe.
    let behind = dot(ls.wi, s.ng) <= 0.0;
    if behind && (bsdf_flags(s.bsdf) & BSDF_TRANSMISSION) == 0u { return none; }
    let wi = ls.wi * tbn;
    let f = bsdf_eval(wo, wi, s.bsdf);
    if all(f == vec3<f32>(0.0)) { return none; }
    let pdf_light = choice.pmf * ls.pdf;
    let weight = select(power_heuristic(pdf_light, bsdf_pdf(wo, wi, s.bsdf)), 1.0, ls.delta);
    let shadow = light_shadow_ray(s.p, select(s.ng, -s.ng, behind), ls);
    var shadow_medium = medium;
    if behind { shadow_medium = medium_after_transmission(s, medium); }
    let absorbed = transmittance(shadow_medium, min(ls.distance, MISS));
    return DirectLight(shadow.ray, shadow.t_max, f * abs(wi.z) * ls.li * absorbed * weight / pdf_light);
}

// Density with which next-event estimation from `last_vertex` would have produced the emissive hit `hit` at
// `p`, seen along `dir` (alpha-blend pass-throughs may lie between, so the distance is measured, not hit.t).
fn direct_pdf_of_hit(hit: Hit, p: vec3<f32>, last_vertex: LightSampleContext, dir: vec3<f32>) -> f32 {
    let light = triangle_light_index(hit.instance, hit.triangle);
    if light == NONE { return 0.0; }
    return light_sampler_pmf_at(last_vertex, light) * emitter_pdf_li(light, last_vertex, dir, distance(p, last_vertex.p));
}

// What a ray leaving the scene along `dir` sees of the lights at infinity, each weighed against next-event
// estimation (whose choice of them does not depend on where it samples from) when the ray was BSDF-sampled with
// density `bsdf_pdf` (0: a camera ray, counted in full).
fn escaped_radiance(dir: vec3<f32>, bsdf_pdf: f32, nee: bool) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    let end = frame.infinite_light_first + frame.infinite_light_count;
    for (var light = frame.infinite_light_first; light < end; light++) {
        let li = infinite_light_li(light, dir, true);
        if all(li.le == vec3<f32>(0.0)) { continue; }
        var weight = 1.0;
        if nee && bsdf_pdf > 0.0 {
            weight = power_heuristic(bsdf_pdf, infinite_light_pmf_at(light) * li.pdf);
        }
        sum += li.le * weight;
    }
    return sum;
}

// The denoisers' albedo and normal follow the path through mirror-like metal (OIDN's rule for delta surfaces,
// Cycles' denoising albedo), so a reflection's texture edges reach the denoiser: where the path samples the
// glossy lobe of a surface this smooth (roughness 0.075, Cycles' threshold) and mostly metal, the AOVs become
// the next surface's, the albedo tinted by the reflectance on the way (Fresnel over the lobe's probability, so
// the expectation over lobes is that of the BSDF's split). A path that leaves the scene on the way adds albedo
// 0 and normal 0, as a miss does; one cut short keeps the reflectance as its albedo. At most AOV_MAX_MIRRORS
// mirrors are followed. The state is one u32 and the reflectance waits in `result.albedo`: more live registers
// in the path loop cost occupancy (a first form with its own variables made the trace 4-17% slower on the H200).
const AOV_MIRROR_MAX_ALPHA: f32 = 0.005625;
const AOV_MAX_MIRRORS: u32 = 4u;
// `aov` state bits: the surface being shaded sets the AOVs; the AOVs follow the path (result.albedo holds the
// reflectance gathered so far); above them, the number of mirrors followed.
const AOV_OPEN: u32 = 1u;
const AOV_FOLLOWING: u32 = 2u;
const AOV_MIRROR_COUNT: u32 = 4u;

fn aov_is_mirror(b: BsdfParams) -> bool {
    return b.alpha <= AOV_MIRROR_MAX_ALPHA && b.metallic >= 0.5;
}

// The glossy lobe's reflectance seen from `wo` over the probability of sampling it.
fn aov_mirror_tint(wo: vec3<f32>, b: BsdfParams) -> vec3<f32> {
    let fw = pow5(1.0 - clamp(wo.z, 0.0, 1.0));
    let f_metal = b.base_color + (vec3<f32>(1.0) - b.base_color) * fw;
    let reflectance = mix(vec3<f32>(0.04 + 0.96 * fw), f_metal, b.metallic);
    return min(reflectance / max(specular_probability(wo, b), 1e-3), vec3<f32>(1.0));
}

struct PathResult {
    radiance: vec3<f32>,
    // The part of `radiance` that no surface scattered (exact: the denoiser leaves it alone).
    unscattered: vec3<f32>,
    albedo: vec3<f32>,
    normal: vec3<f32>,
    depth: f32,
    hit: bool,
}

// How a path begins. The real-time integrator (integrator/realtime.wgsl) starts from the camera ray's first hit,
// already traced into its G-buffer, and may estimate direct light at that hit itself (ReSTIR DI): then this
// integrator does no next-event estimation there, and the emitters and lights at infinity its BSDF-sampled ray
// meets next count for nothing, so that light is counted once.
struct PathStart {
    ray: Ray,
    first_hit: Hit,
    has_first_hit: bool,
    primary_direct_elsewhere: bool,
}

fn trace_path(camera_ray: Ray, forward: vec3<f32>, sampler: Sampler) -> PathResult {
    return trace_path_from(PathStart(camera_ray, Hit(MISS, NONE, 0u, vec2<f32>(0.0)), false, false), forward, sampler);
}

fn trace_path_from(start: PathStart, forward: vec3<f32>, first_sampler: Sampler) -> PathResult {
    var sampler = first_sampler;
    var result = PathResult(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), 0.0, false);
    var ray = start.ray;
    var first_pending = start.has_first_hit;
    var throughput = vec3<f32>(1.0);
    var depth = 0u;
    var pass_throughs = 0u;
    var last_bsdf_pdf = 0.0; // 0: camera ray, emission counts in full
    // Where the last scattering happened (what next-event estimation sampled lights from).
    var last_vertex = LightSampleContext(start.ray.origin, vec3<f32>(0.0));
    let nee = (frame.flags & FRAME_NEE) != 0u && light_count() > 0u;
    // A shadow ray waiting to be traced before the next path ray, and whether the path goes on after it.
    var shadow = DirectLight(ray, 0.0, vec3<f32>(0.0));
    var shadow_pending = false;
    var path_alive = true;
    var aov = 0u;
    // The volume the path ray travels in (KHR_materials_volume), named by its material; NONE in the open.
    var medium = NONE;
    // PATH_REGENERATION: the path has ended and the pixel's next sample starts here.
    var path_done = false;
    loop {
        if PATH_REGENERATION && path_done {
            regeneration.sums = add_sample(regeneration.sums, result);
            if regeneration.next >= regeneration.end { break; }
            let started = camera_sample(regeneration.pixel_xy, regeneration.pixel, frame.sample_base + regeneration.next);
            regeneration.next++;
            sampler = started.sampler;
            ray = started.ray;
            result = PathResult(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), 0.0, false);
            throughput = vec3<f32>(1.0);
            depth = 0u;
            pass_throughs = 0u;
            last_bsdf_pdf = 0.0;
            last_vertex = LightSampleContext(ray.origin, vec3<f32>(0.0));
            path_alive = true;
            aov = 0u;
            medium = NONE;
            path_done = false;
        }
        var next = ray;
        var t_max = MISS;
        if shadow_pending {
            next = shadow.ray;
            t_max = shadow.t_max;
        }
        var hit = start.first_hit;
        if first_pending {
            first_pending = false;
        } else {
            rays_traced++;
            hit = trace(next, t_max, shadow_pending);
        }
        if shadow_pending {
            if hit.instance == NONE { result.radiance += shadow.contribution; }
            shadow_pending = false;
            if path_alive { continue; }
            if PATH_REGENERATION { path_done = true; continue; }
            break;
        }
        if medium != NONE { throughput *= transmittance(medium, hit.t); }
        if hit.instance == NONE {
            // The lights at infinity are in the light list too: ReSTIR counted them at the first hit.
            if depth == 1u && start.primary_direct_elsewhere { break; }
            if PATH_AOVS && (aov & AOV_FOLLOWING) != 0u {
                result.albedo = vec3<f32>(0.0);
                result.normal = vec3<f32>(0.0);
            }
            let escaped = throughput * escaped_radiance(ray.dir, last_bsdf_pdf, nee);
            result.radiance += escaped;
            if PATH_AOVS && depth == 0u { result.unscattered += escaped; }
            if PATH_REGENERATION { path_done = true; continue; }
            break;
        }
        let s = resolve_hit(hit, ray);
        if PATH_AOVS && depth == 0u && !result.hit {
            result.hit = true;
            result.albedo = s.bsdf.base_color;
            result.normal = s.n;
            result.depth = hit.t * dot(ray.dir, forward);
            aov = AOV_OPEN;
        } else if PATH_AOVS && (aov & AOV_FOLLOWING) != 0u {
            result.albedo *= s.bsdf.base_color;
            result.normal = s.n;
            aov = (aov & ~AOV_FOLLOWING) | AOV_OPEN;
        }
        // Alpha blending as stochastic coverage: the path passes through with probability 1 - alpha.
        if (s.flags & MATERIAL_ALPHA_BLEND) != 0u && pass_throughs < MAX_PASS_THROUGHS
            && get_1d(sampler, DIM_PASS_THROUGH + depth * MAX_PASS_THROUGHS + pass_throughs) >= s.alpha {
            ray.origin = offset_ray_origin(s.p, -s.ng);
            pass_throughs++;
            aov &= ~AOV_OPEN;
            continue;
        }
        if any(s.emission > vec3<f32>(0.0)) && emits_towards_viewer(s) {
            var weight = 1.0;
            if nee && last_bsdf_pdf > 0.0 {
                weight = power_heuristic(last_bsdf_pdf, direct_pdf_of_hit(hit, s.p, last_vertex, ray.dir));
            }
            if depth == 1u && start.primary_direct_elsewhere { weight = 0.0; }
            result.radiance += throughput * s.emission * weight;
            if PATH_AOVS && depth == 0u { result.unscattered += throughput * s.emission * weight; }
        }
        // An unlit surface scatters nothing.
        if MATERIAL_LOBES != 0u && (s.flags & MATERIAL_UNLIT) != 0u {
            if PATH_REGENERATION { path_done = true; continue; }
            break;
        }
        if depth >= frame.max_depth {
            if PATH_REGENERATION { path_done = true; continue; }
            break;
        }

        let dims = bounce_dimensions(depth);
        let tbn = basis(s.n);
        let wo = -ray.dir * tbn;
        if nee && !(depth == 0u && start.primary_direct_elsewhere) {
            shadow = sample_direct(s, wo, tbn, sampler, dims, medium);
            shadow.contribution *= throughput;
            shadow_pending = any(shadow.contribution != vec3<f32>(0.0));
        }
        let bs = bsdf_sample(wo, s.bsdf, get_1d(sampler, dims + DIM_LOBE), get_2d(sampler, dims + DIM_DIRECTION));
        let dir = tbn * bs.wi;
        // The direction must leave on the side its lobe says: a reflection above the shading normal's horizon but
        // below the geometry's would leak light (and a transmission the other way round).
        let transmitted = (bs.flags & BSDF_TRANSMISSION) != 0u;
        path_alive = bs.pdf > 0.0 && (dot(dir, s.ng) > 0.0) != transmitted;
        if PATH_AOVS && (aov & AOV_OPEN) != 0u && path_alive && (bs.flags & BSDF_GLOSSY) != 0u && aov_is_mirror(s.bsdf)
            && aov < AOV_MAX_MIRRORS * AOV_MIRROR_COUNT {
            // The reflectance so far: 1 at the first mirror; at a later one, what reached it (its base colour
            // divided back out).
            let so_far = result.albedo / max(s.bsdf.base_color, vec3<f32>(1e-4));
            result.albedo = select(vec3<f32>(1.0), so_far, aov >= AOV_MIRROR_COUNT) * aov_mirror_tint(wo, s.bsdf);
            aov = aov + AOV_MIRROR_COUNT + AOV_FOLLOWING;
        }
        aov &= ~AOV_OPEN;
        if path_alive {
            throughput *= bs.weight;
            last_bsdf_pdf = bs.pdf;
            depth++;
            if depth >= frame.rr_depth {
                let survive = min(max(throughput.x, max(throughput.y, throughput.z)), 0.95);
                if get_1d(sampler, dims + DIM_ROULETTE) >= survive {
                    path_alive = false;
                } else {
                    throughput /= survive;
                }
            }
            ray = Ray(offset_ray_origin(s.p, select(s.ng, -s.ng, transmitted)), dir);
            if transmitted { medium = medium_after_transmission(s, medium); }
            last_vertex = LightSampleContext(s.p, s.ng);
        }
        if !path_alive && !shadow_pending {
            if PATH_REGENERATION { path_done = true; continue; }
            break;
        }
    }
    return result;
}

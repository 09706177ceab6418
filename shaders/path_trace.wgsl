// The path tracer: one invocation per pixel runs `frame.spp` paths and adds them to the accumulation buffers.
// Unidirectional path tracing with next-event estimation on emissive triangles, combined with BRDF sampling
// by multiple importance sampling (power heuristic). `max_depth` = surface interactions after the camera ray.

@group(1) @binding(0) var<storage, read_write> accum: array<vec4<f32>>;
// rgb: first-hit albedo sum, w: camera-space depth sum.
@group(1) @binding(1) var<storage, read_write> aov_albedo_depth: array<vec4<f32>>;
// xyz: first-hit shading normal sum, w: number of samples that hit a surface.
@group(1) @binding(2) var<storage, read_write> aov_normal: array<vec4<f32>>;
// Rays traced by the last dispatch (camera, bounce and shadow rays), for rays/s figures.
@group(1) @binding(3) var<storage, read_write> ray_counter: array<atomic<u32>>;
// What the ray through the pixel centre hits first: instance (NONE: nothing), triangle slot, barycentrics as
// f32 bits. Written only with FRAME_HIT_AOV, once per accumulation (a 16-byte stub is bound otherwise).
@group(1) @binding(4) var<storage, read_write> aov_hit: array<vec4<u32>>;
// For the denoiser: rgb: radiance that reached the camera unscattered (emission seen directly, or the
// environment where the camera ray missed) summed; w: sum of luminance(scattered radiance)^2.
@group(1) @binding(5) var<storage, read_write> moments: array<vec4<f32>>;

var<private> rays_traced: u32;
var<workgroup> workgroup_rays: atomic<u32>;

struct Surface {
    p: vec3<f32>,
    ng: vec3<f32>,      // geometric normal, facing the incoming ray
    n: vec3<f32>,       // shading normal, facing the incoming ray
    front: bool,        // hit the side the triangle's winding faces
    brdf: BrdfParams,
    alpha: f32,
    emission: vec3<f32>,
    flags: u32,
}

fn environment(dir: vec3<f32>) -> vec3<f32> {
    if frame.env_mode == 1u {
        // Sky gradient: white at the horizon and below, blue towards the zenith.
        let t = 0.5 * (dir.y + 1.0);
        return mix(vec3<f32>(1.0), vec3<f32>(0.5, 0.7, 1.0), t);
    }
    return frame.env_color;
}

fn interpolate_uv(offset: u32, tri: vec4<u32>, w: vec3<f32>) -> vec2<f32> {
    return pool_vec2(offset + 2u * tri.x) * w.x + pool_vec2(offset + 2u * tri.y) * w.y + pool_vec2(offset + 2u * tri.z) * w.z;
}

fn texture_uv(texture: u32, mesh: Mesh, tri: vec4<u32>, w: vec3<f32>) -> vec2<f32> {
    let offset = select(mesh.uv0_offset, mesh.uv1_offset, (texture >> 24u) == 1u);
    if offset == NONE { return vec2<f32>(0.0); }
    return interpolate_uv(offset, tri, w);
}

fn surface_at(hit: Hit, ray: Ray) -> Surface {
    let inst = instances[hit.instance];
    let mesh = meshes[inst.mesh];
    let tri = triangles[hit.triangle];
    let m = materials[tri.w];
    let w = vec3<f32>(1.0 - hit.bary.x - hit.bary.y, hit.bary.x, hit.bary.y);
    let p0 = transform_point(inst.world_from_object, vertex_position(mesh, tri.x));
    let p1 = transform_point(inst.world_from_object, vertex_position(mesh, tri.y));
    let p2 = transform_point(inst.world_from_object, vertex_position(mesh, tri.z));
    var s: Surface;
    // The hit point from world-space barycentrics is more precise than origin + t * dir.
    s.p = p0 * w.x + p1 * w.y + p2 * w.z;
    var ng = normalize(cross(p1 - p0, p2 - p0));
    s.front = dot(ng, ray.dir) < 0.0;
    if !s.front { ng = -ng; }
    s.ng = ng;

    var n = ng;
    if mesh.normal_offset != NONE {
        let a = vertex_pool[mesh.normal_offset + tri.x];
        let b = vertex_pool[mesh.normal_offset + tri.y];
        let c = vertex_pool[mesh.normal_offset + tri.z];
        if a != INVALID_OCT && b != INVALID_OCT && c != INVALID_OCT {
            let interpolated = transform_normal(inst.object_from_world, oct_decode(a) * w.x + oct_decode(b) * w.y + oct_decode(c) * w.z);
            if dot(interpolated, interpolated) > 1e-12 {
                n = normalize(interpolated);
                if !s.front { n = -n; }
            }
        }
    }

    var base = m.base_color;
    if m.base_color_texture != NONE {
        let t = sample_texture(m.base_color_texture, texture_uv(m.base_color_texture, mesh, tri, w));
        base *= vec4<f32>(srgb_to_linear(t.rgb), t.a);
    }
    if mesh.color_offset != NONE {
        base *= unpack4x8unorm(vertex_pool[mesh.color_offset + tri.x]) * w.x
            + unpack4x8unorm(vertex_pool[mesh.color_offset + tri.y]) * w.y
            + unpack4x8unorm(vertex_pool[mesh.color_offset + tri.z]) * w.z;
    }
    var metallic = m.metallic;
    var roughness = m.roughness;
    if m.metallic_roughness_texture != NONE {
        let t = sample_texture(m.metallic_roughness_texture, texture_uv(m.metallic_roughness_texture, mesh, tri, w));
        roughness *= t.g;
        metallic *= t.b;
    }
    if m.normal_texture != NONE && mesh.tangent_offset != NONE {
        let ta = vertex_pool[mesh.tangent_offset + 2u * tri.x];
        let tb = vertex_pool[mesh.tangent_offset + 2u * tri.y];
        let tc = vertex_pool[mesh.tangent_offset + 2u * tri.z];
        if ta != INVALID_OCT && tb != INVALID_OCT && tc != INVALID_OCT {
            let sign = bitcast<f32>(vertex_pool[mesh.tangent_offset + 2u * tri.x + 1u]);
            var t = transform_vector(inst.world_from_object, oct_decode(ta) * w.x + oct_decode(tb) * w.y + oct_decode(tc) * w.z);
            t = t - n * dot(n, t);
            if dot(t, t) > 1e-12 {
                t = normalize(t);
                // On back faces n was flipped; the bitangent must follow the surface's own orientation.
                let b = cross(select(-n, n, s.front), t) * sign;
                let tex = sample_texture(m.normal_texture, texture_uv(m.normal_texture, mesh, tri, w)).xyz * 2.0 - 1.0;
                let local = vec3<f32>(tex.xy * m.normal_scale, tex.z);
                let mapped = t * local.x + b * local.y + n * local.z;
                if dot(mapped, mapped) > 1e-12 { n = normalize(mapped); }
            }
        }
    }
    // A shading normal facing away from the viewer would make the BRDF vanish: bend it back just enough.
    let v = -ray.dir;
    let nv = dot(n, v);
    if nv < 1e-3 { n = normalize(n + (1e-3 - nv) * v); }
    s.n = n;

    var emission = m.emissive;
    if m.emissive_texture != NONE && any(emission > vec3<f32>(0.0)) {
        emission *= srgb_to_linear(sample_texture(m.emissive_texture, texture_uv(m.emissive_texture, mesh, tri, w)).rgb);
    }
    s.emission = emission;
    s.brdf = BrdfParams(base.rgb, clamp(metallic, 0.0, 1.0), max(roughness * roughness, MIN_ALPHA));
    s.alpha = base.a;
    s.flags = m.flags;
    return s;
}

fn emits_towards_viewer(s: Surface) -> bool {
    return s.front || (s.flags & MATERIAL_DOUBLE_SIDED) != 0u;
}

// World-space area of a triangle slot of an instance.
fn world_triangle(instance: u32, slot: u32) -> array<vec3<f32>, 3> {
    let inst = instances[instance];
    let mesh = meshes[inst.mesh];
    let tri = triangles[slot];
    return array<vec3<f32>, 3>(
        transform_point(inst.world_from_object, vertex_position(mesh, tri.x)),
        transform_point(inst.world_from_object, vertex_position(mesh, tri.y)),
        transform_point(inst.world_from_object, vertex_position(mesh, tri.z)));
}

// Probability density (solid angle) that next-event estimation picks the point `hit` seen from `origin`.
fn light_pdf(hit: Hit, s: Surface, distance: f32, dir: vec3<f32>) -> f32 {
    let p = world_triangle(hit.instance, hit.triangle);
    let cross_p = cross(p[1] - p[0], p[2] - p[0]);
    let area = 0.5 * length(cross_p);
    let power = luminance(materials[triangles[hit.triangle].w].emissive) * area;
    let cos_l = abs(dot(s.ng, dir));
    if area <= 0.0 || cos_l <= 0.0 || frame.emitter_total_power <= 0.0 { return 0.0; }
    // pmf = power / total; area pdf = pmf / area; solid-angle pdf = area pdf * d^2 / cos.
    return (power / frame.emitter_total_power) / area * distance * distance / cos_l;
}

fn power_heuristic(a: f32, b: f32) -> f32 {
    let a2 = a * a;
    return a2 / (a2 + b * b);
}

// A light sample for next-event estimation: the shadow ray to test and what it adds when unblocked.
struct LightSample {
    ray: Ray,
    t_max: f32,
    // Unoccluded contribution (BRDF x cos x emission x MIS weight / pdf); zero when nothing to test.
    contribution: vec3<f32>,
}

// Direct light from one emissive triangle picked by power, weighted against BRDF sampling. The shadow ray is
// returned, not traced, so that the path loop traces every ray at one call site (smaller kernel).
fn sample_light(s: Surface, v_local: vec3<f32>, frame_basis: mat3x3<f32>, rng: ptr<function, Rng>) -> LightSample {
    var none = LightSample(Ray(vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0)), 0.0, vec3<f32>(0.0));
    let u = rand(rng);
    var lo = 0u;
    var hi = frame.emitter_count - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if emitters[mid].cdf < u { lo = mid + 1u; } else { hi = mid; }
    }
    let e = emitters[lo];
    let p = world_triangle(e.instance, e.triangle);
    var b1 = rand(rng);
    var b2 = rand(rng);
    if b1 + b2 > 1.0 { b1 = 1.0 - b1; b2 = 1.0 - b2; }
    let point = p[0] * (1.0 - b1 - b2) + p[1] * b1 + p[2] * b2;
    let cross_p = cross(p[1] - p[0], p[2] - p[0]);
    let area = 0.5 * length(cross_p);
    if area <= 0.0 { return none; }
    let nl = cross_p / (2.0 * area);
    let m = materials[triangles[e.triangle].w];
    let origin = offset_ray_origin(s.p, s.ng);
    let to_light = point - origin;
    let dist2 = dot(to_light, to_light);
    let dist = sqrt(dist2);
    let dir = to_light / dist;
    let cos_l_signed = -dot(nl, dir);
    let double_sided = (m.flags & MATERIAL_DOUBLE_SIDED) != 0u;
    if cos_l_signed <= 0.0 && !double_sided { return none; }
    let cos_l = abs(cos_l_signed);
    if cos_l <= 1e-7 || dot(dir, s.ng) <= 0.0 { return none; }
    let l_local = dir * frame_basis;
    let f = brdf_eval(v_local, l_local, s.brdf);
    if all(f == vec3<f32>(0.0)) { return none; }
    var emission = m.emissive;
    if m.emissive_texture != NONE {
        let inst = instances[e.instance];
        let mesh = meshes[inst.mesh];
        emission *= srgb_to_linear(sample_texture(m.emissive_texture, texture_uv(m.emissive_texture, mesh, triangles[e.triangle], vec3<f32>(1.0 - b1 - b2, b1, b2))).rgb);
    }
    let power = luminance(m.emissive) * area;
    let pdf_light = (power / frame.emitter_total_power) / area * dist2 / cos_l;
    let pdf_brdf = brdf_pdf(v_local, l_local, s.brdf);
    // Stop the shadow ray just short of the light so it cannot hit the light itself.
    return LightSample(Ray(origin, dir), dist * (1.0 - 1e-4), f * l_local.z * emission * power_heuristic(pdf_light, pdf_brdf) / pdf_light);
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

fn trace_path(camera_ray: Ray, forward: vec3<f32>, rng: ptr<function, Rng>) -> PathResult {
    var result = PathResult(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), 0.0, false);
    var ray = camera_ray;
    var throughput = vec3<f32>(1.0);
    var depth = 0u;
    var pass_throughs = 0u;
    var last_brdf_pdf = 0.0; // 0: camera ray, emission counts in full
    let nee = (frame.flags & FRAME_NEE) != 0u && frame.emitter_count > 0u;
    // A shadow ray waiting to be traced before the next path ray, and whether the path goes on after it.
    var shadow = LightSample(ray, 0.0, vec3<f32>(0.0));
    var shadow_pending = false;
    var path_alive = true;
    loop {
        rays_traced++;
        var next = ray;
        var t_max = MISS;
        if shadow_pending {
            next = shadow.ray;
            t_max = shadow.t_max;
        }
        let hit = trace(next, t_max, shadow_pending);
        if shadow_pending {
            if hit.instance == NONE { result.radiance += shadow.contribution; }
            shadow_pending = false;
            if path_alive { continue; }
            break;
        }
        if hit.instance == NONE {
            result.radiance += throughput * environment(ray.dir);
            if depth == 0u { result.unscattered += throughput * environment(ray.dir); }
            break;
        }
        let s = surface_at(hit, ray);
        if depth == 0u && !result.hit {
            result.hit = true;
            result.albedo = s.brdf.base_color;
            result.normal = s.n;
            result.depth = hit.t * dot(ray.dir, forward);
        }
        // Alpha blending as stochastic coverage: the path passes through with probability 1 - alpha.
        if (s.flags & MATERIAL_ALPHA_BLEND) != 0u && rand(rng) >= s.alpha && pass_throughs < 16u {
            ray.origin = offset_ray_origin(s.p, -s.ng);
            pass_throughs++;
            continue;
        }
        if any(s.emission > vec3<f32>(0.0)) && emits_towards_viewer(s) {
            var weight = 1.0;
            if nee && last_brdf_pdf > 0.0 {
                weight = power_heuristic(last_brdf_pdf, light_pdf(hit, s, hit.t, ray.dir));
            }
            result.radiance += throughput * s.emission * weight;
            if depth == 0u { result.unscattered += throughput * s.emission * weight; }
        }
        if depth >= frame.max_depth { break; }

        let tbn = basis(s.n);
        let v_local = -ray.dir * tbn;
        if nee {
            shadow = sample_light(s, v_local, tbn, rng);
            shadow.contribution *= throughput;
            shadow_pending = any(shadow.contribution != vec3<f32>(0.0));
        }
        let bs = brdf_sample(v_local, s.brdf, vec3<f32>(rand(rng), rand(rng), rand(rng)));
        let dir = tbn * bs.l;
        // A direction above the shading normal's horizon but below the geometry's would leak light.
        path_alive = bs.pdf > 0.0 && dot(dir, s.ng) > 0.0;
        if path_alive {
            throughput *= bs.weight;
            last_brdf_pdf = bs.pdf;
            depth++;
            if depth >= frame.rr_depth {
                let survive = min(max(throughput.x, max(throughput.y, throughput.z)), 0.95);
                if rand(rng) >= survive {
                    path_alive = false;
                } else {
                    throughput /= survive;
                }
            }
            ray = Ray(offset_ray_origin(s.p, s.ng), dir);
        }
        if !path_alive && !shadow_pending { break; }
    }
    return result;
}

fn finite3(v: vec3<f32>) -> bool {
    // NaN fails every comparison; infinities exceed the largest finite f32.
    return all(abs(v) <= vec3<f32>(3.0e38));
}

@compute @workgroup_size(8, 8)
fn trace_pixels(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    rays_traced = 0u;
    if gid.x < frame.width && gid.y < frame.height {
        trace_pixel(gid.xy);
    }
    // One global atomic per workgroup keeps the counter off the critical path.
    atomicAdd(&workgroup_rays, rays_traced);
    workgroupBarrier();
    if lid == 0u {
        atomicAdd(&ray_counter[0], atomicLoad(&workgroup_rays));
    }
}

fn trace_pixel(gid: vec2<u32>) {
    let pixel = gid.y * frame.width + gid.x;
    let cam = frame.world_from_camera;
    let origin = cam[3].xyz;
    let forward = -cam[2].xyz;
    if (frame.flags & FRAME_HIT_AOV) != 0u && frame.sample_base == 0u {
        rays_traced++;
        let hit = trace(Ray(origin, camera_ray_dir(gid, vec2<f32>(0.5))), MISS, false);
        aov_hit[pixel] = vec4<u32>(hit.instance, hit.triangle, bitcast<u32>(hit.bary.x), bitcast<u32>(hit.bary.y));
    }
    var radiance = vec3<f32>(0.0);
    var albedo_depth = vec4<f32>(0.0);
    var normal_hits = vec4<f32>(0.0);
    var unscattered_m2 = vec4<f32>(0.0);
    for (var s = 0u; s < frame.spp; s++) {
        var rng = rng_new(pixel, frame.sample_base + s, frame.seed);
        // Box filter: a uniform point in the pixel.
        let jitter = vec2<f32>(rand(&rng), rand(&rng));
        let dir = camera_ray_dir(gid, jitter);
        let r = trace_path(Ray(origin, dir), forward, &rng);
        // A non-finite sample would poison the pixel forever; it is dropped (it should never happen).
        if finite3(r.radiance) {
            radiance += r.radiance;
            // Capped so that a firefly's square cannot overflow the sum.
            let l = min(max(luminance(r.radiance - r.unscattered), 0.0), 1e15);
            unscattered_m2 += vec4<f32>(r.unscattered, l * l);
        }
        if r.hit {
            albedo_depth += vec4<f32>(r.albedo, r.depth);
            normal_hits += vec4<f32>(r.normal, 1.0);
        }
    }
    accum[pixel] += vec4<f32>(radiance, f32(frame.spp));
    aov_albedo_depth[pixel] += albedo_depth;
    aov_normal[pixel] += normal_hits;
    if (frame.flags & FRAME_MOMENTS) != 0u {
        moments[pixel] += unscattered_m2;
    }
}

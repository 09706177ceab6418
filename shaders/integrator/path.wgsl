// The path integrator: unidirectional path tracing with next-event estimation on the lights, combined with
// BSDF sampling by multiple importance sampling (power heuristic), and Russian roulette. `max_depth` = surface
// interactions after the camera ray. It only calls the library: traversal (`trace`), `resolve_hit`, the BSDF,
// the lights and the environment. The kernel counts rays in `rays_traced`.

var<private> rays_traced: u32;

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
    var last_bsdf_pdf = 0.0; // 0: camera ray, emission counts in full
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
        let s = resolve_hit(hit, ray);
        if depth == 0u && !result.hit {
            result.hit = true;
            result.albedo = s.bsdf.base_color;
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
            if nee && last_bsdf_pdf > 0.0 {
                weight = power_heuristic(last_bsdf_pdf, light_pdf(hit, s, hit.t, ray.dir));
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
        let u_lobe = rand(rng);
        let u_dir = vec2<f32>(rand(rng), rand(rng));
        let bs = bsdf_sample(v_local, s.bsdf, u_lobe, u_dir);
        let dir = tbn * bs.wi;
        // A direction above the shading normal's horizon but below the geometry's would leak light.
        path_alive = bs.pdf > 0.0 && dot(dir, s.ng) > 0.0;
        if path_alive {
            throughput *= bs.weight;
            last_bsdf_pdf = bs.pdf;
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

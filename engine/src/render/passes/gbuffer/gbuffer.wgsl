// The G-buffer pass: one jittered camera ray per pixel (the same ray the real-time path then shades, from the
// same sampler dimensions), and what it hit: position, depth, stable object id, triangle and barycentrics,
// normals, packed BSDF, material, and where that point was one frame earlier (motion vector and previous
// depth), from the previous camera, the instance's previous placement and its mesh's previous positions.
// The previous frame's G-buffer is kept: each pixel moves its old surface there before writing the new one.

@group(1) @binding(2) var<storage, read_write> gbuffer: array<GSurface>;
@group(1) @binding(3) var<storage, read_write> gbuffer_prev: array<GSurface>;
@group(1) @binding(4) var<storage, read_write> ray_counter: array<atomic<u32>>;

var<workgroup> workgroup_rays: atomic<u32>;

@compute @workgroup_size(8, 8)
fn write_gbuffer(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    rays_traced = 0u;
    if gid.x < frame.width && gid.y < frame.height {
        let pixel = gid.y * frame.width + gid.x;
        gbuffer_prev[pixel] = gbuffer[pixel];
        gbuffer[pixel] = primary_surface(gid.xy, pixel);
    }
    atomicAdd(&workgroup_rays, rays_traced);
    workgroupBarrier();
    if lid == 0u {
        atomicAdd(&ray_counter[0], atomicLoad(&workgroup_rays));
    }
}

fn primary_surface(gid: vec2<u32>, pixel: u32) -> GSurface {
    let sampler = sampler_start(pixel, frame.sample_base, frame.seed);
    let u_film = get_2d_independent(sampler, DIM_FILM);
    let ray = generate_ray(gid, u_film, get_2d(sampler, DIM_LENS));
    let here = vec2<f32>(gid) + u_film;
    rays_traced++;
    let hit = trace(ray, MISS, false);
    var g = gsurface_miss();
    if hit.instance == NONE {
        // The environment is at infinity: only the camera's rotation moves it.
        let before = project_direction(realtime.prev_camera_from_world, realtime.prev_tan_half_fov, ray.dir);
        g.motion = select(vec2<f32>(0.0), before.xy - here, before.z > 0.0);
        return g;
    }
    let s = resolve_hit(hit, ray);
    g.position = s.p;
    g.depth = hit.t * dot(ray.dir, camera_forward());
    g.object = motion_instances[hit.instance].object;
    g.triangle = hit.triangle;
    g.bary = hit.bary;
    g.normal = oct_encode(s.n);
    g.geometric = oct_encode(s.ng);
    g.bsdf = pack_bsdf(s.bsdf);
    g.material = s.material;
    let before = project_point(realtime.prev_camera_from_world, realtime.prev_tan_half_fov,
        previous_world_position(hit.instance, hit.triangle, hit.bary));
    // Behind the previous camera: no history can match (prev_depth < 0 fails every depth test).
    g.motion = select(vec2<f32>(0.0), before.xy - here, before.z > 0.0);
    g.prev_depth = select(-1.0, before.z, before.z > 0.0);
    return g;
}

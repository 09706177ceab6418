// Ray-casting throughput without shading, the workload of the speed targets' "primary" and "diffuse bounce"
// rays: traversal and intersection only. `frame.max_depth` 0: one camera ray through each pixel centre; 1: the
// camera ray, then from its hit one cosine-distributed ray about the geometric normal (closest hit).
// The summed hit distances are written out so that no work can be optimised away.

@group(1) @binding(1) var<storage, read_write> hit_distance: array<f32>;
// [0]: rays cast (camera + bounce).
@group(1) @binding(2) var<storage, read_write> rays_cast: array<atomic<u32>>;
// With TRAVERSAL_STATS (traversal/stats.wgsl): the work of camera rays (counters 0-3) and bounce rays (4-7),
// each counter a 64-bit sum as (low, high) words.
@group(1) @binding(3) var<storage, read_write> work_counts: array<atomic<u32>>;

// Adds this invocation's traversal work to counters `first`..`first + 3`, then clears it.
fn add_work(first: u32) {
    if TRAVERSAL_STATS {
        for (var k = 0u; k < 4u; k++) {
            let i = 2u * (first + k);
            let n = traversal_work[k];
            let old = atomicAdd(&work_counts[i], n);
            if old + n < old { atomicAdd(&work_counts[i + 1u], 1u); }
        }
        traversal_work = vec4<u32>(0u);
    }
}

fn geometric_normal(hit: Hit) -> vec3<f32> {
    let p = world_triangle(hit.instance, hit.triangle);
    return normalize(cross(p[1] - p[0], p[2] - p[0]));
}

@compute @workgroup_size(8, 8)
fn cast_rays(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height { return; }
    let pixel = gid.y * frame.width + gid.x;
    let ray = Ray(camera_origin(), camera_ray_dir(gid.xy, vec2<f32>(0.5)));
    let hit = trace(ray, MISS, false);
    add_work(0u);
    var distance = hit.t;
    var rays = 1u;
    if frame.max_depth > 0u && hit.instance != NONE {
        var ng = geometric_normal(hit);
        if dot(ng, ray.dir) > 0.0 { ng = -ng; }
        let p = ray.origin + ray.dir * hit.t;
        let sampler = sampler_start(pixel, frame.sample_base, frame.seed);
        let dir = basis(ng) * sample_cosine_hemisphere(get_2d(sampler, 0u));
        let bounce = trace(Ray(offset_ray_origin(p, ng), dir), MISS, false);
        add_work(4u);
        distance += min(bounce.t, 1e30);
        rays += 1u;
    }
    hit_distance[pixel] = distance;
    atomicAdd(&rays_cast[0], rays);
}

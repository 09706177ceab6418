// The trace pass's kernel: one invocation per pixel runs `frame.spp` paths through the path integrator and adds
// them to the view's accumulation targets (engine/src/render/view.rs), with the first-hit AOVs and the
// denoiser's moments where the kernel is compiled with them (`PATH_AOVS`).

@group(1) @binding(1) var<storage, read_write> accum: array<vec4<f32>>;
// rgb: first-hit albedo sum, w: camera-space depth sum.
@group(1) @binding(2) var<storage, read_write> aov_albedo_depth: array<vec4<f32>>;
// xyz: first-hit shading normal sum, w: number of samples that hit a surface.
@group(1) @binding(3) var<storage, read_write> aov_normal: array<vec4<f32>>;
// Rays traced by the last dispatch (camera, bounce and shadow rays), for rays/s figures.
@group(1) @binding(4) var<storage, read_write> ray_counter: array<atomic<u32>>;
// What the ray through the pixel centre hits first: instance (NONE: nothing), triangle slot, barycentrics as
// f32 bits. Written only with FRAME_HIT_AOV, once per accumulation (a 16-byte stub is bound otherwise).
@group(1) @binding(5) var<storage, read_write> aov_hit: array<vec4<u32>>;
// For the denoiser: rgb: radiance that reached the camera unscattered (emission seen directly, or the
// environment where the camera ray missed) summed; w: sum of luminance(scattered radiance)^2.
@group(1) @binding(6) var<storage, read_write> moments: array<vec4<f32>>;

var<workgroup> workgroup_rays: atomic<u32>;

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
    let origin = camera_origin();
    let forward = camera_forward();
    if (frame.flags & FRAME_HIT_AOV) != 0u && frame.sample_base == 0u {
        rays_traced++;
        let hit = trace(Ray(origin, camera_ray_dir(gid, vec2<f32>(0.5))), MISS, false);
        aov_hit[pixel] = vec4<u32>(hit.instance, hit.triangle, bitcast<u32>(hit.bary.x), bitcast<u32>(hit.bary.y));
    }
    var sums = PixelSums(vec3<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    if PATH_REGENERATION {
        // One path loop over all the samples (integrator/path.wgsl): a lane whose path ends starts its next one.
        if frame.spp > 0u {
            regeneration = Regeneration(gid, pixel, 1u, frame.spp, sums);
            let first = camera_sample(gid, pixel, frame.sample_base);
            trace_path(first.ray, forward, first.sampler);
            sums = regeneration.sums;
        }
    } else {
        for (var s = 0u; s < frame.spp; s++) {
            let sample = camera_sample(gid, pixel, frame.sample_base + s);
            sums = add_sample(sums, trace_path(sample.ray, forward, sample.sampler));
        }
    }
    accum[pixel] += vec4<f32>(sums.radiance, f32(frame.spp));
    if !PATH_AOVS { return; }
    aov_albedo_depth[pixel] += sums.albedo_depth;
    aov_normal[pixel] += sums.normal_hits;
    moments[pixel] += sums.unscattered_m2;
}

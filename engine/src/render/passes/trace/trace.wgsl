// The trace pass's kernel: the invocations of a pixel run `frame.spp` paths through the path integrator and add
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

// Whether the kernel can write `aov_hit` (the frame asks with FRAME_HIT_AOV): views without the hit AOV, every
// render and bench frame, compile without its traversal of the pixel centre's ray, a second inlined copy of
// `trace` (lavapipe spends 9% of its pipeline compile on it: docs/BENCHMARKS.md).
override PATH_HIT_AOV: bool = true;

var<workgroup> workgroup_rays: atomic<u32>;
// One of each invocation's sums of its samples, where several share a pixel (`frame.sample_lanes` > 1): a vec4
// at a time keeps the workgroup's memory at 1 KB (an SM's shared memory comes out of its L1 cache).
var<workgroup> lane_sums: array<vec4<f32>, 64>;

// A workgroup of 64 invocations covers a tile of pixels, `frame.sample_lanes` invocations to a pixel (a power of
// two, at most 16; passes/trace/mod.rs `sample_lanes` says when): lane k of a pixel traces the dispatch's samples
// k, k + lanes, ..., and lane 0 adds the other lanes' sums to its own and writes the pixel.
@compute @workgroup_size(64)
fn trace_pixels(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    rays_traced = 0u;
    let lanes = frame.sample_lanes;
    let lane = lid & (lanes - 1u);
    let tile = pixel_tile(lanes);
    let in_tile = lid / lanes;
    let gid = group.xy * tile + vec2<u32>(in_tile % tile.x, in_tile / tile.x);
    let inside = gid.x < frame.width && gid.y < frame.height;
    var sums = PixelSums(vec3<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    if inside {
        sums = trace_samples(gid, lane, lanes);
    }
    if lanes > 1u {
        sums.radiance = sum_over_lanes(vec4<f32>(sums.radiance, 0.0), lid, lane, lanes).rgb;
        if PATH_AOVS {
            sums.albedo_depth = sum_over_lanes(sums.albedo_depth, lid, lane, lanes);
            sums.normal_hits = sum_over_lanes(sums.normal_hits, lid, lane, lanes);
            sums.unscattered_m2 = sum_over_lanes(sums.unscattered_m2, lid, lane, lanes);
        }
    }
    if inside && lane == 0u {
        add_to_pixel(gid.y * frame.width + gid.x, sums);
    }
    // One global atomic per workgroup keeps the counter off the critical path.
    atomicAdd(&workgroup_rays, rays_traced);
    workgroupBarrier();
    if lid == 0u {
        atomicAdd(&ray_counter[0], atomicLoad(&workgroup_rays));
    }
}

// The pixels of a workgroup with `lanes` invocations to a pixel: 8x8 for one, 4x8, 4x4, 2x4, 2x2 for sixteen
// (passes/trace/mod.rs `pixel_tile` dispatches by the same tiles).
fn pixel_tile(lanes: u32) -> vec2<u32> {
    let log2 = countTrailingZeros(lanes);
    return vec2<u32>(8u >> ((log2 + 1u) / 2u), 8u >> (log2 / 2u));
}

// This lane's samples of the pixel, summed.
fn trace_samples(gid: vec2<u32>, lane: u32, lanes: u32) -> PixelSums {
    let pixel = gid.y * frame.width + gid.x;
    let origin = camera_origin();
    let forward = camera_forward();
    if PATH_HIT_AOV && (frame.flags & FRAME_HIT_AOV) != 0u && frame.sample_base == 0u && lane == 0u {
        rays_traced++;
        let hit = trace(Ray(origin, camera_ray_dir(gid, vec2<f32>(0.5))), MISS, false);
        aov_hit[pixel] = vec4<u32>(hit.instance, hit.triangle, bitcast<u32>(hit.bary.x), bitcast<u32>(hit.bary.y));
    }
    var sums = PixelSums(vec3<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    if PATH_REGENERATION {
        // One path loop over all the samples (integrator/path.wgsl): a lane whose path ends starts its next one.
        // (Regeneration runs with one lane to a pixel.)
        if frame.spp > 0u {
            regeneration = Regeneration(gid, pixel, 1u, frame.spp, sums);
            let first = camera_sample(gid, pixel, frame.sample_base);
            trace_path(first.ray, forward, first.sampler);
            sums = regeneration.sums;
        }
    } else {
        for (var s = lane; s < frame.spp; s += lanes) {
            let sample = camera_sample(gid, pixel, frame.sample_base + s);
            sums = add_sample(sums, trace_path(sample.ray, forward, sample.sampler));
        }
    }
    return sums;
}

// In lane 0 of a pixel: `value` summed over the pixel's lanes (the other lanes get theirs back).
fn sum_over_lanes(value: vec4<f32>, lid: u32, lane: u32, lanes: u32) -> vec4<f32> {
    lane_sums[lid] = value;
    workgroupBarrier();
    var sum = value;
    if lane == 0u {
        for (var k = 1u; k < lanes; k++) {
            sum += lane_sums[lid + k];
        }
    }
    // Every lane has been read before the next sum writes the array again.
    workgroupBarrier();
    return sum;
}

fn add_to_pixel(pixel: u32, sums: PixelSums) {
    accum[pixel] += vec4<f32>(sums.radiance, f32(frame.spp));
    if !PATH_AOVS { return; }
    aov_albedo_depth[pixel] += sums.albedo_depth;
    aov_normal[pixel] += sums.normal_hits;
    moments[pixel] += sums.unscattered_m2;
}

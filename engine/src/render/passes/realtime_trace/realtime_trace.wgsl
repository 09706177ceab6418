// The real-time trace pass: one path per pixel from the G-buffer's first hit (integrator/realtime.wgsl), with
// direct light there from ReSTIR DI when it ran. At each gradient stratum's chosen pixel it also records the
// luminance of the reproducible estimate that next frame's gradient pass shades again (A-SVGF).

@group(1) @binding(2) var<storage, read> gbuffer: array<GSurface>;
// ReSTIR DI's direct light at the first hit (a 16-byte stub while ReSTIR is off).
@group(1) @binding(3) var<storage, read> direct_light: array<vec4<f32>>;
@group(1) @binding(4) var<storage, read_write> samples: array<RealtimeSample>;
// Per gradient stratum: the estimate's luminance at its chosen pixel, < 0 where there is none.
@group(1) @binding(5) var<storage, read_write> gradient_estimates: array<f32>;
@group(1) @binding(6) var<storage, read_write> ray_counter: array<atomic<u32>>;

var<workgroup> workgroup_rays: atomic<u32>;

@compute @workgroup_size(8, 8)
fn trace_realtime(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    rays_traced = 0u;
    if gid.x < frame.width && gid.y < frame.height {
        trace_realtime_pixel(gid.xy);
    }
    atomicAdd(&workgroup_rays, rays_traced);
    workgroupBarrier();
    if lid == 0u {
        atomicAdd(&ray_counter[0], atomicLoad(&workgroup_rays));
    }
}

fn trace_realtime_pixel(gid: vec2<u32>) {
    let pixel = gid.y * frame.width + gid.x;
    let g = gbuffer[pixel];
    let sampler = sampler_start(pixel, frame.sample_base, frame.seed);
    // The G-buffer pass's ray, from the same dimensions.
    let ray = generate_ray(gid, get_2d_independent(sampler, DIM_FILM), get_2d(sampler, DIM_LENS));
    let first = gsurface_first_hit(g, ray.origin);
    let restir = realtime_flag(RT_RESTIR);
    let r = trace_path_from(PathStart(ray, first, true, restir), camera_forward(), sampler);
    var radiance = r.radiance;
    if restir { radiance += direct_light[pixel].rgb; }
    if realtime_flag(RT_INJECT_NONFINITE) {
        // Tests only: prove that a NaN or infinite sample never reaches the history.
        let nan = bitcast<f32>(0x7fc00000u);
        let inf = bitcast<f32>(0x7f800000u);
        radiance = select(radiance, vec3<f32>(nan), pixel % 7u == 3u);
        radiance = select(radiance, vec3<f32>(inf, 0.0, 0.0), pixel % 7u == 5u);
    }
    let valid = finite3(radiance) && finite3(r.unscattered);
    samples[pixel] = RealtimeSample(select(vec3<f32>(0.0), radiance, valid), u32(valid),
        select(vec3<f32>(0.0), r.unscattered, valid), 0u);

    let stratum = stratum_of(gid);
    if realtime_flag(RT_GRADIENTS) && all(gid == gradient_source(stratum, frame.sample_base)) {
        var estimate = -1.0;
        if valid && first.instance != NONE {
            var total = r.radiance;
            if restir {
                total += light_sampled_direct(surface_shading_point(resolve_hit(first, ray), ray), sampler);
            }
            estimate = select(-1.0, luminance(total), finite3(total));
        }
        gradient_estimates[stratum.y * realtime.strata_width + stratum.x] = estimate;
    }
}

// The light sampler (pbrt-v4 `PowerLightSampler`): picks a light in proportion to its power (luminance x world
// area for emissive triangles), from the CDF the CPU built (engine/src/render/gpu_scene/instances.rs), and
// gives the probability of any light it can pick.

struct LightChoice {
    light: u32,
    pmf: f32,
}

fn light_count() -> u32 {
    return frame.emitter_count;
}

fn light_sampler_sample(u: f32) -> LightChoice {
    var lo = 0u;
    var hi = frame.emitter_count - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if emitters[mid].cdf < u { lo = mid + 1u; } else { hi = mid; }
    }
    return LightChoice(lo, emitters[lo].pmf);
}

// Probability of picking the emissive triangle a BSDF-sampled ray hit, from the same power the CPU weighed it by
// (a hit knows its triangle, not its index in the light list).
fn light_sampler_pmf_area(emission: vec3<f32>, area: f32) -> f32 {
    if frame.emitter_total_power <= 0.0 { return 0.0; }
    return luminance(emission) * area / frame.emitter_total_power;
}

// The light sampler. Two ways to pick one of all the lights (emissive triangles, punctual lights, the
// environment and the sun), each with the probability of any light it can pick:
//
// - `light_sampler_sample(u)` / `light_sampler_pmf(light)`: in proportion to power (pbrt-v4
//   `PowerLightSampler`), from the CDF the CPU built (engine/src/render/gpu_scene/lights.rs); no shading point
//   needed (ReSTIR's candidates). The probability is the difference of adjacent CDF entries, exactly the
//   chance that a uniform u lands between them, so sampling and MIS weights agree to the last bit.
// - `light_sampler_sample_at(ctx, u)` / `light_sampler_pmf_at(ctx, light)`: what next-event estimation uses,
//   from its own CDF (`light_cdf`'s second half): the same powers, less the lights it leaves to BSDF sampling
//   (a smooth environment: engine/src/environment/sampling.rs), which get probability 0. With the light
//   tree on (frame.tree_light_count > 0) the lights at finite distance (the list's first tree_light_count)
//   share their probability by the tree's spatial importance (lights/light_tree.wgsl); directional lights, the
//   environment and the sun keep their power share.

fn light_count() -> u32 {
    return frame.light_count;
}

// Where next-event estimation's CDF starts in `light_cdf` (the power CDF starts at 0).
fn next_event_cdf() -> u32 {
    return frame.light_count;
}

// Probability of `light` under the CDF at `base`: the difference of adjacent entries.
fn cdf_pmf(base: u32, light: u32) -> f32 {
    return read_light_cdf(base + light) - select(0.0, read_light_cdf(base + light - 1u), light > 0u);
}

// The first light in first..light_count whose entry of the CDF at `base` exceeds u.
fn cdf_sample(base: u32, first: u32, u: f32) -> LightChoice {
    var lo = first;
    var hi = frame.light_count - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if read_light_cdf(base + mid) <= u { lo = mid + 1u; } else { hi = mid; }
    }
    return LightChoice(lo, cdf_pmf(base, lo));
}

fn light_sampler_pmf(light: u32) -> f32 {
    return cdf_pmf(0u, light);
}

fn light_sampler_sample(u: f32) -> LightChoice {
    return cdf_sample(0u, 0u, u);
}

// The light index of emissive triangle `slot` on `instance` (NONE when it is not a light): the instance's
// lights are sorted by slot.
fn triangle_light_index(instance: u32, slot: u32) -> u32 {
    let inst = read_instance(instance);
    var lo = inst.first_light;
    var hi = inst.first_light + inst.light_count;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if read_light(mid).index_b < slot { lo = mid + 1u; } else { hi = mid; }
    }
    return select(NONE, lo, lo < inst.first_light + inst.light_count && read_light(lo).index_b == slot);
}

fn light_sampler_sample_at(ctx: LightSampleContext, u: f32) -> LightChoice {
    let base = next_event_cdf();
    let tree = frame.tree_light_count;
    if tree == 0u { return cdf_sample(base, 0u, u); }
    let tree_share = read_light_cdf(base + tree - 1u);
    if u < tree_share {
        let choice = light_tree_sample(ctx, min(u / tree_share, ONE_MINUS_EPSILON));
        return LightChoice(choice.light, choice.pmf * tree_share);
    }
    // The rest by power: the first entry past the tree whose CDF exceeds u.
    return cdf_sample(base, tree, u);
}

fn light_sampler_pmf_at(ctx: LightSampleContext, light: u32) -> f32 {
    let base = next_event_cdf();
    let tree = frame.tree_light_count;
    if tree == 0u || light >= tree { return cdf_pmf(base, light); }
    return read_light_cdf(base + tree - 1u) * light_tree_pmf(ctx, light);
}

// `light_sampler_pmf_at` of a light at infinity: its power share, wherever ctx is (the tree holds only lights
// at finite distance), without the tree's code in the kernel.
fn infinite_light_pmf_at(light: u32) -> f32 {
    return cdf_pmf(next_event_cdf(), light);
}

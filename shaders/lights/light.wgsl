// What every light returns to next-event estimation (pbrt-v4 `LightLiSample`): a direction towards the light,
// how far it is, the radiance arriving along it, and the density of having sampled it; and where the light is
// seen from (pbrt-v4 `LightSampleContext`). Every kind of light (lights/dispatch.wgsl) answers with these.

struct LightLiSample {
    // Unit direction from the shading point towards the light.
    wi: vec3<f32>,
    // Distance to the sampled point (MISS for lights at infinity).
    distance: f32,
    // Radiance arriving at the shading point along -wi, before visibility (for a delta light: the radiant
    // intensity x falloff or the irradiance, to be divided by pdf = 1 like any other sample).
    li: vec3<f32>,
    // Solid-angle density of this sample given the light (the light sampler's pmf not included); 0 = no sample.
    pdf: f32,
    // A delta light (point, spot, directional): BSDF sampling cannot hit it, so it takes no MIS weight.
    delta: bool,
    // The light's surface normal at the sampled point, on the side facing the shading point (zero for lights
    // without a surface): where a shadow ray's far end moves off it (traversal/ray.wgsl `spawn_ray_to`).
    n: vec3<f32>,
}

// What a ray leaving the scene sees of a light at infinity, and the density with which next-event estimation
// samples its direction (lights/dispatch.wgsl `infinite_light_li`).
struct InfiniteLightLi {
    le: vec3<f32>,
    pdf: f32,
}

// The point a light is sampled from.
struct LightSampleContext {
    p: vec3<f32>,
    // Geometric normal at p (zero in free space).
    n: vec3<f32>,
}

// A light picked by a light sampler, with the probability of picking it.
struct LightChoice {
    light: u32,
    pmf: f32,
}

fn no_light_sample() -> LightLiSample {
    return LightLiSample(vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0), 0.0, false, vec3<f32>(0.0));
}

// What every light returns to next-event estimation (pbrt-v4 `LightLiSample`): a direction towards the light,
// how far it is, the radiance arriving along it, and the density of having sampled it. Area lights now; punctual
// and environment lights return the same (a delta light with `delta` set: BSDF sampling cannot hit it, so it
// takes no MIS weight).

struct LightLiSample {
    // Unit direction from the shading point towards the light.
    wi: vec3<f32>,
    // Distance to the sampled point (MISS for lights at infinity).
    distance: f32,
    // Radiance arriving at the shading point along -wi, before visibility.
    li: vec3<f32>,
    // Solid-angle density of this sample given the light (the light sampler's pmf not included); 0 = no sample.
    pdf: f32,
    delta: bool,
}

fn no_light_sample() -> LightLiSample {
    return LightLiSample(vec3<f32>(0.0, 0.0, 1.0), 0.0, vec3<f32>(0.0), 0.0, false);
}

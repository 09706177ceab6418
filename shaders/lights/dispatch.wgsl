// Any light by its index in `lights`: the one interface next-event estimation, MIS and ReSTIR use, whatever
// the light's kind (pbrt-v4's `Light` TaggedPointer dispatch).
//
// - light_sample_li(light, ctx, u, allow_incomplete_pdf): a sample towards the light from ctx (LightLiSample);
// - light_pdf_li(light, ctx, wi, distance, allow_incomplete_pdf): the density `light_sample_li` gives `wi` (met
//   at `distance`; MISS for lights at infinity); 0 for delta lights, which BSDF sampling cannot hit;
// - allow_incomplete_pdf (pbrt-v4's name): the caller combines the sample with BSDF sampling by MIS, so the
//   light may leave directions to it (an environment map samples only its light above its mean); ReSTIR's
//   candidates, which nothing completes, pass false;
// - infinite_light_le(light, dir): what a ray leaving the scene along `dir` sees of a light at infinity
//   (lights[frame.infinite_light_first ..]); emissive triangles are seen through `resolve_hit`.

fn light_sample_li(index: u32, ctx: LightSampleContext, u: vec2<f32>, allow_incomplete_pdf: bool) -> LightLiSample {
    let light = read_light(index);
    if light.kind == LIGHT_TRIANGLE { return triangle_light_sample_li(light, ctx, u); }
    if light.kind == LIGHT_POINT || light.kind == LIGHT_SPOT { return point_light_sample_li(light, ctx); }
    if light.kind == LIGHT_DIRECTIONAL { return directional_light_sample_li(light); }
    if light.kind == LIGHT_ENVIRONMENT { return environment_sample_li(light, u, allow_incomplete_pdf); }
    if light.kind == LIGHT_SUN { return sun_sample_li(light, u); }
    return no_light_sample();
}

fn light_pdf_li(index: u32, ctx: LightSampleContext, wi: vec3<f32>, distance: f32, allow_incomplete_pdf: bool) -> f32 {
    let light = read_light(index);
    if light.kind == LIGHT_TRIANGLE { return triangle_light_pdf(light, ctx, wi, distance); }
    if light.kind == LIGHT_ENVIRONMENT { return environment_pdf(light, wi, allow_incomplete_pdf); }
    if light.kind == LIGHT_SUN { return sun_pdf(light, wi); }
    return 0.0;
}

fn infinite_light_le(index: u32, dir: vec3<f32>) -> vec3<f32> {
    let light = read_light(index);
    if light.kind == LIGHT_ENVIRONMENT { return environment_le(light, dir); }
    if light.kind == LIGHT_SUN { return sun_le(light, dir); }
    return vec3<f32>(0.0);
}

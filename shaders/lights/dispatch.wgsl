// Any light by its index in `lights`: the one interface next-event estimation, MIS and ReSTIR use, whatever
// the light's kind (pbrt-v4's `Light` TaggedPointer dispatch).
//
// - light_sample_li(light, ctx, u, allow_incomplete_pdf): a sample towards the light from ctx (LightLiSample);
// - the density `light_sample_li` gives a direction that BSDF sampling met the light along, by where it was met
//   (delta lights, which BSDF sampling cannot hit, need none): `emitter_pdf_li(light, ctx, wi, distance)` for an
//   emissive triangle, `infinite_light_li(light, dir, allow_incomplete_pdf)` for a light at infinity, with what
//   the ray sees of it. Two functions, not one over every kind: a kernel pays for each kind's code at a call
//   site whether a ray can meet that kind there or not (drivers inline; CPU adapters run both sides of an `if`);
// - allow_incomplete_pdf (pbrt-v4's name): the caller combines the sample with BSDF sampling by MIS, so the
//   light may leave directions to it (an environment map samples only its light above its mean); ReSTIR's
//   candidates, which nothing completes, pass false.
// Lights at infinity are lights[frame.infinite_light_first ..]; emissive triangles are seen through `resolve_hit`.

// The kinds of light (bit 1 << LIGHT_*) this kernel's light samples can pick: the path-tracing kernels set the
// kinds next-event estimation samples on CPU adapters (engine/src/render/material_lobes.rs `KernelNeeds`), and
// the other kinds' sampling compiles away, which lavapipe, running every `if` body masked, would pay for each
// sample. An environment outside it (a smooth map, left to BSDF sampling) keeps its radiance lookup, its
// density 0; a sun outside it is absent (every sun is sampled).
override NEXT_EVENT_LIGHT_KINDS: u32 = 0xffffffffu;

fn next_event_samples(kind: u32) -> bool {
    return ((NEXT_EVENT_LIGHT_KINDS >> kind) & 1u) != 0u;
}

fn light_sample_li(index: u32, ctx: LightSampleContext, u: vec2<f32>, allow_incomplete_pdf: bool) -> LightLiSample {
    let light = read_light(index);
    if next_event_samples(LIGHT_TRIANGLE) && light.kind == LIGHT_TRIANGLE { return triangle_light_sample_li(light, ctx, u); }
    if (next_event_samples(LIGHT_POINT) || next_event_samples(LIGHT_SPOT))
        && (light.kind == LIGHT_POINT || light.kind == LIGHT_SPOT) {
        return point_light_sample_li(light, ctx);
    }
    if next_event_samples(LIGHT_DIRECTIONAL) && light.kind == LIGHT_DIRECTIONAL { return directional_light_sample_li(light); }
    if next_event_samples(LIGHT_ENVIRONMENT) && light.kind == LIGHT_ENVIRONMENT {
        return environment_sample_li(light, u, allow_incomplete_pdf);
    }
    if next_event_samples(LIGHT_SUN) && light.kind == LIGHT_SUN { return sun_sample_li(light, u); }
    return no_light_sample();
}

// The shadow ray of light sample `ls` taken at surface point `p`, leaving on the side of `n` (the geometric
// normal, flipped for light from behind): to just short of the light's surface for a light at a finite distance,
// both ends moved off their surfaces (`spawn_ray_to`); to infinity along `ls.wi` otherwise.
fn light_shadow_ray(p: vec3<f32>, n: vec3<f32>, ls: LightLiSample) -> RaySegment {
    if ls.distance >= MISS { return RaySegment(Ray(offset_ray_origin(p, n), ls.wi), MISS); }
    return spawn_ray_to(p, n, p + ls.wi * ls.distance, ls.n);
}

// Density of `wi` for emissive triangle `index`, met at `distance` from ctx.
fn emitter_pdf_li(index: u32, ctx: LightSampleContext, wi: vec3<f32>, distance: f32) -> f32 {
    return triangle_light_pdf(read_light(index), ctx, wi, distance);
}

// What a ray leaving the scene along `dir` sees of light `index` at infinity, and the density with which
// `light_sample_li` gives `dir`.
fn infinite_light_li(index: u32, dir: vec3<f32>, allow_incomplete_pdf: bool) -> InfiniteLightLi {
    let light = read_light(index);
    if light.kind == LIGHT_ENVIRONMENT {
        if !next_event_samples(LIGHT_ENVIRONMENT) { return InfiniteLightLi(environment_le(light, dir), 0.0); }
        return environment_li(light, dir, allow_incomplete_pdf);
    }
    if next_event_samples(LIGHT_SUN) && light.kind == LIGHT_SUN {
        return InfiniteLightLi(sun_le(light, dir), sun_pdf(light, dir));
    }
    return InfiniteLightLi(vec3<f32>(0.0), 0.0);
}

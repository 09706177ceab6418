// What one light sample is worth at a shading point: the integrand of direct lighting in the lights' primary
// sample space (f x |cos| x Li / the light's solid-angle density of that point), whose luminance is ReSTIR's
// target function (unshadowed), and the shadow ray that tests it. Lights through the light-sampler interface
// only (light.wgsl `LightLiSample`), so any light type that returns one plugs in here.

// A surface as light reuse sees it (world space; `wo` points towards the viewer).
struct ShadingPoint {
    p: vec3<f32>,
    ng: vec3<f32>,
    n: vec3<f32>,
    wo: vec3<f32>,
    bsdf: BsdfParams,
}

struct LightEval {
    // f x |cos| x Li / pdf: the direct light estimate is this times the sample's weight.
    value: vec3<f32>,
    shadow: Ray,
    t_max: f32,
}

fn no_light_eval() -> LightEval {
    return LightEval(vec3<f32>(0.0), Ray(vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0)), 0.0);
}

fn evaluate_light_sample(sp: ShadingPoint, light: u32, u: vec2<f32>) -> LightEval {
    if light >= light_count() { return no_light_eval(); }
    let ls = light_sample_li(light, LightSampleContext(sp.p, sp.ng), u, false);
    if ls.pdf <= 0.0 { return no_light_eval(); }
    // As next-event estimation: light from behind the surface counts only through a transmitting lobe.
    let behind = dot(ls.wi, sp.ng) <= 0.0;
    if behind && (bsdf_flags(sp.bsdf) & BSDF_TRANSMISSION) == 0u { return no_light_eval(); }
    let tbn = basis(sp.n);
    let wi = ls.wi * tbn;
    let f = bsdf_eval(sp.wo * tbn, wi, sp.bsdf);
    let value = f * abs(wi.z) * ls.li / ls.pdf;
    if !finite3(value) { return no_light_eval(); }
    let shadow = light_shadow_ray(sp.p, select(sp.ng, -sp.ng, behind), ls);
    return LightEval(value, shadow.ray, shadow.t_max);
}

fn target_function(e: LightEval) -> f32 {
    return max(luminance(e.value), 0.0);
}

// True when nothing blocks the sample's shadow ray.
fn light_visible(e: LightEval) -> bool {
    rays_traced++;
    return trace(e.shadow, e.t_max, true).instance == NONE;
}

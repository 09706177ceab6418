// The real-time path integrator: the path integrator (path.wgsl) started from the G-buffer's first hit, with
// direct light there from ReSTIR DI when it runs; and the reproducible estimate that A-SVGF's temporal
// gradients compare across frames (the same surface point and random numbers, shaded in two frames).

// Sampler dimensions apart from the path's (path.wgsl): ReSTIR's candidates and choices, and the gradient
// estimate's own light sample, so that neither shifts a decision of the path.
const DIM_RESTIR: u32 = 0x20000000u;
const DIM_GRADIENT_LIGHT: u32 = 0x30000000u;

// The G-buffer's first hit as the path integrator takes it (this frame's instance of the object).
fn gsurface_first_hit(g: GSurface, origin: vec3<f32>) -> Hit {
    if !gsurface_hit(g) { return Hit(MISS, NONE, 0u, vec2<f32>(0.0)); }
    return Hit(distance(origin, g.position), instance_of_object(g.object), g.triangle, g.bary);
}

// A G-buffer surface seen from `eye` (the camera of the frame that wrote it). The packed BSDF holds the core
// parameters; the extension lobes and layers take the material's factors (their textures are not applied here,
// the surface is taken as seen from outside, and the coat's normal as the shading normal).
fn gsurface_shading_point(g: GSurface, eye: vec3<f32>) -> ShadingPoint {
    var bsdf = unpack_bsdf(g.bsdf);
    if MATERIAL_LOBES != 0u && g.material != NONE {
        let m = read_material(g.material);
        bsdf.lobes = pack_lobes(m.specular_f0, m.specular_weight, m.transmission, m.refraction_ior, false);
        if (MATERIAL_LOBES & LOBES_LAYERS) != 0u {
            bsdf.layers = pack_layers(m.clearcoat, m.clearcoat_roughness, vec3<f32>(0.0, 0.0, 1.0), m.sheen_color, m.sheen_roughness);
        }
    }
    return ShadingPoint(g.position, oct_decode(g.geometric), oct_decode(g.normal), normalize(eye - g.position), bsdf);
}

fn surface_shading_point(s: SurfaceInteraction, ray: Ray) -> ShadingPoint {
    return ShadingPoint(s.p, s.ng, s.n, -ray.dir, s.bsdf);
}

// Direct light at `sp` from one light-sampler sample, without reuse: unbiased, and reproducible from the
// sampler alone (what the gradient estimate uses in place of ReSTIR). One shadow ray.
fn light_sampled_direct(sp: ShadingPoint, sampler: Sampler) -> vec3<f32> {
    if light_count() == 0u { return vec3<f32>(0.0); }
    let choice = light_sampler_sample(get_1d(sampler, DIM_GRADIENT_LIGHT));
    if choice.pmf <= 0.0 { return vec3<f32>(0.0); }
    let e = evaluate_light_sample(sp, choice.light, get_2d(sampler, DIM_GRADIENT_LIGHT + 1u));
    if all(e.value == vec3<f32>(0.0)) || !light_visible(e) { return vec3<f32>(0.0); }
    return e.value / choice.pmf;
}

// The estimate A-SVGF compares: the path from `first` with `sampler`'s numbers, direct light at the first hit
// by light sampling where ReSTIR provides it in the image. Radiance.
fn gradient_estimate(ray: Ray, first: Hit, sampler: Sampler, restir: bool) -> vec3<f32> {
    let r = trace_path_from(PathStart(ray, first, true, restir), camera_forward(), sampler);
    if !restir || first.instance == NONE { return r.radiance; }
    return r.radiance + light_sampled_direct(surface_shading_point(resolve_hit(first, ray), ray), sampler);
}

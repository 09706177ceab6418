// The glTF 2.0 metallic-roughness BSDF (specification, Appendix B), exactly: Lambert diffuse weighted by
// 1 - F, GGX distribution, height-correlated Smith visibility, Schlick Fresnel, f0 = 0.04 for the dielectric,
// f0 = baseColor for the metal, alpha = roughness^2. Reflection only: zero when either direction is below the
// shading horizon. Sampling: a mixture of cosine-weighted diffuse and GGX visible-normal sampling, with the
// exact mixture pdf.

struct BsdfParams {
    base_color: vec3<f32>,
    metallic: f32,
    alpha: f32,
}

// The lobes this material has (BSDF_* flags): the integrator accepts light from behind the surface only
// when one of them transmits.
fn bsdf_flags(p: BsdfParams) -> u32 {
    return BSDF_REFLECTION | BSDF_DIFFUSE | BSDF_GLOSSY;
}

// f(wo, wi), without the cosine.
fn bsdf_eval(v: vec3<f32>, l: vec3<f32>, p: BsdfParams) -> vec3<f32> {
    if v.z <= 0.0 || l.z <= 0.0 { return vec3<f32>(0.0); }
    let h = normalize(v + l);
    let vh = abs(dot(v, h));
    let a2 = p.alpha * p.alpha;
    let spec = smith_visibility(l.z, v.z, a2) * ggx_d(h, a2);
    let fw = pow5(1.0 - vh);
    let f_dielectric = 0.04 + 0.96 * fw;
    let f_metal = p.base_color + (vec3<f32>(1.0) - p.base_color) * fw;
    let dielectric = (1.0 - f_dielectric) * p.base_color * INV_PI + vec3<f32>(f_dielectric * spec);
    let metal = f_metal * spec;
    return mix(dielectric, metal, p.metallic);
}

// Probability of sampling the specular lobe: its estimated share of the reflected energy.
fn specular_probability(v: vec3<f32>, p: BsdfParams) -> f32 {
    let fw = pow5(1.0 - clamp(v.z, 0.0, 1.0));
    let f_dielectric = 0.04 + 0.96 * fw;
    let f_metal = luminance(p.base_color + (vec3<f32>(1.0) - p.base_color) * fw);
    let spec = mix(f_dielectric, f_metal, p.metallic);
    let diffuse = (1.0 - p.metallic) * (1.0 - f_dielectric) * luminance(p.base_color);
    if diffuse <= 0.0 { return 1.0; }
    return clamp(spec / (spec + diffuse), 0.1, 0.9);
}

fn bsdf_pdf(v: vec3<f32>, l: vec3<f32>, p: BsdfParams) -> f32 {
    if v.z <= 0.0 || l.z <= 0.0 { return 0.0; }
    let ps = specular_probability(v, p);
    let spec_pdf = ggx_reflection_pdf(v, l, p.alpha * p.alpha);
    return ps * spec_pdf + (1.0 - ps) * l.z * INV_PI;
}

// Samples wi: `u_lobe` picks the lobe, `u` the direction within it.
fn bsdf_sample(v: vec3<f32>, p: BsdfParams, u_lobe: f32, u: vec2<f32>) -> BsdfSample {
    var l: vec3<f32>;
    var flags: u32;
    if u_lobe < specular_probability(v, p) {
        let h = sample_vndf(v, p.alpha, u);
        l = reflect(-v, h);
        flags = BSDF_REFLECTION | BSDF_GLOSSY;
    } else {
        l = sample_cosine_hemisphere(u);
        flags = BSDF_REFLECTION | BSDF_DIFFUSE;
    }
    let pdf = bsdf_pdf(v, l, p);
    if l.z <= 0.0 || pdf <= 0.0 {
        return BsdfSample(l, vec3<f32>(0.0), 0.0, 0u);
    }
    return BsdfSample(l, bsdf_eval(v, l, p) * l.z / pdf, pdf, flags);
}

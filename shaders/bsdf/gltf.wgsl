// The glTF 2.0 BSDF: the core metallic-roughness model (specification, Appendix B) exactly, with the layering of
// KHR_materials_ior, _specular and _transmission (their "implementation" sections):
//   f = mix(dielectric, metal, metallic)
//   metal      = F_schlick(baseColor) * specular_brdf
//   dielectric = fresnel_mix(layer = specular_brdf, base = mix(diffuse(baseColor), baseColor * btdf, transmission))
//   fresnel_mix = weight * F * layer + (1 - weight * max(F)) * base,  F = f0 + (1 - f0) (1 - v.h)^5
// specular_brdf is GGX with height-correlated Smith visibility, alpha = roughness^2. The BTDF shares that
// distribution: a refracting microfacet BTDF (Walter et al. 2007) where a volume lies behind the surface, else
// the thin-walled one (the reflection lobe mirrored through the surface: transmitted rays do not bend).
// Leaving a volume, the Fresnel term takes the cosine on the outer side, so total internal reflection reflects
// everything. Sampling picks the glossy reflection, the transmission or the diffuse lobe by their estimated
// shares and samples GGX visible normals or the cosine; the pdf is the exact mixture.
//
// KHR_materials_sheen and _clearcoat layer over that material (their implementation sections), sheen first:
//   sheen_layer = sheenColor * sheen_brdf + material * min(1 - max(sheenColor) E(n.v), 1 - max(sheenColor) E(n.l))
//   coated      = mix(sheen_layer, coat_brdf, clearcoat * F_coat),  F_coat = 0.04 + 0.96 (1 - |n_coat.v|)^5
// sheen_brdf is bsdf/sheen.wgsl's Charlie lobe, E its directional albedo; coat_brdf the GGX specular_brdf about
// the coat's own normal with alpha = clearcoatRoughness^2. Sampling first picks the coat (GGX visible normals about
// its normal), the sheen (uniform over the hemisphere: sheen_brdf x cos has no cosine left, V holds 1 / n.l) or
// the material below, whose own mixture then picks its lobe; the pdf is the exact mixture of all of them.

// Which extension lobes the kernel shades with (engine/src/render/material_lobes.rs, a pipeline constant): bits
// 0-1 the level, 0 the core BSDF only, 1 the extensions' factors, 2 factors and textures; bit 2 (LOBES_LAYERS) the
// sheen and clearcoat layers. Kernels built without it shade everything. At 0 the accessors below return the core
// values as constants, and without LOBES_LAYERS the layer code, so the extension code folds away.
override MATERIAL_LOBES: u32 = 6u;

struct BsdfParams {
    base_color: vec3<f32>,
    metallic: f32,
    alpha: f32,
    // The extension lobes' parameters, packed (the path loop's registers are what limits its speed; unpacked
    // they made every scene 12-38% slower on the H200): see `pack_lobes`.
    lobes: vec2<u32>,
    // The sheen and clearcoat layers, packed (see `pack_layers`); zero without them.
    layers: vec3<u32>,
}

// x: the dielectric f0 per channel, clamped to 1, as round(sqrt(f0) * 1020) in 10 bits each (0.04 is exact);
// y: transmission (unorm, bits 0-7), the specular layer's weight (unorm, bits 8-14), wo inside the volume
// (bit 15), the IOR that bends transmitted rays (f16, bits 16-31; exactly 1 for thin-walled transmission).
const LOBE_F0_SCALE: f32 = 1020.0;
const LOBE_INSIDE: u32 = 0x8000u;

fn pack_lobes(f0: vec3<f32>, weight: f32, transmission: f32, ior: f32, inside: bool) -> vec2<u32> {
    let q = vec3<u32>(round(sqrt(clamp(f0, vec3<f32>(0.0), vec3<f32>(1.0))) * LOBE_F0_SCALE));
    let x = q.x | (q.y << 10u) | (q.z << 20u);
    let t = u32(round(clamp(transmission, 0.0, 1.0) * 255.0));
    let w = u32(round(clamp(weight, 0.0, 1.0) * 127.0));
    let y = t | (w << 8u) | select(0u, LOBE_INSIDE, inside) | (pack2x16float(vec2<f32>(ior, 0.0)) << 16u);
    return vec2<u32>(x, y);
}

// The core specification's material: f0 = 0.04 (IOR 1.5), weight 1, no transmission.
const CORE_LOBES: vec2<u32> = vec2<u32>(204u | (204u << 10u) | (204u << 20u), (127u << 8u) | (0x3c00u << 16u));

fn core_bsdf(base_color: vec3<f32>, metallic: f32, alpha: f32) -> BsdfParams {
    return BsdfParams(base_color, metallic, alpha, CORE_LOBES, vec3<u32>(0u));
}

// x: the clearcoat factor (unorm, bits 0-7), clearcoat roughness (unorm, bits 8-15), sheen roughness (unorm, bits
// 16-23); y: sqrt of the sheen colour (unorm8 x 3, bits 0-23); z: the coat's normal in the local shading frame
// (octahedral). A layer whose factor or colour is 0 is absent.
fn pack_layers(coat: f32, coat_roughness: f32, coat_normal: vec3<f32>, sheen_color: vec3<f32>, sheen_roughness: f32) -> vec3<u32> {
    let x = pack4x8unorm(vec4<f32>(coat, coat_roughness, sheen_roughness, 0.0));
    let y = pack4x8unorm(vec4<f32>(sqrt(clamp(sheen_color, vec3<f32>(0.0), vec3<f32>(1.0))), 0.0));
    return vec3<u32>(x, y, oct_encode(coat_normal));
}

fn has_layers(p: BsdfParams) -> bool {
    if (MATERIAL_LOBES & LOBES_LAYERS) == 0u { return false; }
    return ((p.layers.x & 0xffu) | (p.layers.y & 0xffffffu)) != 0u;
}

fn coat_weight(p: BsdfParams) -> f32 {
    return f32(p.layers.x & 0xffu) / 255.0;
}

fn coat_alpha(p: BsdfParams) -> f32 {
    let r = f32((p.layers.x >> 8u) & 0xffu) / 255.0;
    return max(r * r, MIN_ALPHA);
}

fn coat_normal(p: BsdfParams) -> vec3<f32> {
    return oct_decode(p.layers.z);
}

fn sheen_color(p: BsdfParams) -> vec3<f32> {
    let c = unpack4x8unorm(p.layers.y).rgb;
    return c * c;
}

fn sheen_roughness(p: BsdfParams) -> f32 {
    return f32((p.layers.x >> 16u) & 0xffu) / 255.0;
}

fn sheen_alpha(roughness: f32) -> f32 {
    return max(roughness * roughness, SHEEN_MIN_ALPHA);
}

fn lobe_f0(p: BsdfParams) -> vec3<f32> {
    if MATERIAL_LOBES == 0u { return vec3<f32>(0.04); }
    let q = vec3<f32>(vec3<u32>(p.lobes.x, p.lobes.x >> 10u, p.lobes.x >> 20u) & vec3<u32>(0x3ffu)) / LOBE_F0_SCALE;
    return q * q;
}

fn lobe_transmission(p: BsdfParams) -> f32 {
    if MATERIAL_LOBES == 0u { return 0.0; }
    return f32(p.lobes.y & 0xffu) / 255.0;
}

fn lobe_weight(p: BsdfParams) -> f32 {
    if MATERIAL_LOBES == 0u { return 1.0; }
    return f32((p.lobes.y >> 8u) & 0x7fu) / 127.0;
}

// Relative index of refraction across the surface seen from wo (far side over near side): the IOR when wo is
// outside, its inverse inside; exactly 1 for thin-walled transmission.
fn lobe_eta(p: BsdfParams) -> f32 {
    if MATERIAL_LOBES == 0u { return 1.5; }
    let ior = unpack2x16float(p.lobes.y >> 16u).x;
    return select(ior, 1.0 / ior, (p.lobes.y & LOBE_INSIDE) != 0u);
}

// The lobes this material has (BSDF_* flags): the integrator accepts light from behind the surface only
// when one of them transmits.
fn bsdf_flags(p: BsdfParams) -> u32 {
    if MATERIAL_LOBES != 0u && lobe_transmission(p) > 0.0 && p.metallic < 1.0 {
        return BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_DIFFUSE | BSDF_GLOSSY;
    }
    return BSDF_REFLECTION | BSDF_DIFFUSE | BSDF_GLOSSY;
}

fn max3(c: vec3<f32>) -> f32 {
    return max(c.x, max(c.y, c.z));
}

// The dielectric layer's Fresnel term for a microfacet at cosine `c` with wo: Schlick's, on the cosine of the
// outer side (the transmitted one when wo is inside a denser volume; 1 beyond the critical angle).
fn dielectric_fresnel(c: f32, p: BsdfParams) -> vec3<f32> {
    var cos_outside = c;
    let eta = lobe_eta(p);
    if eta < 1.0 {
        let sin2_t = (1.0 - c * c) / (eta * eta);
        if sin2_t >= 1.0 { return vec3<f32>(1.0); }
        cos_outside = sqrt(1.0 - sin2_t);
    }
    let fw = pow5(1.0 - clamp(cos_outside, 0.0, 1.0));
    let f0 = lobe_f0(p);
    return f0 + (vec3<f32>(1.0) - f0) * fw;
}

fn thin_walled(p: BsdfParams) -> bool {
    if MATERIAL_LOBES == 0u { return false; }
    return (p.lobes.y >> 16u) == 0x3c00u;
}

// The generalized half vector of a refraction from wo = v to wi = l (Walter et al. 2007), on v's side; zero
// where no microfacet refracts v into l (both on its front, or a configuration the distribution excludes).
fn refraction_half_vector(v: vec3<f32>, l: vec3<f32>, eta: f32) -> vec3<f32> {
    var h = v + eta * l;
    if dot(h, h) <= 0.0 { return vec3<f32>(0.0); }
    h = normalize(h);
    if h.z < 0.0 { h = -h; }
    if dot(v, h) <= 0.0 || dot(l, h) >= 0.0 { return vec3<f32>(0.0); }
    return h;
}

// f(wo, wi), without the cosine: the layers over the material.
fn bsdf_eval(v: vec3<f32>, l: vec3<f32>, p: BsdfParams) -> vec3<f32> {
    let base = base_bsdf_eval(v, l, p);
    if !has_layers(p) { return base; }
    return layered_eval(v, l, p, base);
}

// The material under the layers.
fn base_bsdf_eval(v: vec3<f32>, l: vec3<f32>, p: BsdfParams) -> vec3<f32> {
    if v.z <= 0.0 { return vec3<f32>(0.0); }
    let a2 = p.alpha * p.alpha;
    if l.z > 0.0 {
        let h = normalize(v + l);
        let vh = abs(dot(v, h));
        let spec = smith_visibility(l.z, v.z, a2) * ggx_d(h, a2);
        let f_dielectric = dielectric_fresnel(vh, p);
        let base_weight = 1.0 - lobe_weight(p) * max3(f_dielectric);
        let diffuse = base_weight * (1.0 - lobe_transmission(p)) * p.base_color * INV_PI;
        let dielectric = diffuse + lobe_weight(p) * f_dielectric * spec;
        let f_metal = p.base_color + (vec3<f32>(1.0) - p.base_color) * pow5(1.0 - vh);
        return mix(dielectric, f_metal * spec, p.metallic);
    }
    if l.z < 0.0 && (bsdf_flags(p) & BSDF_TRANSMISSION) != 0u {
        let tint = (1.0 - p.metallic) * lobe_transmission(p) * p.base_color;
        if thin_walled(p) {
            let mirrored = vec3<f32>(l.xy, -l.z);
            let h = normalize(v + mirrored);
            let f = dielectric_fresnel(dot(v, h), p);
            let spec = smith_visibility(mirrored.z, v.z, a2) * ggx_d(h, a2);
            return tint * (1.0 - lobe_weight(p) * max3(f)) * spec;
        }
        let eta = lobe_eta(p);
        let h = refraction_half_vector(v, l, eta);
        if h.z == 0.0 { return vec3<f32>(0.0); }
        let vh = dot(v, h);
        let lh = dot(l, h);
        let f = dielectric_fresnel(vh, p);
        let denom = lh + vh / eta;
        let g2 = smith_visibility(-l.z, v.z, a2) * 4.0 * (-l.z) * v.z;
        // Radiance is scaled by 1 / eta^2 crossing into the denser side (and back).
        let btdf = ggx_d(h, a2) * g2 * abs(lh * vh / (l.z * v.z * denom * denom)) / (eta * eta);
        return tint * (1.0 - lobe_weight(p) * max3(f)) * btdf;
    }
    return vec3<f32>(0.0);
}

// Probabilities of sampling the glossy reflection, the transmission and the diffuse lobe: their estimated
// shares of the scattered energy. Every lobe that can be non-zero keeps some probability.
fn lobe_probabilities(v: vec3<f32>, p: BsdfParams) -> vec3<f32> {
    let fw = pow5(1.0 - clamp(v.z, 0.0, 1.0));
    let f_dielectric = dielectric_fresnel(v.z, p);
    let f_metal = luminance(p.base_color + (vec3<f32>(1.0) - p.base_color) * fw);
    let spec = mix(lobe_weight(p) * luminance(f_dielectric), f_metal, p.metallic);
    let base = (1.0 - p.metallic) * (1.0 - lobe_weight(p) * max3(f_dielectric)) * luminance(p.base_color);
    if (bsdf_flags(p) & BSDF_TRANSMISSION) == 0u {
        if base <= 0.0 { return vec3<f32>(1.0, 0.0, 0.0); }
        let ps = clamp(spec / (spec + base), 0.1, 0.9);
        return vec3<f32>(ps, 0.0, 1.0 - ps);
    }
    let ps = clamp(spec / max(spec + base, 1e-6), 0.1, 0.9);
    return vec3<f32>(ps, (1.0 - ps) * lobe_transmission(p), (1.0 - ps) * (1.0 - lobe_transmission(p)));
}

// Probability of sampling the glossy reflection lobe (the mirror AOVs' tint divides by it).
fn specular_probability(v: vec3<f32>, p: BsdfParams) -> f32 {
    return lobe_probabilities(v, p).x;
}

fn bsdf_pdf(v: vec3<f32>, l: vec3<f32>, p: BsdfParams) -> f32 {
    if !has_layers(p) { return base_bsdf_pdf(v, l, p); }
    if v.z <= 0.0 { return 0.0; }
    return layered_pdf(v, l, p, layer_probabilities(v, p));
}

fn base_bsdf_pdf(v: vec3<f32>, l: vec3<f32>, p: BsdfParams) -> f32 {
    if v.z <= 0.0 { return 0.0; }
    return mixture_pdf(v, l, p, lobe_probabilities(v, p));
}

// The density of sampling `l` from `v` with lobe probabilities `probs` (v above the horizon).
fn mixture_pdf(v: vec3<f32>, l: vec3<f32>, p: BsdfParams, probs: vec3<f32>) -> f32 {
    let a2 = p.alpha * p.alpha;
    if l.z > 0.0 {
        return probs.x * ggx_reflection_pdf(v, l, a2) + probs.z * l.z * INV_PI;
    }
    if l.z < 0.0 && probs.y > 0.0 {
        if thin_walled(p) {
            return probs.y * ggx_reflection_pdf(v, vec3<f32>(l.xy, -l.z), a2);
        }
        let eta = lobe_eta(p);
        let h = refraction_half_vector(v, l, eta);
        if h.z == 0.0 { return 0.0; }
        let vh = dot(v, h);
        let lh = dot(l, h);
        let denom = lh + vh / eta;
        // Visible-normal density times the refraction's Jacobian |l.h| / (l.h + v.h / eta)^2.
        return probs.y * smith_g1(v.z, a2) * ggx_d(h, a2) * vh / v.z * abs(lh) / (denom * denom);
    }
    return 0.0;
}

// Samples wi: `u_lobe` picks the lobe, `u` the direction within it.
fn bsdf_sample(v: vec3<f32>, p: BsdfParams, u_lobe: f32, u: vec2<f32>) -> BsdfSample {
    if !has_layers(p) { return base_bsdf_sample(v, p, u_lobe, u); }
    return layered_sample(v, p, u_lobe, u);
}

// Samples the material under the layers (its own mixture, weight and pdf).
fn base_bsdf_sample(v: vec3<f32>, p: BsdfParams, u_lobe: f32, u: vec2<f32>) -> BsdfSample {
    let probs = lobe_probabilities(v, p);
    var l: vec3<f32>;
    var flags: u32;
    if u_lobe < probs.x {
        let h = sample_vndf(v, p.alpha, u);
        l = reflect(-v, h);
        flags = BSDF_REFLECTION | BSDF_GLOSSY;
    } else if (bsdf_flags(p) & BSDF_TRANSMISSION) != 0u && u_lobe < probs.x + probs.y {
        // (The flag test folds away in kernels without transmission.)
        let h = sample_vndf(v, p.alpha, u);
        if thin_walled(p) {
            let r = reflect(-v, h);
            l = vec3<f32>(r.xy, -r.z);
        } else {
            // WGSL's refract takes the near side's index over the far side's; zero on total internal reflection.
            l = refract(-v, h, 1.0 / lobe_eta(p));
        }
        flags = BSDF_TRANSMISSION | BSDF_GLOSSY;
    } else {
        l = sample_cosine_hemisphere(u);
        flags = BSDF_REFLECTION | BSDF_DIFFUSE;
    }
    let transmitted = (flags & BSDF_TRANSMISSION) != 0u;
    let pdf = select(0.0, mixture_pdf(v, l, p, probs), v.z > 0.0);
    if (l.z > 0.0) == transmitted || l.z == 0.0 || pdf <= 0.0 {
        return BsdfSample(l, vec3<f32>(0.0), 0.0, 0u);
    }
    return BsdfSample(l, bsdf_eval(v, l, p) * abs(l.z) / pdf, pdf, flags);
}

// The layers (KHR_materials_sheen, then KHR_materials_clearcoat over it) on the material's value `base`.
fn layered_eval(v: vec3<f32>, l: vec3<f32>, p: BsdfParams, base: vec3<f32>) -> vec3<f32> {
    if v.z <= 0.0 { return vec3<f32>(0.0); }
    var f = base;
    let sheen = sheen_color(p);
    if max3(sheen) > 0.0 {
        let r = sheen_roughness(p);
        let m = max3(sheen);
        // E exceeds 1 at grazing angles for smooth sheens: the scaling stops at 0.
        f *= max(min(1.0 - m * sheen_albedo(v.z, r), 1.0 - m * sheen_albedo(l.z, r)), 0.0);
        if l.z > 0.0 { f += sheen * sheen_brdf(v, l, sheen_alpha(r)); }
    }
    let w = coat_weight(p);
    if w > 0.0 {
        let nc = coat_normal(p);
        let fc = w * coat_fresnel(abs(dot(v, nc)));
        f = f * (1.0 - fc) + vec3<f32>(fc * coat_brdf(v, l, nc, coat_alpha(p)));
    }
    return f;
}

// The coat's Fresnel term: Schlick with IOR 1.5 on the cosine with its normal.
fn coat_fresnel(cos_v: f32) -> f32 {
    return 0.04 + 0.96 * pow5(1.0 - clamp(cos_v, 0.0, 1.0));
}

// GGX specular_brdf about the coat normal `nc`; zero unless v and l lie above both the coat and the surface.
fn coat_brdf(v: vec3<f32>, l: vec3<f32>, nc: vec3<f32>, alpha: f32) -> f32 {
    if l.z <= 0.0 { return 0.0; }
    let frame = basis(nc);
    let vc = v * frame;
    let lc = l * frame;
    if vc.z <= 0.0 || lc.z <= 0.0 { return 0.0; }
    let a2 = alpha * alpha;
    return smith_visibility(lc.z, vc.z, a2) * ggx_d(normalize(vc + lc), a2);
}

// The density of the coat's visible-normal sampling, on the same domain as coat_brdf.
fn coat_pdf(v: vec3<f32>, l: vec3<f32>, nc: vec3<f32>, alpha: f32) -> f32 {
    if l.z <= 0.0 { return 0.0; }
    let frame = basis(nc);
    let vc = v * frame;
    let lc = l * frame;
    if vc.z <= 0.0 || lc.z <= 0.0 { return 0.0; }
    return ggx_reflection_pdf(vc, lc, alpha * alpha);
}

// The material's directional albedo, roughly (luminance): what lobe_probabilities weighs, for the layers' split.
fn base_albedo_estimate(v: vec3<f32>, p: BsdfParams) -> f32 {
    let fw = pow5(1.0 - clamp(v.z, 0.0, 1.0));
    let f_dielectric = dielectric_fresnel(v.z, p);
    let f_metal = luminance(p.base_color + (vec3<f32>(1.0) - p.base_color) * fw);
    let spec = mix(lobe_weight(p) * luminance(f_dielectric), f_metal, p.metallic);
    return spec + (1.0 - p.metallic) * (1.0 - lobe_weight(p) * max3(f_dielectric)) * luminance(p.base_color);
}

// Probabilities of sampling the coat and the sheen (the material below takes the rest): their estimated shares of
// the reflected energy, each present layer at least 0.1, the material at least 0.1.
fn layer_probabilities(v: vec3<f32>, p: BsdfParams) -> vec2<f32> {
    let w = coat_weight(p);
    let fc = w * coat_fresnel(abs(dot(v, coat_normal(p))));
    let sheen_max = max3(sheen_color(p));
    let sheen_e = min(sheen_max * sheen_albedo(v.z, sheen_roughness(p)), 1.0);
    let base_e = (1.0 - sheen_e) * base_albedo_estimate(v, p);
    let under = 1.0 - fc;
    let total = max(fc + under * (sheen_e + base_e), 1e-6);
    var probs = vec2<f32>(0.0);
    if w > 0.0 { probs.x = clamp(fc / total, 0.1, 0.8); }
    if sheen_max > 0.0 { probs.y = clamp(under * sheen_e / total, 0.1, 0.8); }
    let layered = probs.x + probs.y;
    if layered > 0.9 { probs *= 0.9 / layered; }
    return probs;
}

fn layered_pdf(v: vec3<f32>, l: vec3<f32>, p: BsdfParams, probs: vec2<f32>) -> f32 {
    var pdf = (1.0 - probs.x - probs.y) * base_bsdf_pdf(v, l, p);
    if probs.x > 0.0 { pdf += probs.x * coat_pdf(v, l, coat_normal(p), coat_alpha(p)); }
    if probs.y > 0.0 && l.z > 0.0 { pdf += probs.y / (2.0 * PI); }
    return pdf;
}

fn layered_sample(v: vec3<f32>, p: BsdfParams, u_lobe: f32, u: vec2<f32>) -> BsdfSample {
    let failed = BsdfSample(vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0), 0.0, 0u);
    if v.z <= 0.0 { return failed; }
    let probs = layer_probabilities(v, p);
    var l: vec3<f32>;
    var flags = BSDF_REFLECTION | BSDF_GLOSSY;
    if u_lobe < probs.x {
        let frame = basis(coat_normal(p));
        let vc = v * frame;
        if vc.z <= 0.0 { return failed; }
        l = frame * reflect(-vc, sample_vndf(vc, coat_alpha(p), u));
    } else if u_lobe < probs.x + probs.y {
        l = sample_uniform_hemisphere(u);
    } else {
        // The rest of u_lobe's range, stretched back to [0, 1), picks the material's lobe.
        let rest = 1.0 - probs.x - probs.y;
        let b = base_bsdf_sample(v, p, min((u_lobe - probs.x - probs.y) / rest, 0.99999994), u);
        if b.flags == 0u { return failed; }
        l = b.wi;
        flags = b.flags;
    }
    let transmitted = (flags & BSDF_TRANSMISSION) != 0u;
    let pdf = layered_pdf(v, l, p, probs);
    if (l.z > 0.0) == transmitted || l.z == 0.0 || pdf <= 0.0 {
        return BsdfSample(l, vec3<f32>(0.0), 0.0, 0u);
    }
    return BsdfSample(l, layered_eval(v, l, p, base_bsdf_eval(v, l, p)) * abs(l.z) / pdf, pdf, flags);
}

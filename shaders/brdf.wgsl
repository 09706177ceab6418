// The glTF 2.0 metallic-roughness BRDF (specification, Appendix B), exactly: Lambert diffuse weighted by
// 1 - F, GGX distribution, height-correlated Smith visibility, Schlick Fresnel, f0 = 0.04 for the dielectric,
// f0 = baseColor for the metal, alpha = roughness^2. Vectors are in the local shading frame (z = normal).
// Sampling: a mixture of cosine-weighted diffuse and GGX visible-normal sampling, with the exact mixture pdf.

// Below this alpha GGX is a mirror for every practical purpose; the floor keeps D finite at roughness 0.
const MIN_ALPHA: f32 = 1e-4;

struct BrdfParams {
    base_color: vec3<f32>,
    metallic: f32,
    alpha: f32,
}

fn pow5(x: f32) -> f32 {
    let x2 = x * x;
    return x2 * x2 * x;
}

// GGX normal distribution, written with h.x^2 + h.y^2 instead of 1 - (n.h)^2 so it stays exact for tiny alpha.
fn ggx_d(h: vec3<f32>, a2: f32) -> f32 {
    let k = h.x * h.x + h.y * h.y + a2 * h.z * h.z;
    return a2 / (PI * k * k);
}

// Height-correlated Smith visibility V = G2 / (4 n.l n.v).
fn smith_visibility(nl: f32, nv: f32, a2: f32) -> f32 {
    let gv = nl * sqrt(nv * nv * (1.0 - a2) + a2);
    let gl = nv * sqrt(nl * nl * (1.0 - a2) + a2);
    return 0.5 / (gv + gl);
}

fn smith_g1(nv: f32, a2: f32) -> f32 {
    return 2.0 * nv / (nv + sqrt(a2 + (1.0 - a2) * nv * nv));
}

// f(v, l), without the cosine. Zero below either horizon.
fn brdf_eval(v: vec3<f32>, l: vec3<f32>, p: BrdfParams) -> vec3<f32> {
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
fn specular_probability(v: vec3<f32>, p: BrdfParams) -> f32 {
    let fw = pow5(1.0 - clamp(v.z, 0.0, 1.0));
    let f_dielectric = 0.04 + 0.96 * fw;
    let f_metal = luminance(p.base_color + (vec3<f32>(1.0) - p.base_color) * fw);
    let spec = mix(f_dielectric, f_metal, p.metallic);
    let diffuse = (1.0 - p.metallic) * (1.0 - f_dielectric) * luminance(p.base_color);
    if diffuse <= 0.0 { return 1.0; }
    return clamp(spec / (spec + diffuse), 0.1, 0.9);
}

fn brdf_pdf(v: vec3<f32>, l: vec3<f32>, p: BrdfParams) -> f32 {
    if v.z <= 0.0 || l.z <= 0.0 { return 0.0; }
    let ps = specular_probability(v, p);
    let h = normalize(v + l);
    let a2 = p.alpha * p.alpha;
    let spec_pdf = smith_g1(v.z, a2) * ggx_d(h, a2) / (4.0 * v.z);
    return ps * spec_pdf + (1.0 - ps) * l.z * INV_PI;
}

// GGX visible-normal sampling by spherical caps (Dupuy & Benyoub 2023).
fn sample_vndf(v: vec3<f32>, alpha: f32, u: vec2<f32>) -> vec3<f32> {
    let vs = normalize(vec3<f32>(v.xy * alpha, v.z));
    let phi = 2.0 * PI * u.x;
    let z = (1.0 - u.y) * (1.0 + vs.z) - vs.z;
    let sin_theta = sqrt(clamp(1.0 - z * z, 0.0, 1.0));
    let c = vec3<f32>(sin_theta * cos(phi), sin_theta * sin(phi), z);
    let hs = c + vs;
    return normalize(vec3<f32>(hs.xy * alpha, hs.z));
}

fn sample_cosine(u: vec2<f32>) -> vec3<f32> {
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    return vec3<f32>(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u.x)));
}

struct BrdfSample {
    l: vec3<f32>,
    // f * cos / pdf
    weight: vec3<f32>,
    pdf: f32,
}

// Samples a direction; weight is zero when it falls below the horizon.
fn brdf_sample(v: vec3<f32>, p: BrdfParams, u: vec3<f32>) -> BrdfSample {
    var l: vec3<f32>;
    if u.x < specular_probability(v, p) {
        let h = sample_vndf(v, p.alpha, u.yz);
        l = reflect(-v, h);
    } else {
        l = sample_cosine(u.yz);
    }
    let pdf = brdf_pdf(v, l, p);
    if l.z <= 0.0 || pdf <= 0.0 {
        return BrdfSample(l, vec3<f32>(0.0), 0.0);
    }
    return BrdfSample(l, brdf_eval(v, l, p) * l.z / pdf, pdf);
}

// Orthonormal basis around n (Duff et al. 2017).
fn basis(n: vec3<f32>) -> mat3x3<f32> {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let t = vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let bt = vec3<f32>(b, s + n.y * n.y * a, -n.y);
    return mat3x3<f32>(t, bt, n);
}

// The GGX (Trowbridge-Reitz) microfacet model with height-correlated Smith masking, in the local shading frame
// (z = normal): the distribution, the visibility term, and visible-normal sampling.

// Below this alpha GGX is a mirror for every practical purpose; the floor keeps D finite at roughness 0.
const MIN_ALPHA: f32 = 1e-4;

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

// Density of reflecting `v` into `l` by a visible normal: G1(v) D(h) / (4 v.z), with h = normalize(v + l).
fn ggx_reflection_pdf(v: vec3<f32>, l: vec3<f32>, a2: f32) -> f32 {
    let h = normalize(v + l);
    return smith_g1(v.z, a2) * ggx_d(h, a2) / (4.0 * v.z);
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

// The KHR_materials_sheen BRDF (the extension's implementation notes): the "Charlie" distribution and visibility
// of Estevez & Kulla 2017 ("Production Friendly Microfacet Sheen BRDF"), no Fresnel, alpha = sheenRoughness^2
// (at least SHEEN_MIN_ALPHA: at 0 the lobe would be a line on the horizon), and its directional albedo E from the
// generated fit (sheen_albedo.wgsl), which the albedo scaling dims the base with.

fn charlie_d(cos_h: f32, alpha: f32) -> f32 {
    let sin2 = max(1.0 - cos_h * cos_h, 0.0);
    return (2.0 + 1.0 / alpha) * pow(sin2, 0.5 / alpha) / (2.0 * PI);
}

// The fit of Lambda's logarithm that the extension quotes, interpolated between its two alpha ends by (1 - alpha)^2.
fn charlie_fit(x: f32, alpha: f32) -> f32 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let a = mix(21.5473, 25.3245, t);
    let b = mix(3.82987, 3.32435, t);
    let c = mix(0.19823, 0.16801, t);
    let d = mix(-1.97760, -1.27393, t);
    let e = mix(-4.32054, -4.85967, t);
    return a / (1.0 + b * pow(x, c)) + d * x + e;
}

fn charlie_lambda(cos_theta: f32, alpha: f32) -> f32 {
    let c = abs(cos_theta);
    if c < 0.5 { return exp(charlie_fit(c, alpha)); }
    return exp(2.0 * charlie_fit(0.5, alpha) - charlie_fit(1.0 - c, alpha));
}

// D V for v and l above the surface (local frame), without the sheen colour and the cosine.
fn sheen_brdf(v: vec3<f32>, l: vec3<f32>, alpha: f32) -> f32 {
    let h = normalize(v + l);
    let visibility = 1.0 / ((1.0 + charlie_lambda(v.z, alpha) + charlie_lambda(l.z, alpha)) * 4.0 * v.z * l.z);
    return charlie_d(h.z, alpha) * visibility;
}

// E(cos, roughness) from the generated fit, inside the range it was fitted on (cos_view down to 0.01; below
// roughness 0.1 alpha is clamped, so E does not change).
fn sheen_albedo(cos_theta: f32, roughness: f32) -> f32 {
    let x = 2.0 * clamp(abs(cos_theta), 0.01, 1.0) - 1.0;
    let y = 2.0 * log(clamp(roughness, SHEEN_ALBEDO_MIN_ROUGHNESS, 1.0)) / -log(SHEEN_ALBEDO_MIN_ROUGHNESS) + 1.0;
    return max(sheen_albedo_fit(x, y), 0.0);
}

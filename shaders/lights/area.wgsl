// Area lights: emissive triangles, picked in proportion to their power (luminance x world area) for next-event
// estimation, sampled uniformly by area, weighed against BSDF sampling by the power heuristic.

// Probability density (solid angle) that next-event estimation picks the point `hit` seen from `origin`.
fn light_pdf(hit: Hit, s: SurfaceInteraction, distance: f32, dir: vec3<f32>) -> f32 {
    let p = world_triangle(hit.instance, hit.triangle);
    let cross_p = cross(p[1] - p[0], p[2] - p[0]);
    let area = 0.5 * length(cross_p);
    let power = luminance(materials[triangles[hit.triangle].w].emissive) * area;
    let cos_l = abs(dot(s.ng, dir));
    if area <= 0.0 || cos_l <= 0.0 || frame.emitter_total_power <= 0.0 { return 0.0; }
    // pmf = power / total; area pdf = pmf / area; solid-angle pdf = area pdf * d^2 / cos.
    return (power / frame.emitter_total_power) / area * distance * distance / cos_l;
}

// A light sample for next-event estimation: the shadow ray to test and what it adds when unblocked.
struct LightSample {
    ray: Ray,
    t_max: f32,
    // Unoccluded contribution (BSDF x cos x emission x MIS weight / pdf); zero when nothing to test.
    contribution: vec3<f32>,
}

// Direct light from one emissive triangle picked by power, weighted against BSDF sampling. The shadow ray is
// returned, not traced, so that the path loop traces every ray at one call site (smaller kernel).
fn sample_light(s: SurfaceInteraction, v_local: vec3<f32>, frame_basis: mat3x3<f32>, rng: ptr<function, Rng>) -> LightSample {
    var none = LightSample(Ray(vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0)), 0.0, vec3<f32>(0.0));
    let u = rand(rng);
    var lo = 0u;
    var hi = frame.emitter_count - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if emitters[mid].cdf < u { lo = mid + 1u; } else { hi = mid; }
    }
    let e = emitters[lo];
    let p = world_triangle(e.instance, e.triangle);
    var b1 = rand(rng);
    var b2 = rand(rng);
    if b1 + b2 > 1.0 { b1 = 1.0 - b1; b2 = 1.0 - b2; }
    let point = p[0] * (1.0 - b1 - b2) + p[1] * b1 + p[2] * b2;
    let cross_p = cross(p[1] - p[0], p[2] - p[0]);
    let area = 0.5 * length(cross_p);
    if area <= 0.0 { return none; }
    let nl = cross_p / (2.0 * area);
    let m = materials[triangles[e.triangle].w];
    let origin = offset_ray_origin(s.p, s.ng);
    let to_light = point - origin;
    let dist2 = dot(to_light, to_light);
    let dist = sqrt(dist2);
    let dir = to_light / dist;
    let cos_l_signed = -dot(nl, dir);
    let double_sided = (m.flags & MATERIAL_DOUBLE_SIDED) != 0u;
    if cos_l_signed <= 0.0 && !double_sided { return none; }
    let cos_l = abs(cos_l_signed);
    if cos_l <= 1e-7 || dot(dir, s.ng) <= 0.0 { return none; }
    let l_local = dir * frame_basis;
    let f = bsdf_eval(v_local, l_local, s.bsdf);
    if all(f == vec3<f32>(0.0)) { return none; }
    var emission = m.emissive;
    if m.emissive_texture != NONE {
        let inst = instances[e.instance];
        let mesh = meshes[inst.mesh];
        emission *= srgb_to_linear(sample_texture(m.emissive_texture, texture_uv(m.emissive_texture, mesh, triangles[e.triangle], vec3<f32>(1.0 - b1 - b2, b1, b2))).rgb);
    }
    let power = luminance(m.emissive) * area;
    let pdf_light = (power / frame.emitter_total_power) / area * dist2 / cos_l;
    let pdf_brdf = bsdf_pdf(v_local, l_local, s.bsdf);
    // Stop the shadow ray just short of the light so it cannot hit the light itself.
    return LightSample(Ray(origin, dir), dist * (1.0 - 1e-4), f * l_local.z * emission * power_heuristic(pdf_light, pdf_brdf) / pdf_light);
}

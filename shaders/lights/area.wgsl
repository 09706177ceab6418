// Area lights: emissive triangles, sampled uniformly by area (pbrt-v4 `DiffuseAreaLight` with `Triangle`). One-
// or two-sided as the material says; textured emission evaluated at the sampled point.

// Emission of the light's material at barycentrics (b1, b2) of its triangle.
fn area_light_emission(instance: u32, slot: u32, b: vec2<f32>) -> vec3<f32> {
    let m = materials[triangles[slot].w];
    var emission = m.emissive;
    if m.emissive_texture != NONE {
        let mesh = meshes[instances[instance].mesh];
        let w = vec3<f32>(1.0 - b.x - b.y, b.x, b.y);
        emission *= srgb_to_linear(sample_texture(m.emissive_texture, texture_uv(m.emissive_texture, mesh, triangles[slot], w)).rgb);
    }
    return emission;
}

// A point on the emitter seen from the shading point `origin`: direction, distance, arriving radiance and
// the solid-angle density of having picked that point.
fn area_light_sample_li(e: Emitter, origin: vec3<f32>, u: vec2<f32>) -> LightLiSample {
    let p = world_triangle(e.instance, e.triangle);
    let b = sample_triangle_uniform(u);
    let point = p[0] * (1.0 - b.x - b.y) + p[1] * b.x + p[2] * b.y;
    let cross_p = cross(p[1] - p[0], p[2] - p[0]);
    let area = 0.5 * length(cross_p);
    if area <= 0.0 { return no_light_sample(); }
    let nl = cross_p / (2.0 * area);
    let to_light = point - origin;
    let dist2 = dot(to_light, to_light);
    let dist = sqrt(dist2);
    let dir = to_light / dist;
    let cos_l_signed = -dot(nl, dir);
    let double_sided = (materials[triangles[e.triangle].w].flags & MATERIAL_DOUBLE_SIDED) != 0u;
    if cos_l_signed <= 0.0 && !double_sided { return no_light_sample(); }
    let cos_l = abs(cos_l_signed);
    if cos_l <= 1e-7 { return no_light_sample(); }
    return LightLiSample(dir, dist, area_light_emission(e.instance, e.triangle, b), area_light_pdf(area, dist2, cos_l), false);
}

// Solid-angle density of sampling a point on a triangle of `area` by area, seen at squared distance `dist2`
// under cosine `cos_l` at the light.
fn area_light_pdf(area: f32, dist2: f32, cos_l: f32) -> f32 {
    if area <= 0.0 || cos_l <= 0.0 { return 0.0; }
    return dist2 / (cos_l * area);
}

fn triangle_area(p: array<vec3<f32>, 3>) -> f32 {
    return 0.5 * length(cross(p[1] - p[0], p[2] - p[0]));
}

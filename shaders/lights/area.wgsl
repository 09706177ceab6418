// Area lights: emissive triangles (pbrt-v4 `DiffuseAreaLight` with `Triangle`), `index_a` = instance,
// `index_b` = triangle slot. One- or two-sided as the material says; textured emission evaluated at the
// sampled point.
//
// Seen from the shading point, a triangle is sampled uniformly in solid angle (Arvo's spherical triangles):
// the density 1 / solid angle stays bounded however close the light is, so a shading point next to an emitter
// (the Cornell box's ceiling above its lamp) no longer gets the 1/d^2 spikes of area sampling, whose variance
// is infinite there. Triangles that subtend very little (where the spherical formulas lose precision in f32)
// or almost a hemisphere fall back to area sampling, as pbrt-v4 does; the choice depends only on the shading
// point, so `triangle_light_pdf` makes the same one.

const MIN_SPHERICAL_SAMPLE_AREA: f32 = 3e-4;
const MAX_SPHERICAL_SAMPLE_AREA: f32 = 6.22;

// Emission of material `m` of the light's triangle at barycentrics (b1, b2).
fn area_light_emission(m: Material, instance: u32, slot: u32, b: vec2<f32>) -> vec3<f32> {
    var emission = m.emissive;
    if scene_uses_texture(CORE_TEXTURE_EMISSIVE) && m.emissive_texture != NONE {
        let mesh = read_mesh(read_instance(instance).mesh);
        let w = vec3<f32>(1.0 - b.x - b.y, b.x, b.y);
        emission *= srgb_to_linear(sample_texture(m.emissive_texture, texture_uv(m.emissive_texture, mesh, read_triangle(slot), w)).rgb);
    }
    return emission;
}

fn triangle_area(p: array<vec3<f32>, 3>) -> f32 {
    return 0.5 * length(cross(p[1] - p[0], p[2] - p[0]));
}

// The unit directions from `origin` to the triangle's corners (its spherical triangle seen from there).
fn triangle_directions(p: array<vec3<f32>, 3>, origin: vec3<f32>) -> array<vec3<f32>, 3> {
    return array<vec3<f32>, 3>(normalize(p[0] - origin), normalize(p[1] - origin), normalize(p[2] - origin));
}

// Solid angle of the spherical triangle `d` (triangle_directions), or 0 when the triangle is to be area-sampled
// from there.
fn triangle_spherical_area(d: array<vec3<f32>, 3>) -> f32 {
    let omega = spherical_triangle_area(d[0], d[1], d[2]);
    return select(0.0, omega, omega >= MIN_SPHERICAL_SAMPLE_AREA && omega <= MAX_SPHERICAL_SAMPLE_AREA);
}

// Whether the side of the triangle that `origin` sees emits (`m`: the triangle's material).
fn triangle_emits_towards(m: Material, p: array<vec3<f32>, 3>, origin: vec3<f32>) -> bool {
    let side = dot(cross(p[1] - p[0], p[2] - p[0]), origin - p[0]);
    let double_sided = (m.flags & MATERIAL_DOUBLE_SIDED) != 0u;
    return side > 0.0 || (side < 0.0 && double_sided);
}

// The material of the light's triangle.
fn area_light_material(light: Light) -> Material {
    return read_material(read_triangle(light.index_b).w);
}

// Where a direction sampled inside the triangle's solid angle meets its plane: (distance, b1, b2), with the
// barycentrics clamped into the triangle (f32 rounding can put a direction on the edge a hair outside, and such
// a sample must not be lost).
fn triangle_plane_hit(p: array<vec3<f32>, 3>, origin: vec3<f32>, dir: vec3<f32>) -> vec3<f32> {
    let e1 = p[1] - p[0];
    let e2 = p[2] - p[0];
    let n = cross(e1, e2);
    let t = dot(n, p[0] - origin) / dot(n, dir);
    let q = origin + t * dir - p[0];
    // Barycentrics of q by Cramer's rule on the edge vectors.
    let d11 = dot(e1, e1);
    let d12 = dot(e1, e2);
    let d22 = dot(e2, e2);
    let q1 = dot(q, e1);
    let q2 = dot(q, e2);
    let det = d11 * d22 - d12 * d12;
    var b = clamp(vec2<f32>(d22 * q1 - d12 * q2, d11 * q2 - d12 * q1) / det, vec2<f32>(0.0), vec2<f32>(1.0));
    if b.x + b.y > 1.0 { b /= b.x + b.y; }
    return vec3<f32>(t, b);
}

fn triangle_light_sample_li(light: Light, ctx: LightSampleContext, u: vec2<f32>) -> LightLiSample {
    let p = world_triangle(light.index_a, light.index_b);
    let area = triangle_area(p);
    let m = area_light_material(light);
    if area <= 0.0 || !triangle_emits_towards(m, p, ctx.p) { return no_light_sample(); }
    // The direction, distance, barycentrics and density of either way of sampling; the emission there once.
    var dir: vec3<f32>;
    var distance: f32;
    var b: vec2<f32>;
    var pdf: f32;
    let n = cross(p[1] - p[0], p[2] - p[0]) / (2.0 * area);
    let d = triangle_directions(p, ctx.p);
    let omega = triangle_spherical_area(d);
    if omega > 0.0 {
        dir = sample_spherical_triangle(d[0], d[1], d[2], omega, u);
        let h = triangle_plane_hit(p, ctx.p, dir);
        if h.x <= 0.0 || !is_finite(h.x) { return no_light_sample(); }
        distance = h.x;
        b = h.yz;
        pdf = 1.0 / omega;
    } else {
        b = sample_triangle_uniform(u);
        let point = p[0] * (1.0 - b.x - b.y) + p[1] * b.x + p[2] * b.y;
        let to_light = point - ctx.p;
        let distance2 = dot(to_light, to_light);
        if distance2 <= 0.0 { return no_light_sample(); }
        distance = sqrt(distance2);
        dir = to_light / distance;
        let cos_l = abs(dot(n, dir));
        if cos_l <= 1e-7 { return no_light_sample(); }
        pdf = distance2 / (cos_l * area);
    }
    let facing = select(n, -n, dot(n, ctx.p - p[0]) < 0.0);
    return LightLiSample(dir, distance, area_light_emission(m, light.index_a, light.index_b, b), pdf, false, facing);
}

// Solid-angle density with which `triangle_light_sample_li` from ctx gives direction `wi`, which meets the
// triangle at `distance`.
fn triangle_light_pdf(light: Light, ctx: LightSampleContext, wi: vec3<f32>, distance: f32) -> f32 {
    let p = world_triangle(light.index_a, light.index_b);
    let area = triangle_area(p);
    if area <= 0.0 || !triangle_emits_towards(area_light_material(light), p, ctx.p) { return 0.0; }
    let omega = triangle_spherical_area(triangle_directions(p, ctx.p));
    if omega > 0.0 { return 1.0 / omega; }
    let n = cross(p[1] - p[0], p[2] - p[0]) / (2.0 * area);
    let cos_l = abs(dot(n, wi));
    if cos_l <= 0.0 { return 0.0; }
    return distance * distance / (cos_l * area);
}

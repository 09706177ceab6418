// Warps from the unit square to directions and points (pbrt-v4 `sampling.h`).

// Cosine-weighted direction about +z: pdf = z / pi.
fn sample_cosine_hemisphere(u: vec2<f32>) -> vec3<f32> {
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    return vec3<f32>(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u.x)));
}

// Uniform direction over the hemisphere about +z: pdf = 1 / (2 pi).
fn sample_uniform_hemisphere(u: vec2<f32>) -> vec3<f32> {
    let z = u.x;
    let r = sqrt(max(0.0, 1.0 - z * z));
    let phi = 2.0 * PI * u.y;
    return vec3<f32>(r * cos(phi), r * sin(phi), z);
}

// Barycentrics (b1, b2) of a uniform point on a triangle (the fold of the unit square).
fn sample_triangle_uniform(u: vec2<f32>) -> vec2<f32> {
    var b1 = u.x;
    var b2 = u.y;
    if b1 + b2 > 1.0 { b1 = 1.0 - b1; b2 = 1.0 - b2; }
    return vec2<f32>(b1, b2);
}

// Uniform point on the unit disc, Shirley & Chiu's concentric map (low distortion: stratified lens samples stay
// stratified).
fn sample_concentric_disk(u: vec2<f32>) -> vec2<f32> {
    let o = 2.0 * u - 1.0;
    if o.x == 0.0 && o.y == 0.0 { return vec2<f32>(0.0); }
    if abs(o.x) > abs(o.y) {
        let theta = 0.25 * PI * (o.y / o.x);
        return o.x * vec2<f32>(cos(theta), sin(theta));
    }
    let theta = 0.5 * PI - 0.25 * PI * (o.x / o.y);
    return o.y * vec2<f32>(cos(theta), sin(theta));
}

// Uniform direction in the cone of half-angle theta_max about +z, given 1 - cos(theta_max) (kept apart from
// cos for small cones such as the sun's): pdf = 1 / (2 pi (1 - cos theta_max)).
fn sample_uniform_cone(u: vec2<f32>, one_minus_cos_max: f32) -> vec3<f32> {
    let one_minus_cos = u.x * one_minus_cos_max;
    let cos_theta = 1.0 - one_minus_cos;
    let sin_theta = sqrt(max(0.0, one_minus_cos * (2.0 - one_minus_cos)));
    let phi = 2.0 * PI * u.y;
    return vec3<f32>(sin_theta * cos(phi), sin_theta * sin(phi), cos_theta);
}

// The angle between unit vectors, accurate near 0 and pi (where acos(dot) is not).
fn angle_between(a: vec3<f32>, b: vec3<f32>) -> f32 {
    if dot(a, b) < 0.0 { return PI - 2.0 * asin(min(1.0, 0.5 * length(a + b))); }
    return 2.0 * asin(min(1.0, 0.5 * length(b - a)));
}

// Solid angle of the spherical triangle of unit vectors a, b, c (Van Oosterom & Strackee 1983).
fn spherical_triangle_area(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    return abs(2.0 * atan2(dot(a, cross(b, c)), 1.0 + dot(a, b) + dot(a, c) + dot(b, c)));
}

// The part of v orthogonal to unit w, normalised.
fn orthonormal_part(v: vec3<f32>, w: vec3<f32>) -> vec3<f32> {
    return normalize(v - dot(v, w) * w);
}

// A direction uniformly distributed over the spherical triangle of unit vectors a, b, c (Arvo, "Stratified
// Sampling of Spherical Triangles", SIGGRAPH 1995): u.x picks the sub-triangle's area, u.y the point along
// the arc from b. The density is 1 / spherical_triangle_area(a, b, c); a zero vector when the triangle is
// degenerate.
fn sample_spherical_triangle(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    // Normals of the great circles through each edge; the triangle's angles are between them.
    var n_ab = cross(a, b);
    var n_bc = cross(b, c);
    var n_ca = cross(c, a);
    if dot(n_ab, n_ab) == 0.0 || dot(n_bc, n_bc) == 0.0 || dot(n_ca, n_ca) == 0.0 { return vec3<f32>(0.0); }
    n_ab = normalize(n_ab);
    n_bc = normalize(n_bc);
    n_ca = normalize(n_ca);
    let alpha = angle_between(n_ab, -n_ca);
    let beta = angle_between(n_bc, -n_ab);
    let gamma = angle_between(n_ca, -n_bc);
    // The sub-triangle (a, b, c') with area u.x times the whole: its angle sum is that area + pi.
    let area_pi = mix(PI, alpha + beta + gamma, u.x);
    let cos_alpha = cos(alpha);
    let sin_alpha = sin(alpha);
    let sin_phi = sin(area_pi) * cos_alpha - cos(area_pi) * sin_alpha;
    let cos_phi = cos(area_pi) * cos_alpha + sin(area_pi) * sin_alpha;
    let k1 = cos_phi + cos_alpha;
    let k2 = sin_phi - sin_alpha * dot(a, b);
    let denominator = (k2 * sin_phi + k1 * cos_phi) * sin_alpha;
    if denominator == 0.0 { return vec3<f32>(0.0); }
    let cos_bp = clamp((k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha) / denominator, -1.0, 1.0);
    let sin_bp = sqrt(max(0.0, 1.0 - cos_bp * cos_bp));
    // c' on the arc from a to c, then a point on the arc from b to c'.
    let cp = cos_bp * a + sin_bp * orthonormal_part(c, a);
    let cos_theta = 1.0 - u.y * (1.0 - dot(cp, b));
    let sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    return cos_theta * b + sin_theta * orthonormal_part(cp, b);
}

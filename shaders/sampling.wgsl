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

// sin and cos of an angle in [0, 2 pi) as (sin, cos), to the relative precision a small angle needs: below 0.5
// by their Taylor series (truncation below 1e-8), above by the built-ins. The built-ins, like every SPIR-V
// transcendental, are promised only to an absolute error (2^-11 by the specification; Mesa's lavapipe, and its
// asin, much worse than f32's rounding), which is large against a small spherical triangle's area.
fn sin_cos_of_angle(x: f32) -> vec2<f32> {
    if x >= 0.5 { return vec2<f32>(sin(x), cos(x)); }
    let x2 = x * x;
    let s = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0))));
    let c = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)));
    return vec2<f32>(s, c);
}

// Solid angle of the spherical triangle of unit vectors a, b, c (Van Oosterom & Strackee 1983).
fn spherical_triangle_area(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    return abs(2.0 * atan2(dot(a, cross(b, c)), 1.0 + dot(a, b) + dot(a, c) + dot(b, c)));
}

// The part of v orthogonal to unit w, normalised.
fn orthonormal_part(v: vec3<f32>, w: vec3<f32>) -> vec3<f32> {
    return normalize(v - dot(v, w) * w);
}

// A direction uniformly distributed over the spherical triangle of unit vectors a, b, c, whose solid angle is
// `area` (spherical_triangle_area) (Arvo, "Stratified Sampling of Spherical Triangles", SIGGRAPH 1995): u.x picks
// the sub-triangle's area, u.y the point along the arc from b. The density is 1 / area; a zero vector when the
// triangle is degenerate. Arvo's formulas take the sub-triangle's angle sum, pi + its area, from the sum of the
// triangle's three angles; with GPU asin (Mesa's is a cubic) that sum minus pi missed a 0.0007 sr triangle's area
// entirely (and a 0.007 sr one by 5%), and the directions were not spread over the triangle that the density
// 1 / area assumed: light from small and thin emitters came out dark (docs/ACCURACY.md). So the sub-area here is
// u.x times the given area (Van Oosterom and Strackee's formula, accurate however small), and the formulas need
// only the angle at a, whose sine and cosine come from the edge planes' normals without any transcendental.
fn sample_spherical_triangle(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, area: f32, u: vec2<f32>) -> vec3<f32> {
    // Normals of the great circles through the edges at a; the angle at a is between them.
    var n_ab = cross(a, b);
    var n_ac = cross(a, c);
    if dot(n_ab, n_ab) == 0.0 || dot(n_ac, n_ac) == 0.0 { return vec3<f32>(0.0); }
    n_ab = normalize(n_ab);
    n_ac = normalize(n_ac);
    let cos_alpha = dot(n_ab, n_ac);
    let sin_alpha = length(cross(n_ab, n_ac));
    // The sub-triangle (a, b, c') of area s = u.x * area has angle sum pi + s, and Arvo's phi = pi + s - alpha:
    // sin(phi) = sin(alpha - s), cos(phi) = -cos(alpha - s).
    let sc = sin_cos_of_angle(u.x * area);
    let sin_phi = sin_alpha * sc.y - cos_alpha * sc.x;
    let cos_phi = -(cos_alpha * sc.y + sin_alpha * sc.x);
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

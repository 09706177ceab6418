// Warps from the unit square to directions and points (pbrt-v4 `sampling.h`).

// Cosine-weighted direction about +z: pdf = z / pi.
fn sample_cosine_hemisphere(u: vec2<f32>) -> vec3<f32> {
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    return vec3<f32>(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u.x)));
}

// Barycentrics (b1, b2) of a uniform point on a triangle (the fold of the unit square).
fn sample_triangle_uniform(u: vec2<f32>) -> vec2<f32> {
    var b1 = u.x;
    var b2 = u.y;
    if b1 + b2 > 1.0 { b1 = 1.0 - b1; b2 = 1.0 - b2; }
    return vec2<f32>(b1, b2);
}

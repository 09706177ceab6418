// Small numeric helpers shared by every kernel: constants, 3x4 affine transforms, an orthonormal basis, MIS
// weights and finiteness checks.

const PI: f32 = 3.14159265358979;
const INV_PI: f32 = 0.318309886183791;

fn transform_point(m: mat3x4<f32>, p: vec3<f32>) -> vec3<f32> {
    let h = vec4<f32>(p, 1.0);
    return vec3<f32>(dot(m[0], h), dot(m[1], h), dot(m[2], h));
}
fn transform_vector(m: mat3x4<f32>, v: vec3<f32>) -> vec3<f32> {
    let h = vec4<f32>(v, 0.0);
    return vec3<f32>(dot(m[0], h), dot(m[1], h), dot(m[2], h));
}
// Normals transform by the inverse transpose: columns of object_from_world's 3x3.
fn transform_normal(object_from_world: mat3x4<f32>, n: vec3<f32>) -> vec3<f32> {
    return object_from_world[0].xyz * n.x + object_from_world[1].xyz * n.y + object_from_world[2].xyz * n.z;
}

// Orthonormal basis around n (Duff et al. 2017): columns tangent, bitangent, n.
fn basis(n: vec3<f32>) -> mat3x3<f32> {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let t = vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let bt = vec3<f32>(b, s + n.y * n.y * a, -n.y);
    return mat3x3<f32>(t, bt, n);
}

// Veach's power heuristic (beta = 2) for the strategy with pdf `a` against one with pdf `b`.
fn power_heuristic(a: f32, b: f32) -> f32 {
    let a2 = a * a;
    return a2 / (a2 + b * b);
}

fn finite3(v: vec3<f32>) -> bool {
    // NaN fails every comparison; infinities exceed the largest finite f32.
    return all(abs(v) <= vec3<f32>(3.0e38));
}

// Bit test, immune to fast-math assumptions about NaN and infinity.
fn is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

// By the bits, like is_finite: a compiler that assumes finite floats may fold a comparison with NaN away.
fn is_nan(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7fffffffu) > 0x7f800000u;
}

// Each channel clamped to [lo, hi], NaN as 0 (the host's oidn::filter::sanitized).
fn sanitised3(v: vec3<f32>, lo: f32, hi: f32) -> vec3<f32> {
    var out = vec3<f32>(0.0);
    for (var c = 0u; c < 3u; c++) {
        out[c] = select(clamp(v[c], lo, hi), 0.0, is_nan(v[c]));
    }
    return out;
}

// Rust's f32::signum: the sign bit decides, so -0.0 gives -1.
fn signum(x: f32) -> f32 {
    return select(1.0, -1.0, (bitcast<u32>(x) & 0x80000000u) != 0u);
}

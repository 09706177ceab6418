// Octahedral encoding of unit vectors in two snorm16 values (normals and tangents in the vertex pool).
// INVALID_OCT marks a missing vector (pack2x16snorm never produces it).

// Unit vector -> two snorm16 values: engine/src/render/layout.rs `oct_encode`, operation for operation.
fn oct_encode(v: vec3<f32>) -> u32 {
    let len = length(v);
    if !is_finite(len) || len < 1e-12 { return INVALID_OCT; }
    let n = v / (abs(v.x) + abs(v.y) + abs(v.z));
    var e = n.xy;
    if n.z < 0.0 {
        e = vec2<f32>((1.0 - abs(n.y)) * signum(n.x), (1.0 - abs(n.x)) * signum(n.y));
    }
    return pack2x16snorm(e);
}

fn oct_decode(word: u32) -> vec3<f32> {
    let e = unpack2x16snorm(word);
    var n = vec3<f32>(e.x, e.y, 1.0 - abs(e.x) - abs(e.y));
    let t = max(-n.z, 0.0);
    n.x += select(t, -t, n.x >= 0.0);
    n.y += select(t, -t, n.y >= 0.0);
    return normalize(n);
}

// The real-time path's G-buffer: per pixel, what the (jittered) camera ray hit first, enough to shade it
// again, validate history against it and reuse light samples at it (engine/src/render/realtime.rs keeps the
// current and the previous frame's). 64 bytes.

struct GSurface {
    // World position of the hit; camera depth along the view axis, < 0 where the ray left the scene.
    position: vec3<f32>, depth: f32,
    // Stable object id (NONE: nothing hit), triangle slot, barycentrics of the second and third vertices.
    object: u32, triangle: u32, bary: vec2<f32>,
    // Octahedral shading and geometric normals (facing the camera), and the BSDF's parameters packed.
    normal: u32, geometric: u32, bsdf: vec2<u32>,
    // Screen motion to the previous frame (previous minus current position of the hit, pixels), the hit's
    // camera depth in the previous frame, and its material.
    motion: vec2<f32>, prev_depth: f32, material: u32,
}

fn gsurface_miss() -> GSurface {
    var g: GSurface;
    g.position = vec3<f32>(0.0);
    g.depth = -1.0;
    g.object = NONE;
    g.triangle = 0u;
    g.bary = vec2<f32>(0.0);
    g.normal = INVALID_OCT;
    g.geometric = INVALID_OCT;
    g.bsdf = vec2<u32>(0u);
    g.motion = vec2<f32>(0.0);
    g.prev_depth = -1.0;
    g.material = NONE;
    return g;
}

fn gsurface_hit(g: GSurface) -> bool {
    return g.object != NONE;
}

// The BSDF parameters that light reuse evaluates at a G-buffer surface: base colour and metallic as unorm8,
// alpha as f32. The one place to extend when the BSDF grows lobes.
fn pack_bsdf(p: BsdfParams) -> vec2<u32> {
    return vec2<u32>(pack4x8unorm(vec4<f32>(p.base_color, p.metallic)), bitcast<u32>(p.alpha));
}

fn unpack_bsdf(w: vec2<u32>) -> BsdfParams {
    let c = unpack4x8unorm(w.x);
    return core_bsdf(c.rgb, c.a, bitcast<f32>(w.y));
}

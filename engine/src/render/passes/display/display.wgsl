// Shows the tone-mapped image (packed RGBA8, already sRGB-encoded, from tonemap.wgsl) in the viewer's image
// area. A triangle covers the viewport (the area); each fragment reads the image texel under it (nearest), so
// an image drawn at its own size lands pixel for pixel on the window.

struct DisplayParams {
    // Image area in framebuffer pixels: top-left and size.
    origin: vec2<f32>,
    size: vec2<f32>,
    image_width: u32,
    image_height: u32,
    // 1 when the framebuffer is an sRGB format (it expects linear values and encodes them itself).
    srgb_target: u32,
    _pad: u32,
}

@group(0) @binding(0) var<storage, read> pixels: array<u32>;
@group(0) @binding(1) var<uniform> params: DisplayParams;

@vertex
fn display_vertex(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn display_fragment(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let image = vec2<u32>(params.image_width, params.image_height);
    let local = max((pos.xy - params.origin) / params.size, vec2<f32>(0.0));
    let p = min(vec2<u32>(local * vec2<f32>(image)), image - vec2<u32>(1u));
    let c = unpack4x8unorm(pixels[p.y * image.x + p.x]);
    if params.srgb_target == 1u {
        return vec4<f32>(srgb_to_linear(c.rgb), 1.0);
    }
    return vec4<f32>(c.rgb, 1.0);
}

// Picking: what the ray through one pixel centre of the last traced frame hits, i.e. what the viewer shows there
// (GPU-deformed poses, wide BVHs and alpha cut-outs included, since it is the path kernel's traversal over the
// same buffers). One invocation per click, so the path kernel never spends a ray per pixel on it.
// io[0].xy: the pixel (in), io[0].z: the hit's distance along the ray as f32 bits (out); io[1]: instance (NONE:
// nothing), triangle slot, barycentrics as f32 bits (out), the encoding of the path kernel's hit AOV.
@group(1) @binding(1) var<storage, read_write> io: array<vec4<u32>, 2>;

@compute @workgroup_size(1)
fn pick() {
    let pixel = io[0].xy;
    let hit = trace(Ray(camera_origin(), camera_ray_dir(pixel, vec2<f32>(0.5))), MISS, false);
    io[0].z = bitcast<u32>(hit.t);
    io[1] = vec4<u32>(hit.instance, hit.triangle, bitcast<u32>(hit.bary.x), bitcast<u32>(hit.bary.y));
}

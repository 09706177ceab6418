// The view: per-dispatch constants of the camera, image and sampling (engine/src/render/layout.rs `GpuFrame`),
// bound as group 1 binding 0 by every kernel that generates camera rays.

struct Frame {
    world_from_camera: mat4x4<f32>,
    // Thin lens: aperture radius 0 is a pinhole; the plane at focus_distance along the view axis is sharp.
    tan_half_fov: f32, lens_radius: f32, focus_distance: f32, light_count: u32,
    width: u32, height: u32, sample_base: u32, spp: u32,
    max_depth: u32, seed: u32, rr_depth: u32, flags: u32,
    // Lights at infinity (the environment, the sun): lights[infinite_light_first ..][.. infinite_light_count].
    infinite_light_first: u32, infinite_light_count: u32,
    // Lights in the light tree (the list's first ones); 0: the light sampler samples by power alone.
    tree_light_count: u32,
    // Invocations sharing each pixel's samples in the trace pass (engine/src/render/passes/trace/mod.rs).
    sample_lanes: u32,
}

@group(1) @binding(0) var<uniform> frame: Frame;

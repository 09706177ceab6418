// The view: per-dispatch constants of the camera, image and sampling (engine/src/render/layout.rs `GpuFrame`),
// bound as group 1 binding 0 by every kernel that generates camera rays.

struct Frame {
    world_from_camera: mat4x4<f32>,
    env_color: vec3<f32>, tan_half_fov: f32,
    width: u32, height: u32, sample_base: u32, spp: u32,
    max_depth: u32, seed: u32, env_mode: u32, rr_depth: u32,
    emitter_count: u32, flags: u32, emitter_total_power: f32, _pad: u32,
}

@group(1) @binding(0) var<uniform> frame: Frame;

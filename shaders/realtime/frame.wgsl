// The real-time path's per-frame constants (engine/src/render/layout.rs `GpuRealtimeFrame`): both frames'
// cameras for reprojection, the frame index, which stages run and their tuning. Group 1 binding 1 of every
// real-time kernel; `frame` (view.wgsl) stays binding 0 and `frame.sample_base` is the frame index.

struct RealtimeFrame {
    camera_from_world: mat4x4<f32>,
    prev_camera_from_world: mat4x4<f32>,
    prev_camera_origin: vec3<f32>, prev_tan_half_fov: f32,
    // RT_* flags: stages on, history present.
    flags: u32,
    // Cap of the per-pixel history length (frames).
    history_cap: f32,
    // Gradient strata across and down (GRADIENT_STRATUM pixels square each).
    strata_width: u32, strata_height: u32,
    restir_candidates: u32, restir_neighbours: u32, restir_radius: f32, restir_max_confidence: f32,
    // Relative depth tolerance of history validation, and the cosine a normal may turn by.
    depth_tolerance: f32, normal_tolerance: f32, _pad0: u32, _pad1: u32,
}

@group(1) @binding(1) var<uniform> realtime: RealtimeFrame;

fn realtime_flag(bit: u32) -> bool {
    return (realtime.flags & bit) != 0u;
}

// Continuous pixel coordinates (pixel centres at i + 0.5, y down) and view depth of world point `p` seen by a
// camera; depth <= 0 behind it. The pinhole of camera.wgsl, inverted.
fn project_point(camera_from_world: mat4x4<f32>, tan_half_fov: f32, p: vec3<f32>) -> vec3<f32> {
    let q = (camera_from_world * vec4<f32>(p, 1.0)).xyz;
    return project_camera_space(q, tan_half_fov);
}

// The same for a direction at infinity (what a ray that left the scene saw).
fn project_direction(camera_from_world: mat4x4<f32>, tan_half_fov: f32, d: vec3<f32>) -> vec3<f32> {
    let q = (camera_from_world * vec4<f32>(d, 0.0)).xyz;
    return project_camera_space(q, tan_half_fov);
}

fn project_camera_space(q: vec3<f32>, tan_half_fov: f32) -> vec3<f32> {
    let depth = -q.z;
    let aspect = f32(frame.width) / f32(frame.height);
    let safe = select(depth, 1e-20, abs(depth) < 1e-20);
    let ndc = vec2<f32>(q.x / (safe * tan_half_fov * aspect), q.y / (safe * tan_half_fov));
    return vec3<f32>((ndc.x + 1.0) * 0.5 * f32(frame.width), (1.0 - ndc.y) * 0.5 * f32(frame.height), depth);
}

// The gradient stratum of a pixel, and the pixel of stratum `s` that frame `frame_index` shades twice (A-SVGF):
// one per GRADIENT_STRATUM x GRADIENT_STRATUM block, chosen by a hash so that it moves every frame.
fn stratum_of(pixel: vec2<u32>) -> vec2<u32> {
    return pixel / GRADIENT_STRATUM;
}

fn gradient_source(s: vec2<u32>, frame_index: u32) -> vec2<u32> {
    let h = pcg4d(vec4<u32>(s.x, s.y, frame_index, 0x9e3779b9u)).x;
    let k = h % (GRADIENT_STRATUM * GRADIENT_STRATUM);
    let p = s * GRADIENT_STRATUM + vec2<u32>(k % GRADIENT_STRATUM, k / GRADIENT_STRATUM);
    return min(p, vec2<u32>(frame.width - 1u, frame.height - 1u));
}

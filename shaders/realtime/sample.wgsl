// One frame's real-time sample per pixel (the realtime trace pass writes it, the temporal pass reads it):
// radiance, the part of it no surface scattered, and whether it is usable (finite).

struct RealtimeSample {
    radiance: vec3<f32>,
    valid: u32,
    unscattered: vec3<f32>,
    _pad: u32,
}

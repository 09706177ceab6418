// The camera model: a pinhole at the view's origin looking down its -Z axis, with glTF's vertical field of
// view. `u_film` places the ray inside the pixel (the box filter), `u_lens` is reserved for a lens.

// Direction of the camera ray through `offset` (in pixels, 0..1 each way) of pixel `pixel`.
fn camera_ray_dir(pixel: vec2<u32>, offset: vec2<f32>) -> vec3<f32> {
    let aspect = f32(frame.width) / f32(frame.height);
    let ndc = vec2<f32>(
        (f32(pixel.x) + offset.x) / f32(frame.width) * 2.0 - 1.0,
        1.0 - (f32(pixel.y) + offset.y) / f32(frame.height) * 2.0);
    let d_cam = vec3<f32>(ndc.x * frame.tan_half_fov * aspect, ndc.y * frame.tan_half_fov, -1.0);
    return normalize((frame.world_from_camera * vec4<f32>(d_cam, 0.0)).xyz);
}

fn camera_origin() -> vec3<f32> {
    return frame.world_from_camera[3].xyz;
}

// The view direction (camera -Z) in world space: camera depth is distance along it.
fn camera_forward() -> vec3<f32> {
    return -frame.world_from_camera[2].xyz;
}

fn generate_ray(pixel: vec2<u32>, u_film: vec2<f32>, u_lens: vec2<f32>) -> Ray {
    return Ray(camera_origin(), camera_ray_dir(pixel, u_film));
}

// The camera model: a thin lens at the view's origin looking down its -Z axis, with glTF's vertical field of
// view (pbrt-v4's `PerspectiveCamera`). `u_film` places the ray inside the pixel (the box filter), `u_lens` on
// the lens; with a zero aperture the lens is a pinhole and `u_lens` is ignored.

// Direction of the pinhole ray through `offset` (in pixels, 0..1 each way) of pixel `pixel`, in camera space,
// on the plane z = -1.
fn camera_film_point(pixel: vec2<u32>, offset: vec2<f32>) -> vec3<f32> {
    let aspect = f32(frame.width) / f32(frame.height);
    let ndc = vec2<f32>(
        (f32(pixel.x) + offset.x) / f32(frame.width) * 2.0 - 1.0,
        1.0 - (f32(pixel.y) + offset.y) / f32(frame.height) * 2.0);
    return vec3<f32>(ndc.x * frame.tan_half_fov * aspect, ndc.y * frame.tan_half_fov, -1.0);
}

// Direction of the pinhole (lens-centre) ray through `offset` of pixel `pixel`, world space.
fn camera_ray_dir(pixel: vec2<u32>, offset: vec2<f32>) -> vec3<f32> {
    return normalize((frame.world_from_camera * vec4<f32>(camera_film_point(pixel, offset), 0.0)).xyz);
}

fn camera_origin() -> vec3<f32> {
    return frame.world_from_camera[3].xyz;
}

// The view direction (camera -Z) in world space: camera depth is distance along it.
fn camera_forward() -> vec3<f32> {
    return -frame.world_from_camera[2].xyz;
}

// The camera ray for a film and a lens sample: from a point on the lens disc towards the point of the focus
// plane that the pinhole ray through the film sample meets, so that plane stays sharp.
fn generate_ray(pixel: vec2<u32>, u_film: vec2<f32>, u_lens: vec2<f32>) -> Ray {
    let film = camera_film_point(pixel, u_film);
    if frame.lens_radius <= 0.0 {
        return Ray(camera_origin(), normalize((frame.world_from_camera * vec4<f32>(film, 0.0)).xyz));
    }
    let lens = vec3<f32>(frame.lens_radius * sample_concentric_disk(u_lens), 0.0);
    let focus = film * frame.focus_distance;
    let origin = (frame.world_from_camera * vec4<f32>(lens, 1.0)).xyz;
    let dir = normalize((frame.world_from_camera * vec4<f32>(focus - lens, 0.0)).xyz);
    return Ray(origin, dir);
}

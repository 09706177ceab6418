// The environment: radiance arriving from infinitely far away along `dir`, a constant colour or a sky
// gradient (the view's env_mode); what a ray that leaves the scene sees.

fn environment(dir: vec3<f32>) -> vec3<f32> {
    if frame.env_mode == 1u {
        // Sky gradient: white at the horizon and below, blue towards the zenith.
        let t = 0.5 * (dir.y + 1.0);
        return mix(vec3<f32>(1.0), vec3<f32>(0.5, 0.7, 1.0), t);
    }
    return frame.env_color;
}

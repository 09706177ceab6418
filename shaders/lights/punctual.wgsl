// KHR_lights_punctual lights, in the glTF Sample Viewer's units: point and spot lights hold radiant intensity
// (colour x intensity, per steradian) with inverse-square falloff and the spec's recommended range window;
// spots add the spec's smooth angular attenuation; directional lights hold irradiance. All are delta lights.

// clamp(1 - (d / range)^4, 0, 1) / d^2; range 0 means unbounded.
fn punctual_distance_falloff(light: Light, distance: f32) -> f32 {
    var window = 1.0;
    if light.range > 0.0 {
        let r = distance / light.range;
        let r2 = r * r;
        window = clamp(1.0 - r2 * r2, 0.0, 1.0);
    }
    return window / (distance * distance);
}

// The spec's implementation note: saturate(cd * scale + offset)^2 with scale = 1 / max(0.001, cos inner -
// cos outer) and offset = -cos outer x scale, where cd is the cosine from the spot's axis.
fn spot_angular_falloff(light: Light, cos_from_axis: f32) -> f32 {
    let scale = 1.0 / max(0.001, light.cos_inner - light.cos_outer);
    let t = clamp((cos_from_axis - light.cos_outer) * scale, 0.0, 1.0);
    return t * t;
}

// Point and spot lights: `position`, `direction` (the axis the spot shines along), `radiance` = intensity.
fn point_light_sample_li(light: Light, ctx: LightSampleContext) -> LightLiSample {
    let to_light = light.position - ctx.p;
    let distance2 = dot(to_light, to_light);
    if distance2 <= 0.0 { return no_light_sample(); }
    let distance = sqrt(distance2);
    let wi = to_light / distance;
    var li = light.radiance * punctual_distance_falloff(light, distance);
    if light.kind == LIGHT_SPOT {
        li *= spot_angular_falloff(light, dot(light.direction, -wi));
    }
    if all(li == vec3<f32>(0.0)) { return no_light_sample(); }
    return LightLiSample(wi, distance, li, 1.0, true, vec3<f32>(0.0));
}

// Directional lights: `direction` is where the light travels, `radiance` the irradiance it gives.
fn directional_light_sample_li(light: Light) -> LightLiSample {
    return LightLiSample(-light.direction, MISS, light.radiance, 1.0, true, vec3<f32>(0.0));
}

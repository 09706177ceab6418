// The sun (`LIGHT_SUN`): a disc at infinity of uniform radiance, sampled uniformly inside its cone.
// Fields: direction = unit direction towards the sun, range = 1 - cos(angular radius) (kept apart from cos
// for precision: the cone is 0.27 degrees), radiance = the disc's radiance (engine/src/environment/sun_sky.rs).

// Whether unit `dir` lies inside the disc. 1 - cos is taken as |dir - sun|^2 / 2 (the half-angle form): 1 - dot
// cancels to a few bits at the sun's 1e-5, which would put samples near its rim outside it.
fn sun_contains(light: Light, dir: vec3<f32>) -> bool {
    let chord = dir - light.direction;
    return 0.5 * dot(chord, chord) <= light.range;
}

fn sun_le(light: Light, dir: vec3<f32>) -> vec3<f32> {
    return select(vec3<f32>(0.0), light.radiance, sun_contains(light, dir));
}

fn sun_pdf(light: Light, dir: vec3<f32>) -> f32 {
    return select(0.0, 1.0 / (2.0 * PI * light.range), sun_contains(light, dir));
}

fn sun_sample_li(light: Light, u: vec2<f32>) -> LightLiSample {
    let dir = normalize(basis(light.direction) * sample_uniform_cone(u, light.range));
    return LightLiSample(dir, MISS, light.radiance, 1.0 / (2.0 * PI * light.range), false, vec3<f32>(0.0));
}

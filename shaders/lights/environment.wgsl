// The environment light (`LIGHT_ENVIRONMENT`): an equirectangular radiance map at infinity, turned about +Y,
// scaled, bilinear between texels and importance-sampled by a 2D distribution over luminance x sin(theta).
// Conventions (exactly Mitsuba 3's `envmap`): engine/src/environment/map.rs; the distribution and its CPU
// twin: engine/src/environment/sampling.rs.
//
// Fields: index_a = map width W, index_b = map height H, position.xy = (cos, sin) of the rotation about +Y,
// radiance = strength. `environment_map` holds 3 W H texel values, then W (H - 1) conditional CDF entries (row
// by row), then H - 1 marginal CDF entries.

// A world direction in the map's frame.
fn environment_to_map(light: Light, d: vec3<f32>) -> vec3<f32> {
    let c = light.position.x;
    let s = light.position.y;
    return vec3<f32>(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
}

fn environment_to_world(light: Light, d: vec3<f32>) -> vec3<f32> {
    let c = light.position.x;
    let s = light.position.y;
    return vec3<f32>(c * d.x + s * d.z, d.y, c * d.z - s * d.x);
}

// Latitude-longitude coordinates of a map-frame direction: u in [0, 1) from atan2(x, -z), v = acos(y) / pi.
fn environment_uv(d: vec3<f32>) -> vec2<f32> {
    let u = atan2(d.x, -d.z) * (0.5 * INV_PI);
    return vec2<f32>(u - floor(u), acos(clamp(d.y, -1.0, 1.0)) * INV_PI);
}

fn environment_direction(uv: vec2<f32>) -> vec3<f32> {
    let theta = uv.y * PI;
    let phi = uv.x * 2.0 * PI;
    return vec3<f32>(sin(phi) * sin(theta), cos(theta), -cos(phi) * sin(theta));
}

fn environment_texel(width: u32, i: u32, j: u32) -> vec3<f32> {
    let k = 3u * (j * width + i);
    return vec3<f32>(environment_map[k], environment_map[k + 1u], environment_map[k + 2u]);
}

// Radiance arriving from world direction `dir`: texel column i sits at u = (i + 1/2) / W (wrapping), row j
// at v = j / (H - 1).
fn environment_le(light: Light, dir: vec3<f32>) -> vec3<f32> {
    let w = light.index_a;
    let h = light.index_b;
    let uv = environment_uv(environment_to_map(light, dir));
    let x = uv.x * f32(w) - 0.5;
    let y = clamp(uv.y * f32(h - 1u), 0.0, f32(h - 1u));
    let x0 = floor(x);
    let fx = x - x0;
    let i0 = u32((i32(x0) + i32(w)) % i32(w));
    let i1 = (i0 + 1u) % w;
    let j0 = min(u32(y), h - 2u);
    let fy = y - f32(j0);
    let top = mix(environment_texel(w, i0, j0), environment_texel(w, i1, j0), fx);
    let bottom = mix(environment_texel(w, i0, j0 + 1u), environment_texel(w, i1, j0 + 1u), fx);
    return mix(top, bottom, fy) * light.radiance;
}

// Entry k of a CDF starting at `base`, less entry k - 1 (0 before the first).
fn environment_cdf_step(base: u32, k: u32) -> f32 {
    return environment_map[base + k] - select(0.0, environment_map[base + k - 1u], k > 0u);
}

// The first of `count` CDF entries at `base` that exceeds u.
fn environment_cdf_search(base: u32, count: u32, u: f32) -> u32 {
    var lo = 0u;
    var hi = count - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if environment_map[base + mid] <= u { lo = mid + 1u; } else { hi = mid; }
    }
    return lo;
}

// Density of the cell (column i, row j) in (u, v), times the map's cell count.
fn environment_cell_density(w: u32, rows: u32, i: u32, j: u32) -> f32 {
    let conditional = 3u * w * (rows + 1u);
    let marginal = conditional + w * rows;
    return environment_cdf_step(marginal, j) * environment_cdf_step(conditional + j * w, i) * f32(w * rows);
}

// Solid-angle density with which `environment_sample_li` gives world direction `dir`.
fn environment_pdf(light: Light, dir: vec3<f32>) -> f32 {
    let w = light.index_a;
    let rows = light.index_b - 1u;
    let d = environment_to_map(light, dir);
    let sin_theta = sqrt(max(0.0, 1.0 - d.y * d.y));
    if sin_theta <= 0.0 { return 0.0; }
    let uv = environment_uv(d);
    let i = u32((i32(floor(uv.x * f32(w) - 0.5)) + i32(w)) % i32(w));
    let j = min(u32(uv.y * f32(rows)), rows - 1u);
    return environment_cell_density(w, rows, i, j) / (2.0 * PI * PI * sin_theta);
}

fn environment_sample_li(light: Light, u: vec2<f32>) -> LightLiSample {
    let w = light.index_a;
    let rows = light.index_b - 1u;
    let conditional = 3u * w * (rows + 1u);
    let marginal = conditional + w * rows;
    let j = environment_cdf_search(marginal, rows, u.y);
    let row = conditional + j * w;
    let i = environment_cdf_search(row, w, u.x);
    // Where u falls inside the chosen entries places the point inside the cell.
    let fy = clamp((u.y - (environment_map[marginal + j] - environment_cdf_step(marginal, j))) / environment_cdf_step(marginal, j), 0.0, 0.99999994);
    let fx = clamp((u.x - (environment_map[row + i] - environment_cdf_step(row, i))) / environment_cdf_step(row, i), 0.0, 0.99999994);
    let su = (f32(i) + 0.5 + fx) / f32(w);
    let d = environment_direction(vec2<f32>(su - floor(su), (f32(j) + fy) / f32(rows)));
    let sin_theta = sqrt(max(0.0, 1.0 - d.y * d.y));
    if sin_theta <= 0.0 { return no_light_sample(); }
    let pdf = environment_cell_density(w, rows, i, j) / (2.0 * PI * PI * sin_theta);
    if pdf <= 0.0 { return no_light_sample(); }
    let dir = environment_to_world(light, d);
    return LightLiSample(dir, MISS, environment_le(light, dir), pdf, false);
}

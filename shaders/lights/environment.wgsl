// The environment light (`LIGHT_ENVIRONMENT`): an equirectangular radiance map at infinity, turned about +Y,
// scaled, bilinear between texels and importance-sampled by a 2D distribution over luminance x sin(theta):
// a cell by its corners' mean, the point inside it in proportion to their bilinear interpolation where the map's
// cells have enough contrast for that to pay (`LIGHT_ENVIRONMENT_BILINEAR`), else uniformly.
// Conventions (exactly Mitsuba 3's `envmap`): engine/src/environment/map.rs; the distribution and its CPU
// twin: engine/src/environment/sampling.rs.
//
// Fields: index_a = map width W, index_b = map height H, position.xy = (cos, sin) of the rotation about +Y,
// range = the compensated distribution's offset, radiance = strength, flags: LIGHT_ENVIRONMENT_BILINEAR,
// LIGHT_ENVIRONMENT_COMPENSATED, LIGHT_ENVIRONMENT_COMPENSATED_BILINEAR. `environment_map` holds W H texels of ENVIRONMENT_TEXEL_WORDS values (rgb, 0), then W (H - 1)
// conditional CDF entries (row by row) and H - 1 marginal CDF entries, then the same two for the compensated
// distribution where next-event estimation uses one (LIGHT_ENVIRONMENT_COMPENSATED).

// Whether any environment's sampling follows the bilinear density inside its cells: the trace kernels set it
// false where none does (engine/src/render/material_lobes.rs `KernelNeeds`), and that code compiles away. Smooth
// maps (the sky gradient, constants) sample cells uniformly; on lavapipe, whose `if`s skip nothing, the bilinear
// branches still cost them 9% of the Cornell box's render (docs/BENCHMARKS.md).
override ENVIRONMENT_BILINEAR: bool = true;

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
    return read_environment_texel(ENVIRONMENT_TEXEL_WORDS * (j * width + i));
}

// Column `i` wrapped into 0..w, for i in [-w, 2w) (every caller's column is in [-1, w]): selects instead of an
// integer remainder, which CPU adapters compute as one scalar division per SIMD lane.
fn environment_wrap_column(i: i32, w: u32) -> u32 {
    let n = i32(w);
    return u32(select(select(i, i + n, i < 0), i - n, i >= n));
}

// Radiance and next-event estimation's density of world direction `dir` (a BSDF-sampled ray that left the
// scene), the direction's map coordinates computed once for both.
fn environment_li(light: Light, dir: vec3<f32>, compensated: bool) -> InfiniteLightLi {
    let d = environment_to_map(light, dir);
    let uv = environment_uv(d);
    return InfiniteLightLi(environment_le_at(light, uv), environment_pdf_at(light, d, uv, compensated));
}

// Radiance arriving from world direction `dir`.
fn environment_le(light: Light, dir: vec3<f32>) -> vec3<f32> {
    return environment_le_at(light, environment_uv(environment_to_map(light, dir)));
}

// Radiance arriving from the direction at map coordinates `uv` (environment_uv): texel column i sits at
// u = (i + 1/2) / W (wrapping), row j at v = j / (H - 1).
fn environment_le_at(light: Light, uv: vec2<f32>) -> vec3<f32> {
    let w = light.index_a;
    let h = light.index_b;
    let x = uv.x * f32(w) - 0.5;
    let y = clamp(uv.y * f32(h - 1u), 0.0, f32(h - 1u));
    let x0 = floor(x);
    let fx = x - x0;
    let i0 = environment_wrap_column(i32(x0), w);
    let i1 = environment_wrap_column(i32(i0) + 1, w);
    let j0 = min(u32(y), h - 2u);
    let fy = y - f32(j0);
    let top = mix(environment_texel(w, i0, j0), environment_texel(w, i1, j0), fx);
    let bottom = mix(environment_texel(w, i0, j0 + 1u), environment_texel(w, i1, j0 + 1u), fx);
    return mix(top, bottom, fy) * light.radiance;
}

// Entry k of a CDF starting at `base`, less entry k - 1 (0 before the first).
fn environment_cdf_step(base: u32, k: u32) -> f32 {
    return read_environment(base + k) - select(0.0, read_environment(base + k - 1u), k > 0u);
}

// The first of `count` CDF entries at `base` that exceeds u.
fn environment_cdf_search(base: u32, count: u32, u: f32) -> u32 {
    var lo = 0u;
    var hi = count - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if read_environment(base + mid) <= u { lo = mid + 1u; } else { hi = mid; }
    }
    return lo;
}

// One of the map's two sampling distributions (engine/src/environment/sampling.rs): in proportion to the
// luminance (ReSTIR's candidates, and next-event estimation on smooth maps), or MIS-compensated, in proportion
// to the luminance above the map's mean (next-event estimation, whose light samples BSDF sampling completes:
// pbrt-v4's `allowIncompletePDF`, on maps whose light is concentrated: LIGHT_ENVIRONMENT_COMPENSATED).
struct EnvironmentDistribution {
    // Where its conditional CDF (rows x W entries) and marginal CDF (rows entries) start in environment_map.
    conditional: u32,
    marginal: u32,
    // Luminance subtracted from each corner before the clamp at 0.
    offset: f32,
    bilinear: bool,
}

fn environment_distribution(light: Light, compensated: bool) -> EnvironmentDistribution {
    let w = light.index_a;
    let rows = light.index_b - 1u;
    let conditional = ENVIRONMENT_TEXEL_WORDS * w * (rows + 1u);
    let marginal = conditional + w * rows;
    if compensated && (light.flags & LIGHT_ENVIRONMENT_COMPENSATED) != 0u {
        let compensated_conditional = marginal + rows;
        return EnvironmentDistribution(compensated_conditional, compensated_conditional + w * rows, light.range,
            ENVIRONMENT_BILINEAR && (light.flags & LIGHT_ENVIRONMENT_COMPENSATED_BILINEAR) != 0u);
    }
    return EnvironmentDistribution(conditional, marginal, 0.0,
        ENVIRONMENT_BILINEAR && (light.flags & LIGHT_ENVIRONMENT_BILINEAR) != 0u);
}

// Density of the cell (column i, row j) in (u, v), times the map's cell count.
fn environment_cell_density(dist: EnvironmentDistribution, w: u32, rows: u32, i: u32, j: u32) -> f32 {
    return environment_cdf_step(dist.marginal, j) * environment_cdf_step(dist.conditional + j * w, i) * f32(w * rows);
}

// The distribution's values at the corners of cell (i, j): (i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1),
// columns wrapping.
fn environment_corners(dist: EnvironmentDistribution, w: u32, i: u32, j: u32) -> vec4<f32> {
    let i1 = environment_wrap_column(i32(i) + 1, w);
    let l = vec4<f32>(
        luminance(environment_texel(w, i, j)),
        luminance(environment_texel(w, i1, j)),
        luminance(environment_texel(w, i, j + 1u)),
        luminance(environment_texel(w, i1, j + 1u)),
    );
    return max(l - vec4<f32>(dist.offset), vec4<f32>(0.0));
}

// The bilinear density of corners `c` at f inside the cell, relative to their mean (1 where all are 0).
fn environment_bilinear_density(c: vec4<f32>, f: vec2<f32>) -> f32 {
    let mean = 0.25 * (c.x + c.y + c.z + c.w);
    if mean <= 0.0 { return 1.0; }
    return mix(mix(c.x, c.y, f.x), mix(c.z, c.w, f.x), f.y) / mean;
}

// The point in [0, 1) below which a density linear from a (at 0) to b (at 1) holds the fraction r: the root of
// ((b - a) / 2) x^2 + a x = r (a + b) / 2, written so that it stays exact as b - a goes to 0.
fn environment_sample_linear(r: f32, a: f32, b: f32) -> f32 {
    let denominator = a + sqrt(max(mix(a * a, b * b, r), 0.0));
    if a + b <= 0.0 || denominator <= 0.0 { return r; }
    return clamp(r * (a + b) / denominator, 0.0, 0.99999994);
}

// Solid-angle density with which `environment_sample_li` gives the world direction whose map-frame direction is
// `d`, at map coordinates `uv` (environment_uv(d)).
fn environment_pdf_at(light: Light, d: vec3<f32>, uv: vec2<f32>, compensated: bool) -> f32 {
    let w = light.index_a;
    let rows = light.index_b - 1u;
    let dist = environment_distribution(light, compensated);
    let sin_theta = sqrt(max(0.0, 1.0 - d.y * d.y));
    if sin_theta <= 0.0 { return 0.0; }
    let x = uv.x * f32(w) - 0.5;
    let i = environment_wrap_column(i32(floor(x)), w);
    let y = uv.y * f32(rows);
    let j = min(u32(y), rows - 1u);
    var inside = 1.0;
    if dist.bilinear {
        let f = vec2<f32>(x - floor(x), clamp(y - f32(j), 0.0, 1.0));
        inside = environment_bilinear_density(environment_corners(dist, w, i, j), f);
    }
    return environment_cell_density(dist, w, rows, i, j) * inside / (2.0 * PI * PI * sin_theta);
}

fn environment_sample_li(light: Light, u: vec2<f32>, compensated: bool) -> LightLiSample {
    let w = light.index_a;
    let rows = light.index_b - 1u;
    let dist = environment_distribution(light, compensated);
    let marginal = dist.marginal;
    let j = environment_cdf_search(marginal, rows, u.y);
    let row = dist.conditional + j * w;
    let i = environment_cdf_search(row, w, u.x);
    // Where u falls inside the chosen entries places the point inside the cell, through the bilinear density
    // of the cell's corner luminances: v by its linear marginal, then u by the linear conditional.
    let ry = clamp((u.y - (read_environment(marginal + j) - environment_cdf_step(marginal, j))) / environment_cdf_step(marginal, j), 0.0, 0.99999994);
    let rx = clamp((u.x - (read_environment(row + i) - environment_cdf_step(row, i))) / environment_cdf_step(row, i), 0.0, 0.99999994);
    let bilinear = dist.bilinear;
    var f = vec2<f32>(rx, ry);
    if bilinear {
        let c = environment_corners(dist, w, i, j);
        f.y = environment_sample_linear(ry, c.x + c.y, c.z + c.w);
        f.x = environment_sample_linear(rx, mix(c.x, c.z, f.y), mix(c.y, c.w, f.y));
    }
    let su = (f32(i) + 0.5 + f.x) / f32(w);
    let d = environment_direction(vec2<f32>(su - floor(su), (f32(j) + f.y) / f32(rows)));
    let dir = environment_to_world(light, d);
    // The radiance (and the bilinear density) from the direction's own map coordinates, computed once.
    let back = environment_to_map(light, dir);
    let uv = environment_uv(back);
    var pdf: f32;
    if bilinear {
        // The density from the direction, as BSDF-sampled rays that reach the map get it: where the bilinear
        // density is steep (a sun texel beside dark ones) the point's round trip through the direction moves it
        // by enough to change its density by more than 0.2%, and both must agree for MIS.
        pdf = environment_pdf_at(light, back, uv, compensated);
    } else {
        let sin_theta = sqrt(max(0.0, 1.0 - d.y * d.y));
        if sin_theta <= 0.0 { return no_light_sample(); }
        pdf = environment_cell_density(dist, w, rows, i, j) / (2.0 * PI * PI * sin_theta);
    }
    if pdf <= 0.0 { return no_light_sample(); }
    return LightLiSample(dir, MISS, environment_le_at(light, uv), pdf, false, vec3<f32>(0.0));
}

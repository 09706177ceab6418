// How a pixel's mean reaches the display through the denoiser (oidn::inputs::PixelSplit on the host, which
// says why): both kernels bind `accum` (w: samples) and `normal_hits` (w: samples whose first hit met a surface).

// Every sample met a surface: the scattered radiance is denoised, the unscattered part added back.
const SPLIT_SCATTERED: u32 = 0u;
// An outline against the environment: the whole mean is denoised.
const SPLIT_WHOLE: u32 = 1u;
// The environment seen directly, away from any surface: exact, shown as its mean.
const SPLIT_KEPT: u32 = 2u;

fn pixel_split(x: u32, y: u32) -> u32 {
    let i = y * params.width + x;
    let hits = normal_hits[i].w;
    if hits > 0.0 && hits >= accum[i].w { return SPLIT_SCATTERED; }
    for (var ny = max(y, 1u) - 1u; ny <= min(y + 1u, params.height - 1u); ny++) {
        for (var nx = max(x, 1u) - 1u; nx <= min(x + 1u, params.width - 1u); nx++) {
            if normal_hits[ny * params.width + nx].w > 0.0 { return SPLIT_WHOLE; }
        }
    }
    return SPLIT_KEPT;
}

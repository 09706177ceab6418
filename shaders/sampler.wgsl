// Random numbers: a PCG stream per (pixel, sample, seed).

struct Rng { state: u32 }

fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn rng_new(pixel: u32, sample_index: u32, seed: u32) -> Rng {
    return Rng(pcg_hash(pixel ^ pcg_hash(sample_index ^ pcg_hash(seed + 0x9e3779b9u))));
}

fn rand(rng: ptr<function, Rng>) -> f32 {
    (*rng).state = (*rng).state * 747796405u + 2891336453u;
    let s = (*rng).state;
    let word = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    // 24 random bits: uniform in [0, 1).
    return f32(((word >> 22u) ^ word) >> 8u) * (1.0 / 16777216.0);
}

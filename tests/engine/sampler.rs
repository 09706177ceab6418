//! The sampler library (`shaders/sampler.wgsl`) on the GPU, through a probe kernel: a pixel's first 2^k samples
//! of any dimension pair form a (0,k,2)-net (every elementary interval of area 2^-k holds exactly one point) and
//! of any single dimension one point per interval of length 2^-k, for any pixel, seed and dimension, and for the
//! prefix of every power-of-two length; values of different dimensions, and of neighbouring pixels, are
//! independent (a chi-square test over a grid of their joint distribution). What the padding must give: without
//! the per-dimension index shuffle two dimensions' values are functions of the same index digits and fill one
//! grid cell per row.

use crate::common::*;
use raykin::gpu::bind::{Binding, bind_group, compute_layout, params_buffer, storage_buffer};
use raykin::render::shaders::{ShaderModule, compose};

const PROBE: &str = r#"
struct Probe { pixel: u32, seed: u32, dimension: u32, count: u32, other_pixel: u32, other_dimension: u32, pixels: u32, pad: u32 }
@group(0) @binding(0) var<uniform> probe: Probe;
@group(0) @binding(1) var<storage, read_write> out: array<vec4<f32>>;

// Sample i of pixel probe.pixel + p (output 2 (p count + i)): (get_2d at the dimension, get_1d at the
// dimension), then (get_1d at the other dimension, get_1d of pixel probe.other_pixel + p at the dimension).
@compute @workgroup_size(64)
fn draw(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    let p = gid.y;
    if i >= probe.count || p >= probe.pixels { return; }
    let s = sampler_start(probe.pixel + p, i, probe.seed);
    let other = sampler_start(probe.other_pixel + p, i, probe.seed);
    let o = 2u * (p * probe.count + i);
    out[o] = vec4<f32>(get_2d(s, probe.dimension), get_1d(s, probe.dimension), 0.0);
    out[o + 1u] = vec4<f32>(get_1d(s, probe.other_dimension), get_1d(other, probe.dimension), 0.0, 0.0);
}
"#;

const KERNEL: ShaderModule = ShaderModule {
    name: "sampler_probe",
    source: PROBE,
    requires: &["sampler"],
};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Probe {
    pixel: u32,
    seed: u32,
    dimension: u32,
    count: u32,
    other_pixel: u32,
    other_dimension: u32,
    /// Pixels probed: pixel, pixel + 1, ...
    pixels: u32,
    pad: u32,
}

/// The probe's output for `probe.count` samples of `probe.pixels` pixels (pixel-major): per sample its two vec4s.
fn draw(ctx: &raykin::gpu::GpuContext, probe: Probe) -> Vec<[[f32; 4]; 2]> {
    let layout = compute_layout(ctx, "sampler probe", &[Binding::Params, Binding::ReadWrite]);
    let pipeline = raykin::gpu::compute_pipeline(
        ctx,
        "sampler probe",
        compose(&KERNEL),
        &[Some(&layout)],
        "draw",
    );
    let uniform = params_buffer(ctx, "probe", std::mem::size_of::<Probe>());
    ctx.queue
        .write_buffer(&uniform, 0, bytemuck::bytes_of(&probe));
    let bytes = (probe.count * probe.pixels) as u64 * 32;
    let out = storage_buffer(ctx, "probe out", bytes);
    let group = bind_group(ctx, "sampler probe", &layout, &[&uniform, &out]);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(probe.count.div_ceil(64), probe.pixels, 1);
    }
    ctx.queue.submit([encoder.finish()]);
    bytemuck::cast_slice::<u8, [[f32; 4]; 2]>(&ctx.read_buffer(&out, bytes)).to_vec()
}

/// Whether `points` (2^k of them) hold exactly one point in every elementary interval 2^-a x 2^-b, a + b = k.
fn is_net(points: &[(f32, f32)], k: u32) -> Result<(), String> {
    for a in 0..=k {
        let b = k - a;
        let mut seen = vec![false; 1 << k];
        for &(x, y) in points {
            let (cx, cy) = (
                (x * (1u32 << a) as f32) as usize,
                (y * (1u32 << b) as f32) as usize,
            );
            let cell = (cy << a) | cx;
            if seen[cell] {
                return Err(format!("2^{k} points: two in one 2^-{a} x 2^-{b} interval"));
            }
            seen[cell] = true;
        }
    }
    Ok(())
}

/// Pearson's chi-square of `pairs` over a `cells` x `cells` grid against the uniform distribution.
fn chi_square(pairs: impl Iterator<Item = (f32, f32)>, cells: usize) -> (f64, usize) {
    let mut counts = vec![0usize; cells * cells];
    let mut n = 0;
    for (x, y) in pairs {
        let (cx, cy) = ((x * cells as f32) as usize, (y * cells as f32) as usize);
        counts[cy.min(cells - 1) * cells + cx.min(cells - 1)] += 1;
        n += 1;
    }
    let expected = n as f64 / (cells * cells) as f64;
    let chi = counts
        .iter()
        .map(|&c| (c as f64 - expected).powi(2) / expected)
        .sum();
    (chi, cells * cells - 1)
}

#[test]
fn every_power_of_two_prefix_is_a_net_and_dimensions_are_independent() {
    let (ctx, _gpu) = gpu();
    const COUNT: u32 = 4096;
    const PIXELS: u32 = 32;
    // Pixels, seeds and dimensions as the integrator uses them: the camera's, a bounce's, a deep bounce's, an
    // alpha pass-through's (above 2^30).
    let cases = [
        (0u32, 0u32, 0u32, 7u32, 1u32),
        (12345, 1000, 4, 2, 12346),
        (640 * 360 - 40, 0xdead_beef, 4 + 5 * 8 + 4, 4 + 5 * 8 + 6, 0),
        (77, 3, 0x4000_0000 + 37, 0x4000_0000 + 38, 78),
    ];
    for (first_pixel, seed, dimension, other_dimension, other_pixel) in cases {
        let samples = draw(
            &ctx,
            Probe {
                pixel: first_pixel,
                seed,
                dimension,
                count: COUNT,
                other_pixel,
                other_dimension,
                pixels: PIXELS,
                pad: 0,
            },
        );
        let mut chi_sums = [0.0f64; 3];
        for (p, samples) in samples.chunks(COUNT as usize).enumerate() {
            let what = format!(
                "pixel {} seed {seed} dimension {dimension}",
                first_pixel + p as u32
            );
            for s in samples {
                for v in [s[0][0], s[0][1], s[0][2], s[1][0], s[1][1]] {
                    assert!((0.0..1.0).contains(&v), "{what}: value {v} outside [0, 1)");
                }
            }
            for k in 0..=12u32 {
                let prefix = &samples[..1 << k];
                let pairs: Vec<(f32, f32)> = prefix.iter().map(|s| (s[0][0], s[0][1])).collect();
                is_net(&pairs, k).unwrap_or_else(|e| panic!("{what}, get_2d: {e}"));
                let mut strata: Vec<usize> = prefix
                    .iter()
                    .map(|s| (s[0][2] * (1u32 << k) as f32) as usize)
                    .collect();
                strata.sort_unstable();
                strata.dedup();
                assert_eq!(
                    strata.len(),
                    1 << k,
                    "{what}, get_1d: 2^{k} points not one per interval of length 2^-{k}"
                );
            }
            // Independence: 4096 pairs over 16 x 16 cells. A pairing that shares the index order (no shuffle)
            // puts every point in 16 cells: chi-square 61440.
            let joint: [Vec<(f32, f32)>; 3] = [
                samples.iter().map(|s| (s[0][0], s[0][2])).collect(),
                samples.iter().map(|s| (s[0][2], s[1][0])).collect(),
                samples.iter().map(|s| (s[0][2], s[1][1])).collect(),
            ];
            for (sum, pairs) in chi_sums.iter_mut().zip(joint) {
                let (chi, _) = chi_square(pairs.into_iter(), 16);
                assert!(
                    chi < 600.0,
                    "{what}: chi-square {chi:.1} of one pixel's pairs: correlated"
                );
                *sum += chi;
            }
        }
        // The mean over pixels: ~224 for ideal nested scrambles and exactly stratified marginals, 255 for
        // independent uniform pairs; the hashed scrambles measured 241 (spread 50 per pixel, so +-9 over 32
        // pixels) over 300 random cases. 300 leaves 6 standard errors to the mean and catches a partial
        // correlation that one pixel's test could miss.
        let labels = [
            "get_2d's first value against get_1d at the same dimension",
            "get_1d against another dimension's",
            "get_1d against another pixel's",
        ];
        for (label, sum) in labels.iter().zip(chi_sums) {
            let mean = sum / PIXELS as f64;
            eprintln!(
                "pixels {first_pixel}.. seed {seed} dimension {dimension}: {label}: mean chi-square {mean:.1} (255 degrees of freedom)"
            );
            assert!(
                mean < 300.0,
                "{label}: mean chi-square {mean:.1} over {PIXELS} pixels: correlated"
            );
        }
    }
}

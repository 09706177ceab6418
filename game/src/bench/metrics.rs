//! Image error metrics for the error-vs-time curves: relMSE and FLIP (NVIDIA's perceptual metric, through the
//! `nv-flip` crate) on the tone-mapped images a user looks at, and relMSE on linear radiance as well.
//!
//! Why both relMSEs: on linear radiance a rare very bright sample (a firefly) dominates the error for many
//! frames, so a heavy-tailed estimator (the Cornell box's double-sided light, docs/ACCURACY.md)
//! gives a curve that jumps up and down; the display transform bounds each pixel, which is what a viewer sees.

/// Epsilon of the relMSE denominator (as in tests/common/cornell.rs): keeps black pixels from dominating.
pub const REL_MSE_EPS: f64 = 1e-2;

/// Relative MSE over pixels and channels: mean of (x - r)^2 / (r^2 + eps).
pub fn rel_mse(image: &[[f32; 3]], reference: &[[f32; 3]]) -> f64 {
    let mut sum = 0.0;
    for (p, r) in image.iter().zip(reference) {
        for c in 0..3 {
            let d = p[c] as f64 - r[c] as f64;
            sum += d * d / (r[c] as f64 * r[c] as f64 + REL_MSE_EPS);
        }
    }
    sum / (3 * image.len().max(1)) as f64
}

/// The viewer's and PNG output's display transform (render/passes/tonemap/tonemap.wgsl: Hill's ACES fit, then sRGB), on the
/// CPU so that the reference (read from the cache) and each test image go through the same code. Values in
/// 0..=1, not yet quantised.
pub fn tonemap(image: &[[f32; 3]]) -> Vec<[f32; 3]> {
    fn aces_fitted(c: [f32; 3]) -> [f32; 3] {
        // Column-major as in the shader: v = input * c.
        const INPUT: [[f32; 3]; 3] = [
            [0.59719, 0.07600, 0.02840],
            [0.35458, 0.90834, 0.13383],
            [0.04823, 0.01566, 0.83777],
        ];
        const OUTPUT: [[f32; 3]; 3] = [
            [1.60475, -0.10208, -0.00327],
            [-0.53108, 1.10813, -0.07276],
            [-0.07367, -0.00605, 1.07602],
        ];
        let mul = |m: &[[f32; 3]; 3], v: [f32; 3]| {
            [0, 1, 2].map(|r| m[0][r] * v[0] + m[1][r] * v[1] + m[2][r] * v[2])
        };
        let v = mul(&INPUT, c);
        let curve = v.map(|x| {
            let a = x * (x + 0.0245786) - 0.000090537;
            let b = x * (0.983729 * x + 0.432951) + 0.238081;
            a / b
        });
        mul(&OUTPUT, curve).map(|x| x.clamp(0.0, 1.0))
    }
    fn srgb(x: f32) -> f32 {
        if x <= 0.0031308 {
            x * 12.92
        } else {
            1.055 * x.powf(1.0 / 2.4) - 0.055
        }
    }
    image
        .iter()
        .map(|p| aces_fitted(p.map(|v| v.max(0.0))).map(srgb))
        .collect()
}

/// Display values quantised to 8 bits, RGB interleaved (FLIP's input).
pub fn srgb8(display: &[[f32; 3]]) -> Vec<u8> {
    display
        .iter()
        .flatten()
        .map(|v| (v * 255.0 + 0.5).clamp(0.0, 255.0) as u8)
        .collect()
}

/// Mean FLIP error of `test` against `reference` (both tone-mapped sRGB8 RGB), at FLIP's default viewing
/// condition (67 pixels per degree: a 0.7 m wide 4K monitor at 0.7 m).
pub fn flip_mean(reference_srgb8: &[u8], test_srgb8: &[u8], width: u32, height: u32) -> f64 {
    let reference = nv_flip::FlipImageRgb8::with_data(width, height, reference_srgb8);
    let test = nv_flip::FlipImageRgb8::with_data(width, height, test_srgb8);
    let error = nv_flip::flip(reference, test, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    nv_flip::FlipPool::from_image(&error).mean() as f64
}

/// The standard error of each channel's image mean of the average of two independent halves `a` and `b`: an
/// averaged pixel's variance is estimated by (a - b)^2 / 4 and the mean's by their sum over n^2 (pixels taken
/// as independent). Heavy-tailed light (rare bright paths) makes it an underestimate.
pub fn mean_standard_error(a: &[[f32; 3]], b: &[[f32; 3]]) -> [f64; 3] {
    let n = a.len().min(b.len()).max(1) as f64;
    [0, 1, 2].map(|c| {
        let sum: f64 = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x[c] as f64 - y[c] as f64).powi(2) / 4.0)
            .sum();
        sum.sqrt() / n
    })
}

/// How many standard errors the ratio of two image means lies from 1, given each mean's standard error (first
/// order: the ratio's relative error is the two relative errors in quadrature). 0 where it cannot be told.
pub fn ratio_standard_errors(
    ratio: f64,
    mean: f64,
    error: f64,
    other_mean: f64,
    other_error: f64,
) -> f64 {
    let relative = ((error / mean).powi(2) + (other_error / other_mean).powi(2)).sqrt();
    let sigmas = (ratio - 1.0) / (ratio * relative);
    if sigmas.is_finite() { sigmas } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_standard_error_of_known_halves() {
        // Halves that differ by +-d in every pixel: each averaged pixel has variance d^2 / 4, the mean of n of
        // them d / (2 sqrt(n)).
        let n = 400;
        let a = vec![[1.1f32, 2.0, 0.0]; n];
        let b = vec![[0.9f32, 2.0, 0.0]; n];
        let e = mean_standard_error(&a, &b);
        assert!(
            (e[0] - 0.2 / (2.0 * (n as f64).sqrt())).abs() < 1e-6,
            "{e:?}"
        );
        assert_eq!((e[1], e[2]), (0.0, 0.0));
        // A 1% difference of means known to 0.1% each is about 7 standard errors; none where no error is known.
        let s = ratio_standard_errors(0.99, 1.0, 0.001, 1.0, 0.001);
        assert!((s + 7.14).abs() < 0.05, "{s}");
        assert_eq!(ratio_standard_errors(1.0, 1.0, 0.0, 1.0, 0.0), 0.0);
    }

    #[test]
    fn rel_mse_of_known_images() {
        let reference = vec![[1.0f32; 3]; 4];
        assert_eq!(rel_mse(&reference, &reference), 0.0);
        let brighter = vec![[1.1f32; 3]; 4];
        let expected = 0.01 / (1.0 + REL_MSE_EPS);
        assert!((rel_mse(&brighter, &reference) - expected).abs() < 1e-7);
    }

    #[test]
    fn tonemap_matches_the_shader_curve() {
        // Black stays black and a large value saturates. Grey 0.18 by hand: the matrices' rows sum to ~1, so
        // v ~ 0.18; (v(v + 0.0245786) - 0.000090537) / (v(0.983729 v + 0.432951) + 0.238081) = 0.1056;
        // sRGB: 1.055 * 0.1056^(1/2.4) - 0.055 = 0.359 -> 91.6 of 255.
        let display = tonemap(&[[0.0; 3], [100.0; 3], [0.18; 3]]);
        let out = srgb8(&display);
        assert_eq!(&out[0..3], &[0, 0, 0]);
        assert_eq!(&out[3..6], &[255, 255, 255]);
        for c in 0..3 {
            assert!(
                (display[2][c] - 0.359).abs() < 0.003,
                "grey -> {:?}",
                display[2]
            );
        }
    }

    #[test]
    fn flip_is_zero_for_equal_images_and_grows_with_noise() {
        let (w, h) = (32u32, 32u32);
        let reference: Vec<u8> = (0..w * h * 3).map(|i| ((i * 7) % 200) as u8 + 20).collect();
        assert!(flip_mean(&reference, &reference, w, h) < 1e-6);
        let noisy = |amplitude: i32| -> Vec<u8> {
            reference
                .iter()
                .enumerate()
                .map(|(i, &v)| {
                    let n = if (i * 2654435761) % 7 < 3 {
                        amplitude
                    } else {
                        -amplitude
                    };
                    (v as i32 + n).clamp(0, 255) as u8
                })
                .collect()
        };
        let small = flip_mean(&reference, &noisy(8), w, h);
        let large = flip_mean(&reference, &noisy(40), w, h);
        assert!(small > 0.0 && large > small, "FLIP {small} then {large}");
    }
}

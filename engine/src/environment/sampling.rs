//! Importance sampling of an environment map: a 2D distribution over the cells between the map's texel
//! lattice (W columns x H-1 rows, see [`super::map`]), each cell weighed by the mean luminance of its four
//! corner texels times the mean sin(theta) over its rows, and inside a cell a point drawn in proportion to the
//! bilinear interpolation of those four luminances, which is how the radiance itself is reconstructed. So a
//! one-texel sun is sampled as the tent it is rendered as (a uniform point in its cells would put as many
//! samples at the tent's dark edges as at its peak: measured 2.1x Mitsuba's per-sample variance on the
//! env-lit scene, whose `envmap` samples bilinearly too). The density is zero only where the radiance is.
//!
//! The bilinear shaping costs a map lookup's worth of loads per sample and per density (H200: 15% more trace
//! time on the env-lit bench scene, 4% on FlightHelmet's sky gradient), so it is on only for maps where some
//! cell's corners differ by more than [`BILINEAR_CONTRAST`]: a uniform point in a cell whose corners are within
//! that factor has a relative variance below 4% of the tent's, while one sun texel beside dark ones is 0.78.
//!
//! A row is picked by the marginal CDF, a cell within it by that row's conditional CDF, and the point inside
//! the cell by inverting the bilinear density (first its linear marginal in v, then the linear conditional in
//! u), reusing where the uniform numbers fell inside the CDF entries. The density of a direction is computed
//! from the same CDFs and corner luminances, so it is exactly the density the sampler draws from, and it
//! integrates to 1 over the sphere (`tests`). The WGSL twin is `shaders/lights/environment.wgsl`.
//!
//! Next-event estimation may sample a second distribution, MIS-compensated (Karlik et al. 2019, "MIS
//! compensation"; pbrt-v4's `ImageInfiniteLight::compensatedDistribution`): the same construction over the
//! luminance less the map's mean, clamped at 0. Where the map is darker than its mean, BSDF sampling, which the
//! path combines with it by MIS, covers it alone, so light samples go where they add most. That pays on maps
//! whose light is concentrated (the env-lit bench scene's one-texel sun: 0.57x the time to equal error on the
//! H200) and costs on smooth ones, where two samples (light and BSDF) of the dim part beat one (the sky
//! gradient: 1.12x on FlightHelmet), so [`next_event_sampling`] compensates only maps with at least
//! [`COMPENSATION_MIN_SHARE`] of their light above the mean. A smooth map, whose brightest texel is at most
//! [`SMOOTH_PEAK_TO_MEAN`] times its mean (a uniform one: pbrt-v4's `UniformInfiniteLight`; the sky gradient),
//! is left to BSDF sampling entirely, as Cycles leaves a plain world: cosine and glossy-lobe directions sample
//! its light nearly as well, and the path saves the shadow ray. ReSTIR's candidates, which no BSDF sample
//! completes, always use the full distribution. Figures: docs/BENCHMARKS.md.

use super::map::{EnvironmentMap, direction_to_uv, uv_to_direction};
use glam::Vec3;
use std::f64::consts::PI;

/// The CDFs, as the GPU reads them.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentDistribution {
    pub columns: u32,
    pub rows: u32,
    /// Per row, the cumulative probability of its cells (each row ends at 1).
    pub conditional_cdf: Vec<f32>,
    /// The cumulative probability of the rows (ends at 1).
    pub marginal_cdf: Vec<f32>,
    /// Integral of luminance over the sphere (W/m^2 per unit luminance scale): the power estimate's input.
    pub luminance_integral: f64,
    /// Luminance of every texel (W x H, row by row): the corners of the bilinear density inside a cell (the GPU
    /// computes it from the texels it already holds).
    pub texel_luminance: Vec<f32>,
    /// Whether points inside a cell follow its bilinear luminance (else uniform): some cell's brightest corner
    /// exceeds [`BILINEAR_CONTRAST`] times its darkest.
    pub bilinear: bool,
    /// The luminance subtracted from every texel before the clamp at 0 (0: the full distribution; the map's
    /// mean luminance: the compensated one).
    pub offset: f32,
}

/// The corner contrast within one cell above which a map is sampled bilinearly inside its cells.
pub const BILINEAR_CONTRAST: f32 = 2.0;

/// The share of a map's light above its mean from which next-event estimation samples it MIS-compensated
/// (the sky gradient has 0.05, the env-lit scene's sunny map 0.70).
pub const COMPENSATION_MIN_SHARE: f64 = 0.25;

/// The peak-to-mean luminance ratio up to which a map is left to BSDF sampling. Without next-event estimation
/// a path's variance grew about as this ratio on FlightHelmet (1.27x under the sky gradient, whose ratio is
/// 1.19; 1.9x at 1.86, 4.8x at 4.8), while its shadow rays and light samples cost 20-40% of a sample's time
/// (the H100 ablations of docs/BENCHMARKS.md): skipping them pays below 1/(1 - 0.2) = 1.25 wherever they cost
/// at least a fifth.
pub const SMOOTH_PEAK_TO_MEAN: f64 = 1.25;

/// How next-event estimation samples an environment map.
#[derive(Clone, Debug, PartialEq)]
pub enum NextEventSampling {
    /// Not at all: the map is smooth, BSDF sampling covers it (next-event estimation never picks it).
    None,
    /// From the full distribution, as ReSTIR's candidates.
    Full,
    /// From the compensated distribution.
    Compensated(EnvironmentDistribution),
}

/// [`NextEventSampling`] for `map`, whose full distribution is `full`: none for a smooth map (peak at most
/// [`SMOOTH_PEAK_TO_MEAN`] times the mean, or less than 1e-4 of its light above the mean), compensated from
/// [`COMPENSATION_MIN_SHARE`] of it, else full.
pub fn next_event_sampling(
    map: &EnvironmentMap,
    full: &EnvironmentDistribution,
) -> NextEventSampling {
    let mean = full.luminance_integral / (4.0 * PI);
    let peak = full.texel_luminance.iter().fold(0.0f32, |m, &l| m.max(l));
    if peak as f64 <= SMOOTH_PEAK_TO_MEAN * mean {
        return NextEventSampling::None;
    }
    match EnvironmentDistribution::compensated(map, full) {
        None => NextEventSampling::None,
        Some(c) if c.luminance_integral >= COMPENSATION_MIN_SHARE * full.luminance_integral => {
            NextEventSampling::Compensated(c)
        }
        Some(_) => NextEventSampling::Full,
    }
}

impl EnvironmentDistribution {
    /// In proportion to the map's luminance (what ReSTIR's candidates and the power estimate use).
    pub fn new(map: &EnvironmentMap) -> Self {
        Self::with_offset(map, 0.0)
    }

    /// Next-event estimation's: in proportion to the luminance above the map's mean (solid-angle weighted);
    /// `None` where that leaves less than 1e-4 of the map's light (a uniform map).
    pub fn compensated(map: &EnvironmentMap, full: &Self) -> Option<Self> {
        let mean = full.luminance_integral / (4.0 * PI);
        let compensated = Self::with_offset(map, mean as f32);
        (compensated.luminance_integral > 1e-4 * full.luminance_integral).then_some(compensated)
    }

    fn with_offset(map: &EnvironmentMap, offset: f32) -> Self {
        let (w, h) = (map.width as usize, map.height as usize);
        let rows = h - 1;
        let texel_luminance = |x: usize, y: usize| {
            let t = map.texel(x as u32, y as u32);
            0.2126 * t[0] as f64 + 0.7152 * t[1] as f64 + 0.0722 * t[2] as f64
        };
        // As `corners` computes it, in f32 from the f32 luminance, so the CDFs and the densities agree.
        let luminance =
            |x: usize, y: usize| (texel_luminance(x, y) as f32 - offset).max(0.0) as f64;
        let mut conditional_cdf = Vec::with_capacity(w * rows);
        let mut row_weights = Vec::with_capacity(rows);
        let mut luminance_integral = 0.0;
        let d_theta = PI / rows as f64;
        for j in 0..rows {
            let (t0, t1) = (j as f64 * d_theta, (j + 1) as f64 * d_theta);
            // Mean of sin(theta) over the row's band.
            let mean_sin = (t0.cos() - t1.cos()) / d_theta;
            let weights: Vec<f64> = (0..w)
                .map(|i| {
                    let i1 = (i + 1) % w;
                    0.25 * (luminance(i, j)
                        + luminance(i1, j)
                        + luminance(i, j + 1)
                        + luminance(i1, j + 1))
                        * mean_sin
                })
                .collect();
            let total: f64 = weights.iter().sum();
            // Solid angle of a cell is (2pi / W) (pi / rows) sin(theta).
            luminance_integral += total * (2.0 * PI / w as f64) * d_theta;
            push_cdf(&mut conditional_cdf, &weights, total);
            row_weights.push(total);
        }
        let total: f64 = row_weights.iter().sum();
        let mut marginal_cdf = Vec::with_capacity(rows);
        push_cdf(&mut marginal_cdf, &row_weights, total);
        let texel_luminance = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| texel_luminance(x, y) as f32)
            .collect();
        let mut dist = Self {
            columns: w as u32,
            rows: rows as u32,
            conditional_cdf,
            marginal_cdf,
            luminance_integral,
            texel_luminance,
            bilinear: false,
            offset,
        };
        dist.bilinear = (0..rows as u32).any(|j| {
            (0..w as u32).any(|i| {
                let c = dist.corners(i, j);
                let (lo, hi) = c
                    .iter()
                    .fold((f32::MAX, 0.0f32), |(lo, hi), &x| (lo.min(x), hi.max(x)));
                hi > BILINEAR_CONTRAST * lo
            })
        });
        dist
    }

    /// Luminance at the corners of cell (i, j): (i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1), columns wrapping.
    fn corners(&self, i: u32, j: u32) -> [f32; 4] {
        let w = self.columns as usize;
        let (i0, i1, j0) = (i as usize, (i as usize + 1) % w, j as usize);
        let at = |x: usize, y: usize| (self.texel_luminance[y * w + x] - self.offset).max(0.0);
        [at(i0, j0), at(i1, j0), at(i0, j0 + 1), at(i1, j0 + 1)]
    }

    fn row_cdf(&self, j: u32) -> &[f32] {
        let w = self.columns as usize;
        &self.conditional_cdf[j as usize * w..(j as usize + 1) * w]
    }

    /// Solid-angle density of the map-local direction `d`.
    pub fn pdf(&self, d: Vec3) -> f32 {
        let (u, v) = direction_to_uv(d);
        let (i, j, fx, fy) = self.cell_of(u, v);
        let sin_theta = (1.0 - d.y * d.y).max(0.0).sqrt();
        if sin_theta <= 0.0 {
            return 0.0;
        }
        let inside = if self.bilinear {
            bilinear_density(self.corners(i, j), fx, fy)
        } else {
            1.0
        };
        let p = difference(&self.marginal_cdf, j) * difference(self.row_cdf(j), i) * inside;
        p * (self.columns * self.rows) as f32 / (2.0 * std::f32::consts::PI.powi(2) * sin_theta)
    }

    /// The cell holding (u, v) and where in it: column i spans u in [(i + 1/2) / W, (i + 3/2) / W)
    /// (wrapping), row j spans v in [j / rows, (j + 1) / rows].
    fn cell_of(&self, u: f32, v: f32) -> (u32, u32, f32, f32) {
        let x = u * self.columns as f32 - 0.5;
        let i = (x.floor() as i64).rem_euclid(self.columns as i64) as u32;
        let y = v * self.rows as f32;
        let j = (y.floor().max(0.0) as u32).min(self.rows - 1);
        (i, j, x - x.floor(), (y - j as f32).clamp(0.0, 1.0))
    }

    /// A map-local direction for the uniform pair `u`, with its solid-angle density (0: no sample).
    pub fn sample(&self, u: [f32; 2]) -> (Vec3, f32) {
        let (j, ry) = sample_cdf(&self.marginal_cdf, u[1]);
        let (i, rx) = sample_cdf(self.row_cdf(j), u[0]);
        let (fx, fy) = if self.bilinear {
            let [c00, c10, c01, c11] = self.corners(i, j);
            let fy = sample_linear(ry, c00 + c10, c01 + c11);
            (
                sample_linear(rx, lerp(c00, c01, fy), lerp(c10, c11, fy)),
                fy,
            )
        } else {
            (rx, ry)
        };
        let uu = (i as f32 + 0.5 + fx) / self.columns as f32;
        let d = uv_to_direction(uu - uu.floor(), (j as f32 + fy) / self.rows as f32);
        (d, self.pdf(d))
    }
}

fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// The point in [0, 1) below which a density linear from `a` at 0 to `b` at 1 holds the fraction `r`: the root
/// of ((b - a) / 2) x^2 + a x = r (a + b) / 2, written as r (a + b) / (a + sqrt(a^2 + r (b^2 - a^2))) so that
/// it stays exact as b - a goes to 0 (uniform).
fn sample_linear(r: f32, a: f32, b: f32) -> f32 {
    let denominator = a + lerp(a * a, b * b, r).max(0.0).sqrt();
    if a + b <= 0.0 || denominator <= 0.0 {
        return r;
    }
    (r * (a + b) / denominator).clamp(0.0, 0.99999994)
}

/// The bilinear density of corners `c` at (fx, fy) relative to the cell's mean (1 where all corners are 0).
fn bilinear_density(c: [f32; 4], fx: f32, fy: f32) -> f32 {
    let mean = 0.25 * (c[0] + c[1] + c[2] + c[3]);
    if mean <= 0.0 {
        return 1.0;
    }
    lerp(lerp(c[0], c[1], fx), lerp(c[2], c[3], fx), fy) / mean
}

/// Appends the normalised running sum of `weights` (uniform when they sum to 0); the last entry is exactly 1.
fn push_cdf(out: &mut Vec<f32>, weights: &[f64], total: f64) {
    let n = weights.len();
    let mut running = 0.0;
    for (k, w) in weights.iter().enumerate() {
        running += w;
        let c = if total > 0.0 {
            running / total
        } else {
            (k + 1) as f64 / n as f64
        };
        out.push(if k + 1 == n { 1.0 } else { c.min(1.0) as f32 });
    }
}

fn difference(cdf: &[f32], k: u32) -> f32 {
    let k = k as usize;
    cdf[k] - if k == 0 { 0.0 } else { cdf[k - 1] }
}

/// The first entry whose CDF exceeds `u`, and where `u` falls inside it (0..1).
fn sample_cdf(cdf: &[f32], u: f32) -> (u32, f32) {
    let k = cdf.partition_point(|&c| c <= u).min(cdf.len() - 1);
    let lo = if k == 0 { 0.0 } else { cdf[k - 1] };
    let width = cdf[k] - lo;
    let f = if width > 0.0 {
        ((u - lo) / width).clamp(0.0, 0.99999994)
    } else {
        0.5
    };
    (k as u32, f)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A map with a small, very bright "sun" and a dim gradient.
    pub fn sunny_map() -> EnvironmentMap {
        let (w, h) = (32u32, 17u32);
        let mut texels = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let sky = 0.2 + 0.5 * (1.0 - y as f32 / (h - 1) as f32);
                let sun = if (x, y) == (7, 5) { 5000.0 } else { 0.0 };
                texels.push([sky + sun, sky + sun * 0.9, sky * 1.3 + sun * 0.8]);
            }
        }
        EnvironmentMap::new(w, h, texels)
    }

    /// A linear congruential stream of uniform numbers in [0, 1) from `seed`.
    fn uniforms(seed: u64) -> impl FnMut() -> f32 {
        let mut state = seed;
        move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    /// Calls `f(direction, solid angle)` at the midpoints of an nt x np (theta, phi) grid over the sphere.
    fn for_sphere_grid(nt: usize, np: usize, mut f: impl FnMut(Vec3, f64)) {
        for a in 0..nt {
            let theta = (a as f64 + 0.5) / nt as f64 * PI;
            for b in 0..np {
                let phi = (b as f64 + 0.5) / np as f64 * 2.0 * PI;
                let d = uv_to_direction((phi / (2.0 * PI)) as f32, (theta / PI) as f32);
                f(d, theta.sin() * (PI / nt as f64) * (2.0 * PI / np as f64));
            }
        }
    }

    /// Integrates the density over the sphere with a fine (theta, phi) midpoint rule.
    #[test]
    fn pdf_integrates_to_one() {
        for map in [
            sunny_map(),
            EnvironmentMap::constant([1.0, 2.0, 3.0]),
            EnvironmentMap::new(3, 4, (0..12).map(|i| [i as f32; 3]).collect()),
        ] {
            let dist = EnvironmentDistribution::new(&map);
            let mut sum = 0.0f64;
            for_sphere_grid(1200, 2400, |d, d_omega| sum += dist.pdf(d) as f64 * d_omega);
            assert!((sum - 1.0).abs() < 2e-3, "integral of the pdf {sum}");
        }
    }

    #[test]
    fn samples_carry_their_density_and_favour_the_sun() {
        let map = sunny_map();
        let dist = EnvironmentDistribution::new(&map);
        let sun = uv_to_direction(7.5 / 32.0, 5.0 / 16.0);
        let mut near_sun = 0;
        let n = 20000;
        let mut rand = uniforms(12345);
        for _ in 0..n {
            let (d, pdf) = dist.sample([rand(), rand()]);
            assert!(pdf > 0.0 && (d.length() - 1.0).abs() < 1e-4);
            assert!((pdf - dist.pdf(d)).abs() <= 1e-3 * pdf);
            if d.dot(sun) > 0.98 {
                near_sun += 1;
            }
        }
        // The sun texel carries most of the map's power.
        assert!(near_sun > n / 2, "{near_sun} of {n} samples near the sun");
    }

    /// Luminance / pdf over the samples estimates the map's luminance integral: its mean must be that integral
    /// (the samples follow the density they report) and, with the density shaped like the bilinear radiance,
    /// its spread must be small even with a one-texel sun (measured 0.042; 0.87 with uniform points inside the
    /// cells, as before).
    #[test]
    fn samples_follow_the_bilinear_radiance() {
        let map = sunny_map();
        let dist = EnvironmentDistribution::new(&map);
        let mut rand = uniforms(99);
        let n = 200_000;
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let (d, pdf) = dist.sample([rand(), rand()]);
            let l = map.lookup(d);
            let x = (0.2126 * l[0] + 0.7152 * l[1] + 0.0722 * l[2]) as f64 / pdf as f64;
            sum += x;
            sum2 += x * x;
        }
        let mean = sum / n as f64;
        let relative_spread = (sum2 / n as f64 - mean * mean).max(0.0).sqrt() / mean;
        let integral = dist.luminance_integral;
        assert!(
            (mean / integral - 1.0).abs() < 0.01,
            "mean {mean} vs integral {integral}"
        );
        assert!(relative_spread < 0.3, "relative spread {relative_spread}");
    }

    /// Bilinear shaping only where it pays: on with a sun texel, off for a constant map and a smooth gradient
    /// (rows 2% apart), whose points stay uniform inside their cells as before.
    #[test]
    fn bilinear_only_for_contrasty_maps() {
        assert!(EnvironmentDistribution::new(&sunny_map()).bilinear);
        assert!(!EnvironmentDistribution::new(&EnvironmentMap::constant([1.0; 3])).bilinear);
        let gradient = (0..65).map(|j| [1.0 + j as f32 / 64.0; 3]).collect();
        assert!(!EnvironmentDistribution::new(&EnvironmentMap::new(1, 65, gradient)).bilinear);
    }

    /// The compensated distribution: a density (integrates to 1) that is zero exactly where the map is darker
    /// than its mean, whose samples carry it; none for a uniform map.
    #[test]
    fn compensated_samples_only_the_light_above_the_mean() {
        let constant = EnvironmentMap::constant([1.0, 2.0, 3.0]);
        let full = EnvironmentDistribution::new(&constant);
        assert!(EnvironmentDistribution::compensated(&constant, &full).is_none());
        // Brighter towards +y (v = 0): the upper half is above the mean.
        let gradient = EnvironmentMap::new(
            4,
            33,
            (0..33)
                .flat_map(|j| [[2.0 - j as f32 / 32.0; 3]; 4])
                .collect(),
        );
        // Where every corner of the cell is below the mean: the sunny map's sky away from the sun's cells
        // (the sun alone lifts the mean above the sky), the gradient's lower half (v > 0.5) with a margin.
        let sun = uv_to_direction(7.5 / 32.0, 5.0 / 16.0);
        let away_from_sun = move |d: Vec3, _: f32| d.dot(sun) < 0.9;
        let dark_half = |d: Vec3, offset: f32| d.y < -0.1 && offset > 1.0;
        type BelowMean<'a> = &'a dyn Fn(Vec3, f32) -> bool;
        let cases: [(EnvironmentMap, BelowMean); 2] =
            [(sunny_map(), &away_from_sun), (gradient, &dark_half)];
        for (map, below_mean) in cases {
            let full = EnvironmentDistribution::new(&map);
            let dist = EnvironmentDistribution::compensated(&map, &full).expect("not uniform");
            assert!(
                dist.luminance_integral > 0.0 && dist.luminance_integral < full.luminance_integral
            );
            let mut sum = 0.0f64;
            for_sphere_grid(600, 1200, |d, d_omega| {
                let pdf = dist.pdf(d) as f64;
                if below_mean(d, dist.offset) {
                    assert_eq!(pdf, 0.0, "density {pdf} at {d} below the mean");
                }
                sum += pdf * d_omega;
            });
            assert!((sum - 1.0).abs() < 3e-3, "integral of the pdf {sum}");
            let mut rand = uniforms(7);
            for _ in 0..5000 {
                let (d, pdf) = dist.sample([rand(), rand()]);
                assert!(pdf > 0.0 && (pdf - dist.pdf(d)).abs() <= 1e-3 * pdf);
                assert!(
                    !below_mean(d, dist.offset),
                    "a sample at {d}, below the mean"
                );
            }
        }
    }

    /// Compensation where the light is concentrated (a sun), the full distribution where it varies, none for a
    /// uniform map or the smooth sky gradient.
    #[test]
    fn next_event_sampling_follows_how_concentrated_the_light_is() {
        let rule = |map: EnvironmentMap| {
            let full = EnvironmentDistribution::new(&map);
            next_event_sampling(&map, &full)
        };
        assert!(matches!(
            rule(sunny_map()),
            NextEventSampling::Compensated(_)
        ));
        assert_eq!(
            rule(EnvironmentMap::constant([1.0, 2.0, 3.0])),
            NextEventSampling::None
        );
        // Gradients along the height: t = 0 at the nadir, 1 at the zenith.
        let gradient = |texel: fn(f32) -> [f32; 3]| {
            let column = (0..65)
                .map(|j| texel(0.5 * ((std::f32::consts::PI * j as f32 / 64.0).cos() + 1.0)))
                .collect();
            rule(EnvironmentMap::new(1, 65, column))
        };
        // The sky gradient (render::environment), white to (0.5, 0.7, 1): peak 1.19 times the mean.
        assert_eq!(
            gradient(|t| [1.0 - 0.5 * t, 1.0 - 0.3 * t, 1.0]),
            NextEventSampling::None
        );
        // Grey 0.2 to white: peak 1.67 times the mean, a sixth of the light above it.
        assert_eq!(gradient(|t| [0.2 + 0.8 * t; 3]), NextEventSampling::Full);
    }

    #[test]
    fn luminance_integral_of_a_constant_map_is_4pi_times_luminance() {
        let dist = EnvironmentDistribution::new(&EnvironmentMap::constant([2.0; 3]));
        assert!((dist.luminance_integral - 8.0 * PI).abs() < 1e-6 * 8.0 * PI);
    }
}

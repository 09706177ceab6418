//! Mitsuba 3 side by side: the bench's static scenes rendered by Mitsuba on the same machine, and raykin's
//! error-vs-time curve set beside Mitsuba's.
//!
//! Three steps, so that Mitsuba (Python) and raykin never share a process: `raykin bench --export-mitsuba
//! DIR` writes each scene ([`export`]); `scripts/mitsuba-side-by-side.py DIR` renders in Mitsuba, with the
//! glTF BRDF plugin of tests/reference, a two-half reference and one render per curve sample count, each
//! timed on its own; `raykin bench --parts errors --mitsuba DIR` reads those images and measures them with
//! the same metric as raykin's curves ([`compare`]).
//!
//! Each renderer's error is taken against its own converged image (both halves' noise subtracted), so the
//! time-to-equal-error ratio compares estimators and speed, not the small differences between the two
//! models; those differences are reported on their own (`references_rel_mse`).

pub mod export;

use super::error_curves::{
    CurvePoint, CurveResult, SceneErrors, excess, excess_curve, time_to_rel_mse,
};
use super::metrics::{flip_mean, rel_mse, srgb8, tonemap};
use crate::stats::time_to_reach;
use anyhow::{Context, Result};
use std::path::Path;

/// What `scripts/mitsuba-side-by-side.py` writes into `DIR/SCENE/mitsuba.json`.
#[derive(serde::Deserialize)]
struct MitsubaRun {
    variant: String,
    mitsuba_version: String,
    device: String,
    reference: MitsubaReference,
    points: Vec<MitsubaPoint>,
}

#[derive(serde::Deserialize)]
struct MitsubaReference {
    spp: u32,
    files: [String; 2],
}

#[derive(serde::Deserialize)]
struct MitsubaPoint {
    spp: u32,
    seconds: f64,
    file: String,
}

/// One scene's comparison (a row of docs/BENCHMARKS.md's side-by-side table).
#[derive(Clone, Debug, serde::Serialize)]
pub struct SideBySide {
    pub scene: String,
    pub mitsuba_variant: String,
    pub mitsuba_version: String,
    pub mitsuba_device: String,
    pub mitsuba_reference_spp: u32,
    /// Tone-mapped relMSE of Mitsuba's reference (from its halves).
    pub mitsuba_reference_noise: f64,
    /// Samples per second at the largest common sample count: raykin by GPU trace time and by wall time of
    /// its frames, Mitsuba by the wall time of `mi.render` (kernel compilation excluded).
    pub raykin_samples_per_s_trace: f64,
    pub raykin_samples_per_s_wall: f64,
    pub mitsuba_samples_per_s: f64,
    /// Per-sample variance ratio, raykin / Mitsuba: (relMSE - noise) x spp at the largest common count.
    pub variance_ratio: f64,
    /// Time to equal error, raykin / Mitsuba: (relMSE - noise) x time over the curves' second halves
    /// (median), by raykin's trace time and by its wall time. Below 1: raykin is faster.
    pub time_to_equal_error_trace: f64,
    pub time_to_equal_error_wall: f64,
    /// The same from steady rates: the variance ratio times raykin's trace ms per sample over its curve's last
    /// segment (where the GPU has settled) over Mitsuba's ms per sample at that count. The curve-based figures
    /// include every transient of the accumulation loop (on the H200 a 3-4x slower stretch mid-curve).
    pub time_to_equal_error_steady: f64,
    /// Time to equal error as the words say, raykin (trace) / Mitsuba: the ratio of the times at which the two
    /// curves first reach the same (relMSE - noise), read off each curve by log-log interpolation between its
    /// points (never extrapolated), at the lowest error both reach (`EqualError::rel_mse`) and its least and
    /// greatest over nine levels spread geometrically from there up to the higher of the two first points. The
    /// products above equal it only where relMSE falls as 1/time; tone-mapped errors of scenes with rare bright
    /// paths fall slower (log-log slopes -0.44 to -0.72) over the curves, so that raykin, at a lower error for
    /// the same samples, is compared further down its flatter stretch. `None` where the curves share no error.
    pub time_at_equal_error: Option<EqualError>,
    /// Where raykin's first point is already below every error Mitsuba's curve reaches (no common error), an
    /// upper bound instead: raykin's time at its first point over Mitsuba's at its lowest error.
    pub time_at_equal_error_at_most: Option<f64>,
    /// Milliseconds to reach tone-mapped relMSE 0.01 (noise subtracted; extrapolated along the fitted power law
    /// where a curve stopped short): raykin (trace) and Mitsuba.
    pub raykin_ms_to_0_01: Option<f64>,
    pub mitsuba_ms_to_0_01: Option<f64>,
    /// How far apart the two converged images are: tone-mapped relMSE of raykin's reference against
    /// Mitsuba's, both noises subtracted, and the ratio of their mean radiance per channel.
    pub references_rel_mse: f64,
    pub reference_mean_ratio: [f64; 3],
    /// How many standard errors each of those ratios lies from 1, by both references' halves
    /// (`metrics::ratio_standard_errors`): beyond a few, the two renderers do not compute the same image.
    pub reference_mean_ratio_sigmas: [f64; 3],
    /// Pixels of Mitsuba's reference halves with a negative or non-finite channel (a sound renderer has none).
    pub mitsuba_bad_pixels: usize,
    /// The raykin curve compared: the most efficient of those running the default estimator.
    pub raykin_curve: String,
    /// What the export could not give Mitsuba (scene.json's `unsupported`).
    pub unsupported: Vec<String>,
}

/// Time-to-equal-error ratios of one curve to another over the errors both reach.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct EqualError {
    /// The lowest error both curves reach.
    pub rel_mse: f64,
    /// The ratio of their times to first reach it.
    pub ratio: f64,
    /// The least and greatest ratio over nine levels from there up to the higher of the two first points.
    pub range: [f64; 2],
}

/// Beyond this many standard errors (and `MEAN_RATIO_TOLERANCE`), the converged images' means differ by more than
/// their noise and the bench says so: the Cornell box's 0.990, 12-20 standard errors, was a shadow-ray bug that
/// stood in this table unremarked for sessions (docs/ACCURACY.md).
const MEAN_RATIO_SIGMAS: f64 = 5.0;
/// Differences of means this small are not reported, however many standard errors they are.
const MEAN_RATIO_TOLERANCE: f64 = 0.002;

/// Reads `dir/SCENE/mitsuba.json` when it is there and compares; adds Mitsuba's curve to `errors`.
pub fn compare(
    dir: &Path,
    errors: &mut SceneErrors,
    raykin_reference: &[[f32; 3]],
) -> Result<Option<SideBySide>> {
    let scene_dir = dir.join(&errors.scene);
    let run_path = scene_dir.join("mitsuba.json");
    if !run_path.exists() {
        eprintln!(
            "raykin bench: {}: no Mitsuba renders in {} (run scripts/mitsuba-side-by-side.py first)",
            errors.scene,
            scene_dir.display()
        );
        return Ok(None);
    }
    let run: MitsubaRun = serde_json::from_slice(
        &std::fs::read(&run_path)
            .with_context(|| format!("{}: cannot read", run_path.display()))?,
    )
    .with_context(|| format!("{}: not a Mitsuba run", run_path.display()))?;
    let description: serde_json::Value = serde_json::from_slice(
        &std::fs::read(scene_dir.join("scene.json")).context("scene.json of the export")?,
    )?;
    let unsupported = description["unsupported"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|v| v.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default();
    let (w, h) = (errors.width, errors.height);
    let read = |file: &str| -> Result<Vec<[f32; 3]>> {
        let (iw, ih, image) = raykin::image_io::read_exr(&scene_dir.join(file))?;
        anyhow::ensure!(
            (iw, ih) == (w, h),
            "{file}: {iw}x{ih}, the bench measures {w}x{h}: export again"
        );
        Ok(image)
    };
    let halves = [
        read(&run.reference.files[0])?,
        read(&run.reference.files[1])?,
    ];
    let mean: Vec<[f32; 3]> = halves[0]
        .iter()
        .zip(&halves[1])
        .map(|(a, b)| [0, 1, 2].map(|c| 0.5 * (a[c] + b[c])))
        .collect();
    let noise = rel_mse(&tonemap(&halves[0]), &tonemap(&halves[1])) / 4.0;
    let display = tonemap(&mean);
    let display8 = srgb8(&display);
    let mut points = Vec::new();
    for p in &run.points {
        let image = read(&p.file)?;
        let shown = tonemap(&image);
        let e = rel_mse(&shown, &display);
        let flip = flip_mean(&display8, &srgb8(&shown), w, h);
        points.push(CurvePoint {
            spp: p.spp,
            time_ms: p.seconds * 1e3,
            wall_ms: p.seconds * 1e3,
            rel_mse: e,
            rel_mse_min: e,
            rel_mse_max: e,
            rel_mse_linear: rel_mse(&image, &mean),
            flip,
            flip_min: flip,
            flip_max: flip,
        });
    }
    points.sort_by_key(|p| p.spp);
    anyhow::ensure!(
        !points.is_empty(),
        "{}: no curve points",
        run_path.display()
    );
    // raykin's side: of the curves that run the default estimator (1 spp per frame, or more per dispatch,
    // which keeps a GPU busier, as Mitsuba renders all of a count's samples in one launch), the fastest to
    // equal error.
    let reference_noise = errors.reference_noise_rel_mse;
    let mitsuba_curve = excess_curve(&points, noise);
    let mitsuba_efficiency = efficiency(&points, noise, |p| p.time_ms);
    let candidates: Vec<&CurveResult> = errors
        .curves
        .iter()
        .filter(|c| c.name.starts_with("default") || c.name.ends_with("spp/frame"))
        .collect();
    let best = fastest_to_equal_error(
        candidates.iter().map(|c| c.points.as_slice()),
        reference_noise,
        &mitsuba_curve,
        mitsuba_efficiency,
    )
    .map_or(&errors.curves[0], |k| candidates[k]);
    let raykin_curve = best.name.clone();
    let raykin = &best.points;
    let common = raykin
        .iter()
        .filter(|r| points.iter().any(|m| m.spp == r.spp))
        .map(|r| r.spp)
        .max()
        .context("raykin's and Mitsuba's curves share no sample count")?;
    let at = |curve: &[CurvePoint]| curve.iter().find(|p| p.spp == common).cloned();
    let (r, m) = (
        at(raykin).unwrap_or_else(|| raykin[0].clone()),
        at(&points).unwrap_or_else(|| points[0].clone()),
    );
    let pixels = (w * h) as f64 * common as f64;
    let references_rel_mse =
        rel_mse(&tonemap(raykin_reference), &display) - noise - reference_noise;
    let channel_means = |image: &[[f32; 3]]| {
        [0, 1, 2]
            .map(|c| image.iter().map(|p| p[c] as f64).sum::<f64>() / image.len().max(1) as f64)
    };
    let (raykin_means, mitsuba_means) = (channel_means(raykin_reference), channel_means(&mean));
    // A mean at or below 0 (negative outliers) has no ratio: NaN, written as null.
    let reference_mean_ratio = [0, 1, 2].map(|c| {
        if mitsuba_means[c] > 0.0 {
            raykin_means[c] / mitsuba_means[c]
        } else {
            f64::NAN
        }
    });
    let mitsuba_mean_error = super::metrics::mean_standard_error(&halves[0], &halves[1]);
    let reference_mean_ratio_sigmas = [0, 1, 2].map(|c| {
        super::metrics::ratio_standard_errors(
            reference_mean_ratio[c],
            raykin_means[c],
            errors.reference_mean_standard_error[c],
            mitsuba_means[c],
            mitsuba_mean_error[c],
        )
    });
    let worst = reference_mean_ratio_sigmas
        .iter()
        .zip(&reference_mean_ratio)
        .filter(|(s, r)| s.abs() > MEAN_RATIO_SIGMAS && (*r - 1.0).abs() > MEAN_RATIO_TOLERANCE)
        .max_by(|a, b| a.0.abs().total_cmp(&b.0.abs()));
    if let Some((sigmas, ratio)) = worst {
        eprintln!(
            "raykin bench: {}: warning: raykin's converged image is {:.2}x Mitsuba's in mean ({sigmas:+.0} standard \
             errors by both references' halves): the two renderers do not compute the same image (a difference \
             of model, scene export or estimator, not noise; rare bright paths make the standard error an \
             underestimate)",
            errors.scene, ratio
        );
    }
    let mitsuba_bad_pixels = halves
        .iter()
        .flatten()
        .filter(|p| p.iter().any(|v| !v.is_finite() || *v < 0.0))
        .count();
    let raykin_curve_excess = excess_curve(raykin, reference_noise);
    let result = SideBySide {
        scene: errors.scene.clone(),
        mitsuba_variant: run.variant.clone(),
        mitsuba_version: run.mitsuba_version,
        mitsuba_device: run.device,
        mitsuba_reference_spp: run.reference.spp,
        mitsuba_reference_noise: noise,
        raykin_samples_per_s_trace: pixels / (r.time_ms * 1e-3),
        raykin_samples_per_s_wall: pixels / (r.wall_ms * 1e-3),
        mitsuba_samples_per_s: pixels / (m.time_ms * 1e-3),
        variance_ratio: excess(&r, reference_noise) / excess(&m, noise),
        time_to_equal_error_trace: efficiency(raykin, reference_noise, |p| p.time_ms)
            / mitsuba_efficiency,
        time_to_equal_error_wall: efficiency(raykin, reference_noise, |p| p.wall_ms)
            / mitsuba_efficiency,
        time_to_equal_error_steady: excess(&r, reference_noise) / excess(&m, noise)
            * steady_ms_per_spp(raykin)
            / (m.time_ms / m.spp.max(1) as f64),
        time_at_equal_error: at_equal_error(&raykin_curve_excess, &mitsuba_curve),
        time_at_equal_error_at_most: equal_error_bound(&raykin_curve_excess, &mitsuba_curve),
        raykin_ms_to_0_01: time_to_rel_mse(&raykin_curve_excess, 0.01).0,
        mitsuba_ms_to_0_01: time_to_rel_mse(&mitsuba_curve, 0.01).0,
        references_rel_mse,
        reference_mean_ratio,
        reference_mean_ratio_sigmas,
        mitsuba_bad_pixels,
        raykin_curve,
        unsupported,
    };
    errors.curves.push(CurveResult {
        name: format!(
            "Mitsuba 3 {} (wall time of mi.render, own reference)",
            run.variant
        ),
        ms_to_rel_mse_0_01: result.mitsuba_ms_to_0_01,
        points,
        frame_trace_ms: Vec::new(),
        integrator: format!("Mitsuba's path ({})", run.variant),
        auto_trials: Vec::new(),
        sort_trials: Vec::new(),
    });
    Ok(Some(result))
}

/// Trace ms per sample per pixel between a curve's last two points.
fn steady_ms_per_spp(curve: &[CurvePoint]) -> f64 {
    match curve {
        [.., a, b] if b.spp > a.spp => (b.time_ms - a.time_ms) / (b.spp - a.spp) as f64,
        [.., b] => b.time_ms / b.spp.max(1) as f64,
        [] => f64::NAN,
    }
}

/// relMSE above the reference's noise.
/// (relMSE - noise) x time over a curve's second half (median): constant for an estimator converging at 1/t,
/// so the ratio of two curves' is their time to equal error.
fn efficiency(curve: &[CurvePoint], noise: f64, time: fn(&CurvePoint) -> f64) -> f64 {
    let tail: Vec<f64> = curve[curve.len() / 2..]
        .iter()
        .map(|p| excess(p, noise) * time(p))
        .collect();
    crate::stats::Spread::of(&tail).median
}

/// Which of raykin's `curves` (relMSE against a reference of noise `noise`) reaches Mitsuba's errors (`mitsuba`,
/// relMSE - noise) soonest: the least time at equal error, the figure the table leads with, or where a curve
/// shares no error with Mitsuba's, its relMSE x time over Mitsuba's (`mitsuba_efficiency`). relMSE x time alone
/// parts from it where relMSE falls slower than 1/time: it picked the Cornell box's 1-spp curve, 0.23x at equal
/// error, over its 16-spp curve, 0.21x (H100, 2026-12-06).
fn fastest_to_equal_error<'a>(
    curves: impl Iterator<Item = &'a [CurvePoint]>,
    noise: f64,
    mitsuba: &[(f64, f64)],
    mitsuba_efficiency: f64,
) -> Option<usize> {
    let ratio = |points: &[CurvePoint]| {
        at_equal_error(&excess_curve(points, noise), mitsuba).map_or_else(
            || efficiency(points, noise, |p| p.time_ms) / mitsuba_efficiency,
            |e| e.ratio,
        )
    };
    curves
        .map(ratio)
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(k, _)| k)
}

/// Time-to-equal-error ratios of curve `a` to curve `b` ((time, error) points in time order).
fn at_equal_error(a: &[(f64, f64)], b: &[(f64, f64)]) -> Option<EqualError> {
    let lowest = |c: &[(f64, f64)]| c.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let (lo, hi) = (lowest(a).max(lowest(b)), a.first()?.1.min(b.first()?.1));
    if !(lo > 0.0 && hi >= lo) {
        return None;
    }
    let ratio_at = |e: f64| Some(time_to_reach(a, e)? / time_to_reach(b, e)?);
    let ratio = ratio_at(lo)?;
    let levels: Vec<f64> = (1..9)
        .filter_map(|k| ratio_at(lo * (hi / lo).powf(f64::from(k) / 8.0)))
        .chain([ratio])
        .collect();
    let least = levels.iter().copied().fold(f64::INFINITY, f64::min);
    let greatest = levels.iter().copied().fold(0.0, f64::max);
    Some(EqualError {
        rel_mse: lo,
        ratio,
        range: [least, greatest],
    })
}

/// Where `a`'s first point is already below every error `b` reaches, the curves share none, but `a` reached `b`'s
/// lowest no later than that first point: the time-to-equal-error ratio is at most its time over `b`'s there.
fn equal_error_bound(a: &[(f64, f64)], b: &[(f64, f64)]) -> Option<f64> {
    let first = a.first()?;
    let lowest = b.iter().min_by(|x, y| x.1.total_cmp(&y.1))?;
    (first.1 < lowest.1 && lowest.0 > 0.0).then(|| first.0 / lowest.0)
}

/// The side-by-side table for summary.md and docs/BENCHMARKS.md.
pub fn markdown(rows: &[SideBySide]) -> String {
    let mut s = String::from(
        "| scene | raykin curve | Mitsuba | samples/s raykin (trace / wall) | samples/s Mitsuba | throughput | variance ratio | relMSE x time (trace / wall / steady) | time at equal error: at the lowest common relMSE; range | ms to relMSE 0.01 raykin / Mitsuba | references apart (relMSE; mean ratio, the largest in standard errors; Mitsuba's negative or non-finite pixels) |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let ms = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.1}"));
    let equal = |r: &SideBySide| match (r.time_at_equal_error, r.time_at_equal_error_at_most) {
        (Some(e), _) => format!(
            "**{:.2}x** at {:.1e}; {:.2}-{:.2}x",
            e.ratio, e.rel_mse, e.range[0], e.range[1]
        ),
        (None, Some(b)) => {
            format!("**at most {b:.4}x** (raykin's first point below Mitsuba's whole curve)")
        }
        (None, None) => "-".to_string(),
    };
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {:.2} M / {:.2} M | {:.2} M | {:.2}x | {:.2} | {:.2}x / {:.2}x / {:.2}x | {} | {} / {} | {:.1e}; {:.3} {:.3} {:.3} ({:+.0} s.e.); {} |\n",
            r.scene,
            r.raykin_curve,
            r.mitsuba_variant,
            r.raykin_samples_per_s_trace / 1e6,
            r.raykin_samples_per_s_wall / 1e6,
            r.mitsuba_samples_per_s / 1e6,
            r.raykin_samples_per_s_trace / r.mitsuba_samples_per_s,
            r.variance_ratio,
            r.time_to_equal_error_trace,
            r.time_to_equal_error_wall,
            r.time_to_equal_error_steady,
            equal(r),
            ms(r.raykin_ms_to_0_01),
            ms(r.mitsuba_ms_to_0_01),
            r.references_rel_mse,
            r.reference_mean_ratio[0],
            r.reference_mean_ratio[1],
            r.reference_mean_ratio[2],
            r.reference_mean_ratio_sigmas
                .iter()
                .copied()
                .max_by(|a, b| a.abs().total_cmp(&b.abs()))
                .unwrap_or(0.0),
            r.mitsuba_bad_pixels,
        );
    }
    for r in rows.iter().filter(|r| !r.unsupported.is_empty()) {
        s += &format!(
            "\n{}: not given to Mitsuba: {}.",
            r.scene,
            r.unsupported.join("; ")
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve(error: impl Fn(f64) -> f64) -> Vec<(f64, f64)> {
        (0..11)
            .map(|k| 2f64.powi(k))
            .map(|t| (t, error(t)))
            .collect()
    }

    fn points(errors: &[(f64, f64)]) -> Vec<CurvePoint> {
        errors
            .iter()
            .enumerate()
            .map(|(k, &(time_ms, rel_mse))| CurvePoint {
                spp: 1 << k,
                time_ms,
                wall_ms: time_ms,
                rel_mse,
                rel_mse_min: rel_mse,
                rel_mse_max: rel_mse,
                rel_mse_linear: rel_mse,
                flip: 0.0,
                flip_min: 0.0,
                flip_max: 0.0,
            })
            .collect()
    }

    /// The Cornell box's case: curve 0 falls as 1/t throughout (relMSE x time 1), curve 1 lies above it until
    /// t = 128 and then falls faster. By relMSE x time over the second half curve 0 is ahead (median 1 against
    /// 1.03); to Mitsuba's lowest error (4/1024) curve 1 gets there first (t of about 230 against 256).
    #[test]
    fn the_curve_fastest_to_equal_error_leads() {
        let steady = curve(|t| 1.0 / t);
        let late = curve(|t| match t as u32 {
            ..=128 => 1.2 / t,
            256 => 1.0 / 300.0,
            512 => 1.0 / 700.0,
            _ => 1.0 / 1600.0,
        });
        let mitsuba = curve(|t| 4.0 / t);
        let candidates = [points(&steady), points(&late)];
        let products = |c: &[CurvePoint]| efficiency(c, 0.0, |p| p.time_ms);
        assert!(products(&candidates[0]) < products(&candidates[1]));
        let mitsuba_efficiency = efficiency(&points(&mitsuba), 0.0, |p| p.time_ms);
        let pick = |c: &[Vec<CurvePoint>]| {
            fastest_to_equal_error(
                c.iter().map(Vec::as_slice),
                0.0,
                &mitsuba,
                mitsuba_efficiency,
            )
        };
        assert_eq!(pick(&candidates), Some(1));
        // Where no curve shares an error with Mitsuba's, relMSE x time decides.
        let far = curve(|t| 1e-6 / t);
        let below = [points(&far), points(&curve(|t| 0.5e-6 / t))];
        assert_eq!(pick(&below), Some(1));
        assert_eq!(pick(&[]), None);
    }

    /// Two estimators at 1/t: the ratio is their constant, at every level.
    #[test]
    fn equal_error_of_parallel_curves_is_their_ratio() {
        let (a, b) = (curve(|t| 1.0 / t), curve(|t| 4.0 / t));
        let EqualError {
            rel_mse: lowest,
            ratio,
            range: [least, greatest],
        } = at_equal_error(&a, &b).unwrap();
        assert!((lowest - 4.0 / 1024.0).abs() < 1e-12, "{lowest}");
        for r in [ratio, least, greatest] {
            assert!((r - 0.25).abs() < 1e-9, "{r}");
        }
    }

    /// A flatter curve (t^-0.5) below a steeper one (t^-1): at the top they cross, further down the flatter one
    /// needs ever more time. The products' ratio over equal times would say neither.
    #[test]
    fn equal_error_follows_curves_of_different_slopes() {
        let (a, b) = (curve(|t| 0.5 / t.sqrt()), curve(|t| 1.0 / t));
        let EqualError {
            rel_mse: lowest,
            ratio,
            range: [least, greatest],
        } = at_equal_error(&a, &b).unwrap();
        // a reaches b's lowest error, 1/1024, at t = (512)^2: beyond its curve, so the lowest common error is a's
        // own lowest, 0.5/32, which b reaches at t = 64 and a at 1024.
        assert!((lowest - 0.5 / 32.0).abs() < 1e-12, "{lowest}");
        assert!((ratio - 16.0).abs() < 1e-9, "{ratio}");
        assert!(
            (greatest - 16.0).abs() < 1e-9 && least < 1.0,
            "{least} {greatest}"
        );
    }

    /// Curves that share no error have no ratio; where the first lies wholly below the second, a bound: its first
    /// time over the second's time at its lowest error.
    #[test]
    fn disjoint_curves_have_no_equal_error() {
        let (low, high) = (curve(|t| 1.0 / t), curve(|t| 100.0 + 1.0 / t));
        assert!(at_equal_error(&low, &high).is_none());
        assert!(at_equal_error(&high, &low).is_none());
        assert_eq!(equal_error_bound(&low, &high), Some(1.0 / 1024.0));
        assert!(
            equal_error_bound(&high, &low).is_none(),
            "high is above low"
        );
        let (a, b) = (curve(|t| 1.0 / t), curve(|t| 4.0 / t));
        assert!(
            equal_error_bound(&a, &b).is_none(),
            "curves that share errors"
        );
    }
}

//! Error against time: each rendering setting's image error (relMSE, FLIP) against a cached high-spp raykin
//! reference of the same scene, as a function of the GPU time spent tracing.
//!
//! The reference is the scene at the bench's base settings (depth, RR, NEE), rendered as two independent
//! halves so that its own noise is known and subtracted. Curves that change only the estimator (samples per
//! frame, Russian roulette, NEE) converge to it; curves that change the image (a lower max depth) level off
//! at their bias, which is what a user trading depth for speed needs to see.

use super::metrics::{flip_mean, rel_mse, srgb8, tonemap};
use super::scenes::BenchScene;
use crate::stats::{log_log_fit, time_to_reach};
use anyhow::{Context, Result};
use raykin::gpu::GpuContext;
use raykin::oidn::Quality;
use raykin::render::integrator_choice::{Decision, SortDecision};
use raykin::render::{DenoiserKind, RenderSettings};
use sha2::Digest;
use std::path::Path;

/// One curve of the error-vs-time charts: a name and how it changes the bench's base settings.
/// Adding a curve is adding one line here.
pub struct Curve {
    pub name: &'static str,
    pub apply: fn(&mut RenderSettings),
}

const fn curve(name: &'static str, apply: fn(&mut RenderSettings)) -> Curve {
    Curve { name, apply }
}

/// The first curve is the default the table's time-to-error and convergence slope come from.
pub const CURVES: &[Curve] = &[
    curve("default (1 spp/frame, RR, NEE+MIS)", |_| {}),
    curve("4 spp/frame", |s| s.spp_per_frame = 4),
    curve("16 spp/frame", |s| s.spp_per_frame = 16),
    curve("max depth 2", |s| s.max_depth = s.max_depth.min(2)),
    curve("max depth 3", |s| s.max_depth = s.max_depth.min(3)),
    curve("Russian roulette off", |s| s.russian_roulette = false),
    curve("NEE/MIS off (BRDF sampling only)", |s| s.nee = false),
    // The light sampler the default does not use (power vs the spatial tree).
    curve("power light sampler", |s| {
        s.light_sampler = raykin::render::LightSampler::Power
    }),
    // The image at each point is denoised once; its time includes that pass (for OIDN: the copy of the
    // accumulation and AOVs to the host, OIDN's own copies, prefilters and filter).
    curve("svgf (a-trous)", |s| {
        s.denoise = true;
        s.denoiser = DenoiserKind::Svgf;
    }),
    curve("OIDN (high quality)", |s| {
        s.denoise = true;
        s.denoiser = DenoiserKind::Oidn;
        s.oidn.quality = Quality::High;
    }),
    curve("OIDN fast", |s| {
        s.denoise = true;
        s.denoiser = DenoiserKind::Oidn;
        s.oidn.quality = Quality::Fast;
    }),
];

/// Seeds of the reference halves; curves use seeds far from these.
const REFERENCE_SEEDS: [u32; 2] = [0x5EED_0001, 0x5EED_0002];

#[derive(Clone, Debug, serde::Serialize)]
pub struct CurvePoint {
    pub spp: u32,
    /// Cumulative trace time (median over repeats), ms.
    pub time_ms: f64,
    /// Cumulative wall time of the frames (median over repeats), ms: what the trace time leaves out (frame
    /// set-up, submission, the other passes, waiting for the GPU).
    pub wall_ms: f64,
    /// relMSE of the tone-mapped image against the tone-mapped reference (median over repeats, min, max).
    pub rel_mse: f64,
    pub rel_mse_min: f64,
    pub rel_mse_max: f64,
    /// relMSE on linear radiance (median over repeats).
    pub rel_mse_linear: f64,
    pub flip: f64,
    pub flip_min: f64,
    pub flip_max: f64,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct CurveResult {
    pub name: String,
    pub points: Vec<CurvePoint>,
    /// Trace ms until the tone-mapped relMSE (reference noise subtracted) first reaches 0.01, where the curve
    /// got there: how curves compare (importance sampling vs BSDF sampling only, light samplers).
    pub ms_to_rel_mse_0_01: Option<f64>,
    /// Trace ms of every frame, per repeat, in order: where the time of a curve went (runs of slow frames).
    pub frame_trace_ms: Vec<Vec<f64>>,
    /// The form of the path integrator that traced the curve's last frame (`auto` resolved by its trial in the
    /// warm-up frames); where repeats ended in different forms, each repeat's, in order, joined by `, `.
    pub integrator: String,
    /// Per repeat, auto's decision: each form's fastest trace ms a frame and the trials it took (`None`: no
    /// trial ran).
    pub auto_trials: Vec<Option<Decision>>,
    /// Per repeat, auto's decision on the waves' ray sort (`None`: no trial ran).
    pub sort_trials: Vec<Option<SortDecision>>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct SceneErrors {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub max_depth: u32,
    pub timing_source: &'static str,
    pub reference_spp: u32,
    pub reference_key: String,
    pub reference_from_cache: bool,
    /// relMSE of the reference itself (from its two halves), tone-mapped and linear: subtracted before fits
    /// and time-to-error.
    pub reference_noise_rel_mse: f64,
    pub reference_noise_rel_mse_linear: f64,
    pub repeats: usize,
    pub curves: Vec<CurveResult>,
    /// The reference image (mean of its halves), for comparisons with other renderers.
    #[serde(skip)]
    pub reference_mean: Vec<[f32; 3]>,
    /// Standard error of each channel's mean of the reference, from its halves.
    pub reference_mean_standard_error: [f64; 3],
    /// Default curve: least-squares slope of log relMSE against log spp (Monte Carlo: -1), and of log relative
    /// RMSE (= half of it; the TARGETS figure, -0.5 +- 0.05); tone-mapped, then linear radiance.
    pub slope_rel_mse_vs_spp: Option<f64>,
    pub slope_rel_rmse_vs_spp: Option<f64>,
    pub slope_rel_rmse_linear_vs_spp: Option<f64>,
    /// Default curve: trace ms to reach relMSE 0.01 and 0.001 (reference noise subtracted); measured when the
    /// curve got there, else extrapolated along the fitted power law (then `*_extrapolated` is true).
    pub ms_to_rel_mse_0_01: Option<f64>,
    pub ms_to_rel_mse_0_01_extrapolated: bool,
    pub ms_to_rel_mse_0_001: Option<f64>,
    pub ms_to_rel_mse_0_001_extrapolated: bool,
}

/// Measures the curves of [`CURVES`] on `scene` at `base` settings: the default and those whose name contains
/// one of `only` (every curve when `only` is empty).
pub fn measure(
    ctx: &GpuContext,
    scene: &BenchScene,
    base: &RenderSettings,
    suite: &super::suite::Suite,
    cache: &Path,
    only: &[String],
) -> Result<SceneErrors> {
    let r = reference(ctx, scene, base, suite, cache)?;
    let reference_display = tonemap(&r.mean);
    let reference_srgb8 = srgb8(&reference_display);
    let (w, h) = (base.width, base.height);
    let mut curves = Vec::new();
    let mut timing_source = "gpu-timestamps";
    let wanted = |index: usize, c: &Curve| {
        index == 0 || only.is_empty() || only.iter().any(|o| c.name.contains(o.as_str()))
    };
    for (index, c) in CURVES.iter().enumerate().filter(|(i, c)| wanted(*i, c)) {
        let mut settings = base.clone();
        (c.apply)(&mut settings);
        let spf = settings.spp_per_frame.max(1);
        let checkpoints = checkpoints(spf, suite.error_max_spp);
        // runs[r][k] = (time, relMSE, FLIP, linear relMSE, wall time) at checkpoint k of repeat r.
        let mut runs: Vec<Vec<[f64; 5]>> = Vec::new();
        let mut frame_trace_ms = Vec::new();
        let mut forms = Vec::new();
        let mut auto_trials = Vec::new();
        let mut sort_trials = Vec::new();
        let oidn = settings.denoise && settings.denoiser == DenoiserKind::Oidn;
        for repeat in 0..suite.error_repeats {
            settings.seed = 1000 + 100 * index as u32 + repeat as u32;
            let mut app = super::open_app(ctx, scene, settings.clone())?;
            if oidn && let Err(e) = app.open_oidn() {
                eprintln!(
                    "raykin bench: {}: curve `{}` left out: {e}",
                    scene.name, c.name
                );
                break;
            }
            // The first dispatch also compiles the kernel on some drivers (lavapipe): trace untimed frames and
            // start the curve from a cleared accumulation. A GPU also needs its clocks back: after the previous
            // repeat's error computation (seconds of idle) the H200 runs its first ~0.3 s of work at 345 of
            // 1980 MHz, which made the first 100 frames of a curve 5x slower (docs/BENCHMARKS.md); Mitsuba's
            // renders are timed after a warm-up render too.
            super::warm_up(&mut app, 1);
            app.restart_accumulation();
            // The images are only read back during the run; their errors (tone mapping, FLIP: seconds on the CPU
            // at 960x540) are computed after it, so that the GPU never idles long between checkpoints: an idle
            // GPU drops its clocks, and the frames after a pause then ran 3-4x slower on the H200.
            let (mut elapsed_ms, mut wall_ms) = (0.0, 0.0);
            let mut images = Vec::new();
            let mut denoise_times = Vec::new();
            let mut frame_times = Vec::new();
            for &target in &checkpoints {
                while app.samples() < target {
                    let start = std::time::Instant::now();
                    app.step();
                    app.ctx.wait_idle();
                    let frame_wall = start.elapsed().as_secs_f64() * 1e3;
                    wall_ms += frame_wall;
                    let trace_ms = match app.pass_times() {
                        Some(p) => p.trace_ms,
                        None => {
                            timing_source = "cpu-wall";
                            frame_wall
                        }
                    };
                    elapsed_ms += trace_ms;
                    frame_times.push(trace_ms);
                }
                let (image, denoise_ms) = if oidn {
                    let o = app.oidn_denoised()?;
                    (o.color.to_vec(), o.steady_ms())
                } else if settings.denoise {
                    let start = std::time::Instant::now();
                    let image = app.denoised_radiance();
                    let wall = start.elapsed().as_secs_f64() * 1e3;
                    let gpu = app.frame_stats().read_denoise_ms(&app.ctx);
                    (image, gpu.unwrap_or(wall))
                } else {
                    (app.radiance(), 0.0)
                };
                denoise_times.push(denoise_ms);
                images.push((elapsed_ms, wall_ms, image));
            }
            if let Some(form) = app.integrator_choice().last_form_name() {
                forms.push(form);
            }
            auto_trials.push(app.integrator_choice().decision());
            sort_trials.push(app.integrator_choice().sort_decision());
            drop(app);
            frame_trace_ms.push(frame_times);
            let mut run: Vec<[f64; 5]> = images
                .into_iter()
                .map(|(elapsed_ms, wall_ms, image)| {
                    let display = tonemap(&image);
                    let err = rel_mse(&display, &reference_display);
                    let flip = flip_mean(&reference_srgb8, &srgb8(&display), w, h);
                    [elapsed_ms, err, flip, rel_mse(&image, &r.mean), wall_ms]
                })
                .collect();
            // A denoise costs the same at any spp: its median time is added to every point (one pass's
            // jitter would otherwise outweigh the trace time between the first checkpoints).
            let denoise_ms = median(&denoise_times);
            run.iter_mut().for_each(|p| {
                p[0] += denoise_ms;
                p[4] += denoise_ms;
            });
            runs.push(run);
        }
        if runs.is_empty() {
            continue;
        }
        let points: Vec<CurvePoint> = checkpoints
            .iter()
            .enumerate()
            .map(|(k, &spp)| {
                let at = |i: usize| -> Vec<f64> { runs.iter().map(|r| r[k][i]).collect() };
                let (t, e, fl) = (at(0), at(1), at(2));
                let (e_min, e_max) = min_max(&e);
                let (f_min, f_max) = min_max(&fl);
                CurvePoint {
                    spp,
                    time_ms: median(&t),
                    wall_ms: median(&at(4)),
                    rel_mse: median(&e),
                    rel_mse_min: e_min,
                    rel_mse_max: e_max,
                    rel_mse_linear: median(&at(3)),
                    flip: median(&fl),
                    flip_min: f_min,
                    flip_max: f_max,
                }
            })
            .collect();
        let reached = excess_curve(&points, r.noise);
        curves.push(CurveResult {
            // The default curve runs at the bench's samples per frame (`--spp-per-frame`).
            name: if index == 0 {
                format!("default ({spf} spp/frame, RR, NEE+MIS)")
            } else {
                c.name.to_string()
            },
            ms_to_rel_mse_0_01: time_to_reach(&reached, 0.01),
            points,
            frame_trace_ms,
            integrator: forms_of_repeats(&forms),
            auto_trials,
            sort_trials,
        });
        let curve = curves.last().expect("pushed");
        let trials: Vec<String> = curve
            .auto_trials
            .iter()
            .flatten()
            .map(|t| {
                format!(
                    "megakernel {:.3} ms, wavefront {:.3} ms after {} trials",
                    t.megakernel_ms, t.wavefront_ms, t.trials
                )
            })
            .chain(curve.sort_trials.iter().flatten().map(|t| {
                format!(
                    "waves unsorted {:.3} ms, sorted {:.3} ms after {} trials",
                    t.unsorted_ms, t.sorted_ms, t.trials
                )
            }))
            .collect();
        eprintln!(
            "raykin bench: {}: curve `{}` traced by the {} integrator{}",
            scene.name,
            curve.name,
            curve.integrator,
            if trials.is_empty() {
                String::new()
            } else {
                format!(" (auto's trials: {})", trials.join("; "))
            }
        );
    }
    // Fits on the default curve, reference noise subtracted; the first two points (1-2 spp) are left out of
    // the slopes: there the estimator is dominated by which pixels found the light at all.
    let fit_slope = |value: fn(&CurvePoint) -> f64, noise: f64| {
        let points: Vec<(f64, f64)> = curves[0]
            .points
            .iter()
            .filter(|p| p.spp >= 4)
            .map(|p| (p.spp as f64, (value(p) - noise).max(1e-12)))
            .collect();
        log_log_fit(&points).map(|f| f.0)
    };
    let slope = fit_slope(|p| p.rel_mse, r.noise);
    let slope_linear = fit_slope(|p| p.rel_mse_linear, r.noise_linear);
    let time_curve = excess_curve(&curves[0].points, r.noise);
    let (t2, t2x) = time_to_rel_mse(&time_curve, 0.01);
    let (t3, t3x) = time_to_rel_mse(&time_curve, 0.001);
    Ok(SceneErrors {
        scene: scene.name.clone(),
        width: w,
        height: h,
        max_depth: base.max_depth,
        timing_source,
        reference_spp: suite.reference_spp,
        reference_key: r.key,
        reference_from_cache: r.from_cache,
        reference_noise_rel_mse: r.noise,
        reference_noise_rel_mse_linear: r.noise_linear,
        repeats: suite.error_repeats,
        curves,
        reference_mean: r.mean,
        reference_mean_standard_error: r.mean_standard_error,
        slope_rel_mse_vs_spp: slope,
        slope_rel_rmse_vs_spp: slope.map(|s| s * 0.5),
        slope_rel_rmse_linear_vs_spp: slope_linear.map(|s| s * 0.5),
        ms_to_rel_mse_0_01: t2,
        ms_to_rel_mse_0_01_extrapolated: t2x,
        ms_to_rel_mse_0_001: t3,
        ms_to_rel_mse_0_001_extrapolated: t3x,
    })
}

/// The sample counts a curve is measured at: powers of two from `spp_per_frame` to `max_spp`.
pub fn checkpoints(spp_per_frame: u32, max_spp: u32) -> Vec<u32> {
    (0..20)
        .map(|k| 1u32 << k)
        .filter(|&s| s >= spp_per_frame && s <= max_spp.max(spp_per_frame))
        .collect()
}

/// A point's relMSE above a reference's own `noise` (kept positive for log-log fits and interpolation).
pub fn excess(p: &CurvePoint, noise: f64) -> f64 {
    (p.rel_mse - noise).max(1e-12)
}

/// A curve's (trace time, relMSE above `noise`) points.
pub fn excess_curve(curve: &[CurvePoint], noise: f64) -> Vec<(f64, f64)> {
    curve
        .iter()
        .map(|p| (p.time_ms, excess(p, noise)))
        .collect()
}

/// Time until `curve` ((time, relMSE with the reference noise subtracted), in time order) reaches `target`:
/// measured where it got there, else extrapolated along the power law fitted to its second half (then the
/// flag is true).
pub fn time_to_rel_mse(curve: &[(f64, f64)], target: f64) -> (Option<f64>, bool) {
    if let Some(t) = time_to_reach(curve, target) {
        return (Some(t), false);
    }
    match log_log_fit(&curve[curve.len() / 2..]) {
        Some((b, a)) if b < 0.0 => (Some(((target.ln() - a) / b).exp()), true),
        _ => (None, false),
    }
}

fn median(v: &[f64]) -> f64 {
    crate::stats::Spread::of(v).median
}

fn min_max(v: &[f64]) -> (f64, f64) {
    v.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
            (lo.min(x), hi.max(x))
        })
}

/// The reference's cache key: a hash of everything that defines its pixels (scene file bytes, camera,
/// image-affecting settings, size, sample count, seeds, and `extra`: what else a caller varies, such as the
/// pose) and of the kernel source, so that a changed renderer never reuses an old reference.
pub(super) fn reference_key(
    scene: &BenchScene,
    base: &RenderSettings,
    spp: u32,
    extra: &str,
) -> Result<String> {
    let mut hasher = sha2::Sha256::new();
    for file in &scene.source_files {
        let bytes =
            std::fs::read(file).with_context(|| format!("{}: cannot read", file.display()))?;
        hasher.update((bytes.len() as u64).to_le_bytes());
        hasher.update(&bytes);
    }
    let image_settings = RenderSettings {
        spp_per_frame: 1,
        seed: 0,
        mode: raykin::render::RenderMode::Accumulate,
        realtime: Default::default(),
        ..base.clone()
    };
    hasher.update(format!("{:?}", scene.camera).as_bytes());
    hasher.update(serde_json::to_vec(&image_settings)?);
    hasher.update(format!("{spp} {REFERENCE_SEEDS:?} {extra}").as_bytes());
    hasher.update(
        raykin::render::shaders::compose(&raykin::render::passes::trace::KERNEL).as_bytes(),
    );
    let digest = hasher.finalize();
    Ok(raykin::record::output::hex(&digest[..12]))
}

/// A reference image (mean of two halves) and what is known about it.
pub(super) struct Reference {
    pub mean: Vec<[f32; 3]>,
    /// relMSE of the mean against the truth, estimated from the halves: tone-mapped and linear.
    pub noise: f64,
    pub noise_linear: f64,
    /// Standard error of each channel's image mean (`metrics::mean_standard_error` of the halves).
    pub mean_standard_error: [f64; 3],
    pub key: String,
    pub from_cache: bool,
}

/// The reference for `scene` at `base`: from the cache, or rendered and cached.
pub(super) fn reference(
    ctx: &GpuContext,
    scene: &BenchScene,
    base: &RenderSettings,
    suite: &super::suite::Suite,
    cache: &Path,
) -> Result<Reference> {
    let key = reference_key(scene, base, suite.reference_spp, "")?;
    let dir = cache.join(format!("{}-{key}", scene.name));
    cached_reference(&dir, key, (base.width, base.height), &scene.name, |seed| {
        let settings = RenderSettings {
            seed,
            ..base.clone()
        };
        let mut app = super::open_app(ctx, scene, settings)?;
        accumulate_reference(ctx, &mut app, suite.reference_spp / 2);
        Ok(app.radiance())
    })
}

/// Accumulates `spp` samples in chunks sized for the adapter.
pub(super) fn accumulate_reference(
    ctx: &GpuContext,
    app: &mut raykin::headless::HeadlessApp,
    spp: u32,
) {
    let chunk = if ctx.info.device_type == raykin::gpu::DeviceType::Cpu {
        8
    } else {
        64
    };
    app.accumulate(spp, chunk, |_| {});
}

/// Two independent halves of a reference in `dir` (`half_a.exr`, `half_b.exr`): read when they are there at
/// `size`, else each rendered by `render(seed)` and written.
pub(super) fn cached_reference(
    dir: &Path,
    key: String,
    (w, h): (u32, u32),
    what: &str,
    render: impl Fn(u32) -> Result<Vec<[f32; 3]>>,
) -> Result<Reference> {
    let halves = [dir.join("half_a.exr"), dir.join("half_b.exr")];
    let cached = halves
        .iter()
        .map(|p| raykin::image_io::read_exr(p).ok())
        .collect::<Option<Vec<_>>>()
        .filter(|v| v.iter().all(|(iw, ih, _)| (*iw, *ih) == (w, h)));
    let (a, b, from_cache) = match cached {
        Some(mut v) => {
            let b = v.pop().map(|x| x.2).unwrap_or_default();
            let a = v.pop().map(|x| x.2).unwrap_or_default();
            (a, b, true)
        }
        None => {
            eprintln!(
                "raykin bench: {what}: rendering a reference at {w}x{h} (cached as {})",
                dir.display()
            );
            std::fs::create_dir_all(dir)
                .with_context(|| format!("{}: cannot create the cache folder", dir.display()))?;
            let mut images = Vec::new();
            for (seed, path) in REFERENCE_SEEDS.iter().zip(&halves) {
                let image = render(*seed)?;
                if image.iter().flatten().any(|v| !v.is_finite()) {
                    anyhow::bail!("{what}: the reference has non-finite pixels");
                }
                raykin::image_io::write_atomically(path, |p| {
                    raykin::image_io::write_exr(p, w, h, &image)
                })?;
                images.push(image);
            }
            let b = images.pop().unwrap_or_default();
            let a = images.pop().unwrap_or_default();
            (a, b, false)
        }
    };
    // Var of the mean of two halves = E[(a - b)^2] / 4 in relMSE units.
    let mean = a
        .iter()
        .zip(&b)
        .map(|(x, y)| [0, 1, 2].map(|c| 0.5 * (x[c] + y[c])))
        .collect();
    Ok(Reference {
        mean,
        noise: rel_mse(&tonemap(&a), &tonemap(&b)) / 4.0,
        noise_linear: rel_mse(&a, &b) / 4.0,
        mean_standard_error: super::metrics::mean_standard_error(&a, &b),
        key,
        from_cache,
    })
}

/// The integrator forms of a curve's repeats as the curve records them: one name where all agree (or `none`),
/// else every repeat's in order, so that a curve whose repeats chose differently does not read as one form.
fn forms_of_repeats<S: std::borrow::Borrow<str>>(forms: &[S]) -> String {
    match forms {
        [] => "none".to_string(),
        [first, rest @ ..] if rest.iter().all(|f| f.borrow() == first.borrow()) => {
            first.borrow().to_string()
        }
        _ => forms.join(", "),
    }
}

#[cfg(test)]
mod tests {
    use super::forms_of_repeats;

    #[test]
    fn repeats_that_chose_differently_are_all_named() {
        assert_eq!(forms_of_repeats::<&str>(&[]), "none");
        assert_eq!(forms_of_repeats(&["wavefront", "wavefront"]), "wavefront");
        assert_eq!(
            forms_of_repeats(&["megakernel", "wavefront"]),
            "megakernel, wavefront"
        );
    }
}

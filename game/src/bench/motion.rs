//! The real-time path in motion (`--parts motion`): K frames of an animated scene at a fixed time step, the
//! displayed frame compared at a fixed set of frames with a converged image of the same pose (raykin at high
//! spp, cached like the error references), per method:
//! - restart + spatial: each frame starts afresh (one path per pixel) and the a-trous filter cleans it: what
//!   accumulate mode plus the denoiser shows in motion;
//! - + reprojection: temporal accumulation through the motion vectors (SVGF);
//! - + gradients: A-SVGF temporal gradients shorten the history where lighting changed;
//! - + ReSTIR DI: direct light by ReSTIR (candidates, temporal, spatial and visibility reuse);
//! - OIDN per frame (fast, balanced, high): the gradients method with Open Image Denoise over the history in
//!   place of the a-trous filter (through host copies where OIDN cannot read the GPU's memory; skipped, with a
//!   note, where OIDN cannot run at all).
//!
//! Per frame: relMSE and FLIP of the tone-mapped image, GPU time (every pass of the frame) and wall time;
//! the error of pixels disoccluded within the last [`BAND_FRAMES`] frames against the rest; and, where the
//! scene has a light to switch on (the interior's wall lamp), the error on every frame after it is switched
//! on at frame k0, and how many frames each method takes to settle.

use super::error_curves::{Reference, accumulate_reference, cached_reference, reference_key};
use super::metrics::{flip_mean, rel_mse, srgb8, tonemap};
use super::scenes::BenchScene;
use crate::stats::Spread;
use anyhow::Result;
use raykin::gpu::GpuContext;
use raykin::headless::HeadlessApp;
use raykin::oidn::Quality;
use raykin::render::{DenoiserKind, FrameOidn, RealtimeSettings, RenderMode, RenderSettings};
use std::path::Path;

/// One curve: a method of making frames in motion, as a change of the real-time settings.
pub struct Method {
    pub name: &'static str,
    pub apply: fn(&mut RealtimeSettings),
}

/// In order of what each adds; the bench reports every one.
pub const METHODS: &[Method] = &[
    Method {
        name: "restart + spatial",
        apply: |r| {
            r.temporal = false;
            r.gradients = false;
            r.restir.enabled = false;
            r.oidn = FrameOidn::Off;
        },
    },
    Method {
        name: "+ reprojection",
        apply: |r| {
            r.gradients = false;
            r.restir.enabled = false;
            r.oidn = FrameOidn::Off;
        },
    },
    Method {
        name: "+ gradients",
        apply: |r| {
            r.restir.enabled = false;
            r.oidn = FrameOidn::Off;
        },
    },
    Method {
        name: "+ ReSTIR DI",
        apply: |r| {
            r.restir.enabled = true;
            r.oidn = FrameOidn::Off;
        },
    },
    Method {
        name: "gradients + OIDN fast",
        apply: |r| oidn_per_frame(r, Quality::Fast),
    },
    Method {
        name: "gradients + OIDN balanced",
        apply: |r| oidn_per_frame(r, Quality::Balanced),
    },
    Method {
        name: "gradients + OIDN high",
        apply: |r| oidn_per_frame(r, Quality::High),
    },
];

/// The gradients method with OIDN over the history each frame.
fn oidn_per_frame(r: &mut RealtimeSettings, quality: Quality) {
    r.restir.enabled = false;
    r.oidn = FrameOidn::Always;
    r.oidn_quality = quality;
}

/// Index of the method whose history lengths define the disocclusion band (temporal, no gradients: a short
/// history there means the surface was not visible a few frames ago).
const BAND_METHOD: usize = 1;
/// Pixels whose history is at most this long were disoccluded within the last this many frames.
pub const BAND_FRAMES: f32 = 8.0;
/// Seconds per frame.
pub const DT: f32 = 1.0 / 60.0;

#[derive(Clone, Debug, serde::Serialize)]
pub struct MotionPoint {
    pub frame: usize,
    /// Tone-mapped relMSE and mean FLIP of the displayed frame against the converged pose.
    pub rel_mse: f64,
    pub flip: f64,
    /// relMSE of the pixels disoccluded within the last BAND_FRAMES frames, and of the rest (None where a
    /// part is empty).
    pub rel_mse_band: Option<f64>,
    pub rel_mse_rest: Option<f64>,
    pub band_fraction: f64,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct LagResult {
    /// The frame at which the lamp is switched on.
    pub switch_frame: usize,
    /// relMSE on every frame from the switch on.
    pub rel_mse: Vec<(usize, f64)>,
    /// The method's error once settled (median over the second half of the window).
    pub settled_rel_mse: f64,
    /// Frames after the switch until the error is within 1.5x the settled error (None: not within the
    /// window).
    pub frames_to_settle: Option<usize>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct MotionCurve {
    pub method: String,
    pub points: Vec<MotionPoint>,
    /// Every pass of each frame summed (GPU timestamps; OIDN per frame not included), and wall time of frames
    /// without a readback.
    pub gpu_ms: Spread,
    pub wall_ms: Spread,
    /// OIDN per frame: its wall time per frame and the device that ran it (None for the a-trous methods).
    pub oidn_ms: Option<Spread>,
    pub oidn_device: Option<String>,
    /// Median per pass.
    pub passes_median_ms: PassMedians,
    /// Mean tone-mapped relMSE over the evaluated frames from K/4 on (before any switch): the displayed
    /// frame's error once warmed up.
    pub steady_rel_mse: f64,
    pub steady_flip: f64,
    /// Mean over those frames of band relMSE / rest relMSE.
    pub band_to_rest: Option<f64>,
    pub lag: Option<LagResult>,
}

#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct PassMedians {
    pub deform: f64,
    pub gbuffer: f64,
    pub restir: f64,
    pub gradients: f64,
    pub trace: f64,
    pub temporal: f64,
    pub spatial: f64,
    pub tonemap: f64,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct MotionScene {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub frames: usize,
    pub dt: f32,
    pub eval_frames: Vec<usize>,
    pub reference_spp: u32,
    /// Tone-mapped relMSE of each reference itself (from its halves), by evaluated frame.
    pub reference_noise: Vec<f64>,
    pub curves: Vec<MotionCurve>,
}

/// How the suite sizes this part.
pub struct MotionPlan {
    pub size: (u32, u32),
    pub frames: usize,
    pub eval_every: usize,
    pub reference_spp: u32,
    /// Frames after a light switch that are all evaluated.
    pub lag_window: usize,
}

/// The frames compared with a reference: every `eval_every`-th, and every frame of the lag window.
fn eval_frames(plan: &MotionPlan, switch: Option<usize>) -> Vec<usize> {
    let mut frames: Vec<usize> = (plan.eval_every - 1..plan.frames)
        .step_by(plan.eval_every.max(1))
        .collect();
    if let Some(k0) = switch {
        frames.extend(k0..(k0 + plan.lag_window).min(plan.frames));
    }
    frames.sort_unstable();
    frames.dedup();
    frames
}

/// Measures every method of [`METHODS`] on `scene`.
pub fn measure(
    ctx: &GpuContext,
    scene: &BenchScene,
    base: &RenderSettings,
    plan: &MotionPlan,
    cache: &Path,
) -> Result<MotionScene> {
    let (w, h) = plan.size;
    let base = RenderSettings {
        width: w,
        height: h,
        environment: scene.environment.clone(),
        ..base.clone()
    };
    let switch = scene.switchable_light.map(|_| plan.frames / 2);
    let frames = eval_frames(plan, switch);
    let mut references = Vec::new();
    for &k in &frames {
        references.push(reference(ctx, scene, &base, plan, k, switch, cache)?);
    }
    // The band method runs first: its history lengths mark the disoccluded pixels for every method.
    let mut order: Vec<usize> = (0..METHODS.len()).collect();
    order.swap(0, BAND_METHOD);
    let mut bands: Vec<Vec<bool>> = Vec::new();
    let mut curves: Vec<Option<MotionCurve>> = vec![None; METHODS.len()];
    for &m in &order {
        let method = &METHODS[m];
        eprintln!(
            "raykin bench: {}: motion, {} ({} frames at {w}x{h})",
            scene.name, method.name, plan.frames
        );
        let mut settings = RenderSettings {
            mode: RenderMode::Realtime,
            ..base.clone()
        };
        settings.realtime.handover = false;
        (method.apply)(&mut settings.realtime);
        let oidn = settings.realtime.oidn != FrameOidn::Off;
        if oidn {
            settings.denoiser = DenoiserKind::Oidn;
        }
        let mut app = super::open_app(ctx, scene, settings)?;
        let run = match run_method(&mut app, scene, plan, &frames, switch, oidn)? {
            Ok(run) => run,
            Err(why) => {
                eprintln!(
                    "raykin bench: {}: {} skipped: {why}",
                    scene.name, method.name
                );
                continue;
            }
        };
        if m == BAND_METHOD {
            bands = run
                .lengths
                .iter()
                .map(|l| l.iter().map(|&n| n <= BAND_FRAMES).collect())
                .collect();
        }
        curves[m] = Some(score(
            method,
            run,
            &frames,
            &references,
            &bands,
            plan,
            switch,
        ));
    }
    Ok(MotionScene {
        scene: scene.name.clone(),
        width: w,
        height: h,
        frames: plan.frames,
        dt: DT,
        eval_frames: frames,
        reference_spp: plan.reference_spp,
        reference_noise: references.iter().map(|r| r.noise).collect(),
        curves: curves.into_iter().flatten().collect(),
    })
}

/// What one method's run produced: the displayed image and history lengths at each evaluated frame, and
/// per-frame times.
struct Run {
    images: Vec<Vec<[f32; 3]>>,
    lengths: Vec<Vec<f32>>,
    gpu_ms: Vec<f64>,
    wall_ms: Vec<f64>,
    passes: Vec<raykin::render::PassTimes>,
    oidn_ms: Vec<f64>,
    oidn_device: Option<String>,
}

/// One method's frames; the inner error says why OIDN per frame (`oidn`) did not run.
fn run_method(
    app: &mut HeadlessApp,
    scene: &BenchScene,
    plan: &MotionPlan,
    frames: &[usize],
    switch: Option<usize>,
    oidn: bool,
) -> Result<std::result::Result<Run, String>> {
    let mut run = Run {
        images: Vec::new(),
        lengths: Vec::new(),
        gpu_ms: Vec::new(),
        wall_ms: Vec::new(),
        passes: Vec::new(),
        oidn_ms: Vec::new(),
        oidn_device: None,
    };
    for k in 0..plan.frames {
        if Some(k) == switch {
            switch_on(app, scene);
        }
        let start = std::time::Instant::now();
        app.step();
        let wall = start.elapsed().as_secs_f64() * 1e3;
        if oidn {
            match app.take_frame_denoise_report() {
                Ok(Some(report)) => {
                    run.oidn_ms.push(report.ms);
                    run.oidn_device = Some(report.device);
                }
                Ok(None) => return Ok(Err("OIDN per frame did not run".into())),
                Err(why) => return Ok(Err(why)),
            }
        }
        if let Some(p) = app.pass_times() {
            run.gpu_ms.push(
                p.skin_ms
                    + p.refit_ms
                    + p.gbuffer_ms
                    + p.restir_ms
                    + p.gradient_ms
                    + p.trace_ms
                    + p.temporal_ms
                    + p.denoise_ms
                    + p.tonemap_ms,
            );
            run.passes.push(p);
        }
        if frames.contains(&k) {
            let image = app.displayed_radiance();
            anyhow::ensure!(
                image.iter().flatten().all(|v| v.is_finite()),
                "{}: frame {k} has non-finite pixels",
                scene.name
            );
            run.images.push(image);
            run.lengths
                .push(app.realtime_history().iter().map(|(_, n)| *n).collect());
        } else {
            run.wall_ms.push(wall);
        }
    }
    Ok(Ok(run))
}

/// Switches the scene's lamp on (a material edit, as the editor makes it).
fn switch_on(app: &mut HeadlessApp, scene: &BenchScene) {
    if let Some((material, radiance)) = scene.switchable_light {
        let world = app.app.world_mut();
        let mut materials = world.resource_mut::<raykin::scene::Materials>();
        if let Some(m) = materials.0.get_mut(material) {
            m.emissive = radiance;
            m.emissive_strength = 1.0;
        }
    }
}

fn score(
    method: &Method,
    run: Run,
    frames: &[usize],
    references: &[Reference],
    bands: &[Vec<bool>],
    plan: &MotionPlan,
    switch: Option<usize>,
) -> MotionCurve {
    let (w, h) = plan.size;
    let mut points = Vec::new();
    for (i, (&k, image)) in frames.iter().zip(&run.images).enumerate() {
        let reference = &references[i].mean;
        let (shown, truth) = (tonemap(image), tonemap(reference));
        let band = bands.get(i);
        let part = |inside: bool| -> Option<f64> {
            let band = band?;
            let (a, b): (Vec<[f32; 3]>, Vec<[f32; 3]>) = shown
                .iter()
                .zip(&truth)
                .zip(band)
                .filter(|(_, in_band)| **in_band == inside)
                .map(|((a, b), _)| (*a, *b))
                .unzip();
            (!a.is_empty()).then(|| rel_mse(&a, &b))
        };
        points.push(MotionPoint {
            frame: k,
            rel_mse: rel_mse(&shown, &truth),
            flip: flip_mean(&srgb8(&truth), &srgb8(&shown), w, h),
            rel_mse_band: part(true),
            rel_mse_rest: part(false),
            band_fraction: band.map_or(0.0, |b| {
                b.iter().filter(|x| **x).count() as f64 / b.len().max(1) as f64
            }),
        });
    }
    let warm = plan.frames / 4;
    let end = switch.unwrap_or(plan.frames);
    let steady: Vec<&MotionPoint> = points
        .iter()
        .filter(|p| p.frame >= warm && p.frame < end)
        .collect();
    let mean = |f: &dyn Fn(&MotionPoint) -> Option<f64>| -> Option<f64> {
        let v: Vec<f64> = steady.iter().filter_map(|p| f(p)).collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    let lag = switch.map(|k0| {
        let after: Vec<(usize, f64)> = points
            .iter()
            .filter(|p| p.frame >= k0 && p.frame < k0 + plan.lag_window)
            .map(|p| (p.frame, p.rel_mse))
            .collect();
        let second_half: Vec<f64> = after
            .iter()
            .filter(|(k, _)| *k >= k0 + plan.lag_window / 2)
            .map(|(_, e)| *e)
            .collect();
        let settled = Spread::of(&second_half).median;
        LagResult {
            switch_frame: k0,
            frames_to_settle: after
                .iter()
                .find(|(_, e)| *e <= 1.5 * settled)
                .map(|(k, _)| k - k0),
            settled_rel_mse: settled,
            rel_mse: after,
        }
    });
    let pass = |f: fn(&raykin::render::PassTimes) -> f64| {
        Spread::of(&run.passes.iter().map(f).collect::<Vec<_>>()).median
    };
    MotionCurve {
        method: method.name.to_string(),
        gpu_ms: Spread::of(&run.gpu_ms),
        wall_ms: Spread::of(&run.wall_ms),
        oidn_ms: (!run.oidn_ms.is_empty()).then(|| Spread::of(&run.oidn_ms)),
        oidn_device: run.oidn_device.clone(),
        passes_median_ms: PassMedians {
            deform: pass(|p| p.skin_ms + p.refit_ms),
            gbuffer: pass(|p| p.gbuffer_ms),
            restir: pass(|p| p.restir_ms),
            gradients: pass(|p| p.gradient_ms),
            trace: pass(|p| p.trace_ms),
            temporal: pass(|p| p.temporal_ms),
            spatial: pass(|p| p.denoise_ms),
            tonemap: pass(|p| p.tonemap_ms),
        },
        steady_rel_mse: mean(&|p| Some(p.rel_mse)).unwrap_or(f64::NAN),
        steady_flip: mean(&|p| Some(p.flip)).unwrap_or(f64::NAN),
        band_to_rest: mean(&|p| match (p.rel_mse_band, p.rel_mse_rest) {
            (Some(b), Some(r)) if r > 0.0 => Some(b / r),
            _ => None,
        }),
        lag,
        points,
    }
}

/// The converged image of frame `k`'s pose: the players where they are after `k` frames of `DT`, held; the
/// lamp on from the switch frame. Cached by pose.
fn reference(
    ctx: &GpuContext,
    scene: &BenchScene,
    base: &RenderSettings,
    plan: &MotionPlan,
    k: usize,
    switch: Option<usize>,
    cache: &Path,
) -> Result<Reference> {
    let lamp_on = switch.is_some_and(|k0| k >= k0);
    let extra = format!("motion frame {k} dt {DT} lamp {lamp_on}");
    let key = reference_key(scene, base, plan.reference_spp, &extra)?;
    let dir = cache.join(format!("motion-{}-{key}", scene.name));
    let what = format!("{} frame {k}", scene.name);
    cached_reference(&dir, key, plan.size, &what, |seed| {
        let settings = RenderSettings {
            seed,
            mode: RenderMode::Accumulate,
            ..base.clone()
        };
        let mut app = super::open_app(ctx, scene, settings)?;
        hold_pose(&mut app, k);
        if lamp_on {
            switch_on(&mut app, scene);
        }
        accumulate_reference(ctx, &mut app, plan.reference_spp / 2);
        Ok(app.radiance())
    })
}

/// Holds every player where it is after `k` frames of [`DT`] (the same arithmetic as playing: time advanced
/// by DT and wrapped, k times).
fn hold_pose(app: &mut HeadlessApp, k: usize) {
    let world = app.app.world_mut();
    let scene = world.resource::<raykin::scene::SceneAssets>().0.clone();
    let mut players = world.query::<&mut raykin::animation::AnimationPlayer>();
    for mut p in players.iter_mut(world) {
        let duration = scene.animations.get(p.clip).map_or(0.0, |c| c.duration);
        for _ in 0..k {
            p.time += DT * p.speed;
            if duration > 0.0 {
                p.time = p.time.rem_euclid(duration);
            }
        }
        p.playing = false;
    }
}

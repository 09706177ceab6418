//! `raykin bench`: speed against accuracy, measured and charted by raykin itself.
//!
//! One command runs the suite's parts on fixed, named scenes and writes `DIR/results.json` (+ CSVs, a
//! markdown summary) and PNG charts in `DIR/charts/`:
//! - frame loop ([`frame_loop`]): ms per frame, per-pass breakdown, rays/s, memory, per scene and size;
//! - error vs time ([`error_curves`]): relMSE and FLIP against a cached high-spp reference, per setting;
//! - BVH quality ([`bvh_quality`]): obvhs presets, and refit vs rebuild along an animation;
//! - scaling ([`scaling`]): trace time vs instanced triangle count and vs resolution;
//! - Open Image Denoise ([`oidn`]): its cost per frame size, quality and device, and its error gains.

mod bvh_quality;
mod charts;
mod error_curves;
mod frame_loop;
mod metrics;
mod mitsuba;
pub mod motion;
mod oidn;
mod scaling;
mod scenes;
mod suite;

use crate::adapter::open_gpu;
use crate::cli::BenchArgs;
use crate::provenance;
use anyhow::{Context, Result};
use raykin::gpu::GpuContext;
use raykin::headless::HeadlessApp;
use raykin::render::RenderSettings;
use scenes::BenchScene;
use std::path::Path;

/// The parts `--parts` can pick (all by default).
pub const PARTS: &[&str] = &[
    "frames", "errors", "bvh", "refit", "scaling", "motion", "oidn",
];

/// The per-scene table of docs/BENCHMARKS.md.
#[derive(serde::Serialize)]
struct TableRow {
    scene: String,
    triangles: usize,
    sizes: Vec<(u32, u32)>,
    /// Per size: median wall ms of a whole frame, median GPU trace ms, rays/s.
    ms_per_frame: Vec<f64>,
    trace_ms: Vec<f64>,
    primary_rays_per_s: Vec<f64>,
    /// Shading-free ray casting: camera rays/s and diffuse bounce rays/s per size.
    raycast_camera_rays_per_s: Vec<f64>,
    raycast_diffuse_rays_per_s: Vec<f64>,
    all_rays_per_s: Vec<f64>,
    error_size: Option<(u32, u32)>,
    ms_to_rel_mse_0_01: Option<f64>,
    ms_to_rel_mse_0_01_extrapolated: bool,
    ms_to_rel_mse_0_001: Option<f64>,
    ms_to_rel_mse_0_001_extrapolated: bool,
    slope_rel_rmse_vs_spp: Option<f64>,
    slope_rel_rmse_linear_vs_spp: Option<f64>,
}

#[derive(serde::Serialize)]
struct Results {
    adapter: String,
    backend: String,
    device_type: String,
    driver: String,
    commit: String,
    date_unix_s: u64,
    date: String,
    command: String,
    suite: suite::Suite,
    max_depth: u32,
    integrator: raykin::render::Integrator,
    rows: Vec<frame_loop::FrameRow>,
    table: Vec<TableRow>,
    error_vs_time: Vec<error_curves::SceneErrors>,
    mitsuba_side_by_side: Vec<mitsuba::SideBySide>,
    bvh_presets: Vec<bvh_quality::PresetRow>,
    refit_vs_rebuild: Option<bvh_quality::RefitResult>,
    scaling_triangles: Vec<scaling::TriangleScalingRow>,
    scaling_resolution: Vec<scaling::ResolutionScalingRow>,
    motion: Vec<motion::MotionScene>,
    oidn_timings: Vec<oidn::TimingRow>,
    oidn_gains: Vec<oidn::GainRow>,
    charts: Vec<String>,
    wall_seconds: f64,
    /// /proc/loadavg at the start and the end (Linux): on a CPU adapter other processes slow every figure.
    load_average_start: Option<String>,
    load_average_end: Option<String>,
}

/// Untimed frames before anything is timed: at least `frames`, and on a GPU 0.6 s of them, long enough for its
/// clocks to come back from idle (the H200 drops to 345 of 1980 MHz after about 1.5 s without work and needs
/// ~0.3 s of work to climb back); a CPU adapter has no such state. Under `--integrator auto` also until its
/// trials have decided (the forms', then where the waves won the ray sort's; at most 10 s), so that every timed
/// frame is of the form it chose: a trial takes at least
/// half a second of trace time (`IntegratorChoice`), more than 0.6 s of wall time holds for small frames.
fn warm_up(app: &mut HeadlessApp, frames: usize) {
    let gpu = app.ctx.info.device_type != raykin::gpu::DeviceType::Cpu;
    let start = std::time::Instant::now();
    let mut done = 0;
    let trial_pending = |app: &HeadlessApp| {
        let auto = app
            .app
            .world()
            .resource::<raykin::render::RenderSettings>()
            .integrator
            == raykin::render::settings::Integrator::Auto;
        let choice = app.integrator_choice();
        auto && !choice.settled()
    };
    let elapsed = |ms: u64| start.elapsed() >= std::time::Duration::from_millis(ms);
    while done < frames || (gpu && (!elapsed(600) || (trial_pending(app) && !elapsed(10_000)))) {
        app.step();
        app.ctx.wait_idle();
        done += 1;
    }
}

/// A headless app on `scene` with its fixed camera and environment, players attached, GPU passes timed.
fn open_app(ctx: &GpuContext, scene: &BenchScene, settings: RenderSettings) -> Result<HeadlessApp> {
    let settings = RenderSettings {
        environment: scene.environment.clone(),
        ..settings
    };
    let mut app = HeadlessApp::new(ctx.clone(), scene.scene.clone(), settings, &scene.camera)
        .with_context(|| format!("bench scene `{}`", scene.name))?;
    // As `raykin render`: the denoiser's inputs accumulate only where the settings denoise.
    app.set_keep_denoiser_inputs(false);
    let world = app.app.world_mut();
    if !scene.players.is_empty() {
        let root = world
            .query_filtered::<bevy_ecs::entity::Entity, bevy_ecs::query::With<raykin::scene::SceneRoot>>()
            .single(world)
            .map_err(|e| anyhow::anyhow!("{}: scene root: {e}", scene.name))?;
        raykin::animation::attach_players(world, root, &scene.players);
    }
    app.set_time_passes(true);
    Ok(app)
}

fn at_size(base: &RenderSettings, (width, height): (u32, u32)) -> RenderSettings {
    RenderSettings {
        width,
        height,
        ..base.clone()
    }
}

/// `--export-mitsuba DIR`: each static scene as the error part renders it, written for Mitsuba.
fn export_mitsuba(
    ctx: &GpuContext,
    loaded: &[BenchScene],
    base: &RenderSettings,
    suite: &suite::Suite,
    dir: &Path,
) -> Result<()> {
    let (width, height) = suite.error_size;
    let renders = mitsuba::export::Renders {
        width,
        height,
        max_depth: base.max_depth,
        checkpoints: error_curves::checkpoints(1, suite.error_max_spp),
        reference_spp: suite.reference_spp,
    };
    for scene in loaded.iter().filter(|s| !s.animated()) {
        // A fixed view is the camera as is (as the renderer resolves it); any other is resolved by an app.
        let camera = match scene.camera {
            raykin::camera::CameraChoice::LookAt { eye, target, yfov } => {
                raykin::camera::CameraView::look_at(eye, target, glam::Vec3::Y, yfov)
            }
            _ => open_app(ctx, scene, at_size(base, (width, height)))?.camera(),
        };
        let settings = RenderSettings {
            environment: scene.environment.clone(),
            ..base.clone()
        };
        let out = dir.join(&scene.name);
        mitsuba::export::export(scene, &camera, &settings, &renders, &out)?;
        eprintln!(
            "raykin bench: {}: exported for Mitsuba to {}",
            scene.name,
            out.display()
        );
    }
    Ok(())
}

fn wants(args: &BenchArgs, part: &str) -> bool {
    args.parts.is_empty() || args.parts.iter().any(|p| p == part)
}

pub fn run(args: &BenchArgs) -> Result<()> {
    let started = std::time::Instant::now();
    let load_average_start = provenance::load_average();
    for p in &args.parts {
        anyhow::ensure!(
            PARTS.contains(&p.as_str()),
            "--parts {p}: unknown part; the parts are {}",
            PARTS.join(", ")
        );
    }
    let ctx = open_gpu()?;
    let mut suite = suite::Suite::new(&args.suite, ctx.info.device_type)?;
    if let Some(spp) = args.error_max_spp {
        suite.error_max_spp = spp;
    }
    let mut scene_names = if args.crowd {
        vec!["crowd".to_string()]
    } else {
        args.scene.clone()
    };
    if scene_names.is_empty() {
        scene_names = suite.scenes.clone();
    }
    let sizes = match (args.width, args.height) {
        (None, None) => suite.sizes.clone(),
        (w, h) => vec![(w.unwrap_or(64).max(1), h.unwrap_or(36).max(1))],
    };
    let frames = args.frames.unwrap_or(suite.frames).max(1);
    let charts_dir = args.out.join("charts");
    std::fs::create_dir_all(&charts_dir)
        .with_context(|| format!("{}: cannot create the output folder", charts_dir.display()))?;
    let base = RenderSettings {
        spp_per_frame: args.spp_per_frame,
        max_depth: args.max_depth,
        rr_depth: args.rr_depth,
        static_bvh: args.static_bvh.layout(),
        merge_static: args.static_bvh.merged(),
        deform: args.deform.into(),
        integrator: args.integrator.into(),
        ..Default::default()
    };
    let commit = provenance::commit();
    let date_unix_s = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let date = provenance::utc_date(date_unix_s);
    let note = if suite.scaling_note.is_empty() {
        String::new()
    } else {
        format!(" ({})", suite.scaling_note)
    };
    // The charts say which integrator traced them when it is not the default.
    let integrator = match base.integrator {
        raykin::render::Integrator::Auto => String::new(),
        other => format!(" | {} integrator", other.name()),
    };
    let context = format!(
        "{} ({:?}) | {} suite{note}{integrator} | commit {commit} | {date}",
        ctx.info.name, ctx.info.device_type, suite.name
    );
    let title = |what: &str| charts::Title {
        what: what.to_string(),
        context: context.clone(),
    };

    let mut loaded = Vec::new();
    for name in &scene_names {
        eprintln!("raykin bench: loading {name}");
        loaded.push(scenes::resolve(name, &args.assets)?);
    }
    if let Some(dir) = &args.export_mitsuba {
        return export_mitsuba(&ctx, &loaded, &base, &suite, dir);
    }
    let mut charts = Vec::new();
    let mut chart = |name: &str, draw: &dyn Fn(&Path) -> Result<()>| -> Result<()> {
        let path = charts_dir.join(name);
        draw(&path)?;
        eprintln!("raykin bench: wrote {}", path.display());
        charts.push(format!("charts/{name}"));
        Ok(())
    };

    let mut rows = Vec::new();
    if wants(args, "frames") {
        for scene in &loaded {
            for &(width, height) in &sizes {
                let settings = at_size(&base, (width, height));
                let row = frame_loop::measure(&ctx, scene, settings, suite.warmup, frames)?;
                eprintln!(
                    "raykin bench: {} {width}x{height}: {:.2} ms/frame, trace {:.2} ms median ({:.2} p99), {:.3} M primary rays/s, {:.3} M rays/s; ray casting without shading: {:.0} M camera rays/s, {:.0} M diffuse rays/s",
                    row.scene,
                    row.frame_ms.median,
                    row.trace_ms_median,
                    row.trace_ms_p99,
                    row.primary_rays_per_s / 1e6,
                    row.all_rays_per_s / 1e6,
                    row.raycast_camera_rays_per_s / 1e6,
                    row.raycast_diffuse_rays_per_s / 1e6
                );
                eprintln!(
                    "raykin bench: {} {width}x{height}: traced by the {} integrator{}{}{}",
                    row.scene,
                    row.integrator,
                    if row.rays_sorted { ", rays sorted" } else { "" },
                    row.auto_trial_ms.map_or(String::new(), |[m, w]| format!(
                        " (auto's trial: megakernel {m:.3} ms, wavefront {w:.3} ms)"
                    )),
                    row.sort_trial_ms.map_or(String::new(), |[u, s]| format!(
                        " (the sort's trial: unsorted {u:.3} ms, sorted {s:.3} ms)"
                    ))
                );
                let (c, b) = (&row.traversal_per_camera_ray, &row.traversal_per_bounce_ray);
                eprintln!(
                    "raykin bench: {} {width}x{height}: traversal per camera ray {:.1} TLAS + {:.1} BVH2 + {:.1} wide nodes, {:.1} triangles ({:.0} B); per diffuse ray {:.1} + {:.1} + {:.1}, {:.1} ({:.0} B)",
                    row.scene,
                    c.tlas_nodes,
                    c.bvh2_nodes,
                    c.wide_nodes,
                    c.triangles,
                    c.bytes,
                    b.tlas_nodes,
                    b.bvh2_nodes,
                    b.wide_nodes,
                    b.triangles,
                    b.bytes
                );
                if row.animated {
                    let p = &row.passes_median_ms;
                    eprintln!(
                        "raykin bench: {} {width}x{height}: deform backend {}: skinning {:.2} ms CPU + {:.2} ms GPU, refit {:.2} ms CPU + {:.2} ms GPU, rebuild {:.2} ms, top level {:.2} ms: {:.2} ms skin+refit per 100k triangles",
                        row.scene,
                        row.deform_backend,
                        p.skinning,
                        p.skinning_gpu,
                        p.refit,
                        p.refit_gpu,
                        p.rebuild,
                        p.top_level,
                        row.skin_refit_ms_per_100k_tris
                    );
                }
                rows.push(row);
            }
        }
        if !rows.is_empty() {
            chart("frame-breakdown.png", &|p| {
                charts::frame_breakdown(p, &title("Frame time per pass"), &rows)
            })?;
        }
    }

    let mut errors = Vec::new();
    let mut side_by_side = Vec::new();
    if wants(args, "errors") {
        let (w, h) = suite.error_size;
        let settings = at_size(&base, (w, h));
        let cache = args.cache.clone();
        for scene in loaded.iter().filter(|s| !s.animated()) {
            eprintln!("raykin bench: {}: error vs time at {w}x{h}", scene.name);
            let mut e = error_curves::measure(&ctx, scene, &settings, &suite, &cache, &args.curve)?;
            if let Some(dir) = &args.mitsuba {
                let reference = std::mem::take(&mut e.reference_mean);
                side_by_side.extend(mitsuba::compare(dir, &mut e, &reference)?);
            }
            let file = format!("error-vs-time-{}.png", scene.name);
            chart(&file, &|p| {
                charts::error_vs_time(
                    p,
                    &title(&format!(
                        "{}: error vs time, {w}x{h}, depth {}",
                        scene.name, base.max_depth
                    )),
                    &e,
                )
            })?;
            errors.push(e);
        }
    }

    let mut presets = Vec::new();
    if wants(args, "bvh") {
        let (w, h) = suite.scaling_size;
        let settings = at_size(&base, (w, h));
        for name in &suite.bvh_scenes {
            let scene = scenes::find_or_load(&mut loaded, name, &args.assets)?;
            eprintln!("raykin bench: {}: BVH presets", scene.name);
            presets.extend(bvh_quality::presets(
                &ctx,
                scene,
                &settings,
                1,
                suite.bvh_frames,
            )?);
        }
        if !presets.is_empty() {
            chart("bvh-presets.png", &|p| {
                charts::bvh_presets(
                    p,
                    &title(&format!("BVH presets: build vs trace time, {w}x{h}")),
                    &presets,
                )
            })?;
        }
    }

    let mut refit = None;
    if wants(args, "refit") {
        let (w, h) = suite.refit_size;
        let (asset, camera) = scenes::cesium_man(&args.assets)?;
        eprintln!("raykin bench: CesiumMan: refit vs rebuild");
        let settings = at_size(&base, (w, h));
        let r = bvh_quality::refit_vs_rebuild(
            &ctx,
            asset,
            camera,
            &settings,
            suite.refit_fps,
            suite.refit_seconds,
            suite.refit_trace_repeats,
        )?;
        chart("refit-vs-rebuild.png", &|p| {
            charts::refit_vs_rebuild(
                p,
                &title(&format!("CesiumMan walk: refit vs rebuild, {w}x{h}")),
                &r,
            )
        })?;
        refit = Some(r);
    }

    let (mut tri_scaling, mut res_scaling) = (Vec::new(), Vec::new());
    if wants(args, "scaling") {
        let (w, h) = suite.scaling_size;
        let settings = RenderSettings {
            width: w,
            height: h,
            environment: raykin::render::Environment::Sky,
            ..base.clone()
        };
        eprintln!("raykin bench: scaling with triangle count and resolution");
        let asset = scenes::load_scaling_asset(&args.assets)?;
        tri_scaling = scaling::triangles(
            &ctx,
            &asset,
            &suite.scaling_copies,
            &settings,
            suite.scaling_frames,
        )?;
        let cornell = scenes::find_or_load(&mut loaded, "cornell", &args.assets)?;
        res_scaling = scaling::resolution(
            &ctx,
            cornell,
            &suite.scaling_resolutions,
            &base,
            suite.scaling_frames,
        )?;
        chart("scaling.png", &|p| {
            charts::scaling(p, &title("Trace time scaling"), &tri_scaling, &res_scaling)
        })?;
    }

    let mut motion_scenes = Vec::new();
    if wants(args, "motion") {
        let names: Vec<String> = if args.scene.is_empty() && !args.crowd {
            suite.motion_scenes.clone()
        } else {
            scene_names.clone()
        };
        let plan = motion::MotionPlan {
            size: match (args.width, args.height) {
                (None, None) => suite.motion_size,
                (w, h) => (w.unwrap_or(64).max(1), h.unwrap_or(36).max(1)),
            },
            frames: args.frames.unwrap_or(suite.motion_frames).max(2),
            eval_every: suite.motion_eval_every,
            reference_spp: suite.motion_reference_spp,
            lag_window: suite.motion_lag_window,
        };
        for name in &names {
            let scene = match loaded.iter().find(|s| &s.name == name) {
                Some(s) => s,
                None => {
                    loaded.push(scenes::resolve(name, &args.assets)?);
                    loaded.last().expect("just pushed")
                }
            };
            if !scene.animated() {
                eprintln!("raykin bench: {name}: not animated, no motion part");
                continue;
            }
            let m = motion::measure(&ctx, scene, &base, &plan, &args.cache)?;
            for c in &m.curves {
                eprintln!(
                    "raykin bench: {} motion {}x{}: {}: relMSE {:.4} FLIP {:.4} settled, GPU {:.2} ms/frame, wall {:.2} ms{}{}{}",
                    m.scene,
                    m.width,
                    m.height,
                    c.method,
                    c.steady_rel_mse,
                    c.steady_flip,
                    c.gpu_ms.median,
                    c.wall_ms.median,
                    c.oidn_ms.as_ref().map_or(String::new(), |o| format!(
                        ", OIDN {:.2} ms on {}",
                        o.median,
                        c.oidn_device.as_deref().unwrap_or("?")
                    )),
                    c.band_to_rest.map_or(String::new(), |r| format!(
                        ", disoccluded/rest error {r:.2}"
                    )),
                    c.lag.as_ref().map_or(String::new(), |l| format!(
                        ", lamp switch settles in {}",
                        l.frames_to_settle
                            .map_or("> window".into(), |f| format!("{f} frames"))
                    )),
                );
            }
            let file = format!("motion-{}.png", m.scene);
            chart(&file, &|p| {
                charts::motion(
                    p,
                    &title(&format!(
                        "{}: the real-time path in motion, {}x{}, {} frames at 1/60 s",
                        m.scene, m.width, m.height, m.frames
                    )),
                    &m,
                )
            })?;
            motion_scenes.push(m);
        }
    }

    let (mut oidn_timings, mut oidn_gains) = (Vec::new(), Vec::new());
    if wants(args, "oidn") {
        match raykin::oidn::library::Library::shared() {
            Err(e) => eprintln!("raykin bench: the OIDN part is left out: {e}"),
            Ok(_) => {
                let cornell = match loaded.iter().find(|s| s.name == "cornell") {
                    Some(s) => s,
                    None => {
                        loaded.push(scenes::resolve("cornell", &args.assets)?);
                        loaded.last().expect("just pushed")
                    }
                };
                eprintln!("raykin bench: OIDN cost per frame");
                oidn_timings =
                    oidn::timings(&ctx, cornell, &base, &suite.oidn_sizes, suite.oidn_repeats)?;
                let settings = at_size(&base, suite.gain_size);
                // The error curves' scenes (the motion part may have loaded others).
                for scene in loaded.iter().filter(|s| scene_names.contains(&s.name)) {
                    eprintln!("raykin bench: {}: OIDN and svgf error gains", scene.name);
                    oidn_gains.extend(oidn::gains(&ctx, scene, &settings, &suite, &args.cache)?);
                }
            }
        }
    }

    let table = table(&loaded, &rows, &errors);
    let results = Results {
        adapter: ctx.info.name.clone(),
        backend: format!("{:?}", ctx.info.backend),
        device_type: format!("{:?}", ctx.info.device_type),
        driver: format!("{} {}", ctx.info.driver, ctx.info.driver_info),
        commit,
        date_unix_s,
        date,
        command: std::env::args().collect::<Vec<_>>().join(" "),
        suite,
        max_depth: base.max_depth,
        integrator: base.integrator,
        rows,
        table,
        error_vs_time: errors,
        mitsuba_side_by_side: side_by_side,
        bvh_presets: presets,
        refit_vs_rebuild: refit,
        scaling_triangles: tri_scaling,
        scaling_resolution: res_scaling,
        motion: motion_scenes,
        oidn_timings,
        oidn_gains,
        charts,
        wall_seconds: started.elapsed().as_secs_f64(),
        load_average_start,
        load_average_end: provenance::load_average(),
    };
    write_outputs(&args.out, &results)?;
    eprintln!(
        "raykin bench: wrote {}/results.json, results.csv, curves.csv, summary.md and {} charts in {:.0} s",
        args.out.display(),
        results.charts.len(),
        results.wall_seconds
    );
    Ok(())
}

fn table(
    scenes: &[BenchScene],
    rows: &[frame_loop::FrameRow],
    errors: &[error_curves::SceneErrors],
) -> Vec<TableRow> {
    let mut names: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    names.extend(errors.iter().map(|e| e.scene.as_str()));
    let mut seen = Vec::new();
    names.retain(|n| {
        let new = !seen.contains(n);
        seen.push(n);
        new
    });
    names
        .into_iter()
        .map(|name| {
            let mine: Vec<&frame_loop::FrameRow> =
                rows.iter().filter(|r| r.scene == name).collect();
            let e = errors.iter().find(|e| e.scene == name);
            TableRow {
                scene: name.to_string(),
                triangles: scenes
                    .iter()
                    .find(|s| s.name == name)
                    .map_or(0, |s| s.scene.triangle_count()),
                sizes: mine.iter().map(|r| (r.width, r.height)).collect(),
                ms_per_frame: mine.iter().map(|r| r.frame_ms.median).collect(),
                trace_ms: mine.iter().map(|r| r.trace_ms_median).collect(),
                primary_rays_per_s: mine.iter().map(|r| r.primary_rays_per_s).collect(),
                raycast_camera_rays_per_s: mine
                    .iter()
                    .map(|r| r.raycast_camera_rays_per_s)
                    .collect(),
                raycast_diffuse_rays_per_s: mine
                    .iter()
                    .map(|r| r.raycast_diffuse_rays_per_s)
                    .collect(),
                all_rays_per_s: mine.iter().map(|r| r.all_rays_per_s).collect(),
                error_size: e.map(|e| (e.width, e.height)),
                ms_to_rel_mse_0_01: e.and_then(|e| e.ms_to_rel_mse_0_01),
                ms_to_rel_mse_0_01_extrapolated: e
                    .is_some_and(|e| e.ms_to_rel_mse_0_01_extrapolated),
                ms_to_rel_mse_0_001: e.and_then(|e| e.ms_to_rel_mse_0_001),
                ms_to_rel_mse_0_001_extrapolated: e
                    .is_some_and(|e| e.ms_to_rel_mse_0_001_extrapolated),
                slope_rel_rmse_vs_spp: e.and_then(|e| e.slope_rel_rmse_vs_spp),
                slope_rel_rmse_linear_vs_spp: e.and_then(|e| e.slope_rel_rmse_linear_vs_spp),
            }
        })
        .collect()
}

fn write_outputs(out: &Path, results: &Results) -> Result<()> {
    let write = |name: &str, text: String| -> Result<()> {
        let path = out.join(name);
        std::fs::write(&path, text).with_context(|| format!("{}: cannot write", path.display()))
    };
    write("results.json", serde_json::to_string_pretty(results)?)?;
    let mut csv = String::from(
        "scene,width,height,triangles,trace_ms_median,trace_ms_p99,primary_rays_per_s,all_rays_per_s,bvh_build_and_upload_ms,gpu_memory_geometry_bvh_mib,frame_ms_median,raycast_camera_rays_per_s,raycast_diffuse_rays_per_s\n",
    );
    for r in &results.rows {
        csv += &format!(
            "{},{},{},{},{:.4},{:.4},{:.0},{:.0},{:.1},{:.2},{:.4},{:.0},{:.0}\n",
            r.scene,
            r.width,
            r.height,
            r.triangles,
            r.trace_ms_median,
            r.trace_ms_p99,
            r.primary_rays_per_s,
            r.all_rays_per_s,
            r.bvh_build_and_upload_ms,
            r.gpu_memory_geometry_bvh_mib,
            r.frame_ms.median,
            r.raycast_camera_rays_per_s,
            r.raycast_diffuse_rays_per_s
        );
    }
    write("results.csv", csv)?;
    let mut curves = String::from("scene,curve,spp,trace_ms,rel_mse,flip\n");
    for e in &results.error_vs_time {
        for c in &e.curves {
            for p in &c.points {
                curves += &format!(
                    "{},\"{}\",{},{:.4},{:.6e},{:.6}\n",
                    e.scene, c.name, p.spp, p.time_ms, p.rel_mse, p.flip
                );
            }
        }
    }
    write("curves.csv", curves)?;
    let mut motion = String::from(
        "scene,method,frame,rel_mse,flip,rel_mse_band,rel_mse_rest,band_fraction,gpu_ms_median\n",
    );
    for m in &results.motion {
        for c in &m.curves {
            for p in &c.points {
                let opt = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:.6e}"));
                motion += &format!(
                    "{},\"{}\",{},{:.6e},{:.6},{},{},{:.4},{:.4}\n",
                    m.scene,
                    c.method,
                    p.frame,
                    p.rel_mse,
                    p.flip,
                    opt(p.rel_mse_band),
                    opt(p.rel_mse_rest),
                    p.band_fraction,
                    c.gpu_ms.median
                );
            }
        }
    }
    write("motion.csv", motion)?;
    write("summary.md", summary_markdown(results))
}

/// The per-scene table as markdown, for docs/BENCHMARKS.md.
fn summary_markdown(r: &Results) -> String {
    let join = |v: &[f64], f: &dyn Fn(f64) -> String| {
        v.iter().map(|x| f(*x)).collect::<Vec<_>>().join(" / ")
    };
    let rays = |x: f64| {
        if x >= 1e9 {
            format!("{:.2} G", x / 1e9)
        } else {
            format!("{:.3} M", x / 1e6)
        }
    };
    let time = |t: Option<f64>, extrapolated: bool| match t {
        Some(ms) if ms >= 1e4 => {
            format!("{}{:.1} s", if extrapolated { "~" } else { "" }, ms / 1e3)
        }
        Some(ms) => format!("{}{ms:.1} ms", if extrapolated { "~" } else { "" }),
        None => "n/a".into(),
    };
    let mut s = format!(
        "`{}` on {} ({}, driver {}), commit {}, {}; suite `{}`{}.\n\n",
        r.command,
        r.adapter,
        r.device_type,
        r.driver,
        r.commit,
        r.date,
        r.suite.name,
        if r.suite.scaling_note.is_empty() {
            String::new()
        } else {
            format!(" ({})", r.suite.scaling_note)
        }
    );
    s += "| scene | triangles | size | ms/frame | trace ms | primary rays/s | all rays/s | ray casting: camera / diffuse rays/s | error size | trace time to relMSE 0.01 | to 0.001 | slope of log rel. RMSE vs log spp (tone-mapped / linear) |\n";
    s += "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for t in &r.table {
        let sizes: Vec<String> = t.sizes.iter().map(|(w, h)| format!("{w}x{h}")).collect();
        s += &format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            t.scene,
            t.triangles,
            sizes.join(" / "),
            join(&t.ms_per_frame, &|x| format!("{x:.2}")),
            join(&t.trace_ms, &|x| format!("{x:.2}")),
            join(&t.primary_rays_per_s, &rays),
            join(&t.all_rays_per_s, &rays),
            t.raycast_camera_rays_per_s
                .iter()
                .zip(&t.raycast_diffuse_rays_per_s)
                .map(|(c, d)| format!("{} / {}", rays(*c), rays(*d)))
                .collect::<Vec<_>>()
                .join(", "),
            t.error_size.map_or("-".into(), |(w, h)| format!("{w}x{h}")),
            time(t.ms_to_rel_mse_0_01, t.ms_to_rel_mse_0_01_extrapolated),
            time(t.ms_to_rel_mse_0_001, t.ms_to_rel_mse_0_001_extrapolated),
            [t.slope_rel_rmse_vs_spp, t.slope_rel_rmse_linear_vs_spp]
                .map(|x| x.map_or("n/a".into(), |x| format!("{x:.2}")))
                .join(" / "),
        );
    }
    s += "\nms/frame: wall time of a whole frame (all passes, waiting for the GPU); trace ms: GPU timestamps of the \
path-trace kernel; relMSE on tone-mapped images against the cached reference, its own noise subtracted; \
~ = extrapolated along the fitted power law (the curve did not get there within the suite's samples); \
ray casting: the shading-free pass (camera rays through pixel centres, then one cosine-distributed bounce ray \
per hit), per size.\n";
    if r.rows
        .iter()
        .any(|row| row.traversal_per_camera_ray.bytes > 0.0)
    {
        s += "\n| scene | size | per camera ray: TLAS / BVH2 / wide nodes, triangles, bytes | per diffuse bounce ray: the same | diffuse rays/s x bytes per ray |\n";
        s += "|---|---|---|---|---|\n";
        let work = |w: &frame_loop::WorkPerRay| {
            format!(
                "{:.1} / {:.1} / {:.1}, {:.1}, {:.0} B",
                w.tlas_nodes, w.bvh2_nodes, w.wide_nodes, w.triangles, w.bytes
            )
        };
        for row in &r.rows {
            let b = &row.traversal_per_bounce_ray;
            s += &format!(
                "| {} | {}x{} | {} | {} | {:.0} GB/s |\n",
                row.scene,
                row.width,
                row.height,
                work(&row.traversal_per_camera_ray),
                work(b),
                row.raycast_diffuse_rays_per_s * b.bytes / 1e9
            );
        }
        s += "\nTraversal work: the ray-casting pass run once more with counters (`shaders/traversal/stats.wgsl`), \
averages per ray; bytes = nodes x 64 B (BVH2) or 80 B (wide) + triangles x 52 B (record and three positions), what \
the rays would fetch if nothing were cached; times the diffuse rays/s, the bandwidth that would need.\n";
    }
    if !r.motion.is_empty() {
        s += "\n| scene | size | method | GPU ms/frame (median, p99) | wall ms/frame (median) | OIDN ms/frame (median, device) | settled relMSE | settled FLIP | disoccluded / rest error | lamp switch settles in |\n";
        s += "|---|---|---|---|---|---|---|---|---|---|\n";
        for m in &r.motion {
            for c in &m.curves {
                s += &format!(
                    "| {} | {}x{} | {} | {:.2} / {:.2} | {:.2} | {} | {:.4} | {:.4} | {} | {} |\n",
                    m.scene,
                    m.width,
                    m.height,
                    c.method,
                    c.gpu_ms.median,
                    c.gpu_ms.p99,
                    c.wall_ms.median,
                    c.oidn_ms.as_ref().map_or("-".into(), |o| format!(
                        "{:.2} ({})",
                        o.median,
                        c.oidn_device.as_deref().unwrap_or("?")
                    )),
                    c.steady_rel_mse,
                    c.steady_flip,
                    c.band_to_rest.map_or("-".into(), |x| format!("{x:.2}")),
                    c.lag.as_ref().map_or("-".into(), |l| l
                        .frames_to_settle
                        .map_or("> window".into(), |f| format!("{f} frames"))),
                );
            }
        }
        s += "\nMotion: the displayed frame of each method against a converged render of the same pose (tone-mapped \
relMSE and FLIP), settled = mean over the evaluated frames from K/4 (before the lamp switch); GPU ms: every pass of \
the frame (deform, G-buffer, ReSTIR, gradients, trace, temporal, spatial filter, tone map); disoccluded = pixels \
whose history (reprojection without gradients) is at most 8 frames long.\n";
    }
    if !r.mitsuba_side_by_side.is_empty() {
        s += "\n### Mitsuba 3 side by side\n\n";
        s += &mitsuba::markdown(&r.mitsuba_side_by_side);
        s += "\n\nEach renderer's tone-mapped relMSE against its own two-half reference (its noise subtracted); \
throughput at the largest common sample count; variance ratio = (relMSE x spp) raykin / Mitsuba there; relMSE x \
time = median over each curve's second half of relMSE x time, raykin / Mitsuba (below 1: raykin is faster), with \
raykin's time from GPU timestamps of the trace pass or the wall time of its frames, Mitsuba's the wall time of \
`mi.render` after a warm-up render; steady = variance ratio x raykin's trace ms per sample over its last segment / \
Mitsuba's ms per sample (these three are the time to equal error where relMSE falls as 1/time); time at equal error \
= raykin's trace time / Mitsuba's time to first reach the same relMSE, by log-log interpolation along each curve, \
at the lowest relMSE both reach, and its least and greatest over nine levels from there up; references apart = \
relMSE of the two converged images against each other, both noises subtracted, and the ratio of their means per \
channel, with the largest of its distances from 1 in standard errors (from each reference's halves; beyond 5 and 0.2%, the run warns that the images differ).\n";
    }
    s += &oidn_markdown(r);
    s
}

/// OIDN's tables for docs/BENCHMARKS.md: cost per frame, and error gains.
fn oidn_markdown(r: &Results) -> String {
    let mut s = String::new();
    if !r.oidn_timings.is_empty() {
        s += "\n| OIDN device | memory | AOVs | quality | size | ms per frame | without OIDN->host | GPU->host readback | host->OIDN (shared: inputs pass) | prefilter (albedo, normal) | filter | OIDN->host | filter set-up (once) |\n";
        s += "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
        for t in &r.oidn_timings {
            s += &format!(
                "| {} | {} | {} | {} | {}x{} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.0} |\n",
                t.device,
                t.memory,
                t.aux,
                t.quality.name(),
                t.width,
                t.height,
                t.total_ms,
                t.on_device_ms,
                t.readback_ms,
                t.upload_ms,
                t.prefilter_ms,
                t.filter_ms,
                t.download_ms,
                t.setup_ms
            );
        }
    }
    if !r.oidn_gains.is_empty() {
        s += "\n| scene | size | spp | method | relMSE (tone-mapped) | gain | relMSE (linear) | gain | FLIP | gain | mean / noisy mean |\n";
        s += "|---|---|---|---|---|---|---|---|---|---|---|\n";
        for g in &r.oidn_gains {
            s += &format!(
                "| {} | {}x{} | {} | {} | {:.3e} | {:.1}x | {:.3e} | {:.1}x | {:.4} | {:.1}x | {:.4} |\n",
                g.scene,
                g.width,
                g.height,
                g.spp,
                g.method,
                g.rel_mse,
                g.rel_mse_gain,
                g.rel_mse_linear,
                g.rel_mse_linear_gain,
                g.flip,
                g.flip_gain,
                g.mean_ratio
            );
        }
        s += "\nGains: the noisy image's error over the denoised one's, against the cached reference (its own noise \
not subtracted); animated scenes in their rest pose.\n";
    }
    s
}

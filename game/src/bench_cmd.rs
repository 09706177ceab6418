//! `raykin bench`: frame times from GPU timestamps, rays per second, BVH build time and GPU memory per scene and
//! resolution, written to DIR/results.json and DIR/results.csv. (Charts: the bench issue.)

use crate::cli::BenchArgs;
use crate::render_cmd::{load_scene, open_gpu};
use anyhow::{Context, Result};
use raykin::camera::CameraChoice;
use raykin::headless::HeadlessApp;
use raykin::render::{Environment, RenderSettings};
use std::path::PathBuf;
use std::time::Instant;

/// Named bench scenes, relative to the shared assets folder, with fixed cameras.
const NAMED: &[(&str, &str)] = &[
    ("cornell", "CornellBox/CornellBox.glb"),
    ("flight-helmet", "FlightHelmet/glTF/FlightHelmet.gltf"),
    (
        "spheres",
        "MetalRoughSpheresNoTextures/glTF-Binary/MetalRoughSpheresNoTextures.glb",
    ),
];

#[derive(serde::Serialize)]
struct Row {
    scene: String,
    static_bvh: String,
    triangles: usize,
    width: u32,
    height: u32,
    spp_per_frame: u32,
    max_depth: u32,
    frames: usize,
    bvh_build_and_upload_ms: f64,
    gpu_memory_geometry_bvh_mib: f64,
    bytes_per_triangle_geometry_bvh: f64,
    trace_ms_median: f64,
    trace_ms_p99: f64,
    timing_source: &'static str,
    primary_rays_per_s: f64,
    all_rays_per_s: f64,
    rays_per_pixel_per_frame: f64,
    /// Shading-free ray casting (`PathTracer::cast_rays`): camera rays per second, and diffuse bounce rays per
    /// second (the extra rays over the extra time when one bounce is added); 0 without timestamps.
    raycast_primary_rays_per_s: f64,
    raycast_diffuse_rays_per_s: f64,
}

#[derive(serde::Serialize)]
struct Results {
    adapter: String,
    backend: String,
    device_type: String,
    driver: String,
    commit: String,
    date_unix_s: u64,
    rows: Vec<Row>,
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    let i = ((sorted.len() as f64 - 1.0) * p).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

pub fn run(args: &BenchArgs) -> Result<()> {
    let ctx = open_gpu()?;
    let (sizes, frames, warmup): (Vec<(u32, u32)>, usize, usize) = match args.suite.as_str() {
        "quick" => (vec![(64, 36)], 5, 1),
        "full" => (vec![(1920, 1080), (2560, 1440)], 300, 10),
        other => anyhow::bail!("unknown suite `{other}`: quick or full"),
    };
    let frames = args.frames.unwrap_or(frames);
    let scenes: Vec<PathBuf> = if args.scene.is_empty() {
        NAMED.iter().map(|(_, p)| args.assets.join(p)).collect()
    } else {
        args.scene
            .iter()
            .map(|s| {
                NAMED
                    .iter()
                    .find(|(n, _)| n == s)
                    .map_or_else(|| PathBuf::from(s), |(_, p)| args.assets.join(p))
            })
            .collect()
    };
    let sizes = if args.width.is_some() {
        vec![(args.width.unwrap_or(64), args.height.unwrap_or(36))]
    } else {
        sizes
    };
    let mut rows = Vec::new();
    for path in &scenes {
        let scene = load_scene(path)?;
        for &(width, height) in &sizes {
            let settings = RenderSettings {
                width,
                height,
                spp_per_frame: 1,
                max_depth: args.max_depth,
                environment: Environment::Sky,
                static_bvh: args.static_bvh.into(),
                ..Default::default()
            };
            let start = Instant::now();
            let mut app =
                HeadlessApp::new(ctx.clone(), scene.clone(), settings, &CameraChoice::Auto)?;
            ctx.wait_idle();
            let build_ms = start.elapsed().as_secs_f64() * 1e3;
            app.app
                .world_mut()
                .resource_mut::<raykin::render::Renderer>()
                .time_passes = true;
            let (mut times, mut rays) = (Vec::new(), 0u64);
            for f in 0..warmup + frames {
                let t0 = Instant::now();
                app.step();
                let renderer = app.renderer();
                let gpu = renderer.last_pass_times.map(|t| t.trace_ms);
                let wall = t0.elapsed().as_secs_f64() * 1e3;
                if f >= warmup {
                    times.push(gpu.unwrap_or(wall));
                    rays += renderer.tracer.read_ray_count(&app.ctx);
                }
            }
            let timing_source = if app.renderer().last_pass_times.is_some() {
                "gpu-timestamps"
            } else {
                "cpu-wall"
            };
            times.sort_by(f64::total_cmp);
            let (raycast_primary, raycast_diffuse) = raycast_rates(&mut app, frames.clamp(1, 50));
            let total_ms: f64 = times.iter().sum();
            let memory = app.renderer().scene.memory;
            let pixels = width as f64 * height as f64;
            let row = Row {
                scene: path.display().to_string(),
                static_bvh: format!("{:?}", args.static_bvh).to_lowercase(),
                triangles: scene.triangle_count(),
                width,
                height,
                spp_per_frame: 1,
                max_depth: args.max_depth,
                frames,
                bvh_build_and_upload_ms: app.renderer().scene.build_seconds * 1e3,
                gpu_memory_geometry_bvh_mib: memory.geometry_and_bvh() as f64 / 1048576.0,
                bytes_per_triangle_geometry_bvh: memory.geometry_and_bvh() as f64
                    / scene.triangle_count().max(1) as f64,
                trace_ms_median: percentile(&times, 0.5),
                trace_ms_p99: percentile(&times, 0.99),
                timing_source,
                primary_rays_per_s: pixels * frames as f64 / (total_ms / 1e3),
                all_rays_per_s: rays as f64 / (total_ms / 1e3),
                rays_per_pixel_per_frame: rays as f64 / (pixels * frames as f64),
                raycast_primary_rays_per_s: raycast_primary,
                raycast_diffuse_rays_per_s: raycast_diffuse,
            };
            let _ = build_ms;
            eprintln!(
                "{} {}x{}: {:.2} ms/frame median ({:.2} p99), {:.0} M primary rays/s, {:.0} M rays/s, BVH+upload {:.0} ms, {:.1} MiB geometry+BVH; ray casting without shading: {:.0} M camera rays/s, {:.0} M diffuse rays/s",
                row.scene,
                width,
                height,
                row.trace_ms_median,
                row.trace_ms_p99,
                row.primary_rays_per_s / 1e6,
                row.all_rays_per_s / 1e6,
                row.bvh_build_and_upload_ms,
                row.gpu_memory_geometry_bvh_mib,
                row.raycast_primary_rays_per_s / 1e6,
                row.raycast_diffuse_rays_per_s / 1e6
            );
            rows.push(row);
        }
    }
    let results = Results {
        adapter: ctx.info.name.clone(),
        backend: format!("{:?}", ctx.info.backend),
        device_type: format!("{:?}", ctx.info.device_type),
        driver: format!("{} {}", ctx.info.driver, ctx.info.driver_info),
        commit: std::env::var("RAYKIN_COMMIT")
            .ok()
            .or_else(git_commit)
            .unwrap_or_else(|| "unknown".into()),
        date_unix_s: std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs()),
        rows,
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("{}: cannot create", args.out.display()))?;
    std::fs::write(
        args.out.join("results.json"),
        serde_json::to_string_pretty(&results)?,
    )?;
    let mut csv = String::from(
        "scene,width,height,triangles,trace_ms_median,trace_ms_p99,primary_rays_per_s,all_rays_per_s,bvh_build_and_upload_ms,gpu_memory_geometry_bvh_mib\n",
    );
    for r in &results.rows {
        csv += &format!(
            "{},{},{},{},{:.4},{:.4},{:.0},{:.0},{:.1},{:.2}\n",
            r.scene,
            r.width,
            r.height,
            r.triangles,
            r.trace_ms_median,
            r.trace_ms_p99,
            r.primary_rays_per_s,
            r.all_rays_per_s,
            r.bvh_build_and_upload_ms,
            r.gpu_memory_geometry_bvh_mib
        );
    }
    std::fs::write(args.out.join("results.csv"), csv)?;
    eprintln!(
        "raykin: wrote {}/results.json and results.csv",
        args.out.display()
    );
    Ok(())
}

/// Median ray-casting rates over `reps` runs of each pass: (camera rays/s, diffuse bounce rays/s).
fn raycast_rates(app: &mut HeadlessApp, reps: usize) -> (f64, f64) {
    let mut runs = |diffuse| {
        // Warm-up: the first call builds the pipeline.
        app.cast_rays(diffuse);
        let mut samples: Vec<(f64, u64)> = (0..reps)
            .filter_map(|_| app.cast_rays(diffuse))
            .map(|t| (t.gpu_ms, t.rays))
            .collect();
        samples.sort_by(|a, b| a.0.total_cmp(&b.0));
        samples.get(samples.len() / 2).copied()
    };
    let (Some((t0, r0)), Some((t1, r1))) = (runs(false), runs(true)) else {
        return (0.0, 0.0);
    };
    let primary = r0 as f64 / (t0 / 1e3);
    let diffuse = if t1 > t0 {
        (r1 - r0) as f64 / ((t1 - t0) / 1e3)
    } else {
        0.0
    };
    (primary, diffuse)
}

fn git_commit() -> Option<String> {
    let out = std::process::Command::new("git")
        .args(["rev-parse", "--short", "HEAD"])
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

#[derive(serde::Serialize)]
struct CrowdRow {
    width: u32,
    height: u32,
    frames: usize,
    triangles: usize,
    skinned_instances: usize,
    /// Per phase: (median, p99) in ms over the measured frames.
    animate_ms: (f64, f64),
    transform_ms: (f64, f64),
    deform_ms: (f64, f64),
    bvh_ms: (f64, f64),
    refit_ms: (f64, f64),
    rebuild_ms: (f64, f64),
    render_submit_ms: (f64, f64),
    trace_gpu_ms: (f64, f64),
    rebuilds: u64,
    max_sah_ratio_last_frame: f32,
}

/// The crowd scene (64 CesiumMan + 32 Fox) through the frame loop: per-phase CPU times and GPU trace time.
pub fn run_crowd(args: &BenchArgs) -> Result<()> {
    let ctx = open_gpu()?;
    let crowd = raykin::scene::crowd_scene(&args.assets)?;
    let skinned = crowd
        .scene
        .meshes
        .iter()
        .filter(|m| m.skin_weights.is_some())
        .count();
    let triangles = crowd.scene.triangle_count();
    let scene = std::sync::Arc::new(crowd.scene);
    let (sizes, frames, warmup): (Vec<(u32, u32)>, usize, usize) = match args.suite.as_str() {
        "quick" => (vec![(64, 36)], 10, 2),
        _ => (vec![(1920, 1080), (2560, 1440)], 300, 10),
    };
    let frames = args.frames.unwrap_or(frames);
    let mut rows = Vec::new();
    for (width, height) in sizes {
        let settings = RenderSettings {
            width,
            height,
            spp_per_frame: 1,
            max_depth: args.max_depth,
            environment: Environment::Sky,
            ..Default::default()
        };
        let mut app = HeadlessApp::new(ctx.clone(), scene.clone(), settings, &CameraChoice::Auto)?;
        {
            let world = app.app.world_mut();
            let root = world
                .query_filtered::<bevy_ecs::entity::Entity, bevy_ecs::query::With<raykin::scene::SceneRoot>>()
                .single(world)
                .map_err(|e| anyhow::anyhow!("crowd scene root: {e}"))?;
            raykin::animation::attach_players(world, root, &crowd.players);
            world.resource_mut::<raykin::render::Renderer>().time_passes = true;
        }
        let mut phases: Vec<[f64; 8]> = Vec::new();
        for f in 0..warmup + frames {
            app.step();
            if f < warmup {
                continue;
            }
            let world = app.app.world();
            let t = world.resource::<raykin::frame_timing::FrameTimings>().last;
            let stats = world.resource::<raykin::bvh::refit::BvhStats>();
            let trace = app
                .renderer()
                .last_pass_times
                .map_or(f64::NAN, |p| p.trace_ms);
            phases.push([
                t.animate_ms,
                t.transform_ms,
                t.deform_ms,
                t.bvh_ms,
                stats.last_refit_seconds * 1e3,
                stats.last_rebuild_seconds * 1e3,
                t.render_ms,
                trace,
            ]);
        }
        let stat = |i: usize| {
            let mut v: Vec<f64> = phases.iter().map(|p| p[i]).collect();
            v.sort_by(f64::total_cmp);
            (percentile(&v, 0.5), percentile(&v, 0.99))
        };
        let stats = app.app.world().resource::<raykin::bvh::refit::BvhStats>();
        let row = CrowdRow {
            width,
            height,
            frames,
            triangles,
            skinned_instances: skinned,
            animate_ms: stat(0),
            transform_ms: stat(1),
            deform_ms: stat(2),
            bvh_ms: stat(3),
            refit_ms: stat(4),
            rebuild_ms: stat(5),
            render_submit_ms: stat(6),
            trace_gpu_ms: stat(7),
            rebuilds: stats.rebuilds,
            max_sah_ratio_last_frame: stats.sah_ratio.iter().copied().fold(0.0, f32::max),
        };
        eprintln!(
            "crowd {width}x{height} ({triangles} tris, {skinned} skinned): median ms animate {:.2} transform {:.2} deform {:.2} bvh {:.2} (refit {:.2}, rebuild {:.2}) render-submit {:.2} GPU trace {:.2} (p99 {:.2}); {} rebuilds",
            row.animate_ms.0,
            row.transform_ms.0,
            row.deform_ms.0,
            row.bvh_ms.0,
            row.refit_ms.0,
            row.rebuild_ms.0,
            row.render_submit_ms.0,
            row.trace_gpu_ms.0,
            row.trace_gpu_ms.1,
            row.rebuilds
        );
        rows.push(row);
    }
    std::fs::create_dir_all(&args.out)?;
    let json = serde_json::json!({
        "adapter": ctx.info.name, "driver": format!("{} {}", ctx.info.driver, ctx.info.driver_info),
        "commit": std::env::var("RAYKIN_COMMIT").ok().or_else(git_commit).unwrap_or_else(|| "unknown".into()),
        "rows": rows,
    });
    std::fs::write(
        args.out.join("crowd.json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    eprintln!("raykin: wrote {}/crowd.json", args.out.display());
    Ok(())
}

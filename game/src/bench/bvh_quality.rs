//! BVH quality against build/update time: obvhs's build presets (build ms vs trace ms), and refit against a
//! full rebuild along an animation (SAH ratio, update ms, and the trace time of the same pose with each tree).

use super::scenes::BenchScene;
use crate::stats::Spread;
use anyhow::Result;
use raykin::bvh::{BvhQuality, MeshBvh};
use raykin::camera::CameraChoice;
use raykin::gpu::GpuContext;
use raykin::headless::HeadlessApp;
use raykin::render::RenderSettings;
use raykin::scene::SceneAsset;
use std::sync::Arc;
use std::time::Instant;

#[derive(Clone, Debug, serde::Serialize)]
pub struct PresetRow {
    pub scene: String,
    pub preset: BvhQuality,
    pub triangles: usize,
    /// CPU time of obvhs builds plus flattening over all meshes (single thread), median of 3.
    pub build_ms: f64,
    /// Triangle-weighted mean SAH cost of the meshes' BVHs (relative to each root's area).
    pub sah_cost: f64,
    pub trace_ms: Spread,
    pub width: u32,
    pub height: u32,
}

/// Every preset of [`BvhQuality::ALL`] on `scene`: build time, SAH cost, trace time.
pub fn presets(
    ctx: &GpuContext,
    scene: &BenchScene,
    base: &RenderSettings,
    warmup: usize,
    frames: usize,
) -> Result<Vec<PresetRow>> {
    let asset = &scene.scene;
    let triangles = asset.triangle_count();
    let mut rows = Vec::new();
    for preset in BvhQuality::ALL {
        let (mut builds, mut sah) = (Vec::new(), 0.0);
        for _ in 0..3 {
            let start = Instant::now();
            sah = 0.0;
            for mesh in &asset.meshes {
                let bvh = MeshBvh::build(&mesh.positions, &mesh.triangles, preset)?;
                sah += bvh.build_sah as f64 * mesh.triangles.len() as f64;
            }
            builds.push(start.elapsed().as_secs_f64() * 1e3);
        }
        let settings = RenderSettings {
            bvh_quality: preset,
            merged_bvh_quality: preset,
            gpu_deformed_bvh_quality: preset,
            ..base.clone()
        };
        let mut app = super::open_app(ctx, scene, settings)?;
        let trace = trace_times(&mut app, warmup, frames);
        rows.push(PresetRow {
            scene: scene.name.clone(),
            preset,
            triangles,
            build_ms: Spread::of(&builds).median,
            sah_cost: sah / triangles.max(1) as f64,
            trace_ms: Spread::of(&trace),
            width: base.width,
            height: base.height,
        });
    }
    Ok(rows)
}

/// Trace ms of `frames` frames after `warmup` (wall time per frame where the adapter has no timestamps).
fn trace_times(app: &mut HeadlessApp, warmup: usize, frames: usize) -> Vec<f64> {
    let mut out = Vec::with_capacity(frames);
    for f in 0..warmup + frames {
        let start = Instant::now();
        app.step();
        let t = app.pass_times().map_or_else(
            || {
                app.ctx.wait_idle();
                start.elapsed().as_secs_f64() * 1e3
            },
            |p| p.trace_ms,
        );
        if f >= warmup {
            out.push(t);
        }
    }
    out
}

/// One pose of the animation, traced with the refit tree and with a tree rebuilt for that pose.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RefitFrame {
    pub time_s: f32,
    /// SAH cost of the refit tree over its cost at build (never rebuilt since the first pose).
    pub sah_ratio_refit: f32,
    pub refit_ms: f64,
    pub rebuild_ms: f64,
    /// Fastest of the repeated frames at this pose.
    pub trace_ms_refit: f64,
    pub trace_ms_rebuilt: f64,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct RefitResult {
    pub asset: String,
    pub triangles: usize,
    pub width: u32,
    pub height: u32,
    pub frames: Vec<RefitFrame>,
    pub refit_ms: Spread,
    pub rebuild_ms: Spread,
    /// Per pose, trace ms with the refit tree over trace ms with the rebuilt tree.
    pub trace_ratio_refit_over_rebuilt: Spread,
    pub max_sah_ratio: f32,
}

fn set_threshold(app: &mut HeadlessApp, threshold: f32) {
    app.app
        .world_mut()
        .resource_mut::<raykin::bvh::refit::BvhStats>()
        .threshold = threshold;
}

/// Walks `asset`'s clip 0 at `fps` for `seconds`: one app only refits after building at the first pose, the
/// other rebuilds at every pose, so each pose is traced with both trees. Trace times are the fastest of
/// `repeats` frames at the pose (the two trees differ by less than a shared CPU's scheduling noise).
#[allow(clippy::too_many_arguments)]
pub fn refit_vs_rebuild(
    ctx: &GpuContext,
    asset: Arc<SceneAsset>,
    camera: CameraChoice,
    base: &RenderSettings,
    fps: f32,
    seconds: f32,
    repeats: usize,
) -> Result<RefitResult> {
    let scene = BenchScene::still(
        "CesiumMan".into(),
        asset.clone(),
        camera,
        base.environment.clone(),
    );
    // CPU deformation: its refit and rebuild run synchronously in the frame they are asked for, so each pose
    // is traced with exactly the tree this comparison is about (the GPU backend rebuilds asynchronously).
    let base = &RenderSettings {
        deform: raykin::gpu_deform::DeformBackend::Cpu,
        ..base.clone()
    };
    let mut refit_app = super::open_app(ctx, &scene, base.clone())?;
    let mut rebuild_app = super::open_app(ctx, &scene, base.clone())?;
    // One untimed frame each at the rest pose: the first dispatch also compiles the kernel on some drivers.
    refit_app.step();
    rebuild_app.step();
    let poses = (fps * seconds).round().max(1.0) as usize;
    let mut frames = Vec::with_capacity(poses);
    for k in 0..=poses {
        let t = k as f32 / fps;
        // Threshold 0 rebuilds at this pose; infinity keeps the refit tree (and the repeats at the same pose
        // from rebuilding again).
        let measure = |app: &mut HeadlessApp, rebuild: bool| -> Result<(f64, f64, f64, f32)> {
            set_threshold(app, if rebuild { 0.0 } else { f32::INFINITY });
            app.set_time(0, t).map_err(anyhow::Error::msg)?;
            app.step();
            set_threshold(app, f32::INFINITY);
            let stats = app.bvh_stats();
            let (refit, rebuild) = (
                stats.last_refit_seconds * 1e3,
                stats.last_rebuild_seconds * 1e3,
            );
            let ratio = stats.sah_ratio.iter().copied().fold(0.0, f32::max);
            // The pose frame's own GPU time counts; without timestamps its wall time would include the BVH
            // update, so only the repeats (at least one) are timed then.
            let pose_trace = app.pass_times().map(|p| p.trace_ms);
            let repeats = repeats
                .saturating_sub(1)
                .max(usize::from(pose_trace.is_none()));
            let mut trace = trace_times(app, 0, repeats);
            trace.extend(pose_trace);
            Ok((refit, rebuild, Spread::of(&trace).min, ratio))
        };
        // Both trees start from a build at the first pose.
        let (refit_ms, _, trace_refit, ratio) = measure(&mut refit_app, k == 0)?;
        let (_, rebuild_ms, trace_rebuilt, _) = measure(&mut rebuild_app, true)?;
        frames.push(RefitFrame {
            time_s: t,
            sah_ratio_refit: ratio,
            refit_ms,
            rebuild_ms,
            trace_ms_refit: trace_refit,
            trace_ms_rebuilt: trace_rebuilt,
        });
    }
    // The first pose is the build pose for both trees: leave it out of the summaries.
    let moving = &frames[1.min(frames.len() - 1)..];
    let col = |f: fn(&RefitFrame) -> f64| Spread::of(&moving.iter().map(f).collect::<Vec<_>>());
    Ok(RefitResult {
        asset: asset.source.clone(),
        triangles: asset.triangle_count(),
        width: base.width,
        height: base.height,
        refit_ms: col(|f| f.refit_ms),
        rebuild_ms: col(|f| f.rebuild_ms),
        trace_ratio_refit_over_rebuilt: col(|f| f.trace_ms_refit / f.trace_ms_rebuilt),
        max_sah_ratio: frames.iter().map(|f| f.sah_ratio_refit).fold(0.0, f32::max),
        frames,
    })
}

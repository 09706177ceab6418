//! Frames through the whole schedule: per-pass time (CPU phases from `raykin::frame_timing`, GPU passes from
//! timestamp queries), trace time, rays per second. One run gives a row of the throughput table and a bar
//! of the frame-time breakdown.

use super::scenes::BenchScene;
use crate::stats::Spread;
use anyhow::Result;
use raykin::gpu::GpuContext;
use raykin::headless::HeadlessApp;
use raykin::render::RenderSettings;

/// Median milliseconds per frame of each pass, in frame order. The CPU phases are the frame-schedule sets;
/// `trace` is the path-trace kernel, which also accumulates (one kernel: there is no separate accumulate
/// pass); `encode_submit` is the Render set's CPU time less the GPU passes it waited for.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct PassBreakdown {
    pub animate: f64,
    /// Global transforms and joint matrices.
    pub transform: f64,
    /// Skinning and morphing on the CPU (and, on the GPU backend, the joint matrices it uploads).
    pub skinning: f64,
    /// CPU refit of deformed BLASes plus their vertex uploads (CPU backend).
    pub refit: f64,
    /// Quality-guard rebuilds.
    pub rebuild: f64,
    /// Top-level BVH build plus instance and emitter upload.
    pub top_level: f64,
    pub upload: f64,
    pub encode_submit: f64,
    /// GPU deformation passes (GPU backend): skinning + morphing, BLAS refit + SAH cost.
    pub skinning_gpu: f64,
    pub refit_gpu: f64,
    pub trace_and_accumulate_gpu: f64,
    pub tonemap_gpu: f64,
}

impl PassBreakdown {
    /// (label, value) in frame order, for the stacked bars.
    pub fn parts(&self) -> [(&'static str, f64); 12] {
        [
            ("animation", self.animate),
            ("transforms + joints", self.transform),
            ("skinning", self.skinning),
            ("refit", self.refit),
            ("rebuild", self.rebuild),
            ("top level + instances", self.top_level),
            ("upload", self.upload),
            ("encode + submit", self.encode_submit),
            ("skinning (GPU)", self.skinning_gpu),
            ("refit (GPU)", self.refit_gpu),
            ("trace + accumulate (GPU)", self.trace_and_accumulate_gpu),
            ("tonemap (GPU)", self.tonemap_gpu),
        ]
    }

    pub fn total(&self) -> f64 {
        self.parts().iter().map(|p| p.1).sum()
    }
}

/// One (scene, size) of the throughput table. The first keys are those docs/BENCHMARKS.md has always used.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FrameRow {
    pub scene: String,
    pub triangles: usize,
    pub width: u32,
    pub height: u32,
    pub spp_per_frame: u32,
    pub max_depth: u32,
    /// The form of the path integrator that traced the measured frames (`--integrator`, resolved by `auto`'s
    /// trial on the warm-up frames).
    pub integrator: String,
    /// `auto`'s trial: the fastest trace ms of a timed frame of the megakernel and of the wavefront form.
    pub auto_trial_ms: Option<[f64; 2]>,
    /// Whether the waves sorted their rays, and `auto`'s trial of that: the fastest trace ms of a timed frame
    /// of the waves unsorted and sorted.
    pub rays_sorted: bool,
    pub sort_trial_ms: Option<[f64; 2]>,
    pub frames: usize,
    pub bvh_build_and_upload_ms: f64,
    pub gpu_memory_geometry_bvh_mib: f64,
    pub bytes_per_triangle_geometry_bvh: f64,
    pub trace_ms_median: f64,
    pub trace_ms_p99: f64,
    pub timing_source: &'static str,
    pub primary_rays_per_s: f64,
    pub all_rays_per_s: f64,
    pub rays_per_pixel_per_frame: f64,
    /// Wall time of a whole frame (`App::update`, which waits for the GPU while pass timing is on).
    pub frame_ms: Spread,
    pub trace_ms: Spread,
    pub passes_median_ms: PassBreakdown,
    pub animated: bool,
    /// Where deformable meshes were skinned, morphed and refit (`--deform`, resolved for the adapter).
    pub deform_backend: String,
    /// Median skinning + refit per frame per 100k deformable triangles (CPU phases on the CPU backend, GPU
    /// passes on the GPU backend; the target is <= 1 ms); 0 for static scenes.
    pub skin_refit_ms_per_100k_tris: f64,
    pub bvh_rebuilds: u64,
    pub max_sah_ratio_last_frame: f32,
    /// Shading-free ray casting (`HeadlessApp::cast_rays`) on the last pose: camera rays per second, and
    /// diffuse bounce rays per second (the extra rays over the extra time when one bounce is added); 0 without
    /// timestamp queries.
    pub raycast_camera_rays_per_s: f64,
    pub raycast_diffuse_rays_per_s: f64,
    /// The same rays' traversal work per ray, counted in a second run (`HeadlessApp::count_traversal_work`).
    pub traversal_per_camera_ray: WorkPerRay,
    pub traversal_per_bounce_ray: WorkPerRay,
}

/// Traversal work of one ray on average, and the bytes it fetches if nothing were cached.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct WorkPerRay {
    pub tlas_nodes: f64,
    pub bvh2_nodes: f64,
    pub wide_nodes: f64,
    pub triangles: f64,
    pub bytes: f64,
}

/// Bytes fetched per top-level or BVH2 node (two child boxes), per wide node (CWBVH, five 16-byte texels) and
/// per triangle tested (its 16-byte record and three 12-byte positions; the material's flag word for the alpha
/// test is left out: it shares a cache line with the rest of the material).
const BVH2_NODE_BYTES: f64 = 64.0;
const WIDE_NODE_BYTES: f64 = 80.0;
const TRIANGLE_BYTES: f64 = 16.0 + 3.0 * 12.0;

impl WorkPerRay {
    fn of(counts: [u64; 4], rays: u64) -> Self {
        let per = |c: u64| c as f64 / rays.max(1) as f64;
        let [tlas_nodes, bvh2_nodes, wide_nodes, triangles] = counts.map(per);
        Self {
            tlas_nodes,
            bvh2_nodes,
            wide_nodes,
            triangles,
            bytes: (tlas_nodes + bvh2_nodes) * BVH2_NODE_BYTES
                + wide_nodes * WIDE_NODE_BYTES
                + triangles * TRIANGLE_BYTES,
        }
    }
}

/// The ray-casting pass's work per camera ray and per bounce ray (one counting run with the diffuse bounce).
fn traversal_per_ray(app: &mut HeadlessApp) -> (WorkPerRay, WorkPerRay) {
    let (work, rays) = app.count_traversal_work(true);
    let pixels = {
        let s = app.app.world().resource::<raykin::render::RenderSettings>();
        s.width as u64 * s.height as u64
    };
    (
        WorkPerRay::of(work.camera, pixels),
        WorkPerRay::of(work.bounce, rays.saturating_sub(pixels)),
    )
}

/// A frame loop over `scene` at `settings`' size: `warmup` frames (more on a GPU: [`super::warm_up`]), then
/// `frames` measured.
pub fn measure(
    ctx: &GpuContext,
    scene: &BenchScene,
    settings: RenderSettings,
    warmup: usize,
    frames: usize,
) -> Result<FrameRow> {
    let (width, height) = (settings.width, settings.height);
    let mut app = super::open_app(ctx, scene, settings.clone())?;
    app.accumulation_mut().display_each_frame = true;
    let mut samples: Vec<[f64; SAMPLE_COLUMNS]> = Vec::with_capacity(frames);
    let mut rays = 0u64;
    super::warm_up(&mut app, warmup);
    for _ in 0..frames {
        let start = std::time::Instant::now();
        app.step();
        let wall = start.elapsed().as_secs_f64() * 1e3;
        rays += app.view().read_ray_count(&app.ctx);
        samples.push(frame_sample(&app, wall));
    }
    let column = |i: usize| Spread::of(&samples.iter().map(|s| s[i]).collect::<Vec<_>>());
    let passes = PassBreakdown {
        animate: column(0).median,
        transform: column(1).median,
        skinning: column(2).median,
        refit: column(3).median,
        rebuild: column(4).median,
        top_level: column(5).median,
        upload: column(6).median,
        encode_submit: column(7).median,
        trace_and_accumulate_gpu: column(8).median,
        tonemap_gpu: column(9).median,
        skinning_gpu: column(11).median,
        refit_gpu: column(12).median,
    };
    let gpu_timed = app.pass_times().is_some();
    // Without timestamps the trace column holds whole-frame wall times.
    let trace = if gpu_timed { column(8) } else { column(10) };
    let frame = column(10);
    let trace_total_s: f64 = samples
        .iter()
        .map(|s| if gpu_timed { s[8] } else { s[10] })
        .sum::<f64>()
        / 1e3;
    let pixels = width as f64 * height as f64;
    let spp = settings.spp_per_frame as f64;
    let (raycast_camera, raycast_diffuse) = raycast_rates(&mut app, frames.clamp(1, 50));
    let (traversal_camera, traversal_bounce) = traversal_per_ray(&mut app);
    let memory = app.gpu_scene().memory;
    let triangles = scene.scene.triangle_count();
    let deformable_triangles: usize = scene
        .scene
        .meshes
        .iter()
        .filter(|m| m.is_deformable())
        .map(|m| m.triangles.len())
        .sum();
    let gpu_deform = app.deformation().deformer.is_some();
    let skin_refit_ms = if gpu_deform {
        passes.skinning_gpu + passes.refit_gpu
    } else {
        passes.skinning + passes.refit
    };
    let deform_backend = format!("{:?}", app.deformation().backend);
    let choice = app.integrator_choice();
    let integrator = choice
        .last_form()
        .map_or("none", raykin::render::Integrator::name)
        .to_string();
    let auto_trial_ms = choice.decision().map(|d| [d.megakernel_ms, d.wavefront_ms]);
    let rays_sorted = choice.rays_sorted();
    let sort_trial_ms = choice.sort_decision().map(|d| [d.unsorted_ms, d.sorted_ms]);
    let stats = app.bvh_stats();
    Ok(FrameRow {
        scene: scene.name.clone(),
        triangles,
        width,
        height,
        spp_per_frame: settings.spp_per_frame,
        max_depth: settings.max_depth,
        integrator,
        auto_trial_ms,
        rays_sorted,
        sort_trial_ms,
        frames,
        bvh_build_and_upload_ms: app.gpu_scene().build_seconds * 1e3,
        gpu_memory_geometry_bvh_mib: memory.geometry_and_bvh() as f64 / 1048576.0,
        bytes_per_triangle_geometry_bvh: memory.geometry_and_bvh() as f64 / triangles.max(1) as f64,
        trace_ms_median: trace.median,
        trace_ms_p99: trace.p99,
        timing_source: if gpu_timed {
            "gpu-timestamps"
        } else {
            "cpu-wall"
        },
        primary_rays_per_s: pixels * spp * frames as f64 / trace_total_s,
        all_rays_per_s: rays as f64 / trace_total_s,
        rays_per_pixel_per_frame: rays as f64 / (pixels * frames as f64),
        frame_ms: frame,
        trace_ms: trace,
        passes_median_ms: passes,
        animated: scene.animated(),
        deform_backend,
        skin_refit_ms_per_100k_tris: if deformable_triangles > 0 {
            skin_refit_ms / (deformable_triangles as f64 / 1e5)
        } else {
            0.0
        },
        bvh_rebuilds: stats.rebuilds,
        max_sah_ratio_last_frame: stats.sah_ratio.iter().copied().fold(0.0, f32::max),
        raycast_camera_rays_per_s: raycast_camera,
        raycast_diffuse_rays_per_s: raycast_diffuse,
        traversal_per_camera_ray: traversal_camera,
        traversal_per_bounce_ray: traversal_bounce,
    })
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
    let camera = r0 as f64 / (t0 / 1e3);
    let diffuse = if t1 > t0 {
        (r1 - r0) as f64 / ((t1 - t0) / 1e3)
    } else {
        0.0
    };
    (camera, diffuse)
}

const SAMPLE_COLUMNS: usize = 13;

/// This frame's pass times: [animate, transform, skinning, refit, rebuild, top level, upload,
/// encode/submit, trace GPU, tonemap GPU, frame wall, skinning GPU, refit GPU].
fn frame_sample(app: &HeadlessApp, wall_ms: f64) -> [f64; SAMPLE_COLUMNS] {
    let world = app.app.world();
    let t = world.resource::<raykin::frame_timing::FrameTimings>().last;
    let stats = app.bvh_stats();
    let refit = stats.last_refit_seconds * 1e3;
    let rebuild = stats.last_rebuild_seconds * 1e3;
    let gpu = app.pass_times();
    let (trace, tonemap) = gpu.map_or((f64::NAN, f64::NAN), |p| (p.trace_ms, p.tonemap_ms));
    let (skin_gpu, refit_gpu) = gpu.map_or((0.0, 0.0), |p| (p.skin_ms, p.refit_ms));
    let gpu_total = gpu.map_or(0.0, |p| p.trace_ms + p.tonemap_ms + p.skin_ms + p.refit_ms);
    [
        t.animate_ms,
        t.transform_ms,
        t.deform_ms,
        refit,
        rebuild,
        (t.bvh_ms - refit - rebuild).max(0.0),
        t.upload_ms,
        (t.render_ms - gpu_total).max(0.0),
        trace,
        tonemap,
        wall_ms,
        skin_gpu,
        refit_gpu,
    ]
}

//! The real-time path: what it keeps beside the view while anything moves, and what it remembers between
//! frames. The passes are in `render::passes` (gbuffer, restir_di, realtime_trace, gradient, temporal, denoise,
//! handover); `render::frame` orders them. docs/ARCHITECTURE.md lists the buffers; docs/ACCURACY.md the methods
//! and their failure regimes.
//!
//! - [`RealtimeTargets`]: view-size buffers (G-buffers of this and the previous frame, samples, colour history
//!   in the accumulation's layout, gradient strata, ReSTIR reservoirs), made at the first real-time frame and
//!   replaced on resize.
//! - [`RealtimeState`]: the frame index, the previous camera, which history is valid, and what invalidated it.
//! - [`scene_motion`]: the systems that keep the scene's previous-frame data (`gpu_scene::motion`) current.

pub mod scene_motion;

use super::layout::*;
use super::passes::denoise::Denoiser;
use super::passes::{gbuffer::GBufferPass, gradient::GradientPass, handover::HandoverPass};
use super::passes::{
    realtime_trace::RealtimeTracePass, restir_di::RestirDiPass, temporal::TemporalPass,
};
use super::settings::RenderSettings;
use crate::camera::CameraView;
use crate::gpu::GpuContext;
use crate::gpu::bind::{
    Binding, CachedGroup, bind_group, compute_layout, storage_buffer, uniform_buffer,
};
use bevy_ecs::prelude::Resource;

/// A-SVGF: a-trous iterations over the gradient strata (taps 1, 2, 4 strata apart: 15 strata, 45 pixels
/// across); the `gradient` pass runs them and the `temporal` pass reads their result.
pub const GRADIENT_FILTER_ITERATIONS: usize = 3;
/// Which of the two gradient buffers holds the filtered gradients: shading writes 0, iterations alternate.
pub const FILTERED_GRADIENTS: usize = GRADIENT_FILTER_ITERATIONS % 2;

/// The bind groups of the scene (group 0) and its previous-frame data (group 2), shared by the real-time
/// kernels that trace rays.
pub struct SceneGroups<'a> {
    pub scene: &'a wgpu::BindGroup,
    pub motion: &'a wgpu::BindGroup,
}

impl SceneGroups<'_> {
    /// A compute pass of a real-time kernel over the scene: the scene as group 0, the pass's own `group` as
    /// group 1, the scene's motion as group 2.
    pub fn begin_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        label: &str,
        group: &wgpu::BindGroup,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) -> wgpu::ComputePass<'e> {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes,
        });
        pass.set_bind_group(0, self.scene, &[]);
        pass.set_bind_group(1, group, &[]);
        pass.set_bind_group(2, self.motion, &[]);
        pass
    }
}

/// A colour history in the accumulation's layout (sums over the history length; see `temporal.wgsl`).
pub struct HistoryBuffers {
    pub accum: wgpu::Buffer,
    pub albedo_depth: wgpu::Buffer,
    pub normal_hits: wgpu::Buffer,
    pub moments: wgpu::Buffer,
}

impl HistoryBuffers {
    fn new(ctx: &GpuContext, pixels: u64, label: &str) -> Self {
        let b = |what: &str| storage_buffer(ctx, &format!("{label} {what}"), pixels * 16);
        Self {
            accum: b("radiance"),
            albedo_depth: b("albedo depth"),
            normal_hits: b("normal hits"),
            moments: b("moments"),
        }
    }

    pub fn buffers(&self) -> [&wgpu::Buffer; 4] {
        [
            &self.accum,
            &self.albedo_depth,
            &self.normal_hits,
            &self.moments,
        ]
    }
}

/// ReSTIR DI's per-pixel buffers, made when it first runs.
pub struct RestirTargets {
    /// The final reservoirs, kept for the next frame.
    pub reservoirs: wgpu::Buffer,
    pub reservoirs_temporal: wgpu::Buffer,
    /// Direct light at each pixel's first hit.
    pub direct_light: wgpu::Buffer,
}

/// Bytes per pixel: two G-buffers (64 each), the samples (32), two histories (64 each), the hand-over image (16).
const BYTES_PER_PIXEL: u64 = 2 * 64 + 32 + 2 * 64 + 16;
/// Bytes per pixel of ReSTIR's buffers.
const RESTIR_BYTES_PER_PIXEL: u64 = 3 * 16;

pub struct RealtimeTargets {
    pub width: u32,
    pub height: u32,
    /// Unique across targets and bumped when a buffer is added, so passes rebind.
    pub generation: u64,
    /// The real-time uniform (`GpuRealtimeFrame`).
    pub uniform: wgpu::Buffer,
    pub gbuffer: wgpu::Buffer,
    pub gbuffer_prev: wgpu::Buffer,
    pub samples: wgpu::Buffer,
    /// This frame's colour history (what the spatial filter and the display read) and last frame's.
    pub history: HistoryBuffers,
    pub history_prev: HistoryBuffers,
    /// Gradient strata across and down.
    pub strata: (u32, u32),
    /// Per stratum: the luminance of the estimate the next frame shades again.
    pub gradient_estimates: wgpu::Buffer,
    /// Per stratum: gradients, ping-pong through the filter.
    pub gradients: [wgpu::Buffer; 2],
    pub restir: Option<RestirTargets>,
    /// Bits of the materials edited since last frame.
    pub edited_materials: wgpu::Buffer,
    /// The hand-over's mix of the last real-time image and the accumulation.
    pub handover: wgpu::Buffer,
    /// Bound where a stage that is off leaves a binding unused.
    pub stub: wgpu::Buffer,
    /// The spatial filter over the history (its own buffers: the accumulation's denoiser keeps its own).
    pub denoiser: Denoiser,
}

fn next_generation() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

impl RealtimeTargets {
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Self {
        let pixels = (width as u64 * height as u64).max(1);
        let strata = (
            width.div_ceil(GRADIENT_STRATUM).max(1),
            height.div_ceil(GRADIENT_STRATUM).max(1),
        );
        let strata_count = strata.0 as u64 * strata.1 as u64;
        let targets = Self {
            width,
            height,
            generation: next_generation(),
            uniform: uniform_buffer(
                ctx,
                "realtime frame",
                std::mem::size_of::<GpuRealtimeFrame>(),
            ),
            gbuffer: storage_buffer(ctx, "gbuffer", pixels * 64),
            gbuffer_prev: storage_buffer(ctx, "gbuffer previous", pixels * 64),
            samples: storage_buffer(ctx, "realtime samples", pixels * 32),
            history: HistoryBuffers::new(ctx, pixels, "history"),
            history_prev: HistoryBuffers::new(ctx, pixels, "history previous"),
            strata,
            gradient_estimates: storage_buffer(ctx, "gradient estimates", strata_count * 4),
            gradients: [
                storage_buffer(ctx, "gradients a", strata_count * 16),
                storage_buffer(ctx, "gradients b", strata_count * 16),
            ],
            restir: None,
            edited_materials: storage_buffer(ctx, "edited materials", 16),
            handover: storage_buffer(ctx, "handover image", pixels * 16),
            stub: storage_buffer(ctx, "realtime stub", 16),
            denoiser: Denoiser::new(ctx),
        };
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        for b in [
            &targets.gbuffer,
            &targets.gbuffer_prev,
            &targets.samples,
            &targets.stub,
        ]
        .into_iter()
        .chain(targets.history.buffers())
        .chain(targets.history_prev.buffers())
        .chain(&targets.gradients)
        {
            encoder.clear_buffer(b, 0, None);
        }
        ctx.queue.submit([encoder.finish()]);
        targets
    }

    /// Makes ReSTIR's buffers the first time it runs.
    pub fn ensure_restir(&mut self, ctx: &GpuContext) {
        if self.restir.is_none() {
            let pixels = (self.width as u64 * self.height as u64).max(1);
            let restir = RestirTargets {
                reservoirs: storage_buffer(ctx, "reservoirs", pixels * 16),
                reservoirs_temporal: storage_buffer(ctx, "reservoirs temporal", pixels * 16),
                direct_light: storage_buffer(ctx, "restir direct light", pixels * 16),
            };
            self.restir = Some(restir);
            self.generation = next_generation();
        }
    }

    /// Uploads the set of edited materials as bits.
    pub fn write_edited_materials(&mut self, ctx: &GpuContext, materials: &[u32]) {
        let Some(&max) = materials.iter().max() else {
            return;
        };
        let mut bits = vec![0u32; (max as usize / 32 + 1).max(4)];
        for &m in materials {
            bits[m as usize / 32] |= 1 << (m % 32);
        }
        if crate::gpu::bind::write_or_grow(
            ctx,
            &mut self.edited_materials,
            bytemuck::cast_slice(&bits),
            "edited materials",
        ) {
            self.generation = next_generation();
        }
    }

    /// GPU memory of these targets (the spatial filter's once it ran).
    pub fn memory_bytes(&self) -> u64 {
        let pixels = self.width as u64 * self.height as u64;
        pixels * BYTES_PER_PIXEL
            + self
                .restir
                .as_ref()
                .map_or(0, |_| pixels * RESTIR_BYTES_PER_PIXEL)
            + self.strata.0 as u64 * self.strata.1 as u64 * 36
            + self.denoiser.memory_bytes()
    }

    pub fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }
}

/// The real-time passes, built the first time the real-time path runs (their kernels compile the whole
/// traversal, which a session that never uses it should not pay for).
pub struct RealtimePasses {
    pub gbuffer: GBufferPass,
    pub restir: RestirDiPass,
    pub trace: RealtimeTracePass,
    pub gradient: GradientPass,
    pub temporal: TemporalPass,
    pub handover: HandoverPass,
    pub motion_layout: wgpu::BindGroupLayout,
    motion_group: CachedGroup<u64>,
}

/// Buffers of group 2 (`shaders/realtime/motion.wgsl`).
const MOTION_BINDINGS: usize = 5;

impl RealtimePasses {
    pub fn new(ctx: &GpuContext, scene_layout: &wgpu::BindGroupLayout) -> Self {
        let motion_layout = compute_layout(ctx, "scene motion", &[Binding::Read; MOTION_BINDINGS]);
        Self {
            gbuffer: GBufferPass::new(ctx, scene_layout, &motion_layout),
            restir: RestirDiPass::new(ctx, scene_layout, &motion_layout),
            trace: RealtimeTracePass::new(ctx, scene_layout, &motion_layout),
            gradient: GradientPass::new(ctx, scene_layout, &motion_layout),
            temporal: TemporalPass::new(ctx),
            handover: HandoverPass::new(ctx),
            motion_layout,
            motion_group: CachedGroup::default(),
        }
    }

    /// Group 2 over the scene's previous-frame data.
    pub fn motion_group(
        &mut self,
        ctx: &GpuContext,
        motion: &super::gpu_scene::motion::SceneMotion,
    ) -> wgpu::BindGroup {
        let layout = &self.motion_layout;
        self.motion_group
            .get_or_make(motion.generation, || {
                bind_group(
                    ctx,
                    "scene motion",
                    layout,
                    &[
                        &motion.instances,
                        &motion.object_instances,
                        &motion.prev_positions,
                        &motion.mesh_motion,
                        &motion.light_remap,
                    ],
                )
            })
            .clone()
    }
}

/// What the last frame showed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Shown {
    /// Plain accumulation (accumulate mode, or a still after the hand-over).
    #[default]
    Accumulation,
    /// A real-time frame.
    Realtime,
    /// The real-time image mixed with the accumulation of a still.
    Handover,
}

/// What the real-time path remembers between frames.
#[derive(Default)]
pub struct RealtimeState {
    /// Real-time frames so far: the sample index of this frame's random numbers (the gradient pass shades
    /// last frame's again with index - 1).
    pub frame_index: u32,
    prev_camera: Option<CameraView>,
    last_settings: Option<RenderSettings>,
    /// The colour history and last frame's G-buffer are valid.
    history_valid: bool,
    /// Last frame's reservoirs are valid.
    reservoirs_valid: bool,
    /// Last frame wrote gradient estimates.
    estimates_valid: bool,
    /// Materials edited since the last real-time frame (their pixels start afresh).
    pub edited_materials: Vec<u32>,
    /// Drop every history at the next frame (a camera cut, a scene change).
    pub reset_requested: bool,
    pub shown: Shown,
    /// How many times every history was dropped (resize, cut, settings, reset).
    pub resets: u64,
}

/// Everything the real-time path holds: empty until it first runs.
#[derive(Resource, Default)]
pub struct Realtime {
    pub passes: Option<RealtimePasses>,
    pub targets: Option<RealtimeTargets>,
    pub state: RealtimeState,
}

/// What this frame's real-time passes do, decided by [`RealtimeState::begin_frame`].
#[derive(Clone, Copy, Debug)]
pub struct RealtimeFramePlan {
    pub uniform: GpuRealtimeFrame,
    pub restir: bool,
    /// Shade last frame's gradient sources again (gradients on, and last frame wrote estimates).
    pub gradients: bool,
    pub spatial: bool,
}

impl Realtime {
    /// The targets at the view's size (new ones, with every history invalid, when the size changed).
    pub fn targets_for(
        &mut self,
        ctx: &GpuContext,
        width: u32,
        height: u32,
    ) -> &mut RealtimeTargets {
        if self
            .targets
            .as_ref()
            .is_none_or(|t| (t.width, t.height) != (width, height))
        {
            self.targets = Some(RealtimeTargets::new(ctx, width, height));
            self.state.invalidate();
        }
        self.targets.as_mut().expect("made above")
    }

    /// Frees the view-size buffers (the view was resized; the next real-time frame makes them again).
    pub fn release_targets(&mut self) {
        self.targets = None;
        self.state.invalidate();
    }
}

/// Cosine of the largest view rotation between two frames that still reprojects (beyond: a camera cut).
const CUT_COSINE: f32 = 0.7;

impl RealtimeState {
    fn invalidate(&mut self) {
        self.history_valid = false;
        self.reservoirs_valid = false;
        self.estimates_valid = false;
        self.resets += 1;
    }

    /// A frame that showed plain accumulation while things moved (accumulate mode): the next real-time frame
    /// has no usable previous frame.
    pub fn skipped_frame(&mut self) {
        self.invalidate();
        self.prev_camera = None;
        self.shown = Shown::Accumulation;
    }

    /// Decides this frame's stages and uniform; `lights` says whether any light-sampler light exists and
    /// `lights_remapped` whether the light list changed since last frame.
    pub fn begin_frame(
        &mut self,
        settings: &RenderSettings,
        camera: &CameraView,
        size: (u32, u32),
        lights: bool,
        lights_remapped: bool,
        strata: (u32, u32),
    ) -> RealtimeFramePlan {
        let rt = &settings.realtime;
        let settings_changed = self
            .last_settings
            .as_ref()
            .is_none_or(|s| s.changes_image(settings) || s.realtime != settings.realtime);
        let cut = self.prev_camera.is_none_or(|prev| is_cut(&prev, camera));
        if settings_changed || cut || self.reset_requested {
            self.invalidate();
        }
        self.reset_requested = false;
        if self.last_settings.as_ref() != Some(settings) {
            self.last_settings = Some(settings.clone());
        }
        let prev = self.prev_camera.unwrap_or(*camera);
        let restir = rt.restir.enabled && settings.nee && lights;
        let r = &rt.restir;
        let mut flags = 0;
        let mut set = |on: bool, bit: u32| {
            if on {
                flags |= bit;
            }
        };
        set(rt.temporal, RT_TEMPORAL);
        set(self.history_valid, RT_HISTORY);
        set(rt.gradients && rt.temporal, RT_GRADIENTS);
        set(restir, RT_RESTIR);
        set(r.temporal, RT_RESTIR_TEMPORAL);
        set(r.spatial, RT_RESTIR_SPATIAL);
        set(r.unbiased, RT_RESTIR_UNBIASED);
        set(r.visibility_reuse, RT_RESTIR_VISIBILITY);
        set(
            self.reservoirs_valid && self.history_valid,
            RT_RESTIR_HISTORY,
        );
        set(lights_remapped, RT_LIGHTS_REMAPPED);
        set(!self.edited_materials.is_empty(), RT_MATERIALS_EDITED);
        set(rt.inject_nonfinite, RT_INJECT_NONFINITE);
        let radius = if r.radius > 0.0 {
            r.radius
        } else {
            (0.025 * size.1 as f32).max(3.0)
        };
        let uniform = GpuRealtimeFrame {
            camera_from_world: camera.world_from_camera.inverse().to_cols_array_2d(),
            prev_camera_from_world: prev.world_from_camera.inverse().to_cols_array_2d(),
            prev_camera_origin: prev.world_from_camera.w_axis.truncate().to_array(),
            prev_tan_half_fov: (prev.yfov * 0.5).tan(),
            flags,
            history_cap: rt.history_cap.max(1) as f32,
            strata_width: strata.0,
            strata_height: strata.1,
            restir_candidates: r.candidates.clamp(1, 64),
            restir_neighbours: r.neighbours.min(8),
            restir_radius: radius,
            restir_max_confidence: r.max_confidence.max(1.0),
            depth_tolerance: rt.depth_tolerance.max(0.0),
            normal_tolerance: rt.normal_tolerance.clamp(-1.0, 1.0),
            _pad: [0; 2],
        };
        RealtimeFramePlan {
            uniform,
            restir,
            gradients: rt.gradients && rt.temporal && self.history_valid && self.estimates_valid,
            spatial: rt.spatial,
        }
    }

    /// After the frame's passes were recorded: what the next frame may reuse.
    pub fn end_frame(&mut self, camera: &CameraView, plan: &RealtimeFramePlan) {
        self.prev_camera = Some(*camera);
        self.history_valid = true;
        self.reservoirs_valid = plan.restir;
        self.estimates_valid = plan.uniform.flags & RT_GRADIENTS != 0;
        self.edited_materials.clear();
        self.frame_index = self.frame_index.wrapping_add(1);
        self.shown = Shown::Realtime;
    }
}

/// The view turned too far, or the field of view changed too much, for last frame to say anything.
fn is_cut(prev: &CameraView, now: &CameraView) -> bool {
    let forward = |c: &CameraView| -c.world_from_camera.z_axis.truncate().normalize_or_zero();
    let turned = forward(prev).dot(forward(now)) < CUT_COSINE;
    let zoomed = (prev.yfov / now.yfov.max(1e-6)).ln().abs() > 0.5;
    turned || zoomed
}

/// Whether the real-time path makes this frame's image (it does not for the AOV views, which show the
/// accumulation's first-hit buffers).
pub fn runs(settings: &RenderSettings) -> bool {
    settings.mode == super::settings::RenderMode::Realtime
        && settings.view == super::settings::AovView::Color
}

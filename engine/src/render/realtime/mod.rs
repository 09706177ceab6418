//! The real-time path: what it keeps beside the view while anything moves, and what it remembers between
//! frames. The passes are in `render::passes` (gbuffer, restir_di, realtime_trace, gradient, temporal, denoise,
//! handover); `render::frame` orders them. docs/ARCHITECTURE.md lists the buffers; docs/ACCURACY.md the methods
//! and their failure regimes.
//!
//! - `render::realtime_targets`: the view-size buffers (re-exported here), made at the first real-time frame
//!   and replaced on resize, with the spatial filter ([`Realtime::spatial_filter`]) beside them.
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
use crate::gpu::bind::{Binding, CachedGroup, bind_group, compute_layout};
use bevy_ecs::prelude::Resource;

pub use super::realtime_targets::*;

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
        let layouts = SceneLayouts {
            scene: scene_layout,
            motion: &motion_layout,
        };
        Self {
            gbuffer: GBufferPass::new(ctx, &layouts),
            restir: RestirDiPass::new(ctx, &layouts),
            trace: RealtimeTracePass::new(ctx, &layouts),
            gradient: GradientPass::new(ctx, &layouts),
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

/// Which image a real-time frame displayed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RealtimeImage {
    /// The colour history itself (no spatial filter).
    #[default]
    History,
    /// The a-trous filter's output over the history.
    Spatial,
    /// The external denoiser's (`render::frame_denoiser`, OIDN per frame): [`Realtime::external_image`].
    External,
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
    /// What the last real-time frame displayed.
    pub image: RealtimeImage,
    /// How many times every history was dropped (resize, cut, settings, reset).
    pub resets: u64,
}

/// Everything the real-time path holds: empty until it first runs.
#[derive(Resource, Default)]
pub struct Realtime {
    pub passes: Option<RealtimePasses>,
    pub targets: Option<RealtimeTargets>,
    /// The SVGF spatial filter over the history, with its own view-size buffers (the accumulation's
    /// denoiser keeps its own); made and released with the targets.
    pub spatial_filter: Option<Denoiser>,
    /// The external denoiser's output in the display's layout (`HostDenoised::image_buffer`), made at its
    /// first frame; released with the targets.
    pub external_image: Option<wgpu::Buffer>,
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
            self.spatial_filter = Some(Denoiser::new(ctx));
            self.external_image = None;
            self.state.invalidate();
        }
        self.targets.as_mut().expect("made above")
    }

    /// Frees the view-size buffers (the view was resized; the next real-time frame makes them again).
    pub fn release_targets(&mut self) {
        self.targets = None;
        self.spatial_filter = None;
        self.external_image = None;
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

    /// After the frame's passes were recorded: what the next frame may reuse, and which `image` it showed.
    pub fn end_frame(
        &mut self,
        camera: &CameraView,
        plan: &RealtimeFramePlan,
        image: RealtimeImage,
    ) {
        self.image = image;
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

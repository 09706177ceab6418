//! The real-time path's view-size targets: G-buffers of this and the previous frame, samples, colour
//! histories in the accumulation's layout, gradient strata and ReSTIR reservoirs, made at the first real-time
//! frame and replaced on resize; and the bind groups its kernels share. Apart from `render::realtime` (which
//! builds the passes) so that the passes can bind these without importing their owner, as `render::view`
//! holds the accumulation's targets.

use super::layout::*;
use crate::gpu::GpuContext;
use crate::gpu::bind::{clear_buffers, params_buffer, storage_buffer};

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

/// The layouts behind [`SceneGroups`]: a real-time kernel is built over the scene (group 0), its pass's own
/// layout (group 1) and the scene's motion (group 2), the order [`SceneGroups::begin_pass`] binds them in.
pub struct SceneLayouts<'a> {
    pub scene: &'a wgpu::BindGroupLayout,
    pub motion: &'a wgpu::BindGroupLayout,
}

impl<'a> SceneLayouts<'a> {
    /// The pipeline's group layouts with `pass` as group 1.
    pub fn with_pass(
        &self,
        pass: &'a wgpu::BindGroupLayout,
    ) -> [Option<&'a wgpu::BindGroupLayout>; 3] {
        [Some(self.scene), Some(pass), Some(self.motion)]
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
    /// The history as an external denoiser reads an accumulation of `view`'s size.
    pub fn denoiser_sources(
        &self,
        view: &super::view::ViewTargets,
    ) -> super::view::DenoiserSources {
        super::view::DenoiserSources {
            accum: self.accum.clone(),
            albedo_depth: self.albedo_depth.clone(),
            normal_hits: self.normal_hits.clone(),
            moments: self.moments.clone(),
            width: view.width,
            height: view.height,
        }
    }

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
            uniform: params_buffer(
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
        };
        clear_buffers(
            ctx,
            [
                &targets.gbuffer,
                &targets.gbuffer_prev,
                &targets.samples,
                &targets.stub,
            ]
            .into_iter()
            .chain(targets.history.buffers())
            .chain(targets.history_prev.buffers())
            .chain(&targets.gradients),
        );
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

    /// GPU memory of these targets.
    pub fn memory_bytes(&self) -> u64 {
        let pixels = self.width as u64 * self.height as u64;
        pixels * BYTES_PER_PIXEL
            + self
                .restir
                .as_ref()
                .map_or(0, |_| pixels * RESTIR_BYTES_PER_PIXEL)
            + self.strata.0 as u64 * self.strata.1 as u64 * 36
    }

    pub fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }
}

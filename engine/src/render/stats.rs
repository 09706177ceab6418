//! What the frame's passes cost on the GPU: timestamp pairs around the trace, tone-map and denoise passes, read
//! back either blocking (benches: `time_passes`) or without stalling through a small ring of staging buffers
//! (the viewer: [`FrameStats::enable_async`]).

use crate::gpu::readback::AsyncReadback;
use crate::gpu::{GpuContext, PassTimestamps};
use bevy_ecs::prelude::Resource;

/// GPU time of the last frame's passes, in milliseconds (0 for a pass that did not run).
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct PassTimes {
    pub trace_ms: f64,
    pub tonemap_ms: f64,
    /// 0 when the last frame did not denoise.
    pub denoise_ms: f64,
    /// GPU skinning + morphing (`passes/deform`).
    pub skin_ms: f64,
    /// GPU BLAS refit + SAH cost (`passes/refit`).
    pub refit_ms: f64,
    /// The real-time path's G-buffer (`passes/gbuffer`); on its frames `trace_ms` is the real-time trace's
    /// and `denoise_ms` its spatial filter's.
    pub gbuffer_ms: f64,
    /// ReSTIR DI: candidates + temporal reuse, spatial reuse + shading (`passes/restir_di`).
    pub restir_ms: f64,
    /// Temporal gradients: shading + filter (`passes/gradient`).
    pub gradient_ms: f64,
    /// Temporal accumulation (`passes/temporal`).
    pub temporal_ms: f64,
}

/// Timestamp pair of each real-time pass within the real-time query set.
pub const GBUFFER_PAIR: u32 = 0;
pub const RESTIR_PAIR: u32 = 1;
pub const GRADIENT_PAIR: u32 = 2;
pub const REALTIME_TRACE_PAIR: u32 = 3;
pub const TEMPORAL_PAIR: u32 = 4;
pub const SPATIAL_PAIR: u32 = 5;
const REALTIME_PAIRS: u32 = 6;

/// What one frame cost on the GPU, read back without blocking.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct GpuFrameStats {
    /// Index of the frame (counts every traced frame).
    pub dispatch: u64,
    /// `None` without timestamp support.
    pub passes: Option<PassTimes>,
    /// Camera, bounce and shadow rays traced.
    pub rays: u64,
}

/// Camera rays, and optionally one diffuse bounce ray per hit, cast without shading.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct RayCastTiming {
    /// GPU time of the pass, from timestamp queries.
    pub gpu_ms: f64,
    pub rays: u64,
}

/// Timestamp pair of each pass within the frame's query set.
pub const TRACE_PAIR: u32 = 0;
pub const TONEMAP_PAIR: u32 = 1;

/// Bytes of one asynchronous statistics readback: trace + tonemap timestamps (32), denoise timestamps (16), ray
/// counter (4), padded; then the real-time passes' timestamps (96) and a flag word for real-time frames.
const STATS_BYTES: u64 = 64 + 16 * REALTIME_PAIRS as u64 + 16;
const REALTIME_OFFSET: u64 = 64;

#[derive(Resource)]
pub struct FrameStats {
    /// Pairs: trace, tonemap.
    pub timestamps: Option<PassTimestamps>,
    /// One pair around the denoiser's pass, resolved by every denoise (in a frame or not).
    pub denoise_timestamps: Option<PassTimestamps>,
    /// Pairs around the real-time passes (`*_PAIR`), resolved by every real-time frame.
    pub realtime_timestamps: Option<PassTimestamps>,
    /// Whether the last traced frame was a real-time one.
    pub realtime_last_frame: bool,
    /// GPU pass times of the last frame when `time_passes` is set (blocks the CPU each frame).
    pub time_passes: bool,
    pub last_pass_times: Option<PassTimes>,
    /// Whether the last frame ran the denoiser.
    pub denoised_last_frame: bool,
    /// Frames traced so far.
    pub frames: u64,
    async_stats: Option<AsyncReadback>,
}

impl FrameStats {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            timestamps: PassTimestamps::new(ctx, "pass timestamps", 2),
            denoise_timestamps: PassTimestamps::new(ctx, "denoise timestamps", 1),
            realtime_timestamps: PassTimestamps::new(ctx, "realtime timestamps", REALTIME_PAIRS),
            realtime_last_frame: false,
            time_passes: false,
            last_pass_times: None,
            denoised_last_frame: false,
            frames: 0,
            async_stats: None,
        }
    }

    pub fn pass_writes(&self, pair: u32) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.timestamps.as_ref().map(|t| t.pass_writes(pair))
    }

    pub fn denoise_writes(&self) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.denoise_timestamps.as_ref().map(|t| t.pass_writes(0))
    }

    pub fn realtime_writes(&self, pair: u32) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.realtime_timestamps
            .as_ref()
            .map(|t| t.pass_writes(pair))
    }

    /// Resolves the real-time pairs (after the frame's passes; a pass that did not run was timed empty).
    pub fn resolve_realtime(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(t) = &self.realtime_timestamps {
            t.resolve(encoder, REALTIME_PAIRS);
        }
    }

    /// Times pair `pair` over an empty compute pass: a stage that did not run this frame reads as 0 ms.
    pub fn time_skipped(&self, encoder: &mut wgpu::CommandEncoder, pair: u32) {
        if let Some(writes) = self.realtime_writes(pair) {
            drop(encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("skipped stage"),
                timestamp_writes: Some(writes),
            }));
        }
    }

    /// From now on every frame also copies its pass times and ray count into a small ring of staging buffers,
    /// read by [`Self::poll`] without stalling (the viewer's frame loop).
    pub fn enable_async(&mut self, ctx: &GpuContext) {
        if self.async_stats.is_none() {
            self.async_stats = Some(AsyncReadback::new(
                ctx,
                "frame stats readback",
                STATS_BYTES,
                3,
            ));
        }
    }

    /// Records this frame's copies into the asynchronous ring (when enabled).
    pub fn encode_async(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        ray_counter: &wgpu::Buffer,
        denoised: bool,
    ) {
        let Some(stats) = &mut self.async_stats else {
            return;
        };
        let mut sources = Vec::new();
        // Fixed offsets: timestamps at 0 (32 bytes), denoise at 32 (16), rays at 48 (4).
        if let Some(t) = &self.timestamps {
            sources.push((t.resolve_buffer(), 0, 32));
        }
        if let (true, Some(t)) = (denoised, &self.denoise_timestamps) {
            sources.push((t.resolve_buffer(), 32, 16));
        }
        sources.push((ray_counter, 48, 4));
        if let (true, Some(t)) = (self.realtime_last_frame, &self.realtime_timestamps) {
            sources.push((
                t.resolve_buffer(),
                REALTIME_OFFSET,
                16 * REALTIME_PAIRS as u64,
            ));
        }
        stats.encode(encoder, &sources, self.frames);
    }

    /// Call after the frame's submission: starts mapping the asynchronous copies.
    pub fn after_submit(&mut self) {
        if let Some(stats) = &mut self.async_stats {
            stats.after_submit();
        }
    }

    /// Statistics of finished frames since the last call, oldest first.
    pub fn poll(&mut self, ctx: &GpuContext) -> Vec<GpuFrameStats> {
        let Some(stats) = &mut self.async_stats else {
            return Vec::new();
        };
        let timestamps = self.timestamps.as_ref();
        let realtime = self.realtime_timestamps.as_ref();
        stats
            .poll(ctx)
            .into_iter()
            .map(|(dispatch, bytes)| {
                let passes = timestamps.map(|t| {
                    let ms = t.ms_from_bytes(&bytes[..48]);
                    let times = PassTimes {
                        trace_ms: ms[0],
                        tonemap_ms: ms[1],
                        denoise_ms: ms[2],
                        ..Default::default()
                    };
                    let end = (REALTIME_OFFSET + 16 * REALTIME_PAIRS as u64) as usize;
                    match realtime {
                        Some(r) if bytes[REALTIME_OFFSET as usize..end].iter().any(|&b| b != 0) => {
                            with_realtime(
                                times,
                                &r.ms_from_bytes(&bytes[REALTIME_OFFSET as usize..end]),
                            )
                        }
                        _ => times,
                    }
                });
                let rays = u32::from_le_bytes(bytes[48..52].try_into().unwrap_or_default());
                GpuFrameStats {
                    dispatch,
                    passes,
                    rays: rays as u64,
                }
            })
            .collect()
    }

    /// GPU times of the last frame (blocks until it finished); `None` without timestamp support.
    pub fn read_pass_times(&self, ctx: &GpuContext) -> Option<PassTimes> {
        let ms = self.timestamps.as_ref()?.read_ms(ctx);
        let times = PassTimes {
            trace_ms: ms[0],
            tonemap_ms: ms[1],
            denoise_ms: if self.denoised_last_frame {
                self.read_denoise_ms(ctx).unwrap_or(0.0)
            } else {
                0.0
            },
            ..Default::default()
        };
        match (&self.realtime_timestamps, self.realtime_last_frame) {
            (Some(r), true) => Some(with_realtime(times, &r.read_ms(ctx))),
            _ => Some(times),
        }
    }

    /// GPU time of the last denoise, in a frame or on its own (blocks until it finished); `None` without
    /// timestamp support.
    pub fn read_denoise_ms(&self, ctx: &GpuContext) -> Option<f64> {
        Some(self.denoise_timestamps.as_ref()?.read_ms(ctx)[0])
    }
}

/// A real-time frame's pass times: its own passes' pairs in place of the trace and denoise pairs.
fn with_realtime(times: PassTimes, ms: &[f64]) -> PassTimes {
    let at = |pair: u32| ms.get(pair as usize).copied().unwrap_or(0.0);
    PassTimes {
        trace_ms: at(REALTIME_TRACE_PAIR),
        denoise_ms: at(SPATIAL_PAIR),
        gbuffer_ms: at(GBUFFER_PAIR),
        restir_ms: at(RESTIR_PAIR),
        gradient_ms: at(GRADIENT_PAIR),
        temporal_ms: at(TEMPORAL_PAIR),
        ..times
    }
}

//! Pipelines and per-view buffers of the path tracer: dispatch, accumulation, tone mapping, readback, and GPU
//! timestamps around each pass where the adapter has them.

use super::denoise::{DenoiseInputs, DenoiseParams, Denoiser};
use super::layout::*;
use super::scene_buffers::GpuScene;
use super::settings::{AovView, DenoiserKind, Environment, RenderSettings};
use crate::camera::CameraView;
use crate::gpu::GpuContext;
use bytemuck::{Pod, Zeroable};
use std::sync::OnceLock;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct TonemapParams {
    width: u32,
    height: u32,
    tonemapper: u32,
    view: u32,
    exposure_scale: f32,
    depth_scale: f32,
    _pad: [u32; 2],
}

/// GPU time of the last frame's passes, in milliseconds (0 for a pass that did not run).
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct PassTimes {
    pub trace_ms: f64,
    pub tonemap_ms: f64,
    /// 0 when the last dispatch did not denoise.
    pub denoise_ms: f64,
    /// GPU skinning + morphing (`shaders/deform.wgsl`).
    pub skin_ms: f64,
    /// GPU BLAS refit + SAH cost (`shaders/refit.wgsl`).
    pub refit_ms: f64,
}

/// What one dispatch cost on the GPU, read back without blocking (see [`PathTracer::enable_async_stats`]).
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct GpuFrameStats {
    /// Index of the dispatch (counts every [`PathTracer::dispatch`]).
    pub dispatch: u64,
    /// `None` without timestamp support.
    pub passes: Option<PassTimes>,
    /// Camera, bounce and shadow rays traced.
    pub rays: u64,
}

/// Bytes of one statistics readback: trace + tonemap timestamps, denoise timestamps, ray counter.
const STATS_BYTES: u64 = 64;

/// Camera rays, and optionally one diffuse bounce ray per hit, cast without shading.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct RayCastTiming {
    /// GPU time of the pass, from timestamp queries.
    pub gpu_ms: f64,
    pub rays: u64,
}

/// The ray-casting benchmark pass, built on first use.
/// The picking pass (`shaders/pick.wgsl`): its pipeline and 32-byte request/result buffer, bound once.
struct Picker {
    pipeline: wgpu::ComputePipeline,
    io: wgpu::Buffer,
    io_group: wgpu::BindGroup,
}

struct RayCaster {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    output: Option<(u64, wgpu::Buffer)>,
}

pub struct PathTracer {
    trace_pipeline: wgpu::ComputePipeline,
    raycaster: Option<RayCaster>,
    tonemap_pipeline: wgpu::ComputePipeline,
    scene_layout: wgpu::BindGroupLayout,
    accum_layout: wgpu::BindGroupLayout,
    tonemap_layout: wgpu::BindGroupLayout,
    frame_uniform: wgpu::Buffer,
    tonemap_uniform: wgpu::Buffer,
    pub accum: wgpu::Buffer,
    pub aov_albedo_depth: wgpu::Buffer,
    pub aov_normal: wgpu::Buffer,
    /// Unscattered radiance sum + sum of luminance(scattered)^2: what the denoiser needs beyond the AOVs.
    pub moments: wgpu::Buffer,
    pub output_rgba8: wgpu::Buffer,
    /// Primary hit through each pixel centre (instance, triangle, barycentrics); a 16-byte stub while
    /// `hit_aov_enabled` is off, so nothing is spent on it unless asked.
    pub aov_hit: wgpu::Buffer,
    hit_aov_enabled: bool,
    /// Accumulate the denoiser's moments even while it is off, so that switching it on mid-accumulation
    /// works (interactive use; the default). Headless renders that never denoise turn this off: the moments
    /// cost about 5% of a path-trace pass (H200, docs/BENCHMARKS.md).
    pub keep_denoiser_inputs: bool,
    /// Rays traced by the last dispatch.
    ray_counter: wgpu::Buffer,
    scene_bind_group: Option<(u64, wgpu::BindGroup)>,
    accum_bind_group: wgpu::BindGroup,
    tonemap_bind_group: wgpu::BindGroup,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel accumulated since the last reset.
    pub samples: u32,
    /// Pairs: trace, tonemap.
    timestamps: Option<crate::gpu::PassTimestamps>,
    denoiser: Denoiser,
    /// One pair around the denoiser's pass, resolved by every denoise (in a frame or not).
    denoise_timestamps: Option<crate::gpu::PassTimestamps>,
    /// The tone mapper's bindings with the denoised image as its input (made when first needed).
    denoised_tonemap_group: OnceLock<wgpu::BindGroup>,
    /// Made at the first pick.
    picker: OnceLock<Picker>,
    denoised_last_dispatch: bool,
    /// Identifies the per-view buffers (unique across tracers; changes on resize), so displays rebind them.
    pub view_generation: u64,
    /// Counts accumulation restarts, so an image denoised off the GPU (OIDN) is shown only with the
    /// accumulation it came from.
    pub accumulation: u64,
    /// An image denoised off the GPU, in the accumulation's layout, and the tone mapper's bindings over it
    /// (made when first shown at this view size).
    external_denoised: OnceLock<(wgpu::Buffer, wgpu::BindGroup)>,
    /// `accumulation + 1` of the image in `external_denoised`; 0: none.
    external_for: std::sync::atomic::AtomicU64,
    dispatches: u64,
    async_stats: Option<crate::gpu::readback::AsyncReadback>,
}

fn next_view_id() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

pub(super) fn layout_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// Whole-buffer bindings 0, 1, 2, ... in order.
pub(super) fn buffer_entries<'a>(buffers: &[&'a wgpu::Buffer]) -> Vec<wgpu::BindGroupEntry<'a>> {
    buffers
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: b.as_entire_binding(),
        })
        .collect()
}

fn bind_group(
    ctx: &GpuContext,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout,
        entries: &buffer_entries(buffers),
    })
}

struct ViewBuffers {
    accum: wgpu::Buffer,
    albedo: wgpu::Buffer,
    normal: wgpu::Buffer,
    moments: wgpu::Buffer,
    rgba8: wgpu::Buffer,
}

fn view_buffers(ctx: &GpuContext, width: u32, height: u32) -> ViewBuffers {
    let pixels = (width as u64 * height as u64).max(1);
    let make = |label, bytes_per_pixel: u64| {
        ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: pixels * bytes_per_pixel,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    };
    ViewBuffers {
        accum: make("accum", 16),
        albedo: make("aov albedo", 16),
        normal: make("aov normal", 16),
        moments: make("denoiser moments", 16),
        rgba8: make("rgba8", 4),
    }
}

impl PathTracer {
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Self {
        let device = &ctx.device;
        let scene_entries: Vec<_> = (0..10)
            .map(|b| layout_entry(b, true))
            .chain([uniform_entry(10), layout_entry(11, true)])
            .collect();
        let scene_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("scene"),
            entries: &scene_entries,
        });
        let accum_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("accumulation"),
            entries: &[
                layout_entry(0, false),
                layout_entry(1, false),
                layout_entry(2, false),
                layout_entry(3, false),
                layout_entry(4, false),
                layout_entry(5, false),
            ],
        });
        let tonemap_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tonemap"),
            entries: &[
                layout_entry(0, true),
                layout_entry(1, true),
                layout_entry(2, true),
                layout_entry(3, false),
                uniform_entry(4),
            ],
        });
        let trace_pipeline = crate::gpu::compute_pipeline(
            device,
            "path trace",
            super::shaders::path_trace_source(),
            &[Some(&scene_layout), Some(&accum_layout)],
            "trace_pixels",
        );
        let tonemap_pipeline = crate::gpu::compute_pipeline(
            device,
            "tonemap",
            super::shaders::tonemap_source(),
            &[Some(&tonemap_layout)],
            "tonemap",
        );
        let uniform = |label, size| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let frame_uniform = uniform("frame", std::mem::size_of::<GpuFrame>() as u64);
        let tonemap_uniform = uniform(
            "tonemap params",
            std::mem::size_of::<TonemapParams>() as u64,
        );
        let v = view_buffers(ctx, width, height);
        let ray_counter = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ray counter"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let aov_hit = hit_buffer(ctx, width, height, false);
        let accum_bind_group = bind_group(
            ctx,
            &accum_layout,
            &[
                &v.accum,
                &v.albedo,
                &v.normal,
                &ray_counter,
                &aov_hit,
                &v.moments,
            ],
        );
        let tonemap_bind_group = bind_group(
            ctx,
            &tonemap_layout,
            &[&v.accum, &v.albedo, &v.normal, &v.rgba8, &tonemap_uniform],
        );
        let timestamps = crate::gpu::PassTimestamps::new(ctx, "pass timestamps", 2);
        let mut tracer = Self {
            trace_pipeline,
            raycaster: None,
            tonemap_pipeline,
            scene_layout,
            accum_layout,
            tonemap_layout,
            frame_uniform,
            tonemap_uniform,
            accum: v.accum,
            aov_albedo_depth: v.albedo,
            aov_normal: v.normal,
            moments: v.moments,
            output_rgba8: v.rgba8,
            aov_hit,
            hit_aov_enabled: false,
            keep_denoiser_inputs: true,
            ray_counter,
            scene_bind_group: None,
            accum_bind_group,
            tonemap_bind_group,
            width,
            height,
            samples: 0,
            timestamps,
            denoiser: Denoiser::new(ctx),
            denoise_timestamps: crate::gpu::PassTimestamps::new(ctx, "denoise timestamps", 1),
            denoised_tonemap_group: OnceLock::new(),
            picker: OnceLock::new(),
            denoised_last_dispatch: false,
            view_generation: next_view_id(),
            accumulation: 0,
            external_denoised: OnceLock::new(),
            external_for: Default::default(),
            dispatches: 0,
            async_stats: None,
        };
        tracer.reset(ctx);
        tracer
    }

    pub fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) {
        if (width, height) == (self.width, self.height) {
            return;
        }
        let v = view_buffers(ctx, width, height);
        self.aov_hit = hit_buffer(ctx, width, height, self.hit_aov_enabled);
        self.accum_bind_group = bind_group(
            ctx,
            &self.accum_layout,
            &[
                &v.accum,
                &v.albedo,
                &v.normal,
                &self.ray_counter,
                &self.aov_hit,
                &v.moments,
            ],
        );
        self.tonemap_bind_group = bind_group(
            ctx,
            &self.tonemap_layout,
            &[
                &v.accum,
                &v.albedo,
                &v.normal,
                &v.rgba8,
                &self.tonemap_uniform,
            ],
        );
        (
            self.accum,
            self.aov_albedo_depth,
            self.aov_normal,
            self.moments,
            self.output_rgba8,
        ) = (v.accum, v.albedo, v.normal, v.moments, v.rgba8);
        (self.width, self.height) = (width, height);
        self.view_generation = next_view_id();
        self.denoiser.release();
        self.denoised_tonemap_group = OnceLock::new();
        self.external_denoised = OnceLock::new();
        self.reset(ctx);
    }

    /// Turns the primary-hit AOV on or off (allocating its buffer only while on); takes effect at the next
    /// accumulation restart.
    pub fn set_hit_aov(&mut self, ctx: &GpuContext, enabled: bool) {
        if enabled == self.hit_aov_enabled {
            return;
        }
        self.hit_aov_enabled = enabled;
        self.aov_hit = hit_buffer(ctx, self.width, self.height, enabled);
        self.accum_bind_group = bind_group(
            ctx,
            &self.accum_layout,
            &[
                &self.accum,
                &self.aov_albedo_depth,
                &self.aov_normal,
                &self.ray_counter,
                &self.aov_hit,
                &self.moments,
            ],
        );
    }

    /// Restarts accumulation (camera, scene or settings changed).
    pub fn reset(&mut self, ctx: &GpuContext) {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        for b in [
            &self.accum,
            &self.aov_albedo_depth,
            &self.aov_normal,
            &self.moments,
        ] {
            encoder.clear_buffer(b, 0, None);
        }
        ctx.queue.submit([encoder.finish()]);
        self.samples = 0;
        self.accumulation += 1;
    }

    fn scene_bind_group(&mut self, ctx: &GpuContext, scene: &GpuScene) -> wgpu::BindGroup {
        if let Some((generation, group)) = &self.scene_bind_group
            && *generation == scene.generation
        {
            return group.clone();
        }
        let group = self.new_scene_bind_group(ctx, scene);
        self.scene_bind_group = Some((scene.generation, group.clone()));
        group
    }

    /// A compute pipeline over the scene bindings (group 0) and its own group 1 (`entries`); `entry` names
    /// the WGSL entry point and labels the objects.
    fn scene_kernel(
        ctx: &GpuContext,
        scene_layout: &wgpu::BindGroupLayout,
        entry: &str,
        source: String,
        entries: &[wgpu::BindGroupLayoutEntry],
    ) -> (wgpu::ComputePipeline, wgpu::BindGroupLayout) {
        let layout = ctx
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(entry),
                entries,
            });
        let pipeline = crate::gpu::compute_pipeline(
            &ctx.device,
            entry,
            source,
            &[Some(scene_layout), Some(&layout)],
            entry,
        );
        (pipeline, layout)
    }

    fn new_scene_bind_group(&self, ctx: &GpuContext, scene: &GpuScene) -> wgpu::BindGroup {
        bind_group(
            ctx,
            &self.scene_layout,
            &[
                &scene.tlas_nodes,
                &scene.blas_nodes,
                &scene.instances,
                &scene.meshes,
                &scene.triangles,
                &scene.vertex_pool,
                &scene.materials,
                &scene.texels,
                &scene.texture_infos,
                &scene.emitters,
                &self.frame_uniform,
                &scene.wide_nodes,
            ],
        )
    }

    /// What the ray through the centre of pixel (`x`, `y`) of the last traced frame hits: one ray on the GPU
    /// over the same buffers and traversal as the path kernel, so exactly what is shown (GPU-deformed poses,
    /// wide BVHs, alpha cut-outs). Blocks for a 16-byte readback; `None` outside the image.
    pub fn pick(&self, ctx: &GpuContext, scene: &GpuScene, x: u32, y: u32) -> Option<PrimaryHit> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let picker = self.picker.get_or_init(|| {
            let (pipeline, group_layout) = Self::scene_kernel(
                ctx,
                &self.scene_layout,
                "pick",
                super::shaders::pick_source(),
                &[layout_entry(0, false)],
            );
            let io = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pick io"),
                size: 32,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let io_group = bind_group(ctx, &group_layout, &[&io]);
            Picker {
                pipeline,
                io,
                io_group,
            }
        });
        ctx.queue
            .write_buffer(&picker.io, 0, bytemuck::cast_slice(&[x, y, 0, 0]));
        let scene_group = self.new_scene_bind_group(ctx, scene);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("pick"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&picker.pipeline);
            pass.set_bind_group(0, &scene_group, &[]);
            pass.set_bind_group(1, &picker.io_group, &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        ctx.queue.submit([encoder.finish()]);
        let bytes = ctx.read_buffer_range(&picker.io, 16, 16);
        Some(primary_hit(bytemuck::cast_slice::<u8, [u32; 4]>(&bytes)[0]))
    }

    /// Traces `spp` more samples per pixel into the accumulation buffers (and tone-maps if asked), in one
    /// submission after `before` (the frame's GPU deform passes).
    #[allow(clippy::too_many_arguments)]
    pub fn dispatch(
        &mut self,
        ctx: &GpuContext,
        scene: &GpuScene,
        settings: &RenderSettings,
        camera: &CameraView,
        spp: u32,
        tonemap: bool,
        before: Vec<wgpu::CommandBuffer>,
    ) {
        self.write_frame(ctx, scene, settings, camera, spp, settings.max_depth);
        let scene_group = self.scene_bind_group(ctx, scene);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&self.ray_counter, 0, None);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("path trace"),
                timestamp_writes: self.trace_timestamps(),
            });
            pass.set_pipeline(&self.trace_pipeline);
            pass.set_bind_group(0, &scene_group, &[]);
            pass.set_bind_group(1, &self.accum_bind_group, &[]);
            pass.dispatch_workgroups(self.width.div_ceil(8), self.height.div_ceil(8), 1);
        }
        self.samples += spp;
        let denoise =
            tonemap && Self::shows_denoised(settings) && self.external_shown(settings).is_none();
        if tonemap {
            self.encode_display(ctx, &mut encoder, settings);
        }
        if let Some(t) = &self.timestamps {
            t.resolve(&mut encoder, if tonemap { 2 } else { 1 });
        }
        self.denoised_last_dispatch = denoise;
        self.dispatches += 1;
        if let Some(stats) = &mut self.async_stats {
            let mut sources = Vec::new();
            // Fixed offsets: timestamps at 0 (32 bytes), denoise at 32 (16), rays at 48 (4).
            if let Some(t) = &self.timestamps {
                sources.push((t.resolve_buffer(), 0, 32));
            }
            if let (true, Some(t)) = (denoise, &self.denoise_timestamps) {
                sources.push((t.resolve_buffer(), 32, 16));
            }
            sources.push((&self.ray_counter, 48, 4));
            stats.encode(&mut encoder, &sources, self.dispatches);
        }
        ctx.queue
            .submit(before.into_iter().chain([encoder.finish()]));
        if let Some(stats) = &mut self.async_stats {
            stats.after_submit();
        }
    }

    /// From now on every dispatch also copies its pass times and ray count into a small ring of staging
    /// buffers, read by [`Self::poll_stats`] without stalling (the viewer's frame loop).
    pub fn enable_async_stats(&mut self, ctx: &GpuContext) {
        if self.async_stats.is_none() {
            self.async_stats = Some(crate::gpu::readback::AsyncReadback::new(
                ctx,
                "frame stats readback",
                STATS_BYTES,
                3,
            ));
        }
    }

    /// Statistics of finished dispatches since the last call, oldest first.
    pub fn poll_stats(&mut self, ctx: &GpuContext) -> Vec<GpuFrameStats> {
        let Some(stats) = &mut self.async_stats else {
            return Vec::new();
        };
        let timestamps = self.timestamps.as_ref();
        stats
            .poll(ctx)
            .into_iter()
            .map(|(dispatch, bytes)| {
                let passes = timestamps.map(|t| {
                    let ms = t.ms_from_bytes(&bytes[..48]);
                    PassTimes {
                        trace_ms: ms[0],
                        tonemap_ms: ms[1],
                        denoise_ms: ms[2],
                        ..Default::default()
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

    /// Whether the display shows the denoised image (colour view with the denoiser on).
    fn shows_denoised(settings: &RenderSettings) -> bool {
        settings.denoise && settings.view == AovView::Color
    }

    fn denoise_inputs(&self) -> DenoiseInputs<'_> {
        DenoiseInputs {
            accum: &self.accum,
            albedo_depth: &self.aov_albedo_depth,
            normal_hits: &self.aov_normal,
            moments: &self.moments,
            width: self.width,
            height: self.height,
        }
    }

    fn encode_denoise(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        params: &DenoiseParams,
    ) -> &wgpu::Buffer {
        let timestamps = self.denoise_timestamps.as_ref().map(|t| t.pass_writes(0));
        let output = self
            .denoiser
            .encode(ctx, encoder, &self.denoise_inputs(), params, timestamps);
        if let Some(t) = &self.denoise_timestamps {
            t.resolve(encoder, 1);
        }
        output
    }

    /// The display transform, denoising first when the settings ask for it.
    fn encode_display(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        settings: &RenderSettings,
    ) {
        if !Self::shows_denoised(settings) {
            self.encode_tonemap(ctx, encoder, settings, &self.tonemap_bind_group);
            return;
        }
        // OIDN's image once it has arrived for this accumulation; the svgf image until then.
        if let Some(group) = self.external_shown(settings) {
            self.encode_tonemap(ctx, encoder, settings, group);
            return;
        }
        let denoised = self.encode_denoise(ctx, encoder, &settings.denoise_params);
        let group = self.denoised_tonemap_group.get_or_init(|| {
            bind_group(
                ctx,
                &self.tonemap_layout,
                &[
                    denoised,
                    &self.aov_albedo_depth,
                    &self.aov_normal,
                    &self.output_rgba8,
                    &self.tonemap_uniform,
                ],
            )
        });
        self.encode_tonemap(ctx, encoder, settings, group);
    }

    /// Shows `image` (linear RGB per pixel, row-major from the top-left, denoised off the GPU) in place of the
    /// svgf image while the current accumulation lasts and the settings ask for OIDN.
    pub fn show_denoised(&self, ctx: &GpuContext, image: &[[f32; 3]]) {
        let (buffer, _) = self.external_denoised.get_or_init(|| {
            let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("externally denoised"),
                size: self.accum.size(),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let group = bind_group(
                ctx,
                &self.tonemap_layout,
                &[
                    &buffer,
                    &self.aov_albedo_depth,
                    &self.aov_normal,
                    &self.output_rgba8,
                    &self.tonemap_uniform,
                ],
            );
            (buffer, group)
        });
        // Sample count 1: the tone mapper divides by it.
        let pixels: Vec<[f32; 4]> = image.iter().map(|p| [p[0], p[1], p[2], 1.0]).collect();
        if pixels.len() as u64 * 16 == buffer.size() {
            ctx.queue
                .write_buffer(buffer, 0, bytemuck::cast_slice(&pixels));
            self.external_for
                .store(self.accumulation + 1, std::sync::atomic::Ordering::Release);
        }
    }

    /// The tone mapper's bindings over the OIDN image when the display should show it.
    fn external_shown(&self, settings: &RenderSettings) -> Option<&wgpu::BindGroup> {
        let current =
            self.external_for.load(std::sync::atomic::Ordering::Acquire) == self.accumulation + 1;
        (settings.denoiser == DenoiserKind::Oidn && current)
            .then(|| self.external_denoised.get().map(|(_, g)| g))
            .flatten()
    }

    /// Denoises the current accumulation (whatever `RenderSettings::denoise` says) and reads it back: linear
    /// RGB per pixel, row-major from the top-left.
    pub fn denoised_radiance(&self, ctx: &GpuContext, params: &DenoiseParams) -> Vec<[f32; 3]> {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let output = self.encode_denoise(ctx, &mut encoder, params);
        ctx.queue.submit([encoder.finish()]);
        let bytes = ctx.read_buffer(output, output.size());
        bytemuck::cast_slice::<u8, [f32; 4]>(&bytes)
            .iter()
            .map(|p| [p[0], p[1], p[2]])
            .collect()
    }

    /// GPU memory of the denoiser's buffers (0 until it first ran at this view size).
    pub fn denoiser_memory_bytes(&self) -> u64 {
        self.denoiser.memory_bytes()
    }

    fn trace_timestamps(&self) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.timestamps.as_ref().map(|t| t.pass_writes(0))
    }

    /// Casts one camera ray per pixel centre and, with `diffuse_bounce`, one cosine-distributed ray from each
    /// hit, without shading: the traversal throughput the speed targets count. Blocks for the result; `None`
    /// without timestamp queries. Leaves the accumulation untouched.
    pub fn cast_rays(
        &mut self,
        ctx: &GpuContext,
        scene: &GpuScene,
        settings: &RenderSettings,
        camera: &CameraView,
        diffuse_bounce: bool,
    ) -> Option<RayCastTiming> {
        self.timestamps.as_ref()?;
        let pixels = self.width as u64 * self.height as u64;
        let caster = self.raycaster.get_or_insert_with(|| {
            let (pipeline, layout) = Self::scene_kernel(
                ctx,
                &self.scene_layout,
                "cast_rays",
                super::shaders::raycast_source(),
                &[layout_entry(0, false), layout_entry(1, false)],
            );
            RayCaster {
                pipeline,
                layout,
                output: None,
            }
        });
        if caster.output.as_ref().is_none_or(|(n, _)| *n != pixels) {
            let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("raycast distances"),
                size: pixels.max(1) * 4,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            });
            caster.output = Some((pixels, buffer));
        }
        let output_group = {
            let caster = self.raycaster.as_ref().expect("created above");
            let (_, output) = caster.output.as_ref().expect("created above");
            bind_group(ctx, &caster.layout, &[output, &self.ray_counter])
        };
        self.write_frame(ctx, scene, settings, camera, 1, u32::from(diffuse_bounce));
        let scene_group = self.scene_bind_group(ctx, scene);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&self.ray_counter, 0, None);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("raycast"),
                timestamp_writes: self.trace_timestamps(),
            });
            let caster = self.raycaster.as_ref().expect("created above");
            pass.set_pipeline(&caster.pipeline);
            pass.set_bind_group(0, &scene_group, &[]);
            pass.set_bind_group(1, &output_group, &[]);
            pass.dispatch_workgroups(self.width.div_ceil(8), self.height.div_ceil(8), 1);
        }
        if let Some(t) = &self.timestamps {
            t.resolve(&mut encoder, 1);
        }
        self.denoised_last_dispatch = false;
        ctx.queue.submit([encoder.finish()]);
        let gpu_ms = self.read_pass_times(ctx)?.trace_ms;
        Some(RayCastTiming {
            gpu_ms,
            rays: self.read_ray_count(ctx),
        })
    }

    fn write_frame(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        settings: &RenderSettings,
        camera: &CameraView,
        spp: u32,
        max_depth: u32,
    ) {
        let (env_mode, env_color) = match settings.environment {
            Environment::Constant(c) => (0, c),
            Environment::Sky => (1, [0.0; 3]),
        };
        let frame = GpuFrame {
            world_from_camera: camera.world_from_camera.to_cols_array_2d(),
            env_color,
            tan_half_fov: (camera.yfov * 0.5).tan(),
            width: self.width,
            height: self.height,
            sample_base: self.samples,
            spp,
            max_depth,
            seed: settings.seed,
            env_mode,
            rr_depth: if settings.russian_roulette {
                settings.rr_depth
            } else {
                u32::MAX
            },
            emitter_count: scene.emitter_count,
            // The primary-hit AOV is written by the first dispatch of an accumulation (the path kernel).
            flags: if settings.nee { FRAME_NEE } else { 0 }
                | if self.hit_aov_enabled && self.samples == 0 {
                    FRAME_HIT_AOV
                } else {
                    0
                }
                | if settings.denoise || self.keep_denoiser_inputs {
                    FRAME_MOMENTS
                } else {
                    0
                },
            emitter_total_power: scene.emitter_total_power,
            _pad: 0,
        };
        ctx.queue
            .write_buffer(&self.frame_uniform, 0, bytemuck::bytes_of(&frame));
    }

    fn encode_tonemap(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        settings: &RenderSettings,
        group: &wgpu::BindGroup,
    ) {
        let params = TonemapParams {
            width: self.width,
            height: self.height,
            tonemapper: settings.tonemapper as u32,
            view: settings.view as u32,
            exposure_scale: 2f32.powf(settings.exposure),
            depth_scale: settings.depth_view_scale,
            _pad: [0; 2],
        };
        ctx.queue
            .write_buffer(&self.tonemap_uniform, 0, bytemuck::bytes_of(&params));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("tonemap"),
            timestamp_writes: self.timestamps.as_ref().map(|t| t.pass_writes(1)),
        });
        pass.set_pipeline(&self.tonemap_pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(self.width.div_ceil(8), self.height.div_ceil(8), 1);
    }

    /// Tone-maps the current accumulation (denoised if the settings say so) into `output_rgba8`.
    pub fn tonemap(&self, ctx: &GpuContext, settings: &RenderSettings) {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        self.encode_display(ctx, &mut encoder, settings);
        ctx.queue.submit([encoder.finish()]);
    }

    /// GPU times of the last dispatch (blocks until it finished); `None` without timestamp support.
    pub fn read_pass_times(&self, ctx: &GpuContext) -> Option<PassTimes> {
        let ms = self.timestamps.as_ref()?.read_ms(ctx);
        Some(PassTimes {
            trace_ms: ms[0],
            tonemap_ms: ms[1],
            denoise_ms: if self.denoised_last_dispatch {
                self.read_denoise_ms(ctx).unwrap_or(0.0)
            } else {
                0.0
            },
            ..Default::default()
        })
    }

    /// GPU time of the last denoise, in a frame or through [`Self::denoised_radiance`] (blocks until it
    /// finished); `None` without timestamp support.
    pub fn read_denoise_ms(&self, ctx: &GpuContext) -> Option<f64> {
        Some(self.denoise_timestamps.as_ref()?.read_ms(ctx)[0])
    }

    /// Rays (camera, bounce, shadow) traced by the last dispatch (blocks until it finished).
    pub fn read_ray_count(&self, ctx: &GpuContext) -> u64 {
        let bytes = ctx.read_buffer(&self.ray_counter, 4);
        u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) as u64
    }

    /// Mean linear radiance per pixel (RGB), row-major from the top-left.
    pub fn read_radiance(&self, ctx: &GpuContext) -> Vec<[f32; 3]> {
        let bytes = ctx.read_buffer(&self.accum, self.accum.size());
        bytemuck::cast_slice::<u8, [f32; 4]>(&bytes)
            .iter()
            .map(|p| {
                let n = p[3].max(1.0);
                [p[0] / n, p[1] / n, p[2] / n]
            })
            .collect()
    }

    /// First-hit AOVs: albedo (mean), normal (mean, renormalised; zero where nothing was hit), camera depth
    /// (mean over samples that hit; +inf where none did).
    pub fn read_aovs(&self, ctx: &GpuContext) -> Aovs {
        let samples = self.samples.max(1) as f32;
        let ad = ctx.read_buffer(&self.aov_albedo_depth, self.aov_albedo_depth.size());
        let nh = ctx.read_buffer(&self.aov_normal, self.aov_normal.size());
        let ad: &[[f32; 4]] = bytemuck::cast_slice(&ad);
        let nh: &[[f32; 4]] = bytemuck::cast_slice(&nh);
        let mut aovs = Aovs::default();
        for (a, n) in ad.iter().zip(nh) {
            aovs.albedo
                .push([a[0] / samples, a[1] / samples, a[2] / samples]);
            let v = glam::Vec3::new(n[0], n[1], n[2]).normalize_or_zero();
            aovs.normal.push(v.to_array());
            aovs.depth.push(if n[3] > 0.0 {
                a[3] / n[3]
            } else {
                f32::INFINITY
            });
        }
        aovs
    }

    pub fn read_rgba8(&self, ctx: &GpuContext) -> Vec<u8> {
        ctx.read_buffer(&self.output_rgba8, self.output_rgba8.size())
    }

    /// The primary hit through each pixel centre, row-major (empty while the hit AOV is off).
    pub fn read_hits(&self, ctx: &GpuContext) -> Vec<PrimaryHit> {
        if !self.hit_aov_enabled {
            return Vec::new();
        }
        let bytes = ctx.read_buffer(&self.aov_hit, self.aov_hit.size());
        bytemuck::cast_slice::<u8, [u32; 4]>(&bytes)
            .iter()
            .map(|h| primary_hit(*h))
            .collect()
    }
}

/// Decodes one texel of the hit AOV.
fn primary_hit(h: [u32; 4]) -> PrimaryHit {
    PrimaryHit {
        instance: (h[0] != NONE).then_some(h[0]),
        triangle: h[1],
        barycentrics: [f32::from_bits(h[2]), f32::from_bits(h[3])],
    }
}

/// The first surface the ray through a pixel centre hits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimaryHit {
    /// Index into the GPU instance buffer (TLAS leaf order); `None` where the ray left the scene.
    pub instance: Option<u32>,
    /// Slot in the GPU triangle buffer (the mesh's triangle offset included).
    pub triangle: u32,
    /// Weights of the triangle's second and third vertices.
    pub barycentrics: [f32; 2],
}

fn hit_buffer(ctx: &GpuContext, width: u32, height: u32, enabled: bool) -> wgpu::Buffer {
    let size = if enabled {
        (width as u64 * height as u64).max(1) * 16
    } else {
        16
    };
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("aov primary hit"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

#[derive(Clone, Debug, Default)]
pub struct Aovs {
    pub albedo: Vec<[f32; 3]>,
    pub normal: Vec<[f32; 3]>,
    pub depth: Vec<f32>,
}

//! The denoiser: an edge-avoiding a-trous wavelet filter in the SVGF style over the accumulated image
//! (`denoise.wgsl` beside this file describes the passes). It is display-side: it reads the accumulation and writes its
//! own output buffer, so turning it on or off never restarts accumulation, and its buffers are allocated the
//! first time it runs at a view size.

use crate::gpu::GpuContext;
use crate::gpu::bind::{
    Binding, buffer_entries, layout_entries, params_buffer, params_entry_dynamic,
};
use crate::render::shaders::{ShaderModule, compose};
use crate::render::view::ViewTargets;
use bevy_ecs::prelude::Resource;
use bytemuck::{Pod, Zeroable};
use std::sync::OnceLock;

pub const KERNEL: ShaderModule = ShaderModule {
    name: "denoise",
    source: include_str!("denoise.wgsl"),
    requires: &["color"],
};

pub use crate::render::settings::DenoiseParams;

/// One pass's uniform (the `Params` struct of denoise.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct DenoisePassParams {
    pub width: u32,
    pub height: u32,
    pub step: u32,
    pub last: u32,
    pub sigma_luminance: f32,
    pub sigma_normal: f32,
    pub sigma_depth: f32,
    pub _pad: u32,
}

/// The accumulation the denoiser reads: the view's targets.
pub struct DenoiseInputs<'a> {
    pub accum: &'a wgpu::Buffer,
    pub albedo_depth: &'a wgpu::Buffer,
    pub normal_hits: &'a wgpu::Buffer,
    pub moments: &'a wgpu::Buffer,
    pub width: u32,
    pub height: u32,
}

impl<'a> DenoiseInputs<'a> {
    pub fn of(view: &'a ViewTargets) -> Self {
        Self {
            accum: &view.accum,
            albedo_depth: &view.albedo_depth,
            normal_hits: &view.normal_hits,
            moments: &view.moments,
            width: view.width,
            height: view.height,
        }
    }
}

/// Per-view buffers: guide, two illumination buffers (ping-pong) and the output.
struct Targets {
    output: wgpu::Buffer,
    /// `[0]` reads illumination A and writes B, `[1]` the reverse.
    groups: [wgpu::BindGroup; 2],
    size: (u32, u32),
    bytes: u64,
}

#[derive(Resource)]
pub struct Denoiser {
    module: crate::gpu::ComputeModule,
    /// prepare, variance, atrous: compiled at the first run, so that views that never denoise (a `raykin
    /// render`) do not compile them.
    pipelines: OnceLock<[wgpu::ComputePipeline; 3]>,
    layout: wgpu::BindGroupLayout,
    /// One [`DenoisePassParams`] per pass, `params_stride` apart (bound with a dynamic offset).
    params: wgpu::Buffer,
    params_stride: u64,
    targets: OnceLock<Targets>,
}

/// Bytes per pixel of the denoiser's own buffers: guide, 2 x illumination, output.
const BYTES_PER_PIXEL: u64 = 4 * 16;

impl Denoiser {
    pub fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        // accum, albedo + depth, normal + hits, moments, guide, illumination in, out, denoised; params below
        let mut entries = layout_entries(
            ctx,
            &[
                Read, Read, Read, Read, ReadWrite, Read, ReadWrite, ReadWrite,
            ],
            wgpu::ShaderStages::COMPUTE,
        );
        entries.push(params_entry_dynamic(
            ctx,
            8,
            std::mem::size_of::<DenoisePassParams>() as u64,
        ));
        let layout = ctx.pipelines.bind_group_layout("denoise", &entries);
        let module = crate::gpu::ComputeModule::new(ctx, compose(&KERNEL), &[Some(&layout)]);
        let params_stride = (std::mem::size_of::<DenoisePassParams>() as u64)
            .next_multiple_of(ctx.params_offset_alignment());
        let params = params_buffer(
            ctx,
            "denoise params",
            (params_stride * (2 + DenoiseParams::MAX_ITERATIONS as u64)) as usize,
        );
        Self {
            module,
            pipelines: OnceLock::new(),
            layout,
            params,
            params_stride,
            targets: OnceLock::new(),
        }
    }

    /// Frees the per-view buffers (the view was resized; the next run allocates them again).
    pub fn release(&mut self) {
        self.targets = OnceLock::new();
    }

    /// The output buffer of the last [`Self::encode`] (`None` before the first).
    pub fn output(&self) -> Option<&wgpu::Buffer> {
        self.targets.get().map(|t| &t.output)
    }

    /// GPU memory held for the current view (0 until the denoiser first runs).
    pub fn memory_bytes(&self) -> u64 {
        self.targets.get().map_or(0, |t| t.bytes)
    }

    fn targets(&self, ctx: &GpuContext, inputs: &DenoiseInputs) -> &Targets {
        let targets = self.targets.get_or_init(|| {
            let pixels = (inputs.width as u64 * inputs.height as u64).max(1);
            let buffer = |label| {
                ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: pixels * 16,
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                })
            };
            let guide = buffer("denoise guide");
            let illum = [
                buffer("denoise illumination a"),
                buffer("denoise illumination b"),
            ];
            let output = buffer("denoised radiance");
            let group = |read: &wgpu::Buffer, write: &wgpu::Buffer| {
                let buffers = [
                    inputs.accum,
                    inputs.albedo_depth,
                    inputs.normal_hits,
                    inputs.moments,
                    &guide,
                    read,
                    write,
                    &output,
                ];
                let mut entries = buffer_entries(&buffers);
                entries.push(wgpu::BindGroupEntry {
                        binding: 8,
                        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: &self.params,
                            offset: 0,
                            size: wgpu::BufferSize::new(
                                std::mem::size_of::<DenoisePassParams>() as u64
                            ),
                        }),
                    });
                ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("denoise"),
                    layout: &self.layout,
                    entries: &entries,
                })
            };
            Targets {
                groups: [group(&illum[0], &illum[1]), group(&illum[1], &illum[0])],
                output,
                size: (inputs.width, inputs.height),
                bytes: pixels * BYTES_PER_PIXEL,
            }
        });
        assert_eq!(
            targets.size,
            (inputs.width, inputs.height),
            "denoiser buffers not released after a resize"
        );
        targets
    }

    /// Records the denoising passes (one compute pass) over `inputs`; returns the output buffer, which holds
    /// `vec4(rgb, 1)` per pixel once the encoder's commands ran.
    pub fn encode(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &DenoiseInputs,
        params: &DenoiseParams,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites>,
    ) -> &wgpu::Buffer {
        let targets = self.targets(ctx, inputs);
        let p = params.sanitized();
        let stride = self.params_stride as usize;
        let slots = 2 + p.iterations as usize;
        let mut bytes = vec![0u8; stride * slots];
        for slot in 0..slots {
            let iteration = slot.saturating_sub(2) as u32;
            let pass = DenoisePassParams {
                width: inputs.width,
                height: inputs.height,
                step: 1 << iteration,
                last: (slot == slots - 1) as u32,
                sigma_luminance: p.sigma_luminance,
                sigma_normal: p.sigma_normal,
                sigma_depth: p.sigma_depth,
                _pad: 0,
            };
            bytes[slot * stride..][..std::mem::size_of::<DenoisePassParams>()]
                .copy_from_slice(bytemuck::bytes_of(&pass));
        }
        ctx.queue.write_buffer(&self.params, 0, &bytes);

        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("denoise"),
            timestamp_writes,
        });
        let workgroups = (inputs.width.div_ceil(8), inputs.height.div_ceil(8));
        // prepare writes A; variance reads A, writes B; the iterations alternate from B.
        let mut run = |slot: usize, pipeline: &wgpu::ComputePipeline, group: usize| {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &targets.groups[group], &[(slot * stride) as u32]);
            pass.dispatch_workgroups(workgroups.0, workgroups.1, 1);
        };
        let [prepare, variance, atrous] = self.pipelines.get_or_init(|| {
            ["prepare", "variance", "atrous"].map(|e| self.module.pipeline(e, e, &[]))
        });
        run(0, prepare, 1);
        run(1, variance, 0);
        for k in 0..p.iterations as usize {
            run(2 + k, atrous, if k % 2 == 0 { 1 } else { 0 });
        }
        &targets.output
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sanitized_params_are_usable() {
        let bad = DenoiseParams {
            iterations: 0,
            sigma_luminance: f32::NAN,
            sigma_normal: -1.0,
            sigma_depth: f32::INFINITY,
        };
        assert_eq!(
            bad.sanitized(),
            DenoiseParams {
                iterations: 1,
                ..DenoiseParams::default()
            }
        );
        let many = DenoiseParams {
            iterations: 100,
            sigma_luminance: 2.0,
            ..Default::default()
        };
        assert_eq!(many.sanitized().iterations, DenoiseParams::MAX_ITERATIONS);
        assert_eq!(many.sanitized().sigma_luminance, 2.0);
    }
}

//! The denoiser-inputs pass (`denoiser_inputs.wgsl`): the accumulation's mean radiance and first-hit albedo and
//! normal, sanitised, as packed float3 planes in buffers an external denoiser (Open Image Denoise's GPU device)
//! reads in place, so that its inputs never travel through host memory.

use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, bind_group, compute_layout, params_buffer};
use crate::render::shaders::{ShaderModule, compose};
use bytemuck::{Pod, Zeroable};

pub const KERNEL: ShaderModule = ShaderModule {
    name: "denoiser_inputs",
    source: include_str!("denoiser_inputs.wgsl"),
    requires: &[],
};

/// Radiance above this is clamped before denoising (here and on the host path): OIDN's HDR transfer must not
/// overflow to infinity.
pub const MAX_RADIANCE: f32 = 1e30;

/// Bytes of one packed float3 plane of `pixels` pixels.
pub fn plane_bytes(pixels: u64) -> u64 {
    pixels * 12
}

/// The kernel's uniform (`Params` in denoiser_inputs.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct DenoiserInputsParams {
    pub width: u32,
    pub height: u32,
    pub max_radiance: f32,
    pub _pad: u32,
}

/// The accumulation's sums (its layout: radiance + count, albedo + depth, normal + hits) and the three planes
/// written (each at least [`plane_bytes`] of the image).
pub struct DenoiserInputsBuffers<'a> {
    pub accum: &'a wgpu::Buffer,
    pub albedo_depth: &'a wgpu::Buffer,
    pub normal_hits: &'a wgpu::Buffer,
    pub color: &'a wgpu::Buffer,
    pub albedo: &'a wgpu::Buffer,
    pub normal: &'a wgpu::Buffer,
}

pub struct DenoiserInputsPass {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
}

impl DenoiserInputsPass {
    pub fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        let layout = compute_layout(
            ctx,
            "denoiser_inputs",
            &[Read, Read, Read, ReadWrite, ReadWrite, ReadWrite, Params],
        );
        let pipeline = crate::gpu::compute_pipeline(
            ctx,
            "denoiser_inputs",
            compose(&KERNEL),
            &[Some(&layout)],
            "pack",
        );
        Self {
            pipeline,
            layout,
            params: params_buffer(
                ctx,
                "denoiser_inputs params",
                std::mem::size_of::<DenoiserInputsParams>(),
            ),
        }
    }

    pub fn encode(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        buffers: &DenoiserInputsBuffers,
        (width, height): (u32, u32),
    ) {
        let params = DenoiserInputsParams {
            width,
            height,
            max_radiance: MAX_RADIANCE,
            _pad: 0,
        };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let group = bind_group(
            ctx,
            "denoiser_inputs",
            &self.layout,
            &[
                buffers.accum,
                buffers.albedo_depth,
                buffers.normal_hits,
                buffers.color,
                buffers.albedo,
                buffers.normal,
                &self.params,
            ],
        );
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("denoiser_inputs"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
    }
}

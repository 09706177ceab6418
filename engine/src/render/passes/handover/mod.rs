//! The hand-over pass (`handover.wgsl`): once nothing moves, the real-time path's last image is mixed with the
//! growing plain accumulation until the accumulation alone is shown, so a still converges exactly as it does
//! without the real-time path.

use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, bind_group, compute_layout, params_buffer};
use crate::render::shaders::{ShaderModule, compose};
use bytemuck::{Pod, Zeroable};

pub const KERNEL: ShaderModule = ShaderModule {
    name: "handover",
    source: include_str!("handover.wgsl"),
    requires: &[],
};

/// The kernel's uniform (`Params` in handover.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct HandoverParams {
    pub width: u32,
    pub height: u32,
    /// Weight of the accumulation, 0..1.
    pub weight: f32,
    pub _pad: u32,
}

pub struct HandoverPass {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
}

/// What the pass mixes, each in the accumulation's layout, and where the mean goes.
pub struct HandoverBuffers<'a> {
    pub realtime: &'a wgpu::Buffer,
    pub accumulated: &'a wgpu::Buffer,
    pub output: &'a wgpu::Buffer,
}

impl HandoverPass {
    pub fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        let layout = compute_layout(ctx, "handover", &[Read, Read, ReadWrite, Params]);
        let pipeline = crate::gpu::compute_pipeline(
            ctx,
            "handover",
            compose(&KERNEL),
            &[Some(&layout)],
            "blend",
        );
        Self {
            pipeline,
            layout,
            params: params_buffer(
                ctx,
                "handover params",
                std::mem::size_of::<HandoverParams>(),
            ),
        }
    }

    pub fn encode(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        buffers: &HandoverBuffers,
        params: &HandoverParams,
    ) {
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(params));
        let group = bind_group(
            ctx,
            "handover",
            &self.layout,
            &[
                buffers.realtime,
                buffers.accumulated,
                buffers.output,
                &self.params,
            ],
        );
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("handover"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(params.width.div_ceil(8), params.height.div_ceil(8), 1);
    }
}

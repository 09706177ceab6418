//! Picking: what the ray through one pixel centre of the last traced frame hits, i.e. what the viewer shows
//! there. One invocation per click over the same buffers and traversal as the trace pass, so GPU-deformed poses,
//! wide BVHs and alpha cut-outs pick exactly as they render.

use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, bind_group, compute_layout};
use crate::render::shaders::{ShaderModule, compose};
use crate::render::view::{PrimaryHit, ViewTargets};

pub const KERNEL: ShaderModule = ShaderModule {
    name: "pick",
    source: include_str!("pick.wgsl"),
    requires: &["constants", "camera", "traversal/tlas"],
};

pub struct PickPass {
    pipeline: wgpu::ComputePipeline,
    view_layout: wgpu::BindGroupLayout,
    /// 32 bytes: the pixel in, the hit out.
    io: wgpu::Buffer,
}

impl PickPass {
    pub fn new(ctx: &GpuContext, scene_layout: &wgpu::BindGroupLayout) -> Self {
        let view_layout = compute_layout(ctx, "pick", &[Binding::Params, Binding::ReadWrite]);
        let pipeline = crate::gpu::compute_pipeline(
            ctx,
            "pick",
            compose(&KERNEL),
            &[Some(scene_layout), Some(&view_layout)],
            "pick",
        );
        let io = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pick io"),
            size: 32,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Self {
            pipeline,
            view_layout,
            io,
        }
    }

    /// Traces pixel (`x`, `y`) through the view's last frame constants; blocks for a 16-byte readback.
    /// `None` outside the image.
    pub fn pick(
        &self,
        ctx: &GpuContext,
        scene: &wgpu::BindGroup,
        view: &ViewTargets,
        x: u32,
        y: u32,
    ) -> Option<(PrimaryHit, f32)> {
        if x >= view.width || y >= view.height {
            return None;
        }
        ctx.queue
            .write_buffer(&self.io, 0, bytemuck::cast_slice(&[x, y, 0, 0]));
        let group = bind_group(ctx, "pick", &self.view_layout, &[&view.frame, &self.io]);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("pick"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, scene, &[]);
            pass.set_bind_group(1, &group, &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        ctx.queue.submit([encoder.finish()]);
        let bytes = ctx.read_buffer_range(&self.io, 0, 32);
        let words = bytemuck::cast_slice::<u8, [u32; 4]>(&bytes);
        Some((PrimaryHit::decode(words[1]), f32::from_bits(words[0][2])))
    }
}

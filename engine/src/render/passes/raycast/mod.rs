//! The ray-casting benchmark pass: one camera ray per pixel centre and, with `max_depth` 1 in the frame
//! constants, one cosine-distributed bounce per hit, without shading: the traversal throughput the speed targets
//! count.

use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, bind_group, compute_layout};
use crate::render::shaders::{ShaderModule, compose};
use crate::render::view::ViewTargets;

pub const KERNEL: ShaderModule = ShaderModule {
    name: "raycast",
    source: include_str!("raycast.wgsl"),
    requires: &[
        "constants",
        "camera",
        "sampler",
        "sampling",
        "math",
        "traversal/tlas",
    ],
};

pub struct RaycastPass {
    pipeline: wgpu::ComputePipeline,
    view_layout: wgpu::BindGroupLayout,
}

impl RaycastPass {
    pub fn new(ctx: &GpuContext, scene_layout: &wgpu::BindGroupLayout) -> Self {
        use Binding::*;
        // frame, hit distances, ray counter
        let view_layout = compute_layout(ctx, "raycast", &[Params, ReadWrite, ReadWrite]);
        let pipeline = crate::gpu::compute_pipeline(
            ctx,
            "raycast",
            compose(&KERNEL),
            &[Some(scene_layout), Some(&view_layout)],
            "cast_rays",
        );
        Self {
            pipeline,
            view_layout,
        }
    }

    /// Records the pass over the view (its frame uniform already written); rays cast land in the view's ray
    /// counter, which is reset first.
    pub fn encode(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &wgpu::BindGroup,
        view: &ViewTargets,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        // The summed hit distances are written out so that no work can be optimised away.
        let distances = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("raycast distances"),
            size: view.pixels().max(1) * 4,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let group = bind_group(
            ctx,
            "raycast",
            &self.view_layout,
            &[&view.frame, &distances, &view.ray_counter],
        );
        encoder.clear_buffer(&view.ray_counter, 0, None);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("raycast"),
            timestamp_writes,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, scene, &[]);
        pass.set_bind_group(1, &group, &[]);
        let (x, y) = view.workgroups();
        pass.dispatch_workgroups(x, y, 1);
    }
}

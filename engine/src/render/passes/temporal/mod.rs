//! The temporal pass of the real-time path (`temporal.wgsl`): reprojects last frame's history through the
//! motion vectors with validated bilinear taps, shortens it where the temporal gradients say lighting changed,
//! and blends in this frame's sample. The history is in the accumulation's layout, so the spatial filter
//! (passes/denoise) and the tone mapper read it as they read an accumulation. Last frame's history is copied
//! aside first: the pass reads it at reprojected neighbours while writing the new one.

use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, CachedGroup, bind_group, compute_layout};
use crate::render::realtime_targets::RealtimeTargets;
use crate::render::shaders::{ShaderModule, compose};
use crate::render::view::ViewTargets;

pub const KERNEL: ShaderModule = ShaderModule {
    name: "temporal",
    source: include_str!("temporal.wgsl"),
    requires: &[
        "constants",
        "math",
        "color",
        "octahedral",
        "realtime/frame",
        "realtime/gbuffer",
        "realtime/sample",
    ],
};

pub struct TemporalPass {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    group: CachedGroup<(u64, u64)>,
}

impl TemporalPass {
    pub fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        // frame, real-time frame, G-buffer, previous G-buffer, samples, gradients, edited materials,
        // previous history (4), history (4)
        let layout = compute_layout(
            ctx,
            "temporal",
            &[
                Params, Params, Read, Read, Read, Read, Read, Read, Read, Read, Read, ReadWrite,
                ReadWrite, ReadWrite, ReadWrite,
            ],
        );
        let pipeline = crate::gpu::compute_pipeline(
            ctx,
            "temporal",
            compose(&KERNEL),
            &[None, Some(&layout)],
            "accumulate",
        );
        Self {
            pipeline,
            layout,
            group: CachedGroup::default(),
        }
    }

    pub fn encode(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        view: &ViewTargets,
        targets: &RealtimeTargets,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let layout = &self.layout;
        let group = self
            .group
            .get_or_make((view.generation, targets.generation), || {
                let (h, p) = (&targets.history, &targets.history_prev);
                bind_group(
                    ctx,
                    "temporal",
                    layout,
                    &[
                        &view.frame,
                        &targets.uniform,
                        &targets.gbuffer,
                        &targets.gbuffer_prev,
                        &targets.samples,
                        &targets.gradients[crate::render::realtime_targets::FILTERED_GRADIENTS],
                        &targets.edited_materials,
                        &p.accum,
                        &p.albedo_depth,
                        &p.normal_hits,
                        &p.moments,
                        &h.accum,
                        &h.albedo_depth,
                        &h.normal_hits,
                        &h.moments,
                    ],
                )
            });
        for (from, to) in targets
            .history
            .buffers()
            .into_iter()
            .zip(targets.history_prev.buffers())
        {
            encoder.copy_buffer_to_buffer(from, 0, to, 0, None);
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("temporal"),
            timestamp_writes,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(1, group, &[]);
        let (x, y) = view.workgroups();
        pass.dispatch_workgroups(x, y, 1);
    }
}

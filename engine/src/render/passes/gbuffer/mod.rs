//! The G-buffer pass of the real-time path: one jittered camera ray per pixel and what it hit, with motion
//! vectors from the previous camera, placements and deformed positions (`gbuffer.wgsl`). It moves each
//! pixel's previous surface to the previous-frame G-buffer as it writes the new one.

use crate::gpu::ComputeModule;
use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, CachedGroup, bind_group, compute_layout};
use crate::render::material_lobes::MaterialLobes;
use crate::render::realtime_targets::{RealtimeTargets, SceneGroups, SceneLayouts};
use crate::render::shaders::{ShaderModule, compose};
use crate::render::view::ViewTargets;

pub const KERNEL: ShaderModule = ShaderModule {
    name: "gbuffer",
    source: include_str!("gbuffer.wgsl"),
    requires: &[
        "constants",
        "camera",
        "sampler",
        "octahedral",
        "integrator/path",
        "realtime/frame",
        "realtime/gbuffer",
        "realtime/motion",
    ],
};

pub struct GBufferPass {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    group: CachedGroup<(u64, u64)>,
}

impl GBufferPass {
    pub fn new(ctx: &GpuContext, layouts: &SceneLayouts) -> Self {
        use Binding::*;
        // frame, real-time frame, G-buffer, previous G-buffer, ray counter
        let layout = compute_layout(
            ctx,
            "gbuffer",
            &[Params, Params, ReadWrite, ReadWrite, ReadWrite],
        );
        // The G-buffer keeps only the core BSDF parameters (`pack_bsdf`): its kernel skips the extension lobes.
        let pipeline = ComputeModule::new(ctx, compose(&KERNEL), &layouts.with_pass(&layout))
            .pipeline("gbuffer", "write_gbuffer", &MaterialLobes::Core.constants());
        Self {
            pipeline,
            layout,
            group: CachedGroup::default(),
        }
    }

    /// Records the pass; the view's frame uniform and the targets' real-time uniform hold this frame's.
    pub fn encode(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        groups: &SceneGroups,
        view: &ViewTargets,
        targets: &RealtimeTargets,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let layout = &self.layout;
        let group = self
            .group
            .get_or_make((view.generation, targets.generation), || {
                bind_group(
                    ctx,
                    "gbuffer",
                    layout,
                    &[
                        &view.frame,
                        &targets.uniform,
                        &targets.gbuffer,
                        &targets.gbuffer_prev,
                        &view.ray_counter,
                    ],
                )
            });
        let mut pass = groups.begin_pass(encoder, "gbuffer", group, timestamp_writes);
        pass.set_pipeline(&self.pipeline);
        let (x, y) = view.workgroups();
        pass.dispatch_workgroups(x, y, 1);
    }
}

//! ReSTIR DI over the real-time G-buffer (`restir_di.wgsl`): initial candidates with visibility reuse and
//! temporal reuse in one dispatch, spatial reuse and shading in a second; the final reservoirs stay for the
//! next frame. Which stages run, and whether reuse is unbiased, are flags of the real-time uniform.

use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, CachedGroup, bind_group, compute_layout};
use crate::render::realtime_targets::{RealtimeTargets, SceneGroups, SceneLayouts};
use crate::render::shaders::{ShaderModule, compose};
use crate::render::view::ViewTargets;

pub const KERNEL: ShaderModule = ShaderModule {
    name: "restir_di",
    source: include_str!("restir_di.wgsl"),
    requires: &[
        "constants",
        "camera",
        "sampler",
        "realtime/frame",
        "restir/reservoir",
        "integrator/realtime",
    ],
};

pub struct RestirDiPass {
    candidates: wgpu::ComputePipeline,
    spatial: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    group: CachedGroup<(u64, u64)>,
}

impl RestirDiPass {
    pub fn new(ctx: &GpuContext, layouts: &SceneLayouts) -> Self {
        use Binding::*;
        // frame, real-time frame, G-buffer, previous G-buffer, reservoirs, temporal reservoirs, direct light,
        // ray counter
        let layout = compute_layout(
            ctx,
            "restir di",
            &[
                Params, Params, Read, Read, ReadWrite, ReadWrite, ReadWrite, ReadWrite,
            ],
        );
        let [candidates, spatial] = crate::gpu::compute_pipelines(
            ctx,
            "restir di",
            compose(&KERNEL),
            &layouts.with_pass(&layout),
            ["candidates", "spatial"],
        );
        Self {
            candidates,
            spatial,
            layout,
            group: CachedGroup::default(),
        }
    }

    /// Records both dispatches in one compute pass (after the G-buffer pass of this frame).
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
        let restir = targets
            .restir
            .as_ref()
            .expect("ReSTIR buffers allocated before the pass runs");
        let group = self
            .group
            .get_or_make((view.generation, targets.generation), || {
                bind_group(
                    ctx,
                    "restir di",
                    layout,
                    &[
                        &view.frame,
                        &targets.uniform,
                        &targets.gbuffer,
                        &targets.gbuffer_prev,
                        &restir.reservoirs,
                        &restir.reservoirs_temporal,
                        &restir.direct_light,
                        &view.ray_counter,
                    ],
                )
            });
        let mut pass = groups.begin_pass(encoder, "restir di", group, timestamp_writes);
        let (x, y) = view.workgroups();
        for pipeline in [&self.candidates, &self.spatial] {
            pass.set_pipeline(pipeline);
            pass.dispatch_workgroups(x, y, 1);
        }
    }
}

//! The real-time trace pass: one path per pixel from the G-buffer's first hit (`realtime_trace.wgsl`), with
//! ReSTIR DI's direct light when it ran, into the frame's samples; and, at each gradient stratum's chosen
//! pixel, the estimate the next frame's gradient pass compares against.

use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, CachedGroup, bind_group, compute_layout};
use crate::render::material_lobes::{KernelNeeds, LobeKernels};
use crate::render::realtime_targets::{RealtimeTargets, SceneGroups, SceneLayouts};
use crate::render::shaders::{ShaderModule, compose};
use crate::render::view::ViewTargets;

pub const KERNEL: ShaderModule = ShaderModule {
    name: "realtime_trace",
    source: include_str!("realtime_trace.wgsl"),
    requires: &[
        "constants",
        "camera",
        "sampler",
        "realtime/frame",
        "realtime/sample",
        "integrator/realtime",
    ],
};

pub struct RealtimeTracePass {
    kernels: LobeKernels,
    layout: wgpu::BindGroupLayout,
    group: CachedGroup<(u64, u64)>,
}

impl RealtimeTracePass {
    pub fn new(ctx: &GpuContext, layouts: &SceneLayouts) -> Self {
        use Binding::*;
        // frame, real-time frame, G-buffer, direct light, samples, gradient estimates, ray counter
        let layout = compute_layout(
            ctx,
            "realtime trace",
            &[Params, Params, Read, Read, ReadWrite, ReadWrite, ReadWrite],
        );
        let kernels = LobeKernels::new(
            ctx,
            "realtime trace",
            compose(&KERNEL),
            &layouts.with_pass(&layout),
            "trace_realtime",
        );
        Self {
            kernels,
            layout,
            group: CachedGroup::default(),
        }
    }

    /// Records the pass with the kernel for the lobes the scene's materials use (compiled the first time).
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &mut self,
        ctx: &GpuContext,
        needs: KernelNeeds,
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
                let direct = targets
                    .restir
                    .as_ref()
                    .map_or(&targets.stub, |r| &r.direct_light);
                bind_group(
                    ctx,
                    "realtime trace",
                    layout,
                    &[
                        &view.frame,
                        &targets.uniform,
                        &targets.gbuffer,
                        direct,
                        &targets.samples,
                        &targets.gradient_estimates,
                        &view.ray_counter,
                    ],
                )
            });
        let mut pass = groups.begin_pass(encoder, "realtime trace", group, timestamp_writes);
        // Its gradient estimates sample lights by power, whatever next-event estimation leaves out: every kind.
        let needs = KernelNeeds {
            next_event_light_kinds: None,
            ..needs
        };
        pass.set_pipeline(self.kernels.get(needs));
        let (x, y) = view.workgroups();
        pass.dispatch_workgroups(x, y, 1);
    }
}

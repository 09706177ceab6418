//! Temporal gradients (A-SVGF) for the real-time path (`gradient.wgsl`): each previous-frame stratum's chosen
//! surface point shaded again with last frame's random numbers, then [`FILTER_ITERATIONS`] a-trous passes over
//! the strata. The filtered result is in `RealtimeTargets::gradients[FILTERED]`.

use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, bind_group, compute_layout, params_buffer, params_entry_dynamic};
use crate::render::realtime_targets::{RealtimeTargets, SceneGroups, SceneLayouts};
use crate::render::shaders::{ShaderModule, compose};
use crate::render::view::ViewTargets;
use bytemuck::{Pod, Zeroable};

pub const KERNEL: ShaderModule = ShaderModule {
    name: "gradient",
    source: include_str!("gradient.wgsl"),
    requires: &[
        "constants",
        "camera",
        "sampler",
        "realtime/frame",
        "integrator/realtime",
    ],
};

pub use crate::render::realtime_targets::{
    FILTERED_GRADIENTS as FILTERED, GRADIENT_FILTER_ITERATIONS as FILTER_ITERATIONS,
};

/// One filter iteration's uniform (`FilterStep` in gradient.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FilterStep {
    pub step: u32,
    pub _pad: [u32; 3],
}

pub struct GradientPass {
    shade: wgpu::ComputePipeline,
    filter: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    step_group: wgpu::BindGroup,
    step_stride: u32,
    /// For the view and targets generations: [0] writes gradients[0] (reads [1]), [1] the reverse.
    pair: Option<((u64, u64), [wgpu::BindGroup; 2])>,
}

impl GradientPass {
    pub fn new(ctx: &GpuContext, layouts: &SceneLayouts) -> Self {
        use Binding::*;
        // frame, real-time frame, previous G-buffer, estimates, gradients in, gradients out, ray counter
        let layout = compute_layout(
            ctx,
            "gradient",
            &[Params, Params, Read, Read, Read, ReadWrite, ReadWrite],
        );
        let step_size = std::mem::size_of::<FilterStep>() as u64;
        let step_layout = ctx.pipelines.bind_group_layout(
            "gradient filter step",
            &[params_entry_dynamic(ctx, 0, step_size)],
        );
        let stride = step_size.next_multiple_of(ctx.params_offset_alignment());
        let mut bytes = vec![0u8; (stride * FILTER_ITERATIONS as u64) as usize];
        for k in 0..FILTER_ITERATIONS {
            let step = FilterStep {
                step: 1 << k,
                _pad: [0; 3],
            };
            bytes[k * stride as usize..][..step_size as usize]
                .copy_from_slice(bytemuck::bytes_of(&step));
        }
        let step_buffer = params_buffer(ctx, "gradient filter steps", bytes.len());
        ctx.queue.write_buffer(&step_buffer, 0, &bytes);
        let step_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("gradient filter step"),
            layout: &step_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &step_buffer,
                    offset: 0,
                    size: wgpu::BufferSize::new(step_size),
                }),
            }],
        });
        // The filter's step uniform is group 3, after the real-time groups.
        let [scene, pass, motion] = layouts.with_pass(&layout);
        let [shade, filter] = crate::gpu::compute_pipelines(
            ctx,
            "gradient",
            compose(&KERNEL),
            &[scene, pass, motion, Some(&step_layout)],
            ["shade_gradients", "filter_gradients"],
        );
        Self {
            shade,
            filter,
            layout,
            step_group,
            step_stride: stride as u32,
            pair: None,
        }
    }

    /// Records the shading and filter dispatches (after the G-buffer pass, before the real-time trace
    /// overwrites last frame's estimates).
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
        let make = |read: &wgpu::Buffer, write: &wgpu::Buffer| {
            bind_group(
                ctx,
                "gradient",
                layout,
                &[
                    &view.frame,
                    &targets.uniform,
                    &targets.gbuffer_prev,
                    &targets.gradient_estimates,
                    read,
                    write,
                    &view.ray_counter,
                ],
            )
        };
        let key = (view.generation, targets.generation);
        if self.pair.as_ref().is_none_or(|(k, _)| *k != key) {
            let [a, b] = &targets.gradients;
            self.pair = Some((key, [make(b, a), make(a, b)]));
        }
        let pair = &self.pair.as_ref().expect("made above").1;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("gradients"),
            timestamp_writes,
        });
        pass.set_bind_group(0, groups.scene, &[]);
        pass.set_bind_group(2, groups.motion, &[]);
        let (sx, sy) = targets.strata;
        let (x, y) = (sx.div_ceil(8), sy.div_ceil(8));
        pass.set_pipeline(&self.shade);
        pass.set_bind_group(1, &pair[0], &[]);
        pass.set_bind_group(3, &self.step_group, &[0]);
        pass.dispatch_workgroups(x, y, 1);
        pass.set_pipeline(&self.filter);
        for k in 0..FILTER_ITERATIONS {
            // Iteration k reads buffer k % 2 and writes the other.
            pass.set_bind_group(1, &pair[(k + 1) % 2], &[]);
            pass.set_bind_group(3, &self.step_group, &[k as u32 * self.step_stride]);
            pass.dispatch_workgroups(x, y, 1);
        }
    }
}

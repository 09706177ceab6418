//! The display transform: accumulated (or denoised) linear radiance -> exposure -> tone curve -> sRGB, packed
//! RGBA8 into the view's `rgba8` target; or one of the AOVs for inspection.

use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, bind_group, compute_layout, params_buffer};
use crate::render::shaders::{ShaderModule, compose};
use crate::render::view::ViewTargets;
use bevy_ecs::prelude::Resource;
use bytemuck::{Pod, Zeroable};
use std::sync::Mutex;

pub const KERNEL: ShaderModule = ShaderModule {
    name: "tonemap",
    source: include_str!("tonemap.wgsl"),
    requires: &["color"],
};

/// The kernel's uniform (`Params` in tonemap.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct TonemapParams {
    pub width: u32,
    pub height: u32,
    /// 0 ACES fitted, 1 Reinhard on luminance, 2 clamp.
    pub tonemapper: u32,
    /// 0 colour, 1 albedo, 2 normal, 3 depth.
    pub view: u32,
    pub exposure_scale: f32,
    pub depth_scale: f32,
    pub _pad: [u32; 2],
}

#[derive(Resource)]
pub struct TonemapPass {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    /// Over the accumulation and over the last few other inputs (the denoiser's output, the real-time
    /// image), by view generation and input; remade when the view changes. Behind a lock so that a one-off
    /// transform (a screenshot, a recorded frame) can run through a shared borrow.
    groups: Mutex<Vec<(GroupKey, wgpu::BindGroup)>>,
}

/// A bind group's view generation and radiance input (`None`: the view's accumulation).
type GroupKey = (u64, Option<wgpu::Buffer>);

/// Bind groups kept: the accumulation, the denoiser's output, the real-time image, the hand-over's and the
/// host-denoised image.
const CACHED_GROUPS: usize = 5;

/// Which radiance the transform reads.
#[derive(Clone, Copy)]
pub enum TonemapInput<'a> {
    Accumulation,
    /// Another buffer in the accumulation's layout: the denoiser's output, the real-time image.
    Denoised(&'a wgpu::Buffer),
}

impl TonemapPass {
    pub fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        // radiance, albedo + depth, normal + hits, rgba8 out, params
        let layout = compute_layout(ctx, "tonemap", &[Read, Read, Read, ReadWrite, Params]);
        let pipeline = crate::gpu::compute_pipeline(
            ctx,
            "tonemap",
            compose(&KERNEL),
            &[Some(&layout)],
            "tonemap",
        );
        Self {
            pipeline,
            layout,
            params: params_buffer(ctx, "tonemap params", std::mem::size_of::<TonemapParams>()),
            groups: Mutex::default(),
        }
    }

    /// The bind group over the view and `input` (made again only when the view was replaced).
    fn group(&self, ctx: &GpuContext, view: &ViewTargets, input: TonemapInput) -> wgpu::BindGroup {
        let (radiance, key) = match input {
            TonemapInput::Accumulation => (&view.accum, (view.generation, None)),
            TonemapInput::Denoised(b) => (b, (view.generation, Some(b.clone()))),
        };
        let mut groups = self.groups.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, g)) = groups.iter().find(|(k, _)| *k == key) {
            return g.clone();
        }
        let group = bind_group(
            ctx,
            "tonemap",
            &self.layout,
            &[
                radiance,
                &view.albedo_depth,
                &view.normal_hits,
                &view.rgba8,
                &self.params,
            ],
        );
        groups.retain(|(k, _)| k.0 == view.generation);
        if groups.len() >= CACHED_GROUPS {
            groups.remove(0);
        }
        groups.push((key, group.clone()));
        group
    }

    /// Records the transform of `input` into the view's `rgba8`.
    pub fn encode(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        view: &ViewTargets,
        input: TonemapInput,
        params: &TonemapParams,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let group = self.group(ctx, view, input);
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(params));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("tonemap"),
            timestamp_writes,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        let (x, y) = view.workgroups();
        pass.dispatch_workgroups(x, y, 1);
    }
}

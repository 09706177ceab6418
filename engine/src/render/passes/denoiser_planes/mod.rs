//! The denoiser-planes pass: the accumulation's mean radiance (split as `oidn::inputs::PixelSplit` says, in
//! `split.wgsl`) and first-hit albedo and normal,
//! sanitised, written as packed float3 planes (`pack.wgsl`) into buffers an external denoiser (Open Image
//! Denoise's GPU device) reads in place, and its packed output plus the exact unscattered radiance turned back
//! into the accumulation's layout for display (`unpack.wgsl`), so that neither the inputs nor a displayed result
//! travel through host memory.

use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, bind_group, compute_layout, params_buffer};
use crate::render::shaders::{ShaderModule, compose};
use bytemuck::{Pod, Zeroable};
// The accumulation buffers the pass reads (defined beside `ViewTargets`, which hands them out).
pub use crate::render::view::DenoiserSources;

pub const PACK_KERNEL: ShaderModule = ShaderModule {
    name: "denoiser_pack",
    // The pixel split both kernels share, then the kernel.
    source: concat!(include_str!("split.wgsl"), include_str!("pack.wgsl")),
    requires: &["math"],
};

pub const UNPACK_KERNEL: ShaderModule = ShaderModule {
    name: "denoiser_unpack",
    source: concat!(include_str!("split.wgsl"), include_str!("unpack.wgsl")),
    requires: &["math"],
};

/// Radiance above this is clamped before denoising (here and on the host path): OIDN's HDR transfer must not
/// overflow to infinity.
pub const MAX_RADIANCE: f32 = 1e30;

/// Bytes of one packed float3 plane of `pixels` pixels.
pub fn plane_bytes(pixels: u64) -> u64 {
    pixels * 12
}

/// Both kernels' uniform (`Params` in pack.wgsl and unpack.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct DenoiserPlanesParams {
    pub width: u32,
    pub height: u32,
    pub max_radiance: f32,
    pub _pad: u32,
}

pub struct DenoiserPlanesPass {
    pack: wgpu::ComputePipeline,
    pack_layout: wgpu::BindGroupLayout,
    unpack: wgpu::ComputePipeline,
    unpack_layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
}

impl DenoiserPlanesPass {
    pub fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        let pack_layout = compute_layout(
            ctx,
            "denoiser_pack",
            &[
                Read, Read, Read, Read, ReadWrite, ReadWrite, ReadWrite, Params,
            ],
        );
        let unpack_layout = compute_layout(
            ctx,
            "denoiser_unpack",
            &[Read, Read, Read, Read, Read, ReadWrite, Params],
        );
        let pipeline = |label, kernel: &ShaderModule, layout, entry| {
            crate::gpu::compute_pipeline(ctx, label, compose(kernel), &[Some(layout)], entry)
        };
        Self {
            pack: pipeline("denoiser_pack", &PACK_KERNEL, &pack_layout, "pack"),
            unpack: pipeline("denoiser_unpack", &UNPACK_KERNEL, &unpack_layout, "unpack"),
            pack_layout,
            unpack_layout,
            params: params_buffer(
                ctx,
                "denoiser_planes params",
                std::mem::size_of::<DenoiserPlanesParams>(),
            ),
        }
    }

    fn write_params(&self, ctx: &GpuContext, width: u32, height: u32) {
        let params = DenoiserPlanesParams {
            width,
            height,
            max_radiance: MAX_RADIANCE,
            _pad: 0,
        };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
    }

    /// Records the packing of `sources` into the `color`, `albedo` and `normal` planes (each at least
    /// [`plane_bytes`] of the image).
    pub fn encode_pack(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        sources: &DenoiserSources,
        [color, albedo, normal]: [&wgpu::Buffer; 3],
    ) {
        self.write_params(ctx, sources.width, sources.height);
        let group = bind_group(
            ctx,
            "denoiser_pack",
            &self.pack_layout,
            &[
                &sources.accum,
                &sources.albedo_depth,
                &sources.normal_hits,
                &sources.moments,
                color,
                albedo,
                normal,
                &self.params,
            ],
        );
        let size = (sources.width, sources.height);
        dispatch(encoder, "denoiser_pack", &self.pack, &group, size);
    }

    /// Records the unpacking of the denoiser's `output` plane (with the `color` plane it was given, for pixels
    /// it returned non-finite and pixels the split keeps), plus the unscattered radiance of `sources` where it
    /// was split off, into `shown`, in the accumulation's layout.
    pub fn encode_unpack(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        sources: &DenoiserSources,
        [output, color]: [&wgpu::Buffer; 2],
        shown: &wgpu::Buffer,
    ) {
        let (width, height) = (sources.width, sources.height);
        self.write_params(ctx, width, height);
        let group = bind_group(
            ctx,
            "denoiser_unpack",
            &self.unpack_layout,
            &[
                output,
                color,
                &sources.accum,
                &sources.normal_hits,
                &sources.moments,
                shown,
                &self.params,
            ],
        );
        dispatch(
            encoder,
            "denoiser_unpack",
            &self.unpack,
            &group,
            (width, height),
        );
    }
}

fn dispatch(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    group: &wgpu::BindGroup,
    (width, height): (u32, u32),
) {
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
}

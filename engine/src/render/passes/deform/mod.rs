//! The skin + morph pass: morph deltas, then linear-blend skinning, written straight into each GPU-deformed
//! mesh's vertex-pool range (`deform.wgsl`; the deform plugin, `crate::gpu_deform`, owns the inputs and decides
//! when it runs).

use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, bind_group, compute_layout, grid};
use crate::render::shaders::{ShaderModule, compose};
use bytemuck::{Pod, Zeroable};

pub const KERNEL: ShaderModule = ShaderModule {
    name: "deform",
    source: include_str!("deform.wgsl"),
    requires: &["constants", "math", "octahedral"],
};

/// The kernel's uniform (`DeformParams` in deform.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct DeformParams {
    pub mesh_count: u32,
    pub groups_x: u32,
    pub _pad: [u32; 2],
}

/// What the pass reads and writes.
pub struct DeformBuffers<'a> {
    /// Rest attributes, influences and morph deltas of every GPU-deformed mesh.
    pub data: &'a wgpu::Buffer,
    /// `DeformMesh` per mesh.
    pub meshes: &'a wgpu::Buffer,
    pub joint_matrices: &'a wgpu::Buffer,
    pub morph_weights: &'a wgpu::Buffer,
    /// Per mesh: deform this frame (bit 0), refit only (bit 1).
    pub mesh_flags: &'a wgpu::Buffer,
    pub vertex_pool: &'a wgpu::Buffer,
    pub params: &'a wgpu::Buffer,
}

pub struct DeformPass {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

impl DeformPass {
    pub fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        let layout = compute_layout(
            ctx,
            "deform",
            &[Read, Read, Read, Read, Read, ReadWrite, Params],
        );
        let pipeline = crate::gpu::compute_pipeline(
            ctx,
            "deform",
            compose(&KERNEL),
            &[Some(&layout)],
            "deform",
        );
        Self { pipeline, layout }
    }

    pub fn bind(&self, ctx: &GpuContext, b: &DeformBuffers) -> wgpu::BindGroup {
        bind_group(
            ctx,
            "deform",
            &self.layout,
            &[
                b.data,
                b.meshes,
                b.joint_matrices,
                b.morph_weights,
                b.mesh_flags,
                b.vertex_pool,
                b.params,
            ],
        )
    }

    /// Records the pass: `workgroups` of `DEFORM_GROUP` vertices (the deform inputs' count); with `run` false an
    /// empty pass (its timestamps still bracket it).
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        group: &wgpu::BindGroup,
        workgroups: u32,
        run: bool,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("deform"),
            timestamp_writes,
        });
        if run {
            let (x, y) = grid(workgroups);
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
    }
}

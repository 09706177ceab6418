//! The BLAS refit pass: one workgroup per GPU-deformed mesh sweeps its child-pair nodes level by level, deepest
//! first, then measures the refit tree's SAH cost for the rebuild guard (`refit.wgsl`).

use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, bind_group, compute_layout, grid};
use crate::render::shaders::{ShaderModule, compose};
use bytemuck::{Pod, Zeroable};

pub const KERNEL: ShaderModule = ShaderModule {
    name: "refit",
    source: include_str!("refit.wgsl"),
    requires: &["constants", "scene/types"],
};

/// `RefitMesh` in refit.wgsl: where a refit mesh's nodes, triangles, positions and level order are.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct RefitMeshGpu {
    pub blas_root: u32,
    pub triangle_offset: u32,
    pub position_offset: u32,
    pub node_count: u32,
    pub order_offset: u32,
    pub level_offset: u32,
    pub levels: u32,
    pub _pad: u32,
}

/// What the pass reads and writes.
pub struct RefitBuffers<'a> {
    pub blas_nodes: &'a wgpu::Buffer,
    pub triangles: &'a wgpu::Buffer,
    pub vertex_pool: &'a wgpu::Buffer,
    /// `RefitMeshGpu` per mesh.
    pub meshes: &'a wgpu::Buffer,
    /// Per mesh, node indices sorted by depth, deepest first.
    pub level_order: &'a wgpu::Buffer,
    pub level_starts: &'a wgpu::Buffer,
    /// Per mesh: non-zero to refit this frame.
    pub mesh_flags: &'a wgpu::Buffer,
    /// Out: SAH cost per mesh.
    pub sah_cost: &'a wgpu::Buffer,
}

pub struct RefitPass {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

impl RefitPass {
    pub fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        let layout = compute_layout(
            ctx,
            "refit",
            &[ReadWrite, Read, Read, Read, Read, Read, Read, ReadWrite],
        );
        let pipeline =
            crate::gpu::compute_pipeline(ctx, "refit", compose(&KERNEL), &[Some(&layout)], "refit");
        Self { pipeline, layout }
    }

    pub fn bind(&self, ctx: &GpuContext, b: &RefitBuffers) -> wgpu::BindGroup {
        bind_group(
            ctx,
            "refit",
            &self.layout,
            &[
                b.blas_nodes,
                b.triangles,
                b.vertex_pool,
                b.meshes,
                b.level_order,
                b.level_starts,
                b.mesh_flags,
                b.sah_cost,
            ],
        )
    }

    /// Records the pass: one workgroup per mesh (meshes not flagged return at once).
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        group: &wgpu::BindGroup,
        meshes: u32,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("refit"),
            timestamp_writes,
        });
        let (x, y) = grid(meshes);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }
}

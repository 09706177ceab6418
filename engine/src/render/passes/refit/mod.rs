//! The BLAS refit pass: one workgroup per GPU-deformed mesh sweeps its child-pair nodes level by level, deepest
//! first, then measures the refit tree's SAH cost for the rebuild guard (`refit.wgsl`); a second dispatch
//! re-quantises the wide trees collapsed from those BVH2s (`refit_wide`), every node independently.

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
    /// The mesh's wide tree: its first node in the wide-node buffer (`NONE` without one), its node count, and
    /// where its nodes' BVH2 sources start in the source table.
    pub wide_root: u32,
    pub wide_count: u32,
    pub source_offset: u32,
    pub _pad: [u32; 2],
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
    /// The wide trees' nodes (re-quantised in place) and the BVH2 node of each.
    pub wide_nodes: &'a wgpu::Buffer,
    pub wide_sources: &'a wgpu::Buffer,
}

pub struct RefitPass {
    pipeline: wgpu::ComputePipeline,
    wide_pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

impl RefitPass {
    pub fn new(ctx: &GpuContext) -> Self {
        use Binding::*;
        let layout = compute_layout(
            ctx,
            "refit",
            &[
                ReadWrite, Read, Read, Read, Read, Read, Read, ReadWrite, ReadWrite, Read,
            ],
        );
        let pipeline =
            crate::gpu::compute_pipeline(ctx, "refit", compose(&KERNEL), &[Some(&layout)], "refit");
        let wide_pipeline = crate::gpu::compute_pipeline(
            ctx,
            "refit wide",
            compose(&KERNEL),
            &[Some(&layout)],
            "refit_wide",
        );
        Self {
            pipeline,
            wide_pipeline,
            layout,
        }
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
                b.wide_nodes,
                b.wide_sources,
            ],
        )
    }

    /// Records the pass: one workgroup per mesh (meshes not flagged return at once), and with `wide` the wide
    /// trees' dispatch after it (wgpu orders the two dispatches' accesses to the BVH2 nodes).
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        group: &wgpu::BindGroup,
        meshes: u32,
        wide: bool,
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
        if wide {
            pass.set_pipeline(&self.wide_pipeline);
            pass.dispatch_workgroups(x, y, 1);
        }
    }
}

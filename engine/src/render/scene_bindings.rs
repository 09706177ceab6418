//! Group 0 of every ray-tracing kernel: the scene's buffers, read only (`shaders/scene/bindings.wgsl`). The
//! layout is made once; the bind group is remade only when the scene replaced a buffer (its `generation`).

use super::gpu_scene::GpuScene;
use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, bind_group, compute_layout};
use bevy_ecs::prelude::Resource;

/// Buffers bound, in binding order.
const SCENE_BINDINGS: usize = 14;

#[derive(Resource)]
pub struct SceneBindings {
    pub layout: wgpu::BindGroupLayout,
    group: Option<(u64, wgpu::BindGroup)>,
}

impl SceneBindings {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            layout: compute_layout(ctx, "scene", &[Binding::Read; SCENE_BINDINGS]),
            group: None,
        }
    }

    /// The bind group over `scene`'s current buffers.
    pub fn group(&mut self, ctx: &GpuContext, scene: &GpuScene) -> &wgpu::BindGroup {
        if self
            .group
            .as_ref()
            .is_none_or(|(g, _)| *g != scene.generation)
        {
            self.group = Some((scene.generation, Self::make(ctx, &self.layout, scene)));
        }
        &self.group.as_ref().expect("made above").1
    }

    /// A bind group over `scene` without touching the cache (for queries made through a shared borrow).
    pub fn fresh(&self, ctx: &GpuContext, scene: &GpuScene) -> wgpu::BindGroup {
        match &self.group {
            Some((g, group)) if *g == scene.generation => group.clone(),
            _ => Self::make(ctx, &self.layout, scene),
        }
    }

    fn make(ctx: &GpuContext, layout: &wgpu::BindGroupLayout, scene: &GpuScene) -> wgpu::BindGroup {
        bind_group(
            ctx,
            "scene",
            layout,
            &[
                &scene.tlas_nodes,
                &scene.blas_nodes,
                &scene.instances,
                &scene.meshes,
                &scene.triangles,
                &scene.vertex_pool,
                &scene.materials,
                &scene.texels,
                &scene.texture_infos,
                &scene.light_buffer,
                &scene.wide_nodes,
                &scene.light_cdf,
                &scene.environment_map,
                &scene.light_tree,
            ],
        )
    }
}

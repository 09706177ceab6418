//! Group 0 of every ray-tracing kernel: the scene's buffers, read only (`shaders/scene/bindings.wgsl`), or on
//! CPU adapters their copies as textures (`render::scene_texels`). The layout is made once; the bind group is
//! remade only when the scene replaced a buffer (its `generation`).

use super::gpu_scene::{GpuScene, SceneWrites};
use super::scene_texels::{self, SceneTexels};
use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, bind_group, compute_layout};
use bevy_ecs::prelude::Resource;

/// Buffers bound, in binding order (on CPU adapters, one storage texture each).
const SCENE_BINDINGS: usize = crate::gpu::SCENE_TEXTURES as usize;

#[derive(Resource)]
pub struct SceneBindings {
    pub layout: wgpu::BindGroupLayout,
    group: Option<(u64, wgpu::BindGroup)>,
    /// CPU adapters: the textures the group binds.
    texels: Option<SceneTexels>,
}

impl SceneBindings {
    pub fn new(ctx: &GpuContext) -> Self {
        let layout = if ctx.scene_in_textures {
            ctx.pipelines
                .bind_group_layout("scene", &scene_texels::layout_entries(SCENE_BINDINGS))
        } else {
            compute_layout(ctx, "scene", &[Binding::Read; SCENE_BINDINGS])
        };
        Self {
            layout,
            group: None,
            texels: None,
        }
    }

    /// The bind group over `scene`'s current buffers. On CPU adapters `encoder` first copies into their
    /// textures the buffers the scene marked written and those in `gpu_written` (GPU passes of this frame, in
    /// command buffers submitted before `encoder`'s).
    pub fn group(
        &mut self,
        ctx: &GpuContext,
        scene: &mut GpuScene,
        encoder: &mut wgpu::CommandEncoder,
        gpu_written: SceneWrites,
    ) -> &wgpu::BindGroup {
        let written = std::mem::take(&mut scene.written) | gpu_written;
        if ctx.scene_in_textures {
            let buffers = Self::buffers(scene);
            match &self.texels {
                Some(texels) if texels.of(scene) => texels.copy(encoder, &buffers, written),
                _ => {
                    self.texels = Some(SceneTexels::new(ctx, encoder, &buffers, scene.generation));
                    self.group = None;
                }
            }
        }
        if self
            .group
            .as_ref()
            .is_none_or(|(g, _)| *g != scene.generation)
        {
            let group = match &self.texels {
                Some(texels) => Self::make_textures(ctx, &self.layout, texels),
                None => Self::make(ctx, &self.layout, scene),
            };
            self.group = Some((scene.generation, group));
        }
        &self.group.as_ref().expect("made above").1
    }

    /// A bind group over `scene` without touching the cache (for queries made through a shared borrow). On
    /// CPU adapters whose textures lag behind the scene, a one-off copy of every buffer is submitted first.
    pub fn fresh(&self, ctx: &GpuContext, scene: &GpuScene) -> wgpu::BindGroup {
        let current = !ctx.scene_in_textures || scene.written == SceneWrites::NONE;
        match &self.group {
            Some((g, group)) if *g == scene.generation && current => group.clone(),
            _ if ctx.scene_in_textures => {
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                let texels =
                    SceneTexels::new(ctx, &mut encoder, &Self::buffers(scene), scene.generation);
                ctx.queue.submit([encoder.finish()]);
                Self::make_textures(ctx, &self.layout, &texels)
            }
            _ => Self::make(ctx, &self.layout, scene),
        }
    }

    /// Bytes of the scene's copies as textures (0 where kernels read the buffers).
    pub fn texture_bytes(&self) -> u64 {
        self.texels.as_ref().map_or(0, SceneTexels::bytes)
    }

    /// The scene's buffers in binding order.
    fn buffers(scene: &GpuScene) -> [&wgpu::Buffer; SCENE_BINDINGS] {
        [
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
        ]
    }

    fn make(ctx: &GpuContext, layout: &wgpu::BindGroupLayout, scene: &GpuScene) -> wgpu::BindGroup {
        bind_group(ctx, "scene", layout, &Self::buffers(scene))
    }

    fn make_textures(
        ctx: &GpuContext,
        layout: &wgpu::BindGroupLayout,
        texels: &SceneTexels,
    ) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry> = texels
            .views()
            .enumerate()
            .map(|(i, view)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: wgpu::BindingResource::TextureView(view),
            })
            .collect();
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene texels"),
            layout,
            entries: &entries,
        })
    }
}

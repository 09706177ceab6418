//! The viewer's display pass: the tone-mapped image (the view's `rgba8` target) drawn into the egui frame as a
//! paint callback, inside egui's own render pass. No copy to a texture: a fragment shader reads the storage
//! buffer directly (`display.wgsl`).

use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, layout_for, uniform_buffer};
use crate::render::shaders::{ShaderModule, compose};
use crate::render::view::ViewTargets;
use bytemuck::{Pod, Zeroable};

pub const KERNEL: ShaderModule = ShaderModule {
    name: "display",
    source: include_str!("display.wgsl"),
    requires: &["color"],
};

/// The fragment shader's uniform (`DisplayParams` in display.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct DisplayParams {
    pub origin: [f32; 2],
    pub size: [f32; 2],
    pub image_width: u32,
    pub image_height: u32,
    pub srgb_target: u32,
    pub _pad: u32,
}

/// GPU objects of the display pass, kept in egui-wgpu's callback resources (one per egui renderer).
pub struct DisplayResources {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    srgb_target: bool,
    /// The image buffer currently bound, by [`ViewTargets::generation`].
    bound: Option<(u64, wgpu::BindGroup)>,
    image_size: (u32, u32),
    source: Option<(u64, wgpu::Buffer)>,
}

impl DisplayResources {
    /// Builds the pipeline for a render target of `format` (the window surface or an offscreen texture).
    pub fn new(ctx: &GpuContext, format: wgpu::TextureFormat) -> Self {
        let device = &ctx.device;
        let layout = layout_for(
            ctx,
            "display",
            &[Binding::Read, Binding::Uniform],
            wgpu::ShaderStages::FRAGMENT,
        );
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("display"),
            source: wgpu::ShaderSource::Wgsl(compose(&KERNEL).into()),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("display"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("display"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("display_vertex"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("display_fragment"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            multiview_mask: None,
            cache: None,
        });
        let params = uniform_buffer(ctx, "display params", std::mem::size_of::<DisplayParams>());
        Self {
            pipeline,
            layout,
            params,
            srgb_target: format.is_srgb(),
            bound: None,
            image_size: (0, 0),
            source: None,
        }
    }

    /// Points the display at the view's current image (call each frame before egui renders; the bind group is
    /// rebuilt only when the view's buffers were replaced).
    pub fn set_source(&mut self, view: &ViewTargets) {
        self.image_size = (view.width, view.height);
        if self.source.as_ref().map(|s| s.0) != Some(view.generation) {
            self.source = Some((view.generation, view.rgba8.clone()));
        }
    }

    fn bind_group(&mut self, device: &wgpu::Device) -> Option<&wgpu::BindGroup> {
        let (generation, buffer) = self.source.as_ref()?;
        if self.bound.as_ref().map(|b| b.0) != Some(*generation) {
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("display"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: buffer.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: self.params.as_entire_binding(),
                    },
                ],
            });
            self.bound = Some((*generation, group));
        }
        self.bound.as_ref().map(|b| &b.1)
    }
}

/// Registers the display pass with an egui-wgpu renderer drawing into `format`.
pub fn install(renderer: &mut egui_wgpu::Renderer, ctx: &GpuContext, format: wgpu::TextureFormat) {
    renderer
        .callback_resources
        .insert(DisplayResources::new(ctx, format));
}

/// Updates the image the display shows; a no-op when [`install`] was not called.
pub fn set_source(renderer: &mut egui_wgpu::Renderer, view: &ViewTargets) {
    if let Some(r) = renderer.callback_resources.get_mut::<DisplayResources>() {
        r.set_source(view);
    }
}

/// The paint callback the editor places where the image goes: `rect_px` is that area in framebuffer pixels.
pub struct ImageCallback {
    pub rect_px: [f32; 4],
}

impl egui_wgpu::CallbackTrait for ImageCallback {
    fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        _screen: &egui_wgpu::ScreenDescriptor,
        _encoder: &mut wgpu::CommandEncoder,
        resources: &mut egui_wgpu::CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        if let Some(r) = resources.get_mut::<DisplayResources>() {
            let params = DisplayParams {
                origin: [self.rect_px[0], self.rect_px[1]],
                size: [self.rect_px[2].max(1.0), self.rect_px[3].max(1.0)],
                image_width: r.image_size.0.max(1),
                image_height: r.image_size.1.max(1),
                srgb_target: r.srgb_target as u32,
                _pad: 0,
            };
            queue.write_buffer(&r.params, 0, bytemuck::bytes_of(&params));
            r.bind_group(device);
        }
        Vec::new()
    }

    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        pass: &mut wgpu::RenderPass<'static>,
        resources: &egui_wgpu::CallbackResources,
    ) {
        let Some(r) = resources.get::<DisplayResources>() else {
            return;
        };
        let Some((_, group)) = &r.bound else {
            return;
        };
        pass.set_pipeline(&r.pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..3, 0..1);
    }
}

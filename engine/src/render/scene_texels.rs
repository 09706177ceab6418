//! The scene's buffers as textures, which kernels on CPU adapters read instead ([`GpuContext::scene_in_textures`],
//! `shaders/scene/bindings_texels.wgsl`). lavapipe compiles every storage-buffer load into a loop over its SIMD
//! lanes with a bounds check per word, and a texel load into straight-line vector code: 6.5x the 16-byte loads
//! per second (docs/BENCHMARKS.md, "The CPU path"). Each buffer's bytes are the rgba32uint texels of one
//! read-only storage texture (cheaper there than a sampled one: no mip level looked up per lane), in rows of
//! `1 << SCENE_TEXEL_ROW_LOG2`. A buffer is copied again only when the scene marked it written
//! ([`GpuScene::written`]) or a GPU pass of the frame wrote it.

use super::gpu_scene::{GpuScene, SceneWrites};
use super::layout::SCENE_TEXEL_ROW_LOG2;
use crate::gpu::GpuContext;

const ROW_TEXELS: u64 = 1 << SCENE_TEXEL_ROW_LOG2;
const TEXEL_BYTES: u64 = 16;

/// One buffer's texture and the number of whole texels it holds.
struct Mirror {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    texels: u64,
}

impl Mirror {
    fn new(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Self {
        // Scene buffers are whole texels (`gpu::bind::storage_with` pads them); a partial one could not be copied.
        debug_assert_eq!(buffer.size() % TEXEL_BYTES, 0, "{buffer:?}");
        let texels = buffer.size() / TEXEL_BYTES;
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("scene texels"),
            size: wgpu::Extent3d {
                width: texels.clamp(1, ROW_TEXELS) as u32,
                height: texels.div_ceil(ROW_TEXELS).max(1) as u32,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Uint,
            usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        Self {
            texture,
            view,
            texels,
        }
    }

    /// Records the copy of `buffer` into the texture: the whole rows, then the last, partial one.
    fn copy(&self, encoder: &mut wgpu::CommandEncoder, buffer: &wgpu::Buffer) {
        let full_rows = self.texels / ROW_TEXELS;
        let rest = self.texels % ROW_TEXELS;
        let mut copy = |row: u64, width: u64, height: u64| {
            encoder.copy_buffer_to_texture(
                wgpu::TexelCopyBufferInfo {
                    buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: row * ROW_TEXELS * TEXEL_BYTES,
                        bytes_per_row: (height > 1).then_some((ROW_TEXELS * TEXEL_BYTES) as u32),
                        rows_per_image: None,
                    },
                },
                wgpu::TexelCopyTextureInfo {
                    texture: &self.texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: row as u32,
                        z: 0,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                wgpu::Extent3d {
                    width: width as u32,
                    height: height as u32,
                    depth_or_array_layers: 1,
                },
            );
        };
        if full_rows > 0 {
            copy(0, ROW_TEXELS, full_rows);
        }
        if rest > 0 {
            copy(full_rows, rest, 1);
        }
    }
}

/// The textures of one scene's buffers (binding order) and the scene generation whose buffers they mirror.
pub struct SceneTexels {
    mirrors: Vec<Mirror>,
    generation: u64,
}

impl SceneTexels {
    /// Textures for `buffers` (the scene's, binding order), copied in `encoder`.
    pub fn new(
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        buffers: &[&wgpu::Buffer],
        generation: u64,
    ) -> Self {
        let mirrors: Vec<Mirror> = buffers.iter().map(|b| Mirror::new(ctx, b)).collect();
        for (mirror, buffer) in mirrors.iter().zip(buffers) {
            mirror.copy(encoder, buffer);
        }
        Self {
            mirrors,
            generation,
        }
    }

    /// Whether these textures are of `scene`'s current buffers.
    pub fn of(&self, scene: &GpuScene) -> bool {
        self.generation == scene.generation
    }

    /// Records the copies of the buffers in `written` (binding order) into their textures.
    pub fn copy(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        buffers: &[&wgpu::Buffer],
        written: SceneWrites,
    ) {
        for (binding, (mirror, buffer)) in self.mirrors.iter().zip(buffers).enumerate() {
            if written.contains(binding) {
                mirror.copy(encoder, buffer);
            }
        }
    }

    pub fn views(&self) -> impl Iterator<Item = &wgpu::TextureView> {
        self.mirrors.iter().map(|m| &m.view)
    }

    /// Bytes the textures hold.
    pub fn bytes(&self) -> u64 {
        self.mirrors.iter().map(|m| m.texels * TEXEL_BYTES).sum()
    }
}

/// Compute-visible layout entries for `count` read-only scene textures at bindings 0, 1, 2, ...
pub fn layout_entries(count: usize) -> Vec<wgpu::BindGroupLayoutEntry> {
    (0..count as u32)
        .map(|binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::ReadOnly,
                format: wgpu::TextureFormat::Rgba32Uint,
                view_dimension: wgpu::TextureViewDimension::D2,
            },
            count: None,
        })
        .collect()
}

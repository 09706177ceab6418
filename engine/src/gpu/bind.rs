//! Bind-group layouts, bind groups and buffers in the shapes every pass uses: whole-buffer bindings numbered in
//! order, storage buffers with a minimum size, uniforms written each dispatch.

use super::GpuContext;
use wgpu::util::DeviceExt;

/// How a pass binds one buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Binding {
    /// A read-only storage buffer.
    Read,
    /// A read-write storage buffer.
    ReadWrite,
    Uniform,
    /// A compute pass's parameters: a uniform buffer on GPUs, a read-only storage buffer on CPU adapters
    /// ([`GpuContext::params_in_storage`]); written with `queue.write_buffer` into a [`params_buffer`].
    Params,
}

impl Binding {
    fn ty(self, ctx: &GpuContext) -> wgpu::BufferBindingType {
        match self {
            Self::Read => wgpu::BufferBindingType::Storage { read_only: true },
            Self::ReadWrite => wgpu::BufferBindingType::Storage { read_only: false },
            Self::Uniform => wgpu::BufferBindingType::Uniform,
            Self::Params => ctx.params_binding_type(),
        }
    }
}

/// A compute bind-group layout with `bindings[i]` at binding `i`.
pub fn compute_layout(
    ctx: &GpuContext,
    label: &str,
    bindings: &[Binding],
) -> wgpu::BindGroupLayout {
    layout_for(ctx, label, bindings, wgpu::ShaderStages::COMPUTE)
}

/// A bind-group layout with `bindings[i]` at binding `i`, visible to `stages`.
pub fn layout_for(
    ctx: &GpuContext,
    label: &str,
    bindings: &[Binding],
    stages: wgpu::ShaderStages,
) -> wgpu::BindGroupLayout {
    ctx.pipelines
        .bind_group_layout(label, &layout_entries(ctx, bindings, stages))
}

/// Layout entries with `bindings[i]` at binding `i`, visible to `stages`.
pub fn layout_entries(
    ctx: &GpuContext,
    bindings: &[Binding],
    stages: wgpu::ShaderStages,
) -> Vec<wgpu::BindGroupLayoutEntry> {
    bindings
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupLayoutEntry {
            binding: i as u32,
            visibility: stages,
            ty: wgpu::BindingType::Buffer {
                ty: b.ty(ctx),
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        })
        .collect()
}

/// Whole-buffer bindings 0, 1, 2, ... in order.
pub fn buffer_entries<'a>(buffers: &[&'a wgpu::Buffer]) -> Vec<wgpu::BindGroupEntry<'a>> {
    buffers
        .iter()
        .enumerate()
        .map(|(i, b)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: b.as_entire_binding(),
        })
        .collect()
}

/// A bind group of whole buffers, `buffers[i]` at binding `i`.
pub fn bind_group(
    ctx: &GpuContext,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &buffer_entries(buffers),
    })
}

/// A compute-visible [`Binding::Params`] entry at `binding` bound with a dynamic offset: one record of `size`
/// bytes among several in a [`params_buffer`] (their stride is [`GpuContext::params_offset_alignment`]).
pub fn params_entry_dynamic(
    ctx: &GpuContext,
    binding: u32,
    size: u64,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: ctx.params_binding_type(),
            has_dynamic_offset: true,
            min_binding_size: wgpu::BufferSize::new(size),
        },
        count: None,
    }
}

/// A buffer of a compute pass's parameters (`size` bytes, written with `queue.write_buffer`), bound as
/// [`Binding::Params`]: usable as a uniform (GPUs) and as a storage buffer (CPU adapters).
pub fn params_buffer(ctx: &GpuContext, label: &str, size: usize) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size as u64,
        usage: wgpu::BufferUsages::UNIFORM
            | wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// A uniform buffer of `size` bytes, written with `queue.write_buffer` (the window's render pipeline).
pub fn uniform_buffer(ctx: &GpuContext, label: &str, size: usize) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// An uninitialised storage buffer of `size` bytes (at least 16) that can be cleared, copied and read back.
pub fn storage_buffer(ctx: &GpuContext, label: &str, size: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Zeroes every buffer of `buffers` in one submission (new targets, a restarted accumulation).
pub fn clear_buffers<'a>(ctx: &GpuContext, buffers: impl IntoIterator<Item = &'a wgpu::Buffer>) {
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    for b in buffers {
        encoder.clear_buffer(b, 0, None);
    }
    ctx.queue.submit([encoder.finish()]);
}

/// A storage buffer holding `bytes`. wgpu rejects empty bindings and ones smaller than one element, so short
/// data is padded to 128 bytes (larger than any element, an instance being 112), and any data to whole 16-byte
/// texels (CPU adapters copy scene buffers into textures: `render::scene_texels`).
pub fn storage_with(ctx: &GpuContext, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    const MIN_BYTES: usize = 128;
    let size = bytes.len().max(MIN_BYTES).next_multiple_of(16);
    let padded;
    let contents = if bytes.len() < size {
        padded = {
            let mut v = bytes.to_vec();
            v.resize(size, 0);
            v
        };
        &padded[..]
    } else {
        bytes
    };
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
        })
}

/// Writes `bytes` into `buffer`, replacing it with a larger one when it does not fit; true when replaced (bind
/// groups must then be rebuilt). Empty data leaves the buffer as it is.
pub fn write_or_grow(
    ctx: &GpuContext,
    buffer: &mut wgpu::Buffer,
    bytes: &[u8],
    label: &str,
) -> bool {
    if bytes.is_empty() {
        return false;
    }
    if (buffer.size() as usize) < bytes.len() {
        *buffer = storage_with(ctx, label, bytes);
        true
    } else {
        ctx.queue.write_buffer(buffer, 0, bytes);
        false
    }
}

/// A dispatch of `groups` workgroups as (x, y) within wgpu's per-dimension limit of 65535.
pub fn grid(groups: u32) -> (u32, u32) {
    const MAX_GROUPS: u32 = 65535;
    if groups <= MAX_GROUPS {
        (groups.max(1), 1)
    } else {
        (MAX_GROUPS, groups.div_ceil(MAX_GROUPS))
    }
}

/// A bind group remade only when what it binds changed (`key`: the generations of its buffers).
pub struct CachedGroup<K: PartialEq> {
    cached: Option<(K, wgpu::BindGroup)>,
}

impl<K: PartialEq> Default for CachedGroup<K> {
    fn default() -> Self {
        Self { cached: None }
    }
}

impl<K: PartialEq> CachedGroup<K> {
    pub fn get_or_make(
        &mut self,
        key: K,
        make: impl FnOnce() -> wgpu::BindGroup,
    ) -> &wgpu::BindGroup {
        if self.cached.as_ref().is_none_or(|(k, _)| *k != key) {
            self.cached = Some((key, make()));
        }
        &self.cached.as_ref().expect("made above").1
    }

    /// The group made for `key`, if it is the cached one.
    pub fn get(&self, key: &K) -> Option<&wgpu::BindGroup> {
        self.cached
            .as_ref()
            .filter(|(k, _)| k == key)
            .map(|(_, g)| g)
    }
}

//! The view's render targets: what one camera's image accumulates into, apart from the scene buffers. They are
//! replaced on resize (a new `generation` tells passes to rebind) and cleared when accumulation restarts.

use super::layout::{GpuFrame, NONE};
use crate::gpu::GpuContext;
use crate::gpu::bind::{clear_buffers, params_buffer, storage_buffer};
use bevy_ecs::prelude::Resource;

#[derive(Resource)]
pub struct ViewTargets {
    pub width: u32,
    pub height: u32,
    /// The view's per-dispatch constants (`shaders/view.wgsl` `Frame`), bound by every ray-generating pass.
    pub frame: wgpu::Buffer,
    /// Radiance sum (rgb) and sample count (w) per pixel.
    pub accum: wgpu::Buffer,
    /// First-hit albedo sum (rgb) and camera-depth sum (w).
    pub albedo_depth: wgpu::Buffer,
    /// First-hit shading-normal sum (xyz) and the number of samples that hit (w).
    pub normal_hits: wgpu::Buffer,
    /// Unscattered radiance sum (rgb) and the sum of luminance(scattered)^2 (w): what the denoiser needs beyond
    /// the AOVs.
    pub moments: wgpu::Buffer,
    /// The tone-mapped image, sRGB RGBA8.
    pub rgba8: wgpu::Buffer,
    /// Rays traced by the last dispatch.
    pub ray_counter: wgpu::Buffer,
    /// Primary hit through each pixel centre (instance, triangle, barycentrics); a 16-byte stub while
    /// `hit_aov` is off, so nothing is spent on it unless asked.
    pub hit: wgpu::Buffer,
    pub hit_aov: bool,
    /// Identifies these buffers (unique across views; changes on resize and when the hit AOV is switched), so
    /// passes and displays rebind them.
    pub generation: u64,
}

fn next_generation() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

impl ViewTargets {
    /// The accumulation's sums an external denoiser reads, as handles another thread can hold.
    pub fn denoiser_sources(&self) -> DenoiserSources {
        DenoiserSources {
            accum: self.accum.clone(),
            albedo_depth: self.albedo_depth.clone(),
            normal_hits: self.normal_hits.clone(),
            moments: self.moments.clone(),
            width: self.width,
            height: self.height,
        }
    }

    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Self {
        let pixels = (width as u64 * height as u64).max(1);
        let view = Self {
            width,
            height,
            frame: params_buffer(ctx, "frame", std::mem::size_of::<GpuFrame>()),
            accum: storage_buffer(ctx, "accum", pixels * 16),
            albedo_depth: storage_buffer(ctx, "aov albedo", pixels * 16),
            normal_hits: storage_buffer(ctx, "aov normal", pixels * 16),
            moments: storage_buffer(ctx, "denoiser moments", pixels * 16),
            rgba8: storage_buffer(ctx, "rgba8", pixels * 4),
            ray_counter: storage_buffer(ctx, "ray counter", 16),
            hit: hit_buffer(ctx, width, height, false),
            hit_aov: false,
            generation: next_generation(),
        };
        view.clear(ctx);
        view
    }

    /// New targets at `width` x `height` (cleared) when the size changed; true when it did.
    pub fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) -> bool {
        if (width, height) == (self.width, self.height) {
            return false;
        }
        let hit_aov = self.hit_aov;
        *self = Self::new(ctx, width, height);
        self.set_hit_aov(ctx, hit_aov);
        true
    }

    /// Turns the primary-hit AOV on or off (allocating its buffer only while on).
    pub fn set_hit_aov(&mut self, ctx: &GpuContext, enabled: bool) {
        if enabled == self.hit_aov {
            return;
        }
        self.hit_aov = enabled;
        self.hit = hit_buffer(ctx, self.width, self.height, enabled);
        self.generation = next_generation();
    }

    /// Zeroes the accumulation: the next dispatch starts a new image.
    pub fn clear(&self, ctx: &GpuContext) {
        clear_buffers(
            ctx,
            [
                &self.accum,
                &self.albedo_depth,
                &self.normal_hits,
                &self.moments,
            ],
        );
    }

    pub fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }

    /// Workgroups of an 8x8 per-pixel kernel.
    pub fn workgroups(&self) -> (u32, u32) {
        (self.width.div_ceil(8), self.height.div_ceil(8))
    }

    /// Mean linear radiance per pixel (RGB), row-major from the top-left.
    pub fn read_radiance(&self, ctx: &GpuContext) -> Vec<[f32; 3]> {
        mean_rgb(&ctx.read_buffer(&self.accum, self.accum.size()))
    }

    /// First-hit AOVs: albedo (mean over `samples`), normal (mean, renormalised; zero where nothing was hit),
    /// camera depth (mean over samples that hit; +inf where none did).
    pub fn read_aovs(&self, ctx: &GpuContext, samples: u32) -> Aovs {
        let samples = samples.max(1) as f32;
        let ad = ctx.read_buffer(&self.albedo_depth, self.albedo_depth.size());
        let nh = ctx.read_buffer(&self.normal_hits, self.normal_hits.size());
        let ad: &[[f32; 4]] = bytemuck::cast_slice(&ad);
        let nh: &[[f32; 4]] = bytemuck::cast_slice(&nh);
        let mut aovs = Aovs::default();
        for (a, n) in ad.iter().zip(nh).take(self.pixels() as usize) {
            aovs.albedo
                .push([a[0] / samples, a[1] / samples, a[2] / samples]);
            let v = glam::Vec3::new(n[0], n[1], n[2]).normalize_or_zero();
            aovs.normal.push(v.to_array());
            aovs.depth.push(if n[3] > 0.0 {
                a[3] / n[3]
            } else {
                f32::INFINITY
            });
        }
        aovs
    }

    pub fn read_rgba8(&self, ctx: &GpuContext) -> Vec<u8> {
        ctx.read_buffer(&self.rgba8, self.pixels().max(1) * 4)
    }

    /// Rays (camera, bounce, shadow) traced by the last dispatch (blocks until it finished).
    pub fn read_ray_count(&self, ctx: &GpuContext) -> u64 {
        let bytes = ctx.read_buffer(&self.ray_counter, 4);
        u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) as u64
    }

    /// The primary hit through each pixel centre, row-major (empty while the hit AOV is off).
    pub fn read_hits(&self, ctx: &GpuContext) -> Vec<PrimaryHit> {
        if !self.hit_aov {
            return Vec::new();
        }
        let bytes = ctx.read_buffer(&self.hit, self.hit.size());
        bytemuck::cast_slice::<u8, [u32; 4]>(&bytes)
            .iter()
            .map(|h| PrimaryHit::decode(*h))
            .collect()
    }
}

/// Radiance sums with counts in w, divided out: linear RGB per pixel.
pub fn mean_rgb(bytes: &[u8]) -> Vec<[f32; 3]> {
    bytemuck::cast_slice::<u8, [f32; 4]>(bytes)
        .iter()
        .map(|p| {
            let n = p[3].max(1.0);
            [p[0] / n, p[1] / n, p[2] / n]
        })
        .collect()
}

fn hit_buffer(ctx: &GpuContext, width: u32, height: u32, enabled: bool) -> wgpu::Buffer {
    let size = if enabled {
        (width as u64 * height as u64).max(1) * 16
    } else {
        16
    };
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("aov primary hit"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

/// First-hit AOVs read back from the view.
#[derive(Clone, Debug, Default)]
pub struct Aovs {
    pub albedo: Vec<[f32; 3]>,
    pub normal: Vec<[f32; 3]>,
    pub depth: Vec<f32>,
}

/// The first surface the ray through a pixel centre hits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimaryHit {
    /// Index into the GPU instance buffer (TLAS leaf order); `None` where the ray left the scene.
    pub instance: Option<u32>,
    /// Slot in the GPU triangle buffer (the mesh's triangle offset included).
    pub triangle: u32,
    /// Weights of the triangle's second and third vertices.
    pub barycentrics: [f32; 2],
}

impl PrimaryHit {
    /// Decodes the kernels' hit encoding: instance (NONE: nothing), triangle slot, barycentrics as f32 bits.
    pub fn decode(h: [u32; 4]) -> Self {
        Self {
            instance: (h[0] != NONE).then_some(h[0]),
            triangle: h[1],
            barycentrics: [f32::from_bits(h[2]), f32::from_bits(h[3])],
        }
    }
}

/// The accumulation's sums a denoiser reads (its layout: radiance + count, albedo + depth, normal + hits,
/// unscattered radiance + a luminance moment), as handles that can travel to another thread (the viewer's
/// denoising worker).
#[derive(Clone, Debug)]
pub struct DenoiserSources {
    pub accum: wgpu::Buffer,
    pub albedo_depth: wgpu::Buffer,
    pub normal_hits: wgpu::Buffer,
    pub moments: wgpu::Buffer,
    pub width: u32,
    pub height: u32,
}

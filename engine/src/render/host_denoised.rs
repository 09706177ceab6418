//! An image denoised outside the renderer (Open Image Denoise, from host copies or in GPU memory it shares
//! with wgpu), which the display shows in place of the svgf image while the accumulation it was denoised from
//! lasts. The renderer only shows it: who denoises, and when, is the `oidn` module's business (it depends on
//! the renderer, not the reverse).

use super::accumulation::Accumulation;
use super::settings::{DenoiserKind, RenderSettings};
use super::view::ViewTargets;
use crate::gpu::GpuContext;
use bevy_ecs::prelude::Resource;
use std::sync::Mutex;

/// The host-denoised image, uploaded in the accumulation's layout (sample count 1) so that the tone mapper
/// reads it unchanged. Behind a lock so that a one-off display (a screenshot, `HeadlessApp::display_rgba8`)
/// can hand it over through a shared borrow.
#[derive(Resource, Default)]
pub struct HostDenoised {
    shown: Mutex<Option<Shown>>,
}

struct Shown {
    buffer: wgpu::Buffer,
    /// The view and accumulation the image belongs to.
    generation: u64,
    epoch: u64,
}

impl HostDenoised {
    /// Shows `image` (linear RGB per pixel, row-major from the top-left, the view's size) until the
    /// accumulation restarts or the view is replaced. False, and nothing changes, when the size does not match.
    pub fn show(
        &self,
        ctx: &GpuContext,
        view: &ViewTargets,
        accumulation: &Accumulation,
        image: &[[f32; 3]],
    ) -> bool {
        if image.is_empty() || image.len() as u64 != view.pixels() {
            return false;
        }
        let reused = {
            let mut shown = self.shown.lock().unwrap_or_else(|e| e.into_inner());
            shown
                .take()
                .filter(|s| s.generation == view.generation)
                .map(|s| s.buffer)
        };
        let buffer = reused.unwrap_or_else(|| Self::image_buffer(ctx, view));
        Self::write_image(ctx, &buffer, image);
        self.show_buffer(view, accumulation, buffer)
    }

    /// Uploads a host image (linear RGB, row-major from the top-left) into a buffer of
    /// [`Self::image_buffer`]'s layout.
    pub fn write_image(ctx: &GpuContext, buffer: &wgpu::Buffer, image: &[[f32; 3]]) {
        // Sample count 1: the tone mapper divides by it.
        let pixels: Vec<[f32; 4]> = image.iter().map(|p| [p[0], p[1], p[2], 1.0]).collect();
        ctx.queue
            .write_buffer(buffer, 0, bytemuck::cast_slice(&pixels));
    }

    /// A buffer for an image of `view` in the display's layout (the accumulation's, sample count 1), for a
    /// denoiser to write on the GPU and hand to [`Self::show_buffer`].
    pub fn image_buffer(ctx: &GpuContext, view: &ViewTargets) -> wgpu::Buffer {
        Self::image_buffer_sized(ctx, view.accum.size())
    }

    /// [`Self::image_buffer`] of `size` bytes (the accumulation buffer's size).
    pub fn image_buffer_sized(ctx: &GpuContext, size: u64) -> wgpu::Buffer {
        ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("denoised image"),
            size,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        })
    }

    /// Shows `buffer`, written on the GPU in the layout [`Self::image_buffer`] describes, until the
    /// accumulation restarts or the view is replaced. False, and nothing changes, when its size does not match.
    pub fn show_buffer(
        &self,
        view: &ViewTargets,
        accumulation: &Accumulation,
        buffer: wgpu::Buffer,
    ) -> bool {
        if buffer.size() != view.accum.size() {
            return false;
        }
        *self.shown.lock().unwrap_or_else(|e| e.into_inner()) = Some(Shown {
            buffer,
            generation: view.generation,
            epoch: accumulation.epoch,
        });
        true
    }

    /// The image to show instead of svgf's: when the settings display OIDN's denoised colour and an image of
    /// this view's current accumulation was handed over.
    pub fn current(
        &self,
        settings: &RenderSettings,
        view: &ViewTargets,
        accumulation: &Accumulation,
    ) -> Option<wgpu::Buffer> {
        if !(settings.shows_denoised() && settings.denoiser == DenoiserKind::Oidn) {
            return None;
        }
        let shown = self.shown.lock().unwrap_or_else(|e| e.into_inner());
        shown
            .as_ref()
            .filter(|s| s.generation == view.generation && s.epoch == accumulation.epoch)
            .map(|s| s.buffer.clone())
    }

    /// GPU memory held (0 until an image was shown).
    pub fn memory_bytes(&self) -> u64 {
        let shown = self.shown.lock().unwrap_or_else(|e| e.into_inner());
        shown.as_ref().map_or(0, |s| s.buffer.size())
    }
}

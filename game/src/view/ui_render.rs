//! Renders one egui frame (editor panels + the path-traced image, via the display pass) into a texture view:
//! the window's surface texture, or an offscreen texture. Times the pass with GPU timestamps where supported,
//! read back without stalling.

use raykin::gpu::GpuContext;
use raykin::gpu::readback::AsyncReadback;
use raykin::render::ViewTargets;

struct PassTimer {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: AsyncReadback,
    period_ns: f64,
}

pub struct UiRenderer {
    renderer: egui_wgpu::Renderer,
    timer: Option<PassTimer>,
    frame: u64,
}

impl UiRenderer {
    pub fn new(ctx: &GpuContext, format: wgpu::TextureFormat) -> Self {
        let mut renderer = egui_wgpu::Renderer::new(
            &ctx.device,
            format,
            egui_wgpu::RendererOptions {
                // The image must reach the window unchanged (the viewer test compares it pixel for pixel).
                dithering: false,
                ..Default::default()
            },
        );
        raykin::render::passes::display::install(&mut renderer, ctx, format);
        let timer = ctx.supports_timestamps().then(|| PassTimer {
            set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("ui pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            }),
            resolve: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("ui timestamp resolve"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            readback: AsyncReadback::new(ctx, "ui timestamp readback", 16, 3),
            period_ns: ctx.queue.get_timestamp_period() as f64,
        });
        Self {
            renderer,
            timer,
            frame: 0,
        }
    }

    /// Paints `output` (this frame's egui output; its texture deltas are applied and consumed) into `target`
    /// of `size_px`, with the view's current image in the image area. Returns the submission, which ends
    /// the frame's GPU work.
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        egui_ctx: &egui::Context,
        output: &mut egui::FullOutput,
        target: &wgpu::TextureView,
        size_px: [u32; 2],
        image: &ViewTargets,
    ) -> wgpu::SubmissionIndex {
        let (device, queue) = (&ctx.device, &ctx.queue);
        raykin::render::passes::display::set_source(&mut self.renderer, image);
        for (id, deltas) in output.textures_delta.set.drain() {
            for delta in deltas {
                self.renderer.update_texture(device, queue, id, &delta);
            }
        }
        let shapes = std::mem::take(&mut output.shapes);
        let jobs = egui_ctx.tessellate(shapes, output.pixels_per_point);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: size_px,
            pixels_per_point: output.pixels_per_point,
        };
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("egui"),
        });
        let callback_buffers =
            self.renderer
                .update_buffers(device, queue, &mut encoder, &jobs, &screen);
        {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("editor ui"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: target,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color {
                                r: 0.02,
                                g: 0.02,
                                b: 0.025,
                                a: 1.0,
                            }),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: self.timer.as_ref().map(|t| {
                        wgpu::RenderPassTimestampWrites {
                            query_set: &t.set,
                            beginning_of_pass_write_index: Some(0),
                            end_of_pass_write_index: Some(1),
                        }
                    }),
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            self.renderer.render(&mut pass, &jobs, &screen);
        }
        self.frame += 1;
        if let Some(t) = &mut self.timer {
            encoder.resolve_query_set(&t.set, 0..2, &t.resolve, 0);
            t.readback
                .encode(&mut encoder, &[(&t.resolve, 0, 16)], self.frame);
        }
        let submission = queue.submit(callback_buffers.into_iter().chain([encoder.finish()]));
        if let Some(t) = &mut self.timer {
            t.readback.after_submit();
        }
        for id in output.textures_delta.free.drain() {
            self.renderer.free_texture(&id);
        }
        submission
    }

    /// Applies `output`'s texture updates without painting (a frame with no surface texture to draw into).
    pub fn discard(&mut self, ctx: &GpuContext, output: &mut egui::FullOutput) {
        for (id, deltas) in output.textures_delta.set.drain() {
            for delta in deltas {
                self.renderer
                    .update_texture(&ctx.device, &ctx.queue, id, &delta);
            }
        }
        for id in output.textures_delta.free.drain() {
            self.renderer.free_texture(&id);
        }
    }

    /// GPU milliseconds of the UI passes that finished since the last call, oldest first (none without
    /// timestamp support).
    pub fn poll_gpu_ms(&mut self, ctx: &GpuContext) -> Vec<f64> {
        let Some(t) = self.timer.as_mut() else {
            return Vec::new();
        };
        let period = t.period_ns;
        t.readback
            .poll(ctx)
            .iter()
            .map(|(_, bytes)| {
                let tick = |i: usize| {
                    u64::from_le_bytes(bytes[i * 8..i * 8 + 8].try_into().unwrap_or_default())
                };
                tick(1).saturating_sub(tick(0)) as f64 * period * 1e-6
            })
            .collect()
    }
}

/// Keeps the CPU at most [`FramePacer::FRAMES_IN_FLIGHT`] frames ahead of the GPU. A swapchain usually does this,
/// but not every present mode and driver blocks (lavapipe under X11 without vsync does not), and an offscreen
/// target never does: unbounded, the queue and its staging memory would grow whenever the GPU is the slower side.
#[derive(Default)]
pub struct FramePacer {
    in_flight: std::collections::VecDeque<wgpu::SubmissionIndex>,
}

impl FramePacer {
    pub const FRAMES_IN_FLIGHT: usize = 2;

    /// Call with each frame's last submission; waits for the frame that many frames back.
    pub fn submitted(&mut self, ctx: &GpuContext, submission: wgpu::SubmissionIndex) {
        self.in_flight.push_back(submission);
        if self.in_flight.len() > Self::FRAMES_IN_FLIGHT
            && let Some(oldest) = self.in_flight.pop_front()
        {
            let _ = ctx.device.poll(wgpu::PollType::Wait {
                submission_index: Some(oldest),
                timeout: None,
            });
        }
    }
}

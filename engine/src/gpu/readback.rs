//! Non-blocking GPU-to-CPU copies for per-frame statistics (timestamps, ray counts): a small ring of staging
//! buffers, each mapped after its frame's submission and read once the GPU has finished it, so an interactive
//! frame loop never waits for the GPU to report how long it took. The buffers are made once and reused.

use super::GpuContext;
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

const PENDING: u8 = 0;
const MAPPED: u8 = 1;
const FAILED: u8 = 2;

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum SlotState {
    Free,
    /// Copies recorded into a command encoder that has not been submitted yet.
    Encoded,
    /// `map_async` requested; `mapped` leaves PENDING when the GPU is done.
    Mapping,
}

struct Slot {
    buffer: wgpu::Buffer,
    state: SlotState,
    mapped: Arc<AtomicU8>,
    tag: u64,
}

pub struct AsyncReadback {
    slots: Vec<Slot>,
    size: u64,
}

impl AsyncReadback {
    /// `slots` staging buffers of `size` bytes: results arrive up to `slots - 1` frames late, and a frame whose
    /// slot is not free yet is skipped rather than waited for.
    pub fn new(ctx: &GpuContext, label: &str, size: u64, slots: usize) -> Self {
        let slots = (0..slots.max(1))
            .map(|_| Slot {
                buffer: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
                state: SlotState::Free,
                mapped: Arc::new(AtomicU8::new(PENDING)),
                tag: 0,
            })
            .collect();
        Self { slots, size }
    }

    /// Bytes per slot.
    pub fn size(&self) -> u64 {
        self.size
    }

    /// Records copies of `sources` (buffer, offset in the slot, byte count; each from the buffer's start)
    /// into a free slot tagged `tag`; false when every slot is still in flight (the frame goes unreported).
    pub fn encode(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        sources: &[(&wgpu::Buffer, u64, u64)],
        tag: u64,
    ) -> bool {
        let Some(slot) = self.slots.iter_mut().find(|s| s.state == SlotState::Free) else {
            return false;
        };
        // Parts no source fills this time read as zero, not as an earlier frame's data.
        encoder.clear_buffer(&slot.buffer, 0, None);
        for (buffer, offset, bytes) in sources {
            debug_assert!(offset + bytes <= self.size, "readback slot too small");
            encoder.copy_buffer_to_buffer(buffer, 0, &slot.buffer, *offset, *bytes);
        }
        slot.state = SlotState::Encoded;
        slot.tag = tag;
        true
    }

    /// Call once the encoder given to [`Self::encode`] is submitted: starts mapping its slot.
    pub fn after_submit(&mut self) {
        for slot in self
            .slots
            .iter_mut()
            .filter(|s| s.state == SlotState::Encoded)
        {
            slot.mapped.store(PENDING, Ordering::Release);
            let mapped = slot.mapped.clone();
            slot.buffer
                .slice(..)
                .map_async(wgpu::MapMode::Read, move |result| {
                    mapped.store(
                        if result.is_ok() { MAPPED } else { FAILED },
                        Ordering::Release,
                    );
                });
            slot.state = SlotState::Mapping;
        }
    }

    /// Copies that have arrived, oldest tag first, without waiting for the GPU.
    pub fn poll(&mut self, ctx: &GpuContext) -> Vec<(u64, Vec<u8>)> {
        if self.slots.iter().all(|s| s.state != SlotState::Mapping) {
            return Vec::new();
        }
        let _ = ctx.device.poll(wgpu::PollType::Poll);
        let mut out = Vec::new();
        for slot in &mut self.slots {
            if slot.state != SlotState::Mapping {
                continue;
            }
            match slot.mapped.load(Ordering::Acquire) {
                MAPPED => {
                    if let Ok(view) = slot.buffer.slice(..).get_mapped_range() {
                        out.push((slot.tag, view.to_vec()));
                    }
                    slot.buffer.unmap();
                    slot.state = SlotState::Free;
                }
                // A failed map (device lost) frees the slot unreported.
                FAILED => slot.state = SlotState::Free,
                _ => {}
            }
        }
        out.sort_by_key(|(tag, _)| *tag);
        out
    }
}

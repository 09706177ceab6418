//! GPU pass timing: a timestamp query set with begin/end pairs around compute passes, read back in ms.

use super::GpuContext;

pub struct PassTimestamps {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    period_ns: f32,
    pairs: u32,
}

impl PassTimestamps {
    /// `pairs` begin/end pairs; `None` when the adapter has no timestamp queries.
    pub fn new(ctx: &GpuContext, label: &str, pairs: u32) -> Option<Self> {
        ctx.supports_timestamps().then(|| Self {
            set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some(label),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * pairs,
            }),
            resolve: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 16 * pairs as u64,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            period_ns: ctx.queue.get_timestamp_period(),
            pairs,
        })
    }

    /// The timestamp writes of a compute pass timed as pair `pair`.
    pub fn pass_writes(&self, pair: u32) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(2 * pair),
            end_of_pass_write_index: Some(2 * pair + 1),
        }
    }

    /// Copies the first `pairs` pairs into the resolve buffer (after the timed passes).
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder, pairs: u32) {
        encoder.resolve_query_set(&self.set, 0..2 * pairs.min(self.pairs), &self.resolve, 0);
    }

    /// Milliseconds between each pair's begin and end (blocks until the GPU has finished).
    pub fn read_ms(&self, ctx: &GpuContext) -> Vec<f64> {
        let bytes = ctx.read_buffer(&self.resolve, self.resolve.size());
        self.ms_from_bytes(&bytes)
    }

    /// The resolved timestamps (16 bytes per pair), for copies that are read later without blocking.
    pub fn resolve_buffer(&self) -> &wgpu::Buffer {
        &self.resolve
    }

    /// Milliseconds per pair from resolved timestamps (begin, end as u64 ticks; a zeroed pair gives 0).
    pub fn ms_from_bytes(&self, bytes: &[u8]) -> Vec<f64> {
        bytes
            .chunks_exact(16)
            .map(|pair| {
                let tick =
                    |i: usize| u64::from_le_bytes(pair[i..i + 8].try_into().unwrap_or_default());
                tick(8).saturating_sub(tick(0)) as f64 * self.period_ns as f64 * 1e-6
            })
            .collect()
    }
}

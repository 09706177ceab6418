//! The asynchronous half of the GPU refit guard: SAH costs come back through a small ring of mapped
//! buffers (a frame or two late), and a mesh past the threshold is rebuilt off the render thread: its
//! deformed positions are read back, obvhs builds the new tree on a worker thread, and the result is
//! installed when it is ready. Nothing here ever waits on the GPU.

use super::levels::LevelOrder;
use crate::bvh::{BvhQuality, BvhTooDeep, MeshBvh};
use crate::gpu::GpuContext;
use crate::render::layout::POSITION_WORDS;
use crate::scene::SceneAsset;
use glam::Vec3;
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

const FREE: u8 = 0;
const IN_FLIGHT: u8 = 1;
const MAPPED: u8 = 2;
const FAILED: u8 = 3;

/// A MAP_READ buffer and the state its map callback reports.
struct Staging {
    buffer: wgpu::Buffer,
    state: Arc<AtomicU8>,
}

impl Staging {
    fn new(ctx: &GpuContext, label: &str, size: u64) -> Self {
        Self {
            buffer: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(4).next_multiple_of(4),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            state: Arc::new(AtomicU8::new(FREE)),
        }
    }

    /// Copies `size` bytes of `src` at `offset` into this buffer and maps it when the submission completes.
    fn capture(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        src: &wgpu::Buffer,
        offset: u64,
        size: u64,
    ) {
        encoder.copy_buffer_to_buffer(src, offset, &self.buffer, 0, size);
        self.state.store(IN_FLIGHT, Ordering::Release);
        let state = self.state.clone();
        encoder.map_buffer_on_submit(&self.buffer, wgpu::MapMode::Read, 0..size, move |r| {
            state.store(if r.is_ok() { MAPPED } else { FAILED }, Ordering::Release);
        });
    }

    /// The mapped bytes once the copy has landed (`Some(None)`: the map failed); the buffer is free again
    /// afterwards. `None` while the copy is in flight.
    fn take(&self, size: u64) -> Option<Option<Vec<u8>>> {
        match self.state.load(Ordering::Acquire) {
            MAPPED => {
                let bytes = self
                    .buffer
                    .get_mapped_range(0..size)
                    .map(|v| v.to_vec())
                    .ok();
                self.buffer.unmap();
                self.state.store(FREE, Ordering::Release);
                Some(bytes)
            }
            FAILED => {
                self.state.store(FREE, Ordering::Release);
                Some(None)
            }
            _ => None,
        }
    }

    fn is_free(&self) -> bool {
        self.state.load(Ordering::Acquire) == FREE
    }
}

/// Which tree each refit mesh had when its cost was captured: a cost measured on a tree that has since been
/// replaced is dropped.
#[derive(Clone, Debug)]
pub struct SahSample {
    pub mesh: usize,
    pub tree: u64,
}

/// Ring of SAH-cost readbacks.
pub struct SahReadback {
    ring: Vec<(Staging, u64, Vec<SahSample>)>,
    bytes: u64,
    sequence: u64,
}

impl SahReadback {
    pub fn new(ctx: &GpuContext, meshes: usize) -> Self {
        let bytes = (meshes as u64 * 4).max(4);
        Self {
            ring: (0..3)
                .map(|_| (Staging::new(ctx, "sah readback", bytes), 0, Vec::new()))
                .collect(),
            bytes,
            sequence: 0,
        }
    }

    /// Queues a copy of this frame's costs when a ring slot is free (otherwise this frame's costs are
    /// skipped: the GPU is more than a ring behind and the next frame measures again).
    pub fn capture(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        costs: &wgpu::Buffer,
        samples: Vec<SahSample>,
    ) {
        let Some(slot) = self.ring.iter_mut().find(|s| s.0.is_free()) else {
            return;
        };
        self.sequence += 1;
        slot.0.capture(encoder, costs, 0, self.bytes);
        slot.1 = self.sequence;
        slot.2 = samples;
    }

    /// Costs that have arrived, oldest capture first: (samples, cost per refit mesh).
    pub fn arrived(&mut self) -> Vec<(Vec<SahSample>, Vec<f32>)> {
        let mut ready: Vec<(u64, Vec<SahSample>, Vec<f32>)> = Vec::new();
        for (staging, sequence, samples) in &mut self.ring {
            if let Some(Some(bytes)) = staging.take(self.bytes) {
                ready.push((
                    *sequence,
                    std::mem::take(samples),
                    bytemuck::cast_slice(&bytes).to_vec(),
                ));
            }
        }
        ready.sort_by_key(|r| r.0);
        ready.into_iter().map(|(_, s, c)| (s, c)).collect()
    }
}

/// A finished background build: the tree and its refit level order.
pub type BuiltTree = Result<(MeshBvh, LevelOrder), BvhTooDeep>;

enum Stage {
    /// Waiting for the deformed positions to map.
    Reading(Staging, u64),
    Building(Option<std::thread::JoinHandle<BuiltTree>>),
}

/// One mesh's rebuild in progress.
pub struct RebuildJob {
    /// Index among the GPU-deformed meshes.
    pub mesh: usize,
    /// The mesh has a wide tree: the rebuild collapses one from the new BVH2.
    wide: bool,
    stage: Stage,
}

impl RebuildJob {
    /// Queues the read-back of `vertices` positions at word `position_offset` of the vertex pool.
    pub fn start(
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        vertex_pool: &wgpu::Buffer,
        mesh: usize,
        position_offset: u32,
        vertices: usize,
        wide: bool,
    ) -> Self {
        let bytes = (vertices as u64 * POSITION_WORDS as u64 * 4).max(4);
        let staging = Staging::new(ctx, "rebuild positions", bytes);
        staging.capture(encoder, vertex_pool, position_offset as u64 * 4, bytes);
        Self {
            mesh,
            wide,
            stage: Stage::Reading(staging, bytes),
        }
    }

    /// Moves the job on: mapped positions go to a worker thread that builds `scene_mesh`'s BVH.
    pub fn poll(
        &mut self,
        scene: &Arc<SceneAsset>,
        scene_mesh: usize,
        quality: BvhQuality,
    ) -> JobState {
        if let Stage::Reading(staging, bytes) = &self.stage {
            let bytes = match staging.take(*bytes) {
                None => return JobState::Pending,
                Some(None) => return JobState::Abandoned,
                Some(Some(bytes)) => bytes,
            };
            let vertices = scene.meshes[scene_mesh].positions.len();
            let positions: Vec<Vec3> =
                bytemuck::cast_slice::<u8, [f32; POSITION_WORDS as usize]>(&bytes)[..vertices]
                    .iter()
                    .map(|p| Vec3::from_slice(p))
                    .collect();
            let scene = scene.clone();
            let wide = self.wide;
            // A worker thread keeps the build out of the frame loop.
            let spawned = std::thread::Builder::new()
                .name("raykin-bvh-rebuild".into())
                .spawn(move || {
                    let triangles = &scene.meshes[scene_mesh].triangles;
                    MeshBvh::build_refittable(&positions, triangles, quality, wide).map(|bvh| {
                        let levels = LevelOrder::of(&bvh.flat);
                        (bvh, levels)
                    })
                });
            match spawned {
                Ok(handle) => self.stage = Stage::Building(Some(handle)),
                Err(e) => {
                    tracing::warn!("BVH rebuild thread: {e}; the refit tree stays");
                    return JobState::Abandoned;
                }
            }
        }
        match &mut self.stage {
            Stage::Building(handle) if handle.as_ref().is_some_and(|h| h.is_finished()) => {
                match handle.take().map(std::thread::JoinHandle::join) {
                    Some(Ok(tree)) => JobState::Done(Box::new(tree)),
                    _ => JobState::Abandoned,
                }
            }
            _ => JobState::Pending,
        }
    }
}

/// Where a rebuild stands after [`RebuildJob::poll`].
pub enum JobState {
    Pending,
    Done(Box<BuiltTree>),
    /// The worker could not run or died: the mesh keeps its refit tree and may be picked again.
    Abandoned,
}

//! Where the scene was one frame earlier, on the GPU, for the real-time path's motion vectors and reuse
//! (`shaders/realtime/motion.wgsl`): each instance's previous placement and a stable object id (instance
//! indices follow the top-level BVH's leaf order, which changes whenever it is rebuilt), the object -> instance
//! table of this frame, the previous positions of the meshes deformed this frame, and how last frame's light
//! indices map to this frame's.
//!
//! Deformed positions never come back to the CPU: each deform backend calls
//! [`GpuScene::keep_previous_positions`] before it overwrites a mesh's vertex-pool range, which records a GPU
//! copy of the range into this mesh's slot of `prev_positions` (the GPU backend in its own command buffer, the
//! CPU backend in a submission ahead of its queued writes). Allocated only while the real-time path runs.

use super::GpuScene;
use crate::gpu::GpuContext;
use crate::gpu::bind::{storage_buffer, storage_with, write_or_grow};
use crate::render::layout::{GpuLight, GpuMotionInstance, NONE, POSITION_WORDS};
use crate::scene::SceneAsset;

pub struct SceneMotion {
    /// By current instance: previous world-from-object rows and the object id.
    pub instances: wgpu::Buffer,
    /// Object id -> current instance (NONE: gone).
    pub object_instances: wgpu::Buffer,
    /// Previous positions of deformable meshes, each mesh's range reserved (3 f32 per vertex).
    pub prev_positions: wgpu::Buffer,
    /// Per mesh: word offset into `prev_positions` when its vertices moved this frame, else NONE.
    pub mesh_motion: wgpu::Buffer,
    /// Last frame's light index -> this frame's.
    pub light_remap: wgpu::Buffer,
    /// Whether this frame's light indices differ from last frame's (`light_remap` then holds the map).
    pub lights_remapped: bool,
    /// Bumped when a buffer is replaced (bind groups are remade).
    pub generation: u64,
    /// Per mesh: (word offset of its range, vertex-pool word offset, words) for deformable meshes.
    ranges: Vec<Option<(u32, u32, u32)>>,
    /// Meshes whose previous positions were kept this frame.
    moved: Vec<bool>,
    uploaded_instances: Vec<GpuMotionInstance>,
    uploaded_objects: Vec<u32>,
    uploaded_table: Vec<u32>,
    /// The light list as last seen: the key (object id, triangle slot) of each light.
    light_keys: Vec<(u32, u32)>,
    pub bytes: u64,
}

impl SceneMotion {
    fn new(ctx: &GpuContext, scene: &SceneAsset, gpu: &GpuScene) -> Self {
        let mut ranges = Vec::with_capacity(scene.meshes.len());
        let mut words = 0u32;
        for (m, mesh) in scene.meshes.iter().enumerate() {
            if mesh.is_deformable() {
                let n = POSITION_WORDS * mesh.positions.len() as u32;
                ranges.push(Some((words, gpu.mesh_slots[m].gpu.position_offset, n)));
                words += n;
            } else {
                ranges.push(None);
            }
        }
        let prev_positions = storage_buffer(ctx, "previous positions", words as u64 * 4);
        let table = vec![NONE; scene.meshes.len().max(1)];
        Self {
            instances: storage_with(ctx, "motion instances", &[]),
            object_instances: storage_with(ctx, "object instances", &[]),
            mesh_motion: storage_with(ctx, "mesh motion", bytemuck::cast_slice(&table)),
            light_remap: storage_with(ctx, "light remap", &[]),
            lights_remapped: false,
            generation: 1,
            bytes: prev_positions.size(),
            prev_positions,
            moved: vec![false; scene.meshes.len()],
            ranges,
            uploaded_instances: Vec::new(),
            uploaded_objects: Vec::new(),
            uploaded_table: table,
            light_keys: Vec::new(),
        }
    }

    /// Uploads this frame's per-instance previous placements and object ids (in current instance order) and
    /// the object -> instance table, where they changed.
    pub fn write_instances(&mut self, ctx: &GpuContext, instances: &[GpuMotionInstance]) {
        if instances != self.uploaded_instances.as_slice() {
            if write_or_grow(
                ctx,
                &mut self.instances,
                bytemuck::cast_slice(instances),
                "motion instances",
            ) {
                self.generation += 1;
            }
            self.uploaded_instances = instances.to_vec();
        }
        // The merged static tree's pseudo-instance is no object (`NONE`).
        let objects = instances
            .iter()
            .map(|i| i.object)
            .filter(|&o| o != NONE)
            .max()
            .map_or(0, |m| m as usize + 1);
        let mut table = vec![NONE; objects];
        for (i, inst) in instances.iter().enumerate() {
            if inst.object != NONE {
                table[inst.object as usize] = i as u32;
            }
        }
        if table != self.uploaded_objects {
            if write_or_grow(
                ctx,
                &mut self.object_instances,
                bytemuck::cast_slice(&table),
                "object instances",
            ) {
                self.generation += 1;
            }
            self.uploaded_objects = table;
        }
    }

    /// The light list of this frame, each light keyed by (object id, triangle slot): when it differs from
    /// last frame's, uploads the map from last frame's indices to this frame's.
    pub fn write_lights(&mut self, ctx: &GpuContext, keys: Vec<(u32, u32)>) {
        self.lights_remapped = keys != self.light_keys;
        if self.lights_remapped {
            let index: std::collections::HashMap<(u32, u32), u32> = keys
                .iter()
                .enumerate()
                .map(|(i, k)| (*k, i as u32))
                .collect();
            let remap: Vec<u32> = self
                .light_keys
                .iter()
                .map(|k| index.get(k).copied().unwrap_or(NONE))
                .collect();
            if write_or_grow(
                ctx,
                &mut self.light_remap,
                bytemuck::cast_slice(&remap),
                "light remap",
            ) {
                self.generation += 1;
            }
            self.light_keys = keys;
        }
    }

    /// Uploads which meshes moved this frame (their previous positions were kept) and starts the next frame.
    pub fn write_mesh_motion(&mut self, ctx: &GpuContext) {
        let table: Vec<u32> = self
            .ranges
            .iter()
            .zip(&self.moved)
            .map(|(r, &moved)| match (r, moved) {
                (Some((offset, _, _)), true) => *offset,
                _ => NONE,
            })
            .collect();
        if !table.is_empty() && table != self.uploaded_table {
            ctx.queue
                .write_buffer(&self.mesh_motion, 0, bytemuck::cast_slice(&table));
            self.uploaded_table = table;
        }
        self.moved.iter_mut().for_each(|m| *m = false);
    }
}

impl GpuScene {
    /// Allocates the previous-frame data of the real-time path (once).
    pub fn enable_motion(&mut self, ctx: &GpuContext, scene: &SceneAsset) {
        if self.motion.is_none() {
            let motion = SceneMotion::new(ctx, scene, self);
            self.memory.motion = motion.bytes;
            self.motion = Some(motion);
        }
    }

    /// Frees it (the real-time path stopped).
    pub fn disable_motion(&mut self) {
        self.motion = None;
        self.memory.motion = 0;
    }

    /// Before a deform backend overwrites `mesh`'s positions this frame: keeps the current ones as the
    /// previous frame's (a GPU copy; nothing while the real-time path is off).
    pub fn keep_previous_positions(&mut self, encoder: &mut wgpu::CommandEncoder, mesh: usize) {
        let Some(motion) = self.motion.as_mut() else {
            return;
        };
        let Some(Some((offset, source, words))) = motion.ranges.get(mesh).copied() else {
            return;
        };
        if words > 0 {
            encoder.copy_buffer_to_buffer(
                &self.vertex_pool,
                source as u64 * 4,
                &motion.prev_positions,
                offset as u64 * 4,
                Some(words as u64 * 4),
            );
        }
        motion.moved[mesh] = true;
    }

    /// The instances as last uploaded, in top-level BVH leaf order.
    pub fn uploaded_instances(&self) -> &[crate::render::layout::GpuInstance] {
        &self.uploaded_instances
    }

    /// The light list as last uploaded (the light sampler's table).
    pub fn light_list(&self) -> &[GpuLight] {
        &self.lights.uploaded
    }
}

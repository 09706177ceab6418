//! Deformation on the GPU: a compute pass morphs and skins every deformable mesh whose pose changed
//! straight into its vertex-pool range, and a second pass refits those meshes' BLASes and measures their
//! SAH cost, both in the same submission as the trace. Per frame only joint matrices, morph weights and a
//! flag per mesh go up; the top-level BVH gets conservative bounds from the pose ([`bounds`]), so nothing
//! is read back on the frame's critical path. The rebuild guard runs a frame or two late ([`readback`]).
//!
//! The CPU path (`animation::deform_meshes` + `render::systems::refit_deformed`) stays the reference and the
//! fallback: meshes with emissive triangles stay on it (next-event estimation weighs emitters by their
//! world area on the CPU), and so does everything when the deform inputs exceed the GPU's binding limit.

pub mod bounds;
pub mod inputs;
pub mod levels;
mod plugin;
pub mod readback;

pub use plugin::{DeformPlugin, GpuDeformation, insert_resources};

use crate::animation::MeshPoses;
use crate::bvh::refit::BvhStats;
use crate::bvh::{BvhQuality, MeshBvh};
use crate::gpu::GpuContext;
use crate::gpu::bind::storage_with as storage;
use crate::render::gpu_scene::GpuScene;
use crate::render::layout::NONE;
use crate::render::passes::deform::{DeformBuffers, DeformParams, DeformPass};
use crate::render::passes::refit::{RefitBuffers, RefitMeshGpu, RefitPass};
use crate::scene::SceneAsset;
use bounds::DeformBounds;
use glam::Mat4;
use inputs::{DeformInputs, DeformTarget};
use levels::{LEVEL_SLOTS, LevelOrder};
use readback::{JobState, RebuildJob, SahReadback, SahSample};
use std::sync::Arc;

pub use crate::render::settings::DeformBackend;

/// `active` flags: deform (and refit) this frame, or refit only (a rebuilt tree that landed).
const DEFORM: u32 = 1;
const REFIT: u32 = 2;

/// Per GPU-deformed mesh, CPU side.
struct Deformed {
    /// Index in the scene.
    mesh: usize,
    bounds: DeformBounds,
    joint_base: usize,
    joint_count: usize,
    weight_base: usize,
    targets: usize,
    /// SAH cost of the installed tree at its build, and a counter bumped when a new tree is installed.
    build_sah: f32,
    tree: u64,
}

/// GPU time of the deform passes of the last frame that ran them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DeformPassTimes {
    pub skin_ms: f64,
    pub refit_ms: f64,
}

/// What one frame of GPU deformation did.
#[derive(Default)]
pub struct DeformFrame {
    /// To submit before the trace, in the same submission.
    pub commands: Option<wgpu::CommandBuffer>,
    /// Vertices moved or a tree changed: the TLAS and accumulation must restart.
    pub geometry_changed: bool,
    /// CPU seconds writing this frame's matrices, weights and flags.
    pub upload_seconds: f64,
    /// CPU seconds installing finished rebuilds.
    pub rebuild_seconds: f64,
}

pub struct GpuDeformer {
    meshes: Vec<Deformed>,
    /// By scene mesh: index among the GPU-deformed meshes.
    index_of: Vec<Option<usize>>,
    deform_pass: DeformPass,
    refit_pass: RefitPass,
    deform_group: wgpu::BindGroup,
    refit_group: wgpu::BindGroup,
    matrix_buffer: wgpu::Buffer,
    weight_buffer: wgpu::Buffer,
    active_buffer: wgpu::Buffer,
    refit_mesh_buffer: wgpu::Buffer,
    level_order_buffer: wgpu::Buffer,
    level_start_buffer: wgpu::Buffer,
    sah_buffer: wgpu::Buffer,
    /// Per wide node of the meshes that have a wide tree, the BVH2 node it stands for.
    wide_source_buffer: wgpu::Buffer,
    /// Some mesh has a wide tree: the refit pass re-quantises them.
    wide: bool,
    refit_meshes: Vec<RefitMeshGpu>,
    matrices: Vec<Mat4>,
    weights: Vec<f32>,
    groups: u32,
    sah: SahReadback,
    rebuilds: Vec<RebuildJob>,
    /// Pairs: deform pass, refit pass.
    timestamps: Option<crate::gpu::PassTimestamps>,
    /// Whether the last encoded frame wrote timestamps.
    timed: bool,
    /// Bytes of every buffer this deformer owns (inputs, per-frame data, refit tables, readbacks).
    pub gpu_bytes: u64,
}

/// The skin's joint count of each mesh's (single) node, when that node is skinned.
fn joint_counts(scene: &SceneAsset) -> Vec<Option<usize>> {
    let mut counts = vec![None; scene.meshes.len()];
    for node in &scene.nodes {
        if let (Some(m), Some(s)) = (node.mesh, node.skin)
            && let (Some(slot), Some(skin)) = (counts.get_mut(m), scene.skins.get(s))
        {
            *slot = Some(skin.joints.len());
        }
    }
    counts
}

impl GpuDeformer {
    /// Meshes the GPU may deform: deformable, and without emissive triangles (their emitter areas are
    /// computed from CPU positions).
    pub fn eligible(scene: &SceneAsset, gpu: &GpuScene) -> Vec<usize> {
        (0..scene.meshes.len())
            .filter(|&m| scene.meshes[m].is_deformable() && !gpu.has_emitters(m))
            .collect()
    }

    /// Uploads the static deform inputs of the eligible meshes and their refit tables. `Ok(None)`: nothing
    /// to deform; `Err`: why the GPU cannot take them (the CPU path then deforms everything).
    pub fn new(
        ctx: &GpuContext,
        scene: &SceneAsset,
        gpu: &GpuScene,
    ) -> Result<Option<Self>, String> {
        let eligible = Self::eligible(scene, gpu);
        if eligible.is_empty() {
            return Ok(None);
        }
        let joints = joint_counts(scene);
        let targets: Vec<DeformTarget> = eligible
            .iter()
            .map(|&m| DeformTarget {
                mesh: &scene.meshes[m],
                out: gpu.mesh_slots[m].gpu,
                joints: joints[m].filter(|_| scene.meshes[m].skin_weights.is_some()),
            })
            .collect();
        let inputs = DeformInputs::pack(&targets);
        let limit = ctx
            .limits
            .max_storage_buffer_binding_size
            .min(ctx.limits.max_buffer_size);
        if inputs.bytes() > limit {
            return Err(format!(
                "{}: GPU deformation inputs need {:.1} MiB, over the {:.1} MiB binding limit of `{}`; deforming on the CPU",
                scene.source,
                inputs.bytes() as f64 / 1048576.0,
                limit as f64 / 1048576.0,
                ctx.info.name
            ));
        }

        let mut meshes = Vec::with_capacity(eligible.len());
        let mut index_of = vec![None; scene.meshes.len()];
        let mut refit_meshes = Vec::with_capacity(eligible.len());
        let mut order_words: Vec<u32> = Vec::new();
        let mut level_starts: Vec<u32> = Vec::new();
        let mut wide_sources: Vec<u32> = Vec::new();
        for (i, (&m, d)) in eligible.iter().zip(&inputs.meshes).enumerate() {
            index_of[m] = Some(i);
            let slot = &gpu.mesh_slots[m];
            let Some(bvh) = slot.blas.binary() else {
                return Err(format!(
                    "{}: mesh `{}` deforms but has no refittable BVH",
                    scene.source, scene.meshes[m].name
                ));
            };
            let levels = LevelOrder::of(&bvh.flat);
            let wide = bvh.wide.as_ref().filter(|_| slot.wide_node_offset != NONE);
            let refit = RefitMeshGpu {
                blas_root: slot.blas_node_offset,
                triangle_offset: slot.gpu.triangle_offset,
                position_offset: slot.gpu.position_offset,
                node_count: bvh.flat.nodes.len() as u32,
                order_offset: order_words.len() as u32,
                level_offset: level_starts.len() as u32,
                levels: levels.levels() as u32,
                wide_root: wide.map_or(NONE, |_| slot.wide_node_offset),
                wide_count: wide.map_or(0, |w| w.nodes.len() as u32),
                source_offset: wide_sources.len() as u32,
                _pad: [0; 2],
            };
            if let Some(w) = wide {
                wide_sources.extend_from_slice(&w.bvh2_node);
                wide_sources.resize(
                    refit.source_offset as usize + slot.wide_capacity as usize,
                    0,
                );
            }
            order_words.extend_from_slice(&levels.order);
            order_words.resize(refit.order_offset as usize + slot.blas_capacity as usize, 0);
            level_starts.extend_from_slice(&levels.starts);
            level_starts.resize(refit.level_offset as usize + LEVEL_SLOTS, 0);
            refit_meshes.push(refit);
            meshes.push(Deformed {
                mesh: m,
                bounds: DeformBounds::new(&scene.meshes[m], targets[i].joints),
                joint_base: d.joint_base as usize,
                joint_count: d.joint_count as usize,
                weight_base: d.weight_base as usize,
                targets: d.morph_targets as usize,
                build_sah: bvh.build_sah,
                tree: 0,
            });
        }

        let copy_dst = |label: &str, bytes: u64| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes.max(16),
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let data_buffer = storage(ctx, "deform inputs", bytemuck::cast_slice(&inputs.words));
        let mesh_buffer = storage(ctx, "deform meshes", bytemuck::cast_slice(&inputs.meshes));
        let matrix_buffer = copy_dst("joint matrices", inputs.matrix_count.max(1) as u64 * 64);
        let weight_buffer = copy_dst("morph weights", inputs.weight_count as u64 * 4);
        let active_buffer = copy_dst("deform active", meshes.len() as u64 * 4);
        let refit_mesh_buffer = storage(ctx, "refit meshes", bytemuck::cast_slice(&refit_meshes));
        let level_order_buffer =
            storage(ctx, "refit level order", bytemuck::cast_slice(&order_words));
        let level_start_buffer = storage(
            ctx,
            "refit level starts",
            bytemuck::cast_slice(&level_starts),
        );
        let sah_buffer = copy_dst("refit sah cost", meshes.len() as u64 * 4);
        let wide = !wide_sources.is_empty();
        if !wide {
            wide_sources.push(0);
        }
        let wide_source_buffer = storage(
            ctx,
            "refit wide sources",
            bytemuck::cast_slice(&wide_sources),
        );
        let (x, _) = crate::gpu::bind::grid(inputs.groups);
        let params = DeformParams {
            mesh_count: meshes.len() as u32,
            groups_x: x,
            _pad: [0; 2],
        };
        let params_buffer = crate::gpu::bind::params_buffer(
            ctx,
            "deform params",
            std::mem::size_of::<DeformParams>(),
        );
        ctx.queue
            .write_buffer(&params_buffer, 0, bytemuck::bytes_of(&params));

        let deform_pass = DeformPass::new(ctx);
        let deform_group = deform_pass.bind(
            ctx,
            &DeformBuffers {
                data: &data_buffer,
                meshes: &mesh_buffer,
                joint_matrices: &matrix_buffer,
                morph_weights: &weight_buffer,
                mesh_flags: &active_buffer,
                vertex_pool: &gpu.vertex_pool,
                params: &params_buffer,
            },
        );
        let refit_pass = RefitPass::new(ctx);
        let refit_group = refit_pass.bind(
            ctx,
            &RefitBuffers {
                blas_nodes: &gpu.blas_nodes,
                triangles: &gpu.triangles,
                vertex_pool: &gpu.vertex_pool,
                meshes: &refit_mesh_buffer,
                level_order: &level_order_buffer,
                level_starts: &level_start_buffer,
                mesh_flags: &active_buffer,
                sah_cost: &sah_buffer,
                wide_nodes: &gpu.wide_nodes,
                wide_sources: &wide_source_buffer,
            },
        );
        let timestamps = crate::gpu::PassTimestamps::new(ctx, "deform timestamps", 2);
        let gpu_bytes = [
            &data_buffer,
            &mesh_buffer,
            &matrix_buffer,
            &weight_buffer,
            &active_buffer,
            &refit_mesh_buffer,
            &level_order_buffer,
            &level_start_buffer,
            &sah_buffer,
            &wide_source_buffer,
        ]
        .iter()
        .map(|b| b.size())
        .sum::<u64>()
            + 3 * meshes.len() as u64 * 4;
        Ok(Some(Self {
            gpu_bytes,
            sah: SahReadback::new(ctx, meshes.len()),
            matrices: vec![Mat4::IDENTITY; inputs.matrix_count as usize],
            weights: vec![0.0; inputs.weight_count as usize],
            groups: inputs.groups,
            meshes,
            index_of,
            deform_pass,
            refit_pass,
            deform_group,
            refit_group,
            matrix_buffer,
            weight_buffer,
            active_buffer,
            refit_mesh_buffer,
            level_order_buffer,
            level_start_buffer,
            sah_buffer,
            wide_source_buffer,
            wide,
            refit_meshes,
            rebuilds: Vec::new(),
            timestamps,
            timed: false,
        }))
    }

    /// By scene mesh: whether this deformer deforms it.
    pub fn owned(&self) -> Vec<bool> {
        self.index_of.iter().map(Option::is_some).collect()
    }

    /// One frame: applies arrived SAH costs and finished rebuilds (built with the upload's preset,
    /// [`GpuScene::deformable_quality`]), writes the changed poses, and encodes the deform and refit passes (plus
    /// this frame's readbacks) for submission before the trace.
    pub fn frame(
        &mut self,
        ctx: &GpuContext,
        scene: &Arc<SceneAsset>,
        gpu: &mut GpuScene,
        poses: &MeshPoses,
        stats: &mut BvhStats,
    ) -> DeformFrame {
        let quality = gpu.deformable_quality();
        let mut out = DeformFrame::default();
        stats.ensure_len(scene.meshes.len());
        // Runs map callbacks of earlier submissions; never blocks.
        let _ = ctx.device.poll(wgpu::PollType::Poll);
        for (samples, costs) in self.sah.arrived() {
            for s in samples {
                let d = &self.meshes[s.mesh];
                if d.tree == s.tree {
                    stats.sah_ratio[d.mesh] = costs[s.mesh] / d.build_sah.max(f32::MIN_POSITIVE);
                }
            }
        }
        let mut active = vec![0u32; self.meshes.len()];
        let start = std::time::Instant::now();
        self.land_rebuilds(ctx, scene, gpu, stats, quality, &mut active);
        out.rebuild_seconds = start.elapsed().as_secs_f64();

        let start = std::time::Instant::now();
        for &m in &poses.changed {
            let (Some(i), Some(Some(pose))) =
                (self.index_of.get(m).copied().flatten(), poses.poses.get(m))
            else {
                continue;
            };
            let d = &self.meshes[i];
            if d.joint_count > 0 {
                let (joints, world) = pose
                    .skin
                    .as_ref()
                    .map_or((&[][..], Mat4::IDENTITY), |(j, w)| (j.as_slice(), *w));
                let range = &mut self.matrices[d.joint_base..d.joint_base + d.joint_count + 1];
                for (k, slot) in range[..d.joint_count].iter_mut().enumerate() {
                    *slot = joints.get(k).copied().unwrap_or(Mat4::IDENTITY);
                }
                range[d.joint_count] = world;
            }
            let weights = &mut self.weights[d.weight_base..d.weight_base + d.targets];
            for (k, w) in weights.iter_mut().enumerate() {
                *w = pose.weights.get(k).copied().unwrap_or(0.0);
            }
            let skin = pose.skin.as_ref().map(|(j, w)| (j.as_slice(), *w));
            gpu.mesh_slots[m].deformed_bounds = Some(d.bounds.bounds(skin, &pose.weights));
            active[i] |= DEFORM;
        }
        let deforming = active.iter().any(|a| a & DEFORM != 0);
        let refitting = active.iter().any(|&a| a != 0);
        if deforming {
            self.upload_runs(ctx, &active);
        }
        if refitting {
            ctx.queue
                .write_buffer(&self.active_buffer, 0, bytemuck::cast_slice(&active));
        }
        out.upload_seconds = start.elapsed().as_secs_f64();

        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("gpu deform"),
            });
        let mut encoded = false;
        self.timed = false;
        if refitting {
            // The real-time path's motion vectors need where the vertices were before this frame.
            for (i, d) in self.meshes.iter().enumerate() {
                if active[i] & DEFORM != 0 {
                    gpu.keep_previous_positions(&mut encoder, d.mesh);
                }
            }
            let ts = |pair: u32| self.timestamps.as_ref().map(|t| t.pass_writes(pair));
            self.deform_pass.encode(
                &mut encoder,
                &self.deform_group,
                self.groups,
                deforming,
                ts(0),
            );
            self.refit_pass.encode(
                &mut encoder,
                &self.refit_group,
                self.meshes.len() as u32,
                self.wide,
                ts(1),
            );
            if let Some(t) = &self.timestamps {
                t.resolve(&mut encoder, 2);
                self.timed = true;
            }
            let samples = (0..self.meshes.len())
                .filter(|&i| active[i] != 0)
                .map(|i| SahSample {
                    mesh: i,
                    tree: self.meshes[i].tree,
                })
                .collect();
            self.sah.capture(&mut encoder, &self.sah_buffer, samples);
            let refits = active.iter().filter(|&&a| a != 0).count() as u64;
            stats.refits += refits;
            out.geometry_changed = true;
            encoded = true;
        }
        // New rebuilds read the positions this submission deforms.
        // At most twice the per-frame cap in flight bounds the worker threads.
        let busy: Vec<usize> = self
            .rebuilds
            .iter()
            .map(|j| self.meshes[j.mesh].mesh)
            .collect();
        let room = (2 * stats.max_rebuilds_per_frame).saturating_sub(busy.len());
        let index_of = &self.index_of;
        let mut due = stats.due(|m| index_of[m].is_some() && !busy.contains(&m));
        due.truncate(room);
        for m in due {
            let Some(i) = self.index_of[m] else { continue };
            let slot = &gpu.mesh_slots[m];
            self.rebuilds.push(RebuildJob::start(
                ctx,
                &mut encoder,
                &gpu.vertex_pool,
                i,
                slot.gpu.position_offset,
                scene.meshes[m].positions.len(),
                slot.wide_node_offset != NONE,
            ));
            encoded = true;
        }
        if encoded {
            out.commands = Some(encoder.finish());
        }
        out
    }

    /// Writes the matrices and weights of the meshes deformed this frame, one write per contiguous run.
    fn upload_runs(&self, ctx: &GpuContext, active: &[u32]) {
        let mut i = 0;
        while i < self.meshes.len() {
            if active[i] & DEFORM == 0 {
                i += 1;
                continue;
            }
            let first = i;
            while i < self.meshes.len() && active[i] & DEFORM != 0 {
                i += 1;
            }
            let (a, b) = (&self.meshes[first], &self.meshes[i - 1]);
            let joints = a.joint_base..b.joint_base + b.joint_count + (b.joint_count > 0) as usize;
            if !joints.is_empty() {
                ctx.queue.write_buffer(
                    &self.matrix_buffer,
                    joints.start as u64 * 64,
                    bytemuck::cast_slice(&self.matrices[joints]),
                );
            }
            let weights = a.weight_base..b.weight_base + b.targets;
            if !weights.is_empty() {
                ctx.queue.write_buffer(
                    &self.weight_buffer,
                    weights.start as u64 * 4,
                    bytemuck::cast_slice(&self.weights[weights]),
                );
            }
        }
    }

    /// Installs finished background builds (at most `max_rebuilds_per_frame` per frame) and marks their
    /// meshes for a refit this frame: the tree was built from positions a few frames old.
    fn land_rebuilds(
        &mut self,
        ctx: &GpuContext,
        scene: &Arc<SceneAsset>,
        gpu: &mut GpuScene,
        stats: &mut BvhStats,
        quality: BvhQuality,
        active: &mut [u32],
    ) {
        let mut landed = 0;
        let mut k = 0;
        while k < self.rebuilds.len() {
            let i = self.rebuilds[k].mesh;
            let m = self.meshes[i].mesh;
            if landed >= stats.max_rebuilds_per_frame {
                break;
            }
            match self.rebuilds[k].poll(scene, m, quality) {
                JobState::Pending => {
                    k += 1;
                    continue;
                }
                JobState::Abandoned => {}
                JobState::Done(built) => match *built {
                    Ok((bvh, levels)) => {
                        if self.install(ctx, scene, gpu, i, bvh, &levels) {
                            stats.mesh_rebuilds[m] += 1;
                            stats.rebuilds += 1;
                            stats.sah_ratio[m] = 1.0;
                            active[i] |= REFIT;
                            landed += 1;
                        }
                    }
                    Err(e) => {
                        tracing::error!(
                            "mesh `{}`: BVH rebuild: {e}; keeping the refit tree",
                            scene.meshes[m].name
                        );
                        stats.sah_ratio[m] = 1.0;
                    }
                },
            }
            self.rebuilds.swap_remove(k);
        }
    }

    fn install(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        gpu: &mut GpuScene,
        i: usize,
        bvh: MeshBvh,
        levels: &LevelOrder,
    ) -> bool {
        let d = &mut self.meshes[i];
        let build_sah = bvh.build_sah;
        let node_count = bvh.flat.nodes.len() as u32;
        let sources = bvh.wide.as_ref().map(|w| w.bvh2_node.clone());
        if levels.starts.len() > LEVEL_SLOTS || !gpu.install_bvh(ctx, scene, d.mesh, bvh) {
            return false;
        }
        d.build_sah = build_sah;
        d.tree += 1;
        let refit = &mut self.refit_meshes[i];
        refit.node_count = node_count;
        refit.levels = levels.levels() as u32;
        ctx.queue.write_buffer(
            &self.level_order_buffer,
            refit.order_offset as u64 * 4,
            bytemuck::cast_slice(&levels.order),
        );
        ctx.queue.write_buffer(
            &self.level_start_buffer,
            refit.level_offset as u64 * 4,
            bytemuck::cast_slice(&levels.starts),
        );
        // `install_bvh` took the rebuilt wide tree only where the mesh has one.
        if let (Some(sources), true) = (sources, refit.wide_root != NONE) {
            refit.wide_count = sources.len() as u32;
            ctx.queue.write_buffer(
                &self.wide_source_buffer,
                refit.source_offset as u64 * 4,
                bytemuck::cast_slice(&sources),
            );
        }
        ctx.queue.write_buffer(
            &self.refit_mesh_buffer,
            (i * std::mem::size_of::<RefitMeshGpu>()) as u64,
            bytemuck::bytes_of(refit),
        );
        true
    }

    /// GPU times of the deform and refit passes of the last frame (blocks until it finished); `None` when
    /// that frame ran no deform pass or the adapter has no timestamps.
    pub fn read_pass_times(&self, ctx: &GpuContext) -> Option<DeformPassTimes> {
        let ms = self
            .timestamps
            .as_ref()
            .filter(|_| self.timed)?
            .read_ms(ctx);
        Some(DeformPassTimes {
            skin_ms: ms[0],
            refit_ms: ms[1],
        })
    }
}

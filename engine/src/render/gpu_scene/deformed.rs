//! Deformed meshes on the CPU backend: their new vertices written over their own vertex-pool ranges, their
//! BLASes refit or rebuilt in place.

use super::packing::{OrderedTriangles, order_triangles, position_words};
use super::{GpuScene, SceneWrites};
use crate::bvh::refit::RebuildPolicy;
use crate::bvh::{Blas, MeshBvh};
use crate::gpu::GpuContext;
use crate::render::layout::*;
use crate::scene::SceneAsset;
use rayon::prelude::*;

impl GpuScene {
    /// Writes this frame's deformed meshes over their own vertex-pool ranges (same encodings as the initial
    /// upload), refits their BLASes and uploads the nodes; returns each mesh's new SAH ratio and the CPU
    /// seconds spent on the queue writes. The CPU work (encoding, refit + SAH in one sweep) runs in parallel
    /// over meshes, the queue writes after it in mesh order. Under [`RebuildPolicy::PoseDetermined`] a
    /// rebuilt mesh first goes back to its upload tree and triangle order, so the refit result depends on
    /// this pose alone.
    pub fn apply_deformations(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        deformed: &crate::animation::DeformedMeshes,
        policy: RebuildPolicy,
    ) -> (Vec<(usize, f32)>, f64) {
        struct Update {
            mesh: usize,
            /// Encoded normals and tangents (positions are written straight from the deformed mesh).
            words: Vec<(u32, Vec<u32>)>,
            sah_ratio: f32,
            /// The triangle order went back to the upload tree's.
            restored: Option<OrderedTriangles>,
        }
        self.written |= SceneWrites::VERTEX_POOL | SceneWrites::BLAS_NODES | SceneWrites::TRIANGLES;
        if self.has_wide_deformed() {
            self.written |= SceneWrites::WIDE_NODES;
        }
        let (materials, quality, variant) =
            (&self.material_data, self.deformable_quality, self.variant);
        let mut changed = vec![false; self.mesh_slots.len()];
        for &m in &deformed.changed {
            if deformed.meshes.get(m).is_some_and(Option::is_some) && m < changed.len() {
                changed[m] = true;
            }
        }
        let updates: Vec<Update> = self
            .mesh_slots
            .par_iter_mut()
            .enumerate()
            .filter(|(m, _)| changed[*m])
            .map(|(m, slot)| {
                let Some(d) = deformed.meshes[m].as_ref() else {
                    unreachable!("filtered to deformed meshes")
                };
                let gpu = slot.gpu;
                let mut words = Vec::new();
                if let (Some(n), true) = (&d.normals, gpu.normal_offset != NONE) {
                    words.push((
                        gpu.normal_offset,
                        n.iter().map(|n| oct_encode(*n)).collect(),
                    ));
                }
                if let (Some(t), true) = (&d.tangents, gpu.tangent_offset != NONE) {
                    let tangent_words = t
                        .iter()
                        .flat_map(|t| {
                            [
                                oct_encode(t.truncate()),
                                if t.w < 0.0 { -1f32 } else { 1f32 }.to_bits(),
                            ]
                        })
                        .collect();
                    words.push((gpu.tangent_offset, tangent_words));
                }
                let restored = (policy == RebuildPolicy::PoseDetermined)
                    .then(|| {
                        slot.restore_upload_tree(&scene.meshes[m], variant, materials, quality)
                    })
                    .flatten();
                let bvh = slot
                    .blas
                    .binary_mut()
                    .expect("deformable meshes have a refittable BVH");
                let sah_ratio = bvh.refit(&d.positions, &slot.gpu_triangles);
                // Reuses the previous frame's allocation.
                match &mut slot.positions {
                    Some(p) => p.clone_from(&d.positions),
                    None => slot.positions = Some(d.positions.clone()),
                }
                Update {
                    mesh: m,
                    words,
                    sah_ratio,
                    restored,
                }
            })
            .collect();
        let start = std::time::Instant::now();
        let ratios = updates
            .into_iter()
            .map(|u| {
                if let Some(ordered) = u.restored {
                    let offset = self.mesh_slots[u.mesh].gpu.triangle_offset;
                    ctx.queue.write_buffer(
                        &self.triangles,
                        offset as u64 * 16,
                        bytemuck::cast_slice(&ordered.packed),
                    );
                    self.emissive_triangles[u.mesh] = ordered.emissive;
                }
                let slot = &self.mesh_slots[u.mesh];
                if let Some(d) = deformed.meshes[u.mesh].as_ref() {
                    let words: Vec<u32> = d
                        .positions
                        .iter()
                        .flat_map(|&p| position_words(p))
                        .collect();
                    ctx.queue.write_buffer(
                        &self.vertex_pool,
                        slot.gpu.position_offset as u64 * 4,
                        bytemuck::cast_slice(&words),
                    );
                }
                for (offset, words) in &u.words {
                    ctx.queue.write_buffer(
                        &self.vertex_pool,
                        *offset as u64 * 4,
                        bytemuck::cast_slice(words),
                    );
                }
                if let Some(bvh) = slot.blas.binary() {
                    self.write_bvh(ctx, u.mesh, bvh);
                }
                (u.mesh, u.sah_ratio)
            })
            .collect();
        (ratios, start.elapsed().as_secs_f64())
    }

    /// Rebuilds a mesh's BLAS from its current positions inside its reserved node range, and rewrites its
    /// triangle range in the new BVH order (same triangles, same count), with the upload's preset.
    pub fn rebuild_mesh(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        mesh: usize,
    ) -> Result<(), crate::bvh::BvhTooDeep> {
        let quality = self.deformable_quality;
        let slot = &self.mesh_slots[mesh];
        let positions = slot
            .positions
            .as_deref()
            .unwrap_or(&scene.meshes[mesh].positions);
        let wide = slot.wide_node_offset != NONE;
        let bvh =
            MeshBvh::build_refittable(positions, &scene.meshes[mesh].triangles, quality, wide)?;
        self.install_bvh(ctx, scene, mesh, bvh);
        Ok(())
    }

    /// Uploads a deforming mesh's refit BVH2 and, where it has one, its wide tree.
    fn write_bvh(&self, ctx: &GpuContext, mesh: usize, bvh: &MeshBvh) {
        let slot = &self.mesh_slots[mesh];
        ctx.queue.write_buffer(
            &self.blas_nodes,
            slot.blas_node_offset as u64 * 64,
            bytemuck::cast_slice(&bvh.flat.nodes),
        );
        self.write_wide_tree(ctx, mesh, bvh);
    }

    /// Uploads a deforming mesh's wide tree, where the mesh has one.
    fn write_wide_tree(&self, ctx: &GpuContext, mesh: usize, bvh: &MeshBvh) {
        let offset = self.mesh_slots[mesh].wide_node_offset;
        if let (Some(wide), true) = (&bvh.wide, offset != NONE) {
            ctx.queue.write_buffer(
                &self.wide_nodes,
                offset as u64 * 80,
                bytemuck::cast_slice(&wide.nodes),
            );
        }
    }

    /// Replaces a deformable mesh's BLAS with `bvh` in its reserved node range and rewrites its triangle
    /// range in the new leaf order. False (and nothing changed) when the tree does not fit the range.
    pub fn install_bvh(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        mesh: usize,
        bvh: MeshBvh,
    ) -> bool {
        let data = &scene.meshes[mesh];
        let slot = &self.mesh_slots[mesh];
        if bvh.flat.nodes.len() > slot.blas_capacity as usize {
            // Cannot happen for a tree with >= 1 triangle per leaf; keep the refit tree rather than overrun.
            tracing::warn!(
                "mesh `{}`: rebuilt BVH needs {} nodes, {} reserved; kept the refit tree",
                data.name,
                bvh.flat.nodes.len(),
                slot.blas_capacity
            );
            return false;
        }
        // The mesh record points at the wide tree, which reads the rebuilt tree's triangle order: a rebuild
        // without one (deeper than the wide stack) keeps the refit trees.
        let wide = slot.wide_node_offset != NONE;
        if wide
            && bvh
                .wide
                .as_ref()
                .is_none_or(|w| w.nodes.len() > slot.wide_capacity as usize)
        {
            tracing::warn!(
                "mesh `{}`: the rebuilt BVH has no wide tree within the {} nodes reserved; kept the refit trees",
                data.name,
                slot.wide_capacity
            );
            return false;
        }
        self.written |= SceneWrites::BLAS_NODES | SceneWrites::TRIANGLES;
        if wide {
            self.written |= SceneWrites::WIDE_NODES;
            self.write_wide_tree(ctx, mesh, &bvh);
        }
        let mut nodes = bvh.flat.nodes.clone();
        nodes.resize(slot.blas_capacity as usize, crate::bvh::GpuBvhNode::EMPTY);
        let ordered = order_triangles(
            data,
            &data.triangle_materials_under(self.variant),
            &bvh.flat.order,
            slot.gpu.triangle_offset,
            &self.material_data,
        );
        ctx.queue.write_buffer(
            &self.blas_nodes,
            slot.blas_node_offset as u64 * 64,
            bytemuck::cast_slice(&nodes),
        );
        ctx.queue.write_buffer(
            &self.triangles,
            slot.gpu.triangle_offset as u64 * 16,
            bytemuck::cast_slice(&ordered.packed),
        );
        self.emissive_triangles[mesh] = ordered.emissive;
        let slot = &mut self.mesh_slots[mesh];
        slot.gpu_triangles = ordered.indices;
        slot.blas = Blas::Binary(bvh);
        slot.rebuilt = true;
        true
    }
}

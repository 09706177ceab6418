//! KHR_materials_variants at run time: switching the variant rewrites the material words of the triangles whose
//! material changes, in place. Geometry, BVHs and vertex data stay as they are; only a change in emission
//! rebuilds the light list's triangles.

use super::packing::{emissive_slots, pack_triangles};
use super::{GpuScene, SceneWrites};
use crate::gpu::GpuContext;
use crate::scene::SceneAsset;

impl GpuScene {
    /// Shows `variant` (`None`: the file's materials). For each mesh with mappings, writes the span of its
    /// triangle range whose materials differ; returns the materials that appeared or disappeared there (the
    /// real-time path's history of those pixels is stale), empty when the image does not change.
    pub fn select_variant(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        variant: Option<usize>,
    ) -> Vec<u32> {
        let previous = std::mem::replace(&mut self.variant, variant);
        let mut changed_materials = Vec::new();
        let mut emission_changed = false;
        for (m, mesh) in scene.meshes.iter().enumerate() {
            if mesh.primitive_variants.is_empty() {
                continue;
            }
            let (before, after) = (
                mesh.triangle_materials_under(previous),
                mesh.triangle_materials_under(variant),
            );
            let slot = &self.mesh_slots[m];
            let order = slot.blas.order();
            // The BVH slots whose triangle changes material: write only the span they cover.
            let differs = |s: &usize| {
                let t = order[*s] as usize;
                before[t] != after[t]
            };
            let Some(first) = (0..order.len()).find(differs) else {
                continue;
            };
            let last = (0..order.len()).rev().find(differs).unwrap_or(first);
            for &t in &order[first..=last] {
                let (old, new) = (before[t as usize], after[t as usize]);
                if old != new {
                    changed_materials.extend([old, new]);
                }
            }
            let packed = pack_triangles(
                &slot.gpu_triangles[first..=last],
                &order[first..=last],
                &after,
            );
            self.written |= SceneWrites::TRIANGLES;
            ctx.queue.write_buffer(
                &self.triangles,
                (slot.gpu.triangle_offset as u64 + first as u64) * 16,
                bytemuck::cast_slice(&packed),
            );
            let emissive =
                emissive_slots(&after, order, slot.gpu.triangle_offset, &self.material_data);
            if emissive != self.emissive_triangles[m] {
                self.emissive_triangles[m] = emissive;
                emission_changed = true;
            }
        }
        if emission_changed {
            self.refresh_triangle_lights(ctx, scene);
        }
        // A member of the merge may now need the alpha test.
        self.merge_materials_changed |= self.merge.is_some() && !changed_materials.is_empty();
        changed_materials.sort_unstable();
        changed_materials.dedup();
        changed_materials
    }
}

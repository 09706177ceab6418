//! Placements: instances in top-level BVH leaf order, the top-level BVH, and the emitter list that follows
//! them (and follows material edits that change emission).

use super::GpuScene;
use super::packing::{emissive_slots, gpu_material, luminance};
use crate::bvh::FlatBvh;
use crate::gpu::GpuContext;
use crate::gpu::bind::write_or_grow;
use crate::render::layout::*;
use crate::scene::SceneAsset;
use bevy_ecs::prelude::{Entity, Resource};
use glam::{Mat4, Vec3};

/// Per-instance data the renderer needs each frame: world matrix and mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceInput {
    pub world: Mat4,
    pub mesh: u32,
}

impl GpuScene {
    /// Uploads instances (in TLAS leaf order), the TLAS and the emitter list for this frame's placements.
    pub fn update_instances(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        inputs: &[InstanceInput],
    ) -> Result<(), crate::bvh::BvhTooDeep> {
        let boxes: Vec<(Vec3, Vec3)> = inputs
            .iter()
            .map(|i| {
                let slot = &self.mesh_slots[i.mesh as usize];
                let (lo, hi) = slot
                    .deformed_bounds
                    .unwrap_or_else(|| slot.blas.root_bounds());
                transform_box(i.world, lo, hi)
            })
            .collect();
        let tlas = crate::bvh::build_tlas(&boxes)?;
        self.upload_instances(ctx, scene, inputs, tlas);
        Ok(())
    }

    /// Uploads instances in `tlas`'s leaf order, the tree itself and the emitter list. [`Self::update_instances`]
    /// builds the tree; tests hand in pathological ones (a top-level tree deeper than any build makes).
    pub fn upload_instances(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        inputs: &[InstanceInput],
        tlas: FlatBvh,
    ) {
        let ordered: Vec<GpuInstance> = tlas
            .order
            .iter()
            .map(|&i| GpuInstance::new(inputs[i as usize].world, inputs[i as usize].mesh))
            .collect();
        let emitters = self.build_emitters(scene, &ordered);
        let instance_bytes = bytemuck::cast_slice::<_, u8>(&ordered);
        let tlas_bytes = bytemuck::cast_slice::<_, u8>(&tlas.nodes);
        let emitter_bytes = bytemuck::cast_slice::<_, u8>(&emitters);
        let mut recreated = false;
        for (buffer, bytes, label) in [
            (&mut self.instances, instance_bytes, "instances"),
            (&mut self.tlas_nodes, tlas_bytes, "tlas nodes"),
            (&mut self.emitters, emitter_bytes, "emitters"),
        ] {
            recreated |= write_or_grow(ctx, buffer, bytes, label);
        }
        if recreated {
            self.generation += 1;
        }
        self.emitter_count = emitters.len() as u32;
        self.instance_order = tlas.order;
        self.memory.instances_and_tlas =
            (instance_bytes.len() + tlas_bytes.len() + emitter_bytes.len()) as u64;
        self.uploaded_instances = ordered;
        self.emitter_list = emitters;
    }

    /// Uploads the materials that differ from what the GPU holds; returns their indices. When the set of
    /// emissive triangles or their power changes, the emitter list is rebuilt for the current instances.
    pub fn update_materials(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        materials: &[crate::scene::Material],
    ) -> Vec<u32> {
        let mut changed = Vec::new();
        let mut emission_changed = false;
        for (i, m) in materials.iter().enumerate().take(self.material_data.len()) {
            let gpu = gpu_material(m);
            if gpu == self.material_data[i] {
                continue;
            }
            emission_changed |= gpu.emissive != self.material_data[i].emissive;
            self.material_data[i] = gpu;
            ctx.queue.write_buffer(
                &self.materials,
                (i * std::mem::size_of::<GpuMaterial>()) as u64,
                bytemuck::bytes_of(&gpu),
            );
            changed.push(i as u32);
        }
        if emission_changed {
            for (m, mesh) in scene.meshes.iter().enumerate() {
                let slot = &self.mesh_slots[m];
                self.emissive_triangles[m] = emissive_slots(
                    mesh,
                    slot.blas.order(),
                    slot.gpu.triangle_offset,
                    &self.material_data,
                );
            }
            let instances = std::mem::take(&mut self.uploaded_instances);
            let emitters = self.build_emitters(scene, &instances);
            if write_or_grow(
                ctx,
                &mut self.emitters,
                bytemuck::cast_slice(&emitters),
                "emitters",
            ) {
                self.generation += 1;
            }
            self.emitter_count = emitters.len() as u32;
            self.emitter_list = emitters;
            self.uploaded_instances = instances;
        }
        changed
    }

    /// Emissive triangles of every instance, with a CDF proportional to luminance x world area (the shader
    /// computes the same power to weigh BRDF-sampled hits against light sampling).
    fn build_emitters(&mut self, scene: &SceneAsset, instances: &[GpuInstance]) -> Vec<GpuEmitter> {
        let mut weighted = Vec::new();
        let mut total = 0.0f64;
        for (i, inst) in instances.iter().enumerate() {
            let mesh = inst.mesh as usize;
            if self.emissive_triangles[mesh].is_empty() {
                continue;
            }
            let r = &inst.world_from_object;
            let world =
                Mat4::from_cols_array_2d(&[r[0], r[1], r[2], [0.0, 0.0, 0.0, 1.0]]).transpose();
            let slot = &self.mesh_slots[mesh];
            let positions = slot
                .positions
                .as_deref()
                .unwrap_or(&scene.meshes[mesh].positions);
            for &(t, material) in &self.emissive_triangles[mesh] {
                let local = (t - slot.gpu.triangle_offset) as usize;
                let [a, b, c] = slot.gpu_triangles[local]
                    .map(|v| world.transform_point3(positions[v as usize]));
                let area = 0.5 * (b - a).cross(c - a).length() as f64;
                let power = luminance(Vec3::from(self.material_data[material as usize].emissive))
                    as f64
                    * area;
                if power > 0.0 {
                    total += power;
                    weighted.push((
                        GpuEmitter {
                            instance: i as u32,
                            triangle: t,
                            cdf: 0.0,
                            pmf: 0.0,
                        },
                        power,
                    ));
                }
            }
        }
        self.emitter_total_power = total as f32;
        let mut running = 0.0f64;
        weighted
            .into_iter()
            .map(|(mut e, p)| {
                running += p;
                e.cdf = ((running / total) as f32).min(1.0);
                e.pmf = (p / total) as f32;
                e
            })
            .collect()
    }
}

pub fn transform_box(m: Mat4, lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
    let mut out_lo = Vec3::MAX;
    let mut out_hi = Vec3::MIN;
    for i in 0..8 {
        let c = Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        let p = m.transform_point3(c);
        out_lo = out_lo.min(p);
        out_hi = out_hi.max(p);
    }
    (out_lo, out_hi)
}

/// The scene's instances as last uploaded, and the entity behind each GPU instance (TLAS leaf order), to map
/// primary hits back to scene nodes.
#[derive(Resource, Default)]
pub struct InstanceMap {
    pub(crate) last_inputs: Vec<InstanceInput>,
    pub entities: Vec<Entity>,
}

impl InstanceMap {
    /// The placements last uploaded, in the order the top-level build received them.
    pub fn inputs(&self) -> &[InstanceInput] {
        &self.last_inputs
    }
}

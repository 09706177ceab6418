//! Placements: instances in top-level BVH leaf order, the top-level BVH, and the emissive triangles of the
//! light list that follow them (and follow material edits that change emission).

use super::GpuScene;
use super::light_tree::LightBounds;
use super::lights::WeightedLight;
use super::packing::{emissive_slots, gpu_material, luminance};
use crate::bvh::FlatBvh;
use crate::gpu::GpuContext;
use crate::gpu::bind::write_or_grow;
use crate::render::layout::*;
use crate::scene::SceneAsset;
use bevy_ecs::prelude::{Entity, Resource};
use bytemuck::Zeroable;
use glam::{Mat4, Vec3};

/// Per-instance data the renderer needs each frame: world matrix and mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceInput {
    pub world: Mat4,
    pub mesh: u32,
}

impl GpuScene {
    /// Uploads instances (in TLAS leaf order), the TLAS and the light list's triangles for this frame's
    /// placements.
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
        let (lo, hi) = boxes.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), b| {
            (lo.min(b.0), hi.max(b.1))
        });
        let radius = if lo.x <= hi.x {
            0.5 * (hi - lo).length()
        } else {
            0.0
        };
        self.lights.set_bounds_radius(radius);
        Ok(())
    }

    /// Uploads instances in `tlas`'s leaf order and the tree itself, and rebuilds the light list's emissive
    /// triangles (uploaded by [`Self::upload_lights`]). [`Self::update_instances`] builds the tree; tests hand in
    /// pathological ones (a top-level tree deeper than any build makes).
    pub fn upload_instances(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        inputs: &[InstanceInput],
        tlas: FlatBvh,
    ) {
        let mut ordered: Vec<GpuInstance> = tlas
            .order
            .iter()
            .map(|&i| GpuInstance::new(inputs[i as usize].world, inputs[i as usize].mesh))
            .collect();
        let triangles = self.triangle_lights(scene, &mut ordered);
        self.lights.set_triangles(triangles);
        let instance_bytes = bytemuck::cast_slice::<_, u8>(&ordered);
        let tlas_bytes = bytemuck::cast_slice::<_, u8>(&tlas.nodes);
        let mut recreated = false;
        for (buffer, bytes, label) in [
            (&mut self.instances, instance_bytes, "instances"),
            (&mut self.tlas_nodes, tlas_bytes, "tlas nodes"),
        ] {
            recreated |= write_or_grow(ctx, buffer, bytes, label);
        }
        if recreated {
            self.generation += 1;
        }
        self.instance_order = tlas.order;
        self.memory.instances_and_tlas = (instance_bytes.len() + tlas_bytes.len()) as u64;
        self.uploaded_instances = ordered;
    }

    /// Uploads the materials that differ from what the GPU holds; returns how many changed. When the set of
    /// emissive triangles or their power changes, the light list's triangles (and the instances' ranges into
    /// it) are rebuilt for the current instances.
    pub fn update_materials(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        materials: &[crate::scene::Material],
    ) -> Vec<u32> {
        let mut changed = Vec::new();
        let mut emission_changed = false;
        for (i, m) in materials.iter().enumerate().take(self.material_data.len()) {
            let gpu = gpu_material(m, &self.texture_slots);
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
                    &mesh.triangle_materials_under(self.variant),
                    slot.blas.order(),
                    slot.gpu.triangle_offset,
                    &self.material_data,
                );
            }
            self.refresh_triangle_lights(ctx, scene);
        }
        changed
    }

    /// Rebuilds the light list's emissive triangles (and the instances' ranges into it) for the current
    /// instances, after the emissive triangles changed.
    pub(super) fn refresh_triangle_lights(&mut self, ctx: &GpuContext, scene: &SceneAsset) {
        let mut instances = std::mem::take(&mut self.uploaded_instances);
        let triangles = self.triangle_lights(scene, &mut instances);
        self.lights.set_triangles(triangles);
        if write_or_grow(
            ctx,
            &mut self.instances,
            bytemuck::cast_slice(&instances),
            "instances",
        ) {
            self.generation += 1;
        }
        self.uploaded_instances = instances;
    }

    /// The emissive triangles of every instance as lights, weighed by power (pi x luminance x world area, twice
    /// for two-sided materials), and each instance's range of them (`first_light`, `light_count`).
    fn triangle_lights(
        &self,
        scene: &SceneAsset,
        instances: &mut [GpuInstance],
    ) -> Vec<WeightedLight> {
        let mut lights = Vec::new();
        for (i, inst) in instances.iter_mut().enumerate() {
            inst.first_light = lights.len() as u32;
            inst.light_count = 0;
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
            let mut emissive = self.emissive_triangles[mesh].clone();
            // Sorted by slot: the shader finds a hit's light by binary search.
            emissive.sort_unstable_by_key(|&(t, _)| t);
            for (t, material) in emissive {
                let local = (t - slot.gpu.triangle_offset) as usize;
                let [a, b, c] = slot.gpu_triangles[local]
                    .map(|v| world.transform_point3(positions[v as usize]));
                let area = 0.5 * (b - a).cross(c - a).length() as f64;
                let m = &self.material_data[material as usize];
                let sides = if m.flags & MATERIAL_DOUBLE_SIDED != 0 {
                    2.0
                } else {
                    1.0
                };
                let power =
                    std::f64::consts::PI * sides * luminance(Vec3::from(m.emissive)) as f64 * area;
                if power > 0.0 {
                    let mut light = GpuLight::zeroed();
                    light.kind = LIGHT_TRIANGLE;
                    light.index_a = i as u32;
                    light.index_b = t;
                    let bounds = LightBounds::triangle(
                        [a, b, c],
                        luminance(Vec3::from(m.emissive)),
                        sides > 1.0,
                    );
                    lights.push(WeightedLight {
                        light,
                        power,
                        bounds: Some(bounds),
                        next_event_power: Some(power),
                    });
                    inst.light_count += 1;
                }
            }
        }
        lights
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

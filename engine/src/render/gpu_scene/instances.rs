//! Placements: instances in top-level BVH leaf order, the top-level BVH, and the emissive triangles of the
//! light list that follow them (and follow material edits that change emission).

use super::light_tree::LightBounds;
use super::lights::WeightedLight;
use super::packing::{emissive_slots, gpu_material, luminance};
use super::static_merge::{self, MergeMember};
use super::{GpuScene, SceneWrites};
use crate::bvh::{FlatBvh, GpuBvhNode};
use crate::gpu::GpuContext;
use crate::gpu::bind::write_or_grow;
use crate::render::layout::*;
use crate::scene::SceneAsset;
use bevy_ecs::prelude::{Entity, Resource};
use bytemuck::Zeroable;
use glam::{Mat4, Vec3};
use std::collections::HashMap;

/// Per-instance data the renderer needs each frame: world matrix, mesh, and the glTF node it draws (`NONE`
/// for instances of no node), by which the merged static instances are recognised.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceInput {
    pub world: Mat4,
    pub mesh: u32,
    pub node: u32,
}

/// The top level as last built: the BVH2 every kernel reads (its leaves indexing the instance buffer), its
/// leaves' world boxes in instance-buffer order from `first_leaf` on, and whether the waves asked for the wide
/// tree over the same boxes (`crate::bvh::tlas`), packed after the BVH2 in the same buffer.
#[derive(Default)]
pub(super) struct TopLevel {
    bvh2: Vec<GpuBvhNode>,
    /// `None` for a tree handed in without boxes (tests' pathological trees): no wide tree is built over it.
    leaf_boxes: Option<Vec<(Vec3, Vec3)>>,
    first_leaf: u32,
    wide_wanted: bool,
    /// The wide tree's first 16-byte word in the buffer, where it is there.
    wide_word: Option<u32>,
}

impl GpuScene {
    /// Uploads instances (the merged static ones first, then the top-level leaves in tree order), the TLAS and
    /// the light list's triangles for this frame's placements.
    pub fn update_instances(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        inputs: &[InstanceInput],
    ) -> Result<(), crate::bvh::BvhTooDeep> {
        let members = self.merged_inputs(ctx, scene, inputs);
        let mut merged = vec![false; inputs.len()];
        members.iter().for_each(|&i| merged[i] = true);
        let leaves: Vec<usize> = (0..inputs.len()).filter(|&i| !merged[i]).collect();
        let mut boxes: Vec<(Vec3, Vec3)> = leaves
            .iter()
            .map(|&i| {
                let input = &inputs[i];
                let slot = &self.mesh_slots[input.mesh as usize];
                let (lo, hi) = slot
                    .deformed_bounds
                    .unwrap_or_else(|| slot.blas.root_bounds());
                transform_box(input.world, lo, hi)
            })
            .collect();
        // The merged tree is the last leaf input.
        boxes.extend(self.merge.as_ref().map(|m| m.bounds));
        let tlas = crate::bvh::build_tlas(&boxes)?;
        self.upload_placements(ctx, scene, inputs, &members, &leaves, tlas, Some(&boxes));
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

    /// Whether a material edit or variant switch is waiting to be checked against the merge.
    pub fn merge_needs_check(&self) -> bool {
        self.merge_materials_changed
    }

    /// The inputs the merge covers, in member order (empty without a merge). Members missing from `inputs`,
    /// moved away from where they were merged, or (after a material change) needing the alpha test leave the
    /// merge; the rest is rebuilt into its room, or the merge is dropped when fewer than two remain.
    fn merged_inputs(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        inputs: &[InstanceInput],
    ) -> Vec<usize> {
        let check_materials = std::mem::take(&mut self.merge_materials_changed);
        let Some(merge) = &self.merge else {
            return Vec::new();
        };
        let by_node: HashMap<u32, usize> = inputs
            .iter()
            .enumerate()
            .filter(|(_, input)| input.node != NONE)
            .map(|(i, input)| (input.node, i))
            .collect();
        let mut alpha_tested = HashMap::new();
        let mut kept = Vec::with_capacity(merge.members.len());
        for member in &merge.members {
            let found = by_node.get(&member.node).copied().filter(|&i| {
                let input = &inputs[i];
                input.mesh == member.mesh
                    && static_merge::same_placement(input.world, member.world)
                    && !(check_materials
                        && *alpha_tested.entry(member.mesh).or_insert_with(|| {
                            static_merge::needs_alpha_test(
                                scene,
                                member.mesh as usize,
                                self.variant,
                                &self.material_data,
                            )
                        }))
            });
            kept.extend(found);
        }
        if kept.len() == merge.members.len() {
            return kept;
        }
        let members: Vec<MergeMember> = kept
            .iter()
            .map(|&i| {
                let input = &inputs[i];
                MergeMember {
                    node: input.node,
                    mesh: input.mesh,
                    world: input.world,
                }
            })
            .collect();
        let opaque = (self.material_data.len() - 1) as u32;
        let rebuilt = (members.len() >= 2)
            .then(|| static_merge::build(scene, &self.mesh_slots, members, merge.quality, opaque))
            .flatten()
            .and_then(|geometry| {
                merge.rebuilt(
                    ctx,
                    [&self.vertex_pool, &self.triangles, &self.wide_nodes],
                    geometry,
                )
            });
        tracing::debug!(
            "static merge: {} of {} members left it; {}",
            merge.members.len() - kept.len(),
            merge.members.len(),
            if rebuilt.is_some() {
                "rebuilt"
            } else {
                "dropped"
            }
        );
        if let Some(m) = &rebuilt {
            // Rebuilt in place: its positions, triangles and nodes, and the pseudo-instance's mesh entry.
            self.written |= SceneWrites::VERTEX_POOL
                | SceneWrites::TRIANGLES
                | SceneWrites::WIDE_NODES
                | SceneWrites::MESHES;
            let index = self.mesh_slots.len() as u64;
            ctx.queue.write_buffer(
                &self.meshes,
                index * std::mem::size_of::<GpuMesh>() as u64,
                bytemuck::bytes_of(&m.mesh),
            );
        } else {
            kept.clear();
        }
        self.merge = rebuilt;
        kept
    }

    /// Uploads instances in `tlas`'s leaf order and the tree itself, and rebuilds the light list's emissive
    /// triangles (uploaded by [`Self::upload_lights`]). [`Self::update_instances`] builds the tree; tests hand in
    /// pathological ones (a top-level tree deeper than any build makes), over every input, none merged.
    pub fn upload_instances(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        inputs: &[InstanceInput],
        tlas: FlatBvh,
    ) {
        let leaves: Vec<usize> = (0..inputs.len()).collect();
        self.upload_placements(ctx, scene, inputs, &[], &leaves, tlas, None);
    }

    /// The instance buffer: `members` (inputs merged, in merge order), then `tlas`'s leaves in tree order, where
    /// leaf `k` is input `leaves[k]` and leaf `leaves.len()` the merged tree, whose world boxes `boxes` holds in
    /// the same order where known.
    #[allow(clippy::too_many_arguments)]
    fn upload_placements(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        inputs: &[InstanceInput],
        members: &[usize],
        leaves: &[usize],
        mut tlas: FlatBvh,
        boxes: Option<&[(Vec3, Vec3)]>,
    ) {
        self.written |= SceneWrites::INSTANCES | SceneWrites::TLAS_NODES;
        let placed = |i: usize| GpuInstance::new(inputs[i].world, inputs[i].mesh);
        let mut ordered: Vec<GpuInstance> = members.iter().map(|&i| placed(i)).collect();
        let mut order: Vec<u32> = members.iter().map(|&i| i as u32).collect();
        for &leaf in &tlas.order {
            match leaves.get(leaf as usize) {
                Some(&i) => {
                    ordered.push(placed(i));
                    order.push(i as u32);
                }
                None => {
                    let merge = self
                        .merge
                        .as_ref()
                        .expect("a leaf past the inputs is the merge");
                    let mut pseudo = GpuInstance::new(Mat4::IDENTITY, self.mesh_slots.len() as u32);
                    pseudo.merged_origins = merge.origins;
                    ordered.push(pseudo);
                    order.push(NONE);
                }
            }
        }
        // The tree's leaves index the instance buffer, where the members come first.
        let shift = members.len() as u32;
        if shift > 0 {
            for child in tlas.nodes.iter_mut().flat_map(|n| n.children.iter_mut()) {
                if child.is_leaf() {
                    child.index += shift;
                }
            }
        }
        let triangles = self.triangle_lights(scene, &mut ordered);
        self.lights.set_triangles(triangles);
        let mut recreated = write_or_grow(
            ctx,
            &mut self.instances,
            bytemuck::cast_slice(&ordered),
            "instances",
        );
        self.instance_order = order;
        // The leaves follow the members in the instance buffer.
        self.sole_instance = (tlas.order.len() == 1).then_some(shift);
        self.blas_layouts = self.blas_layouts_of(&ordered[members.len()..]);
        self.uploaded_instances = ordered;
        self.top_level.leaf_boxes =
            boxes.map(|boxes| tlas.order.iter().map(|&k| boxes[k as usize]).collect());
        self.top_level.first_leaf = shift;
        self.top_level.bvh2 = tlas.nodes;
        recreated |= self.upload_top_level(ctx);
        if recreated {
            self.generation += 1;
        }
    }

    /// The top level's buffer: the BVH2, then where the waves want it and the top level has more than one
    /// leaf, the wide tree built over the same leaves. Returns whether the buffer was made anew.
    fn upload_top_level(&mut self, ctx: &GpuContext) -> bool {
        self.written |= SceneWrites::TLAS_NODES;
        let top = &mut self.top_level;
        let mut words: Vec<[u32; 4]> = bytemuck::cast_slice(&top.bvh2).to_vec();
        top.wide_word = None;
        // The wide tree starts after room for a power of two of BVH2 nodes: its first word is a pipeline constant
        // of the waves' kernels, which then changes only where the leaves' count crosses a power of two.
        words.resize(4 * top.bvh2.len().next_power_of_two(), [0; 4]);
        let boxes = top
            .leaf_boxes
            .as_ref()
            .filter(|_| top.wide_wanted && self.sole_instance.is_none());
        if let Some(boxes) = boxes {
            match crate::bvh::tlas::build_wide_tlas(boxes) {
                Ok(wide) => {
                    let base = words.len() as u32;
                    let first = top.first_leaf;
                    words.extend(wide.packed(base, |k| first + k));
                    top.wide_word = Some(base);
                }
                // The waves trace the BVH2 instead (no placement makes a balanced wide tree this deep).
                Err(e) => tracing::warn!("the wide top level was not built: {e}"),
            }
        }
        let bytes = bytemuck::cast_slice::<_, u8>(&words);
        self.memory.instances_and_tlas = (self.uploaded_instances.len()
            * std::mem::size_of::<GpuInstance>()
            + bytes.len()) as u64;
        write_or_grow(ctx, &mut self.tlas_nodes, bytes, "tlas nodes")
    }

    /// Where the top level's buffer holds the wide tree (its first 16-byte word), if it does.
    pub fn wide_top_level(&self) -> Option<u32> {
        self.top_level.wide_word
    }

    /// Whether the top level's buffer should hold the wide tree (the waves trace this frame), packed again when
    /// that changes; returns where it starts (the kernels' `WIDE_TOP_LEVEL`), or `None` where there is none.
    pub fn want_wide_top_level(&mut self, ctx: &GpuContext, wanted: bool) -> Option<u32> {
        if self.top_level.wide_wanted != wanted {
            self.top_level.wide_wanted = wanted;
            if self.upload_top_level(ctx) {
                self.generation += 1;
            }
        }
        self.top_level.wide_word
    }

    /// The BLAS layouts (`BLAS_LAYOUT_*` bits) of the meshes `leaves` place; the merged tree, past the meshes'
    /// slots, is wide.
    fn blas_layouts_of(&self, leaves: &[GpuInstance]) -> u32 {
        leaves.iter().fold(0, |layouts, leaf| {
            let wide = self
                .mesh_slots
                .get(leaf.mesh as usize)
                .is_none_or(|slot| slot.gpu.blas_root & WIDE_BLAS != 0);
            layouts
                | if wide {
                    BLAS_LAYOUT_WIDE
                } else {
                    BLAS_LAYOUT_BINARY
                }
        })
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
            if (gpu.flags ^ self.material_data[i].flags) & MATERIAL_ALPHA_MASK != 0 {
                self.merge_materials_changed |= self.merge.is_some();
            }
            self.material_data[i] = gpu;
            self.written |= SceneWrites::MATERIALS;
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
        self.written |= SceneWrites::INSTANCES;
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
            // The merged tree's pseudo-instance has no mesh of the scene: its members carry the lights.
            if self.emissive_triangles.get(mesh).is_none_or(Vec::is_empty) {
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

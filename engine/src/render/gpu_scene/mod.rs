//! Packs a scene's meshes, materials and textures into the GPU buffers the kernels read.
//! Static data is uploaded once; instances, the top-level BVH and the light list are rewritten when they change;
//! a deformed mesh rewrites only its own positions/normals and BLAS nodes.

mod deformed;
mod instances;
pub mod light_tree;
pub mod lights;
pub mod motion;
mod packing;
pub mod static_merge;
mod variant;

pub use instances::{InstanceInput, InstanceMap, transform_box};
pub use lights::LightList;
pub use packing::{TextureSlots, gpu_material, luminance};

use super::layout::*;
use crate::bvh::{Blas, MeshBvh, StaticLayout};
use crate::gpu::GpuContext;
use crate::gpu::bind::storage_with as storage;
use crate::scene::{MeshData, SceneAsset};
use glam::Vec3;
use packing::{OrderedTriangles, order_triangles, pack_vertices};
use rayon::prelude::*;

#[derive(Debug, thiserror::Error)]
pub enum UploadError {
    #[error(
        "{scene}: the scene is over this GPU's limits: the {what} buffer needs {needed_mib:.1} MiB, but `{adapter}` binds at most {limit_mib:.1} MiB per buffer"
    )]
    OverLimit {
        scene: String,
        what: &'static str,
        needed_mib: f64,
        limit_mib: f64,
        adapter: String,
    },
    #[error(transparent)]
    Environment(crate::environment::EnvironmentError),
    #[error("{scene}: mesh `{mesh}`: {source}")]
    Bvh {
        scene: String,
        mesh: String,
        source: crate::bvh::BvhTooDeep,
    },
}

/// Where one mesh's data sits, CPU side, so that deformations can rewrite just that range.
#[derive(Clone, Debug)]
pub struct MeshSlot {
    pub gpu: GpuMesh,
    /// Triangles in BVH order (vertex indices).
    pub gpu_triangles: Vec<[u32; 3]>,
    /// Where the mesh's BVH2 starts in `blas_nodes` (the mesh record points at its wide tree where it has one).
    pub blas_node_offset: u32,
    /// Where a deforming mesh's wide tree starts in `wide_nodes` ([`crate::bvh::MeshBvh::wide`]), and the nodes
    /// reserved for it (any rebuilt tree fits: `bvh::wide_refit::node_capacity`); `NONE` and 0 without one.
    pub wide_node_offset: u32,
    pub wide_capacity: u32,
    pub blas: Blas,
    /// Current vertex positions of a deformed mesh; `None` while it is in its rest pose.
    pub positions: Option<Vec<Vec3>>,
    /// BLAS nodes reserved for this mesh (a deformable mesh reserves room for any rebuilt tree).
    pub blas_capacity: u32,
    /// Conservative bounds of a GPU-deformed mesh at its current pose (its CPU tree's boxes are stale);
    /// the top-level BVH uses them instead of the tree's root box.
    pub deformed_bounds: Option<(Vec3, Vec3)>,
    /// The tree was rebuilt since upload (its topology and triangle order are no longer the upload's).
    pub rebuilt: bool,
    /// The tree built at upload, kept once [`RebuildPolicy::PoseDetermined`] first needs it.
    upload_bvh: Option<MeshBvh>,
}

impl MeshSlot {
    /// Puts back the tree built at upload (keeping a copy the first time); returns the upload triangle order
    /// to write when the current tree was a rebuilt one. The tree's bounds are stale until the next refit.
    fn restore_upload_tree(
        &mut self,
        mesh: &MeshData,
        variant: Option<usize>,
        materials: &[GpuMaterial],
        quality: crate::bvh::BvhQuality,
    ) -> Option<OrderedTriangles> {
        if self.upload_bvh.is_none() {
            // Until the first rebuild the current tree has the upload topology; after one, the same
            // deterministic build over the rest positions gives it back.
            let upload = if self.rebuilt {
                let wide = self.wide_node_offset != NONE;
                MeshBvh::build_refittable(&mesh.positions, &mesh.triangles, quality, wide).ok()?
            } else {
                self.blas.binary()?.clone()
            };
            self.upload_bvh = Some(upload);
        }
        if !self.rebuilt {
            return None;
        }
        let upload = self.upload_bvh.clone()?;
        let ordered = order_triangles(
            mesh,
            &mesh.triangle_materials_under(variant),
            &upload.flat.order,
            self.gpu.triangle_offset,
            materials,
        );
        self.blas = Blas::Binary(upload);
        self.gpu_triangles = ordered.indices.clone();
        self.rebuilt = false;
        Some(ordered)
    }
}

/// Byte counts of what the scene occupies on the GPU.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct GpuMemory {
    /// Child-pair BVH2 nodes and compressed wide nodes together.
    pub blas_nodes: u64,
    pub triangles: u64,
    pub vertex_pool: u64,
    pub materials: u64,
    pub texels: u64,
    pub instances_and_tlas: u64,
    /// The light list, its CDF and the environment map.
    pub lights: u64,
    /// GPU deformation: rest attributes, influences, morph deltas, per-frame matrices/weights and refit
    /// tables of the meshes the GPU deforms (0 on the CPU backend).
    pub deform: u64,
    /// The real-time path's previous-frame scene data ([`motion::SceneMotion`]; 0 while it is off).
    pub motion: u64,
}

impl GpuMemory {
    /// Geometry + BVH: the figure the memory target counts (no textures).
    pub fn geometry_and_bvh(&self) -> u64 {
        self.blas_nodes + self.triangles + self.vertex_pool + self.instances_and_tlas + self.deform
    }
    pub fn total(&self) -> u64 {
        self.geometry_and_bvh() + self.materials + self.texels + self.lights
    }
}

/// A set of the scene's buffers, one bit per binding of `shaders/scene/bindings.wgsl` (binding order).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneWrites(pub u16);

impl SceneWrites {
    pub const NONE: Self = Self(0);
    pub const TLAS_NODES: Self = Self(1 << 0);
    pub const BLAS_NODES: Self = Self(1 << 1);
    pub const INSTANCES: Self = Self(1 << 2);
    pub const MESHES: Self = Self(1 << 3);
    pub const TRIANGLES: Self = Self(1 << 4);
    pub const VERTEX_POOL: Self = Self(1 << 5);
    pub const MATERIALS: Self = Self(1 << 6);
    pub const TEXELS: Self = Self(1 << 7);
    pub const TEXTURE_INFOS: Self = Self(1 << 8);
    pub const LIGHTS: Self = Self(1 << 9);
    pub const WIDE_NODES: Self = Self(1 << 10);
    pub const LIGHT_CDF: Self = Self(1 << 11);
    pub const ENVIRONMENT_MAP: Self = Self(1 << 12);
    pub const LIGHT_TREE: Self = Self(1 << 13);
    pub const ALL: Self = Self((1 << 14) - 1);

    pub fn contains(self, binding: usize) -> bool {
        self.0 & (1 << binding) != 0
    }
}

impl std::ops::BitOr for SceneWrites {
    type Output = Self;
    fn bitor(self, other: Self) -> Self {
        Self(self.0 | other.0)
    }
}

impl std::ops::BitOrAssign for SceneWrites {
    fn bitor_assign(&mut self, other: Self) {
        self.0 |= other.0;
    }
}

#[derive(bevy_ecs::prelude::Resource)]
pub struct GpuScene {
    pub blas_nodes: wgpu::Buffer,
    /// Compressed wide nodes of static meshes (`GpuMesh::blas_root` has [`WIDE_BLAS`] set).
    pub wide_nodes: wgpu::Buffer,
    pub triangles: wgpu::Buffer,
    pub vertex_pool: wgpu::Buffer,
    pub materials: wgpu::Buffer,
    pub texels: wgpu::Buffer,
    pub texture_infos: wgpu::Buffer,
    pub tlas_nodes: wgpu::Buffer,
    pub instances: wgpu::Buffer,
    /// Every light (`lights::LightList` says the order).
    pub light_buffer: wgpu::Buffer,
    /// The light sampler's CDF over `light_buffer`.
    pub light_cdf: wgpu::Buffer,
    /// Environment texels and their sampling distribution.
    pub environment_map: wgpu::Buffer,
    /// The light sampler's tree over the lights at finite distance.
    pub light_tree: wgpu::Buffer,
    pub meshes: wgpu::Buffer,
    pub mesh_slots: Vec<MeshSlot>,
    pub material_data: Vec<GpuMaterial>,
    /// The texture-info entries of transformed texture slots (what material edits resolve against).
    pub texture_slots: packing::TextureSlots,
    pub memory: GpuMemory,
    /// The light list's parts and what was last uploaded.
    pub lights: LightList,
    /// For each GPU instance (TLAS leaf order), its index in the last [`Self::update_instances`] input.
    pub instance_order: Vec<u32>,
    /// The instance the top level's one leaf holds, when it holds one (a static scene merged into one tree, or
    /// a scene of one instance): the trace kernels start there (`SOLE_INSTANCE`, `shaders/traversal/tlas.wgsl`).
    pub sole_instance: Option<u32>,
    /// The BLAS layouts the top level's leaves use (`BLAS_LAYOUT_*` bits): the trace kernels compile only their
    /// traversals (`BLAS_LAYOUTS`, `shaders/traversal/tlas.wgsl`).
    pub blas_layouts: u32,
    /// The top level as last built, from which its buffer is packed again when the waves ask for the wide tree
    /// or stop asking ([`Self::want_wide_top_level`]).
    top_level: instances::TopLevel,
    /// The KHR_materials_variants variant whose materials the triangles hold (`None`: the file's).
    pub variant: Option<usize>,
    /// Emissive triangles per mesh (triangle slot, material), for building the light list.
    emissive_triangles: Vec<Vec<(u32, u32)>>,
    /// Instances as last uploaded (TLAS leaf order): material edits rebuild the light list from them.
    uploaded_instances: Vec<GpuInstance>,
    /// The real-time path's previous-frame data, while it runs.
    pub motion: Option<motion::SceneMotion>,
    /// The most bytes one storage buffer may bind on this adapter.
    pub binding_limit: u64,
    /// Bumped whenever buffers are recreated, so bind groups are rebuilt.
    pub generation: u64,
    /// The buffers written since the kernels' texture copies were last made (CPU adapters only read those:
    /// `render::scene_texels`); every method that writes a buffer marks it.
    pub written: SceneWrites,
    /// Build preset of deformable meshes' trees, at upload and at every rebuild (so that a rebuild from the
    /// upload pose gives the upload's tree back).
    deformable_quality: crate::bvh::BvhQuality,
    /// The static instances traced through one tree, while at least two are.
    pub merge: Option<static_merge::StaticMerge>,
    /// A material edit or variant switch may have given a member an alpha-masked material.
    merge_materials_changed: bool,
    pub build_seconds: f64,
}

impl GpuScene {
    /// Whether any deforming mesh is traced through a wide tree refit with its BVH2.
    pub fn has_wide_deformed(&self) -> bool {
        self.mesh_slots.iter().any(|s| s.wide_node_offset != NONE)
    }

    /// The build preset of deformable meshes' trees (every rebuild takes the upload's).
    pub fn deformable_quality(&self) -> crate::bvh::BvhQuality {
        self.deformable_quality
    }

    /// Builds every mesh's BVH and uploads the static data: static meshes' trees with `quality`, deformable ones'
    /// with `deformable_quality`; with `merge_quality`, the static instances' merged tree too, of that preset.
    /// `binding_limit` overrides the adapter's storage binding limit (tests use it to exercise the over-limit
    /// path).
    pub fn new(
        ctx: &GpuContext,
        scene: &SceneAsset,
        quality: crate::bvh::BvhQuality,
        deformable_quality: crate::bvh::BvhQuality,
        layout: StaticLayout,
        merge_quality: Option<crate::bvh::BvhQuality>,
        binding_limit: Option<u64>,
    ) -> Result<(Self, Vec<String>), UploadError> {
        let start = std::time::Instant::now();
        let mut notes = Vec::new();
        let limit = binding_limit
            .unwrap_or(ctx.limits.max_storage_buffer_binding_size)
            .min(ctx.limits.max_buffer_size);
        let check = |what: &'static str, bytes: u64| -> Result<(), UploadError> {
            if bytes > limit {
                return Err(UploadError::OverLimit {
                    scene: scene.source.clone(),
                    what,
                    needed_mib: bytes as f64 / 1048576.0,
                    limit_mib: limit as f64 / 1048576.0,
                    adapter: ctx.info.name.clone(),
                });
            }
            Ok(())
        };

        let mut pool = Vec::new();
        let mut blas_nodes = Vec::new();
        let mut wide_nodes: Vec<obvhs::cwbvh::node::CwBvhNode> = Vec::new();
        let mut triangles: Vec<[u32; 4]> = Vec::new();
        let mut slots = Vec::with_capacity(scene.meshes.len());
        let mut emissive_triangles = Vec::with_capacity(scene.meshes.len());
        let (texels, mut texture_infos, note) =
            packing::pack_textures(scene, limit.min(ctx.limits.max_buffer_size));
        notes.extend(note);
        let texture_slots = packing::TextureSlots::build(&scene.materials, &mut texture_infos);
        let materials: Vec<GpuMaterial> = scene
            .materials
            .iter()
            .chain(std::iter::once(&crate::scene::Material::default()))
            .map(|m| gpu_material(m, &texture_slots))
            .collect();
        // Meshes build their trees in parallel (obvhs also parallelises within one large mesh).
        let blases: Vec<Blas> = scene
            .meshes
            .par_iter()
            .map(|mesh| {
                let deformable = mesh.is_deformable();
                Blas::build(
                    &mesh.positions,
                    &mesh.triangles,
                    if deformable {
                        deformable_quality
                    } else {
                        quality
                    },
                    layout,
                    deformable,
                    ctx.wide_deformed,
                )
                .map_err(|source| UploadError::Bvh {
                    scene: scene.source.clone(),
                    mesh: mesh.name.clone(),
                    source,
                })
            })
            .collect::<Result<_, _>>()?;
        for (mesh, blas) in scene.meshes.iter().zip(blases) {
            let mut gpu = pack_vertices(mesh, &mut pool);
            gpu.triangle_offset = triangles.len() as u32;
            let ordered = order_triangles(
                mesh,
                &mesh.triangle_materials_under(scene.active_variant),
                blas.order(),
                gpu.triangle_offset,
                &materials,
            );
            triangles.extend_from_slice(&ordered.packed);
            let (gpu_triangles, emissive) = (ordered.indices, ordered.emissive);
            emissive_triangles.push(emissive);
            let (mut wide_node_offset, mut wide_capacity) = (NONE, 0);
            match &blas {
                Blas::Wide(wide) => {
                    gpu.blas_root = wide_nodes.len() as u32 | WIDE_BLAS;
                    wide_nodes.extend_from_slice(&wide.nodes);
                }
                Blas::Binary(bvh) => {
                    gpu.blas_root = blas_nodes.len() as u32;
                    if let Some(wide) = &bvh.wide {
                        wide_node_offset = wide_nodes.len() as u32;
                        wide_capacity = crate::bvh::wide_refit::node_capacity(mesh.triangles.len())
                            .max(wide.nodes.len()) as u32;
                        wide_nodes.extend_from_slice(&wide.nodes);
                        wide_nodes.resize(
                            (wide_node_offset + wide_capacity) as usize,
                            Default::default(),
                        );
                    }
                    blas_nodes.extend_from_slice(&bvh.flat.nodes);
                    // Deformable meshes reserve the largest tree a rebuild can produce, so it rewrites in place.
                    if mesh.is_deformable() {
                        let capacity = crate::bvh::refit::node_capacity(mesh.triangles.len())
                            .max(bvh.flat.nodes.len());
                        blas_nodes.resize(
                            gpu.blas_root as usize + capacity,
                            crate::bvh::GpuBvhNode::EMPTY,
                        );
                    }
                }
            }
            let blas_capacity = match &blas {
                Blas::Wide(w) => w.nodes.len() as u32,
                Blas::Binary(_) => (blas_nodes.len() - gpu.blas_root as usize) as u32,
            };
            let blas_node_offset = gpu.blas_root;
            if wide_node_offset != NONE {
                gpu.blas_root = wide_node_offset | WIDE_BLAS;
            }
            slots.push(MeshSlot {
                gpu,
                gpu_triangles,
                blas_node_offset,
                wide_node_offset,
                wide_capacity,
                blas,
                positions: None,
                blas_capacity,
                deformed_bounds: None,
                rebuilt: false,
                upload_bvh: None,
            });
        }
        if wide_nodes.len() as u32 >= WIDE_BLAS {
            return Err(UploadError::OverLimit {
                scene: scene.source.clone(),
                what: "wide BVH node",
                needed_mib: (wide_nodes.len() * 80) as f64 / 1048576.0,
                limit_mib: (WIDE_BLAS as usize * 80) as f64 / 1048576.0,
                adapter: ctx.info.name.clone(),
            });
        }

        let mut merge = None;
        if let (Some(merged_quality), StaticLayout::Wide) = (merge_quality, layout) {
            let members = static_merge::plan(scene, scene.active_variant, &materials);
            let opaque = (materials.len() - 1) as u32;
            let geometry = (!members.is_empty())
                .then(|| static_merge::build(scene, &slots, members, merged_quality, opaque))
                .flatten();
            // Only where every buffer still binds: the merge is a speed-up, never a reason to refuse a scene.
            if let Some(g) = geometry.filter(|g| {
                g.fits(
                    limit,
                    pool.len(),
                    triangles.len(),
                    wide_nodes.len(),
                    WIDE_BLAS,
                )
            }) {
                merge = Some(static_merge::StaticMerge::append(
                    g,
                    &mut pool,
                    &mut triangles,
                    &mut wide_nodes,
                ));
            }
        }
        let meshes: Vec<GpuMesh> = slots
            .iter()
            .map(|s| s.gpu)
            .chain(merge.as_ref().map(|m| m.mesh))
            .collect();
        check("BLAS node", (blas_nodes.len() * 64) as u64)?;
        check("wide BLAS node", (wide_nodes.len() * 80) as u64)?;
        check("triangle", (triangles.len() * 16) as u64)?;
        check("vertex", (pool.len() * 4) as u64)?;
        check("texel", (texels.len() * 4) as u64)?;

        let memory = GpuMemory {
            blas_nodes: (blas_nodes.len() * 64 + wide_nodes.len() * 80) as u64,
            triangles: (triangles.len() * 16) as u64,
            vertex_pool: (pool.len() * 4) as u64,
            materials: (materials.len() * std::mem::size_of::<GpuMaterial>()
                + texture_infos.len() * std::mem::size_of::<GpuTexture>())
                as u64,
            texels: (texels.len() * 4) as u64,
            instances_and_tlas: 0,
            lights: 0,
            deform: 0,
            motion: 0,
        };
        let gpu_scene = Self {
            blas_nodes: storage(ctx, "blas nodes", bytemuck::cast_slice(&blas_nodes)),
            wide_nodes: storage(ctx, "wide blas nodes", bytemuck::cast_slice(&wide_nodes)),
            triangles: storage(ctx, "triangles", bytemuck::cast_slice(&triangles)),
            vertex_pool: storage(ctx, "vertex pool", bytemuck::cast_slice(&pool)),
            materials: storage(ctx, "materials", bytemuck::cast_slice(&materials)),
            texels: storage(ctx, "texels", bytemuck::cast_slice(&texels)),
            texture_infos: storage(ctx, "texture infos", bytemuck::cast_slice(&texture_infos)),
            tlas_nodes: storage(ctx, "tlas nodes", &[0; 64]),
            instances: storage(ctx, "instances", &[0; 112]),
            light_buffer: storage(ctx, "lights", &[0; 64]),
            light_cdf: storage(ctx, "light cdf", &[0; 16]),
            environment_map: storage(ctx, "environment map", &[0; 16]),
            light_tree: storage(ctx, "light tree", &[0; 64]),
            meshes: storage(ctx, "meshes", bytemuck::cast_slice(&meshes)),
            mesh_slots: slots,
            material_data: materials,
            texture_slots,
            memory,
            lights: LightList::default(),
            instance_order: Vec::new(),
            sole_instance: None,
            blas_layouts: BLAS_LAYOUTS_ALL,
            top_level: Default::default(),
            variant: scene.active_variant,
            emissive_triangles,
            uploaded_instances: Vec::new(),
            motion: None,
            generation: 1,
            written: SceneWrites::ALL,
            binding_limit: limit,
            deformable_quality,
            merge,
            merge_materials_changed: false,
            build_seconds: start.elapsed().as_secs_f64(),
        };
        Ok((gpu_scene, notes))
    }

    /// Whether a mesh has emissive triangles (next-event estimation needs their world areas on the CPU).
    pub fn has_emitters(&self, mesh: usize) -> bool {
        self.emissive_triangles
            .get(mesh)
            .is_some_and(|e| !e.is_empty())
    }
}

//! Packs a scene's meshes, materials and textures into the GPU buffers the kernels read.
//! Static data is uploaded once; instances, the top-level BVH and emitters are rewritten when they change;
//! a deformed mesh rewrites only its own positions/normals and BLAS nodes.

use super::layout::*;
use crate::bvh::refit::RebuildPolicy;
use crate::bvh::{Blas, FlatBvh, MeshBvh, StaticLayout};
use crate::gpu::GpuContext;
use crate::scene::{AlphaMode, MeshData, SceneAsset, Wrap};
use glam::{Mat4, Vec3};
use rayon::prelude::*;
use wgpu::util::DeviceExt;

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
    pub blas_node_offset: u32,
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
        materials: &[GpuMaterial],
        quality: crate::bvh::BvhQuality,
    ) -> Option<OrderedTriangles> {
        if self.upload_bvh.is_none() {
            // Until the first rebuild the current tree has the upload topology; after one, the same
            // deterministic build over the rest positions gives it back.
            let upload = if self.rebuilt {
                MeshBvh::build(&mesh.positions, &mesh.triangles, quality).ok()?
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
    /// GPU deformation: rest attributes, influences, morph deltas, per-frame matrices/weights and refit
    /// tables of the meshes the GPU deforms (0 on the CPU backend).
    pub deform: u64,
}

impl GpuMemory {
    /// Geometry + BVH: the figure the memory target counts (no textures).
    pub fn geometry_and_bvh(&self) -> u64 {
        self.blas_nodes + self.triangles + self.vertex_pool + self.instances_and_tlas + self.deform
    }
    pub fn total(&self) -> u64 {
        self.geometry_and_bvh() + self.materials + self.texels
    }
}

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
    pub emitters: wgpu::Buffer,
    pub meshes: wgpu::Buffer,
    pub mesh_slots: Vec<MeshSlot>,
    pub material_data: Vec<GpuMaterial>,
    pub memory: GpuMemory,
    pub emitter_count: u32,
    pub emitter_total_power: f32,
    /// For each GPU instance (TLAS leaf order), its index in the last [`Self::update_instances`] input.
    pub instance_order: Vec<u32>,
    /// Emissive triangles per mesh (triangle slot, material), for building the emitter list.
    emissive_triangles: Vec<Vec<(u32, u32)>>,
    /// Instances as last uploaded (TLAS leaf order): material edits rebuild the emitter list from them.
    uploaded_instances: Vec<GpuInstance>,
    /// Bumped whenever buffers are recreated, so bind groups are rebuilt.
    pub generation: u64,
    /// Build quality of the upload (rebuilds of the upload tree use it).
    bvh_quality: crate::bvh::BvhQuality,
    pub build_seconds: f64,
}

/// Per-instance data the renderer needs each frame: world matrix and mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceInput {
    pub world: Mat4,
    pub mesh: u32,
}

pub(crate) fn storage(ctx: &GpuContext, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    // wgpu rejects empty bindings and ones smaller than one element: keep at least the largest element
    // (an instance, 112 bytes).
    const MIN_BYTES: usize = 128;
    let padded;
    let contents = if bytes.len() < MIN_BYTES {
        padded = {
            let mut v = bytes.to_vec();
            v.resize(MIN_BYTES, 0);
            v
        };
        &padded[..]
    } else {
        bytes
    };
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
        })
}

fn texture_slot(t: Option<crate::scene::TextureRef>) -> u32 {
    t.map_or(NONE, |t| t.texture | (t.tex_coord << 24))
}

pub fn gpu_material(m: &crate::scene::Material) -> GpuMaterial {
    let (cutoff, alpha_flags) = match m.alpha_mode {
        AlphaMode::Opaque => (0.0, 0),
        AlphaMode::Mask(c) => (c, MATERIAL_ALPHA_MASK),
        AlphaMode::Blend => (0.0, MATERIAL_ALPHA_BLEND),
    };
    GpuMaterial {
        base_color: m.base_color.to_array(),
        emissive: m.emitted_radiance().to_array(),
        metallic: m.metallic,
        roughness: m.roughness,
        alpha_cutoff: cutoff,
        normal_scale: m.normal_scale,
        flags: alpha_flags
            | if m.double_sided {
                MATERIAL_DOUBLE_SIDED
            } else {
                0
            },
        base_color_texture: texture_slot(m.base_color_texture),
        metallic_roughness_texture: texture_slot(m.metallic_roughness_texture),
        normal_texture: texture_slot(m.normal_texture),
        emissive_texture: texture_slot(m.emissive_texture),
    }
}

pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// Appends a mesh's attributes to the vertex pool; returns the mesh's offsets.
fn pack_vertices(mesh: &MeshData, pool: &mut Vec<u32>) -> GpuMesh {
    let mut gpu = GpuMesh {
        blas_root: 0,
        triangle_offset: 0,
        position_offset: pool.len() as u32,
        normal_offset: NONE,
        tangent_offset: NONE,
        uv0_offset: NONE,
        uv1_offset: NONE,
        color_offset: NONE,
    };
    pool.extend(
        mesh.positions
            .iter()
            .flat_map(|p| p.to_array().map(f32::to_bits)),
    );
    if let Some(n) = &mesh.normals {
        gpu.normal_offset = pool.len() as u32;
        pool.extend(n.iter().map(|n| oct_encode(*n)));
    }
    if let Some(t) = &mesh.tangents {
        gpu.tangent_offset = pool.len() as u32;
        pool.extend(t.iter().flat_map(|t| {
            [
                oct_encode(t.truncate()),
                if t.w < 0.0 { -1f32 } else { 1f32 }.to_bits(),
            ]
        }));
    }
    for (uv, offset) in [
        (&mesh.uv0, &mut gpu.uv0_offset),
        (&mesh.uv1, &mut gpu.uv1_offset),
    ] {
        if let Some(uv) = uv {
            *offset = pool.len() as u32;
            pool.extend(uv.iter().flat_map(|v| v.to_array().map(f32::to_bits)));
        }
    }
    if let Some(c) = &mesh.colors {
        gpu.color_offset = pool.len() as u32;
        pool.extend(c.iter().map(|c| pack_unorm4x8(*c)));
    }
    gpu
}

/// Halves images (box filter) until all texels fit `budget` bytes; returns the images and a note if any shrank.
type FittedImage = (u32, u32, Vec<u8>);

fn fit_images(scene: &SceneAsset, budget: u64) -> (Vec<FittedImage>, Option<String>) {
    let mut images: Vec<(u32, u32, Vec<u8>)> = scene
        .images
        .iter()
        .map(|i| (i.width, i.height, i.rgba8.clone()))
        .collect();
    let total = |imgs: &[(u32, u32, Vec<u8>)]| imgs.iter().map(|i| i.2.len() as u64).sum::<u64>();
    let before = total(&images);
    let mut halvings = 0;
    while total(&images) > budget {
        let Some(largest) = (0..images.len()).max_by_key(|&i| images[i].2.len()) else {
            break;
        };
        let (w, h, px) = &images[largest];
        if *w <= 1 && *h <= 1 {
            break;
        }
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        let mut out = vec![0u8; (nw * nh * 4) as usize];
        for y in 0..nh {
            for x in 0..nw {
                for c in 0..4 {
                    let mut sum = 0u32;
                    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let sx = (2 * x + dx).min(w - 1);
                        let sy = (2 * y + dy).min(h - 1);
                        sum += px[((sy * w + sx) * 4 + c) as usize] as u32;
                    }
                    out[((y * nw + x) * 4 + c) as usize] = ((sum + 2) / 4) as u8;
                }
            }
        }
        images[largest] = (nw, nh, out);
        halvings += 1;
    }
    let note = (halvings > 0).then(|| {
        format!(
            "textures ({:.1} MiB) exceed the GPU's buffer limit; downscaled {halvings} time(s) to {:.1} MiB",
            before as f64 / 1048576.0,
            total(&images) as f64 / 1048576.0
        )
    });
    (images, note)
}

impl GpuScene {
    /// Builds every mesh's BVH and uploads the static data. `binding_limit` overrides the adapter's storage
    /// binding limit (tests use it to exercise the over-limit path).
    pub fn new(
        ctx: &GpuContext,
        scene: &SceneAsset,
        quality: crate::bvh::BvhQuality,
        layout: StaticLayout,
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
        let materials: Vec<GpuMaterial> = scene
            .materials
            .iter()
            .chain(std::iter::once(&crate::scene::Material::default()))
            .map(gpu_material)
            .collect();
        // Meshes build their trees in parallel (obvhs also parallelises within one large mesh).
        let blases: Vec<Blas> = scene
            .meshes
            .par_iter()
            .map(|mesh| {
                Blas::build(
                    &mesh.positions,
                    &mesh.triangles,
                    quality,
                    layout,
                    mesh.is_deformable(),
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
            let ordered = order_triangles(mesh, blas.order(), gpu.triangle_offset, &materials);
            triangles.extend_from_slice(&ordered.packed);
            let (gpu_triangles, emissive) = (ordered.indices, ordered.emissive);
            emissive_triangles.push(emissive);
            match &blas {
                Blas::Wide(wide) => {
                    gpu.blas_root = wide_nodes.len() as u32 | WIDE_BLAS;
                    wide_nodes.extend_from_slice(&wide.nodes);
                }
                Blas::Binary(bvh) => {
                    gpu.blas_root = blas_nodes.len() as u32;
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
            slots.push(MeshSlot {
                gpu,
                gpu_triangles,
                blas_node_offset: gpu.blas_root,
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

        let texel_budget = limit.min(ctx.limits.max_buffer_size);
        let (images, note) = fit_images(scene, texel_budget);
        notes.extend(note);
        let mut texels: Vec<u32> = Vec::new();
        let mut image_offsets = Vec::new();
        for (_, _, px) in &images {
            image_offsets.push(texels.len() as u32);
            texels.extend(
                px.chunks_exact(4)
                    .map(|p| u32::from_le_bytes([p[0], p[1], p[2], p[3]])),
            );
        }
        let wrap_bits = |w: Wrap| match w {
            Wrap::Repeat => 0,
            Wrap::MirroredRepeat => 1,
            Wrap::ClampToEdge => 2,
        };
        let texture_infos: Vec<GpuTexture> = scene
            .textures
            .iter()
            .map(|t| {
                let i = (t.image as usize).min(images.len().saturating_sub(1));
                let (w, h) = images.get(i).map_or((1, 1), |im| (im.0, im.1));
                GpuTexture {
                    offset: image_offsets.get(i).copied().unwrap_or(0),
                    width: w,
                    height: h,
                    flags: wrap_bits(t.wrap_s)
                        | (wrap_bits(t.wrap_t) << 2)
                        | if t.nearest { TEXTURE_NEAREST } else { 0 },
                }
            })
            .collect();

        let meshes: Vec<GpuMesh> = slots.iter().map(|s| s.gpu).collect();
        check("BLAS node", (blas_nodes.len() * 64) as u64)?;
        check("wide BLAS node", (wide_nodes.len() * 80) as u64)?;
        check("triangle", (triangles.len() * 16) as u64)?;
        check("vertex", (pool.len() * 4) as u64)?;
        check("texel", (texels.len() * 4) as u64)?;

        let memory = GpuMemory {
            blas_nodes: (blas_nodes.len() * 64 + wide_nodes.len() * 80) as u64,
            triangles: (triangles.len() * 16) as u64,
            vertex_pool: (pool.len() * 4) as u64,
            materials: (materials.len() * 64 + texture_infos.len() * 16) as u64,
            texels: (texels.len() * 4) as u64,
            instances_and_tlas: 0,
            deform: 0,
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
            emitters: storage(ctx, "emitters", &[0; 16]),
            meshes: storage(ctx, "meshes", bytemuck::cast_slice(&meshes)),
            mesh_slots: slots,
            material_data: materials,
            memory,
            emitter_count: 0,
            emitter_total_power: 0.0,
            instance_order: Vec::new(),
            emissive_triangles,
            uploaded_instances: Vec::new(),
            generation: 1,
            bvh_quality: quality,
            build_seconds: start.elapsed().as_secs_f64(),
        };
        Ok((gpu_scene, notes))
    }

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
        let (materials, quality) = (&self.material_data, self.bvh_quality);
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
                    .then(|| slot.restore_upload_tree(&scene.meshes[m], materials, quality))
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
                    ctx.queue.write_buffer(
                        &self.vertex_pool,
                        slot.gpu.position_offset as u64 * 4,
                        bytemuck::cast_slice(&d.positions),
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
                    ctx.queue.write_buffer(
                        &self.blas_nodes,
                        slot.gpu.blas_root as u64 * 64,
                        bytemuck::cast_slice(&bvh.flat.nodes),
                    );
                }
                (u.mesh, u.sah_ratio)
            })
            .collect();
        (ratios, start.elapsed().as_secs_f64())
    }

    /// Whether a mesh has emissive triangles (next-event estimation needs their world areas on the CPU).
    pub fn has_emitters(&self, mesh: usize) -> bool {
        self.emissive_triangles
            .get(mesh)
            .is_some_and(|e| !e.is_empty())
    }

    /// Rebuilds a mesh's BLAS from its current positions inside its reserved node range, and rewrites its
    /// triangle range in the new BVH order (same triangles, same count).
    pub fn rebuild_mesh(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        mesh: usize,
        quality: crate::bvh::BvhQuality,
    ) -> Result<(), crate::bvh::BvhTooDeep> {
        let slot = &self.mesh_slots[mesh];
        let positions = slot
            .positions
            .as_deref()
            .unwrap_or(&scene.meshes[mesh].positions);
        let bvh = MeshBvh::build(positions, &scene.meshes[mesh].triangles, quality)?;
        self.install_bvh(ctx, scene, mesh, bvh);
        Ok(())
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
        let mut nodes = bvh.flat.nodes.clone();
        nodes.resize(slot.blas_capacity as usize, crate::bvh::GpuBvhNode::EMPTY);
        let ordered = order_triangles(
            data,
            &bvh.flat.order,
            slot.gpu.triangle_offset,
            &self.material_data,
        );
        ctx.queue.write_buffer(
            &self.blas_nodes,
            slot.gpu.blas_root as u64 * 64,
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
        let tlas: FlatBvh = crate::bvh::build_tlas(&boxes)?;
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
        self.instance_order = tlas.order.clone();
        self.memory.instances_and_tlas =
            (instance_bytes.len() + tlas_bytes.len() + emitter_bytes.len()) as u64;
        self.uploaded_instances = ordered;
        Ok(())
    }

    /// Uploads the materials that differ from what the GPU holds; returns how many changed. When the set of
    /// emissive triangles or their power changes, the emitter list is rebuilt for the current instances.
    pub fn update_materials(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneAsset,
        materials: &[crate::scene::Material],
    ) -> usize {
        let mut changed = 0;
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
            changed += 1;
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

/// A mesh's triangles in its BVH's leaf order, as the upload and an in-place rebuild both need them.
struct OrderedTriangles {
    /// Vertex indices per triangle (kept on the CPU for refits).
    indices: Vec<[u32; 3]>,
    /// The GPU form: vertex indices + material.
    packed: Vec<[u32; 4]>,
    /// Emissive triangles: (slot in the triangle buffer, material).
    emissive: Vec<(u32, u32)>,
}

fn order_triangles(
    mesh: &MeshData,
    order: &[u32],
    triangle_offset: u32,
    materials: &[GpuMaterial],
) -> OrderedTriangles {
    let indices = crate::bvh::ordered_triangles(order, &mesh.triangles);
    let packed = order
        .iter()
        .zip(&indices)
        .map(|(&t, [a, b, c])| [*a, *b, *c, mesh.triangle_materials[t as usize]])
        .collect();
    OrderedTriangles {
        indices,
        packed,
        emissive: emissive_slots(mesh, order, triangle_offset, materials),
    }
}

/// A mesh's emissive triangles in BVH order (`order`: original triangle of each slot): (slot in the
/// triangle buffer, material).
fn emissive_slots(
    mesh: &MeshData,
    order: &[u32],
    triangle_offset: u32,
    materials: &[GpuMaterial],
) -> Vec<(u32, u32)> {
    order
        .iter()
        .enumerate()
        .filter_map(|(slot, &t)| {
            let material = mesh.triangle_materials[t as usize];
            (luminance(Vec3::from(materials[material as usize].emissive)) > 0.0)
                .then_some((triangle_offset + slot as u32, material))
        })
        .collect()
}

/// Writes `bytes` into `buffer`, replacing it with a larger one when it does not fit; true when replaced (bind
/// groups must then be rebuilt). Empty data leaves the buffer as it is.
fn write_or_grow(ctx: &GpuContext, buffer: &mut wgpu::Buffer, bytes: &[u8], label: &str) -> bool {
    if bytes.is_empty() {
        return false;
    }
    if (buffer.size() as usize) < bytes.len() {
        *buffer = storage(ctx, label, bytes);
        true
    } else {
        ctx.queue.write_buffer(buffer, 0, bytes);
        false
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

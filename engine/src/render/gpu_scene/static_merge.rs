//! Static instances traced through one BVH. Every mesh instance that never moves (no animation on its node or
//! an ancestor, no skin, no morph targets) and never needs the alpha test joins one compressed wide BVH over
//! the world-space triangles of all of them, as OptiX and Embree build one acceleration structure over a
//! scene's static shapes: meshes that overlap (a helmet's shell, straps and visor) stop costing one descent
//! each, since the merged tree separates their triangles. The merged tree is one more top-level leaf (a
//! pseudo-instance with the identity placement); the trace kernel maps its hits back to the member instance and
//! that mesh's own triangle slot (`shaders/traversal/tlas.wgsl` `member_hit`), so shading, the light list,
//! picking and motion vectors only ever see the member instances, which keep their entries in the instance
//! buffer (first, so that their indices stay put while the other instances change).
//!
//! The merged data sits after the per-mesh data in the vertex pool, triangle and wide-node buffers, sized at
//! upload for the members the scene file predicts. A member that moves after all (the editor), disappears or
//! gets an alpha-masked material leaves the merge for good: the rest is rebuilt into the same room.

use super::MeshSlot;
use super::packing::{align_positions, position_words};
use crate::bvh::{BvhQuality, WideBvh};
use crate::render::layout::*;
use crate::scene::SceneAsset;
use glam::{Mat4, Vec3};
use obvhs::cwbvh::node::CwBvhNode;

/// At most this many instances of one mesh are merged (each copy adds its triangles to the merged tree);
/// a mesh placed more often stays instanced through the top level, which is what instancing is for.
pub const MAX_MERGED_COPIES: usize = 8;

/// One instance inside the merge: the glTF node it draws, its mesh and its world placement at merge time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MergeMember {
    pub node: u32,
    pub mesh: u32,
    pub world: Mat4,
}

/// Room reserved at upload in each buffer the merged tree lives in (elements of each buffer).
#[derive(Clone, Copy, Debug, Default)]
struct Room {
    pool_words: usize,
    triangle_entries: usize,
    wide_nodes: usize,
}

/// The merged tree of the scene's static instances, as uploaded.
#[derive(Clone, Debug)]
pub struct StaticMerge {
    /// In GPU instance order: member `i` is instance `i`.
    pub members: Vec<MergeMember>,
    /// The merged mesh's record (index: the scene's mesh count): world-space positions, triangles in tree order
    /// (material: the opaque default), the wide tree's root.
    pub mesh: GpuMesh,
    /// Where the (member instance, member triangle slot) pairs sit in the triangle buffer, two per entry: the
    /// pair of merged slot `s` (absolute, as a hit reports it) is in entry `origins + s / 2`, half `s % 2`.
    /// (The merged slots start at an even entry, so no mesh record is read to find it.)
    pub origins: u32,
    pub triangles: u32,
    /// World-space box of the members.
    pub bounds: (Vec3, Vec3),
    /// Bytes of the merged data (positions, triangles, pairs, nodes).
    pub bytes: u64,
    /// The preset its tree was built with, which rebuilds keep.
    pub quality: BvhQuality,
    start: Room,
    room: Room,
}

/// The merged tree and its buffer contents, before they are placed.
pub struct MergedGeometry {
    members: Vec<MergeMember>,
    positions: Vec<u32>,
    /// Triangles in tree order, then the origin pairs.
    entries: Vec<[u32; 4]>,
    triangles: u32,
    nodes: Vec<CwBvhNode>,
    bounds: (Vec3, Vec3),
    quality: BvhQuality,
}

impl MergedGeometry {
    fn room(&self) -> Room {
        Room {
            pool_words: self.positions.len(),
            triangle_entries: self.entries.len(),
            wide_nodes: self.nodes.len(),
        }
    }

    /// Whether the buffers, holding `pool_words`, `triangle_entries` and `wide_nodes` already, still bind
    /// (`limit` bytes each) with this appended, and the wide nodes stay indexable below `max_wide_nodes`.
    pub fn fits(
        &self,
        limit: u64,
        pool_words: usize,
        triangle_entries: usize,
        wide_nodes: usize,
        max_wide_nodes: u32,
    ) -> bool {
        let nodes = wide_nodes + self.nodes.len();
        // `StaticMerge::append` pads the triangle buffer to an even entry first.
        let triangle_entries = triangle_entries + triangle_entries % 2 + self.entries.len();
        ((pool_words + self.positions.len()) * 4) as u64 <= limit
            && (triangle_entries * 16) as u64 <= limit
            && (nodes * 80) as u64 <= limit
            && nodes < max_wide_nodes as usize
    }

    fn bytes(&self) -> u64 {
        (self.positions.len() * 4 + self.entries.len() * 16 + self.nodes.len() * 80) as u64
    }
}

/// Whether any triangle of `mesh` (under `variant`) has an alpha-masked material: the merged triangles skip
/// the alpha test, so such meshes stay outside.
pub fn needs_alpha_test(
    scene: &SceneAsset,
    mesh: usize,
    variant: Option<usize>,
    materials: &[GpuMaterial],
) -> bool {
    let mut used = scene.meshes[mesh]
        .triangle_materials_under(variant)
        .into_owned();
    used.sort_unstable();
    used.dedup();
    used.iter().any(|&m| {
        materials
            .get(m as usize)
            .is_some_and(|g| g.flags & MATERIAL_ALPHA_MASK != 0)
    })
}

/// The instances the scene file says never move: still nodes ([`SceneAsset::still_nodes`]) with a
/// non-empty mesh that needs no alpha test and is placed at most [`MAX_MERGED_COPIES`] times, in node order.
/// Empty when fewer than two qualify (one instance gains nothing from a second tree over the same triangles).
pub fn plan(
    scene: &SceneAsset,
    variant: Option<usize>,
    materials: &[GpuMaterial],
) -> Vec<MergeMember> {
    let still = scene.still_nodes();
    let world = scene.rest_world_matrices();
    let mut copies = vec![0usize; scene.meshes.len()];
    let mut candidates = Vec::new();
    for (n, node) in scene.nodes.iter().enumerate() {
        let Some(mesh) = node.mesh.filter(|&m| still[n] && m < scene.meshes.len()) else {
            continue;
        };
        let placement = world[n];
        if scene.meshes[mesh].triangles.is_empty()
            || !placement.is_finite()
            || placement.determinant() == 0.0
        {
            continue;
        }
        copies[mesh] += 1;
        candidates.push(MergeMember {
            node: n as u32,
            mesh: mesh as u32,
            world: placement,
        });
    }
    let mut alpha_tested = vec![None; scene.meshes.len()];
    candidates.retain(|c| {
        let m = c.mesh as usize;
        copies[m] <= MAX_MERGED_COPIES
            && !*alpha_tested[m]
                .get_or_insert_with(|| needs_alpha_test(scene, m, variant, materials))
    });
    if candidates.len() < 2 {
        candidates.clear();
    }
    candidates
}

/// Builds the merged tree over `members`' world-space triangles (each mesh's triangles in its own slot order,
/// so a pair names the slot shading reads). `None` where the wide build fails (too deep or too large: the
/// instances then stay separate).
pub fn build(
    scene: &SceneAsset,
    slots: &[MeshSlot],
    members: Vec<MergeMember>,
    quality: BvhQuality,
    opaque_material: u32,
) -> Option<MergedGeometry> {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut origins = Vec::new();
    for (i, member) in members.iter().enumerate() {
        let mesh = member.mesh as usize;
        let slot = &slots[mesh];
        let base = positions.len() as u32;
        positions.extend(
            scene.meshes[mesh]
                .positions
                .iter()
                .map(|&p| member.world.transform_point3(p)),
        );
        for (local, t) in slot.gpu_triangles.iter().enumerate() {
            triangles.push(t.map(|v| v + base));
            origins.push([i as u32, slot.gpu.triangle_offset + local as u32]);
        }
    }
    let start = std::time::Instant::now();
    let tree = WideBvh::build_static(&positions, &triangles, quality).ok()?;
    tracing::info!(
        "static merge: {} members, {} triangles in {} leaf slots, {} wide nodes ({quality:?}), built in {:.1} ms",
        members.len(),
        triangles.len(),
        tree.order.len(),
        tree.nodes.len(),
        start.elapsed().as_secs_f64() * 1e3
    );
    let mut entries: Vec<[u32; 4]> = tree
        .order
        .iter()
        .map(|&t| {
            let [a, b, c] = triangles[t as usize];
            [a, b, c, opaque_material]
        })
        .collect();
    let count = entries.len() as u32;
    entries.extend(tree.order.chunks(2).map(|pair| {
        let first = origins[pair[0] as usize];
        let second = pair.get(1).map_or([NONE, NONE], |&t| origins[t as usize]);
        [first[0], first[1], second[0], second[1]]
    }));
    Some(MergedGeometry {
        members,
        positions: positions.iter().flat_map(|&p| position_words(p)).collect(),
        entries,
        triangles: count,
        nodes: tree.nodes,
        bounds: tree.bounds,
        quality,
    })
}

impl StaticMerge {
    /// Appends `geometry` to the buffers' contents at upload; the room it takes is what later rebuilds reuse.
    pub fn append(
        geometry: MergedGeometry,
        pool: &mut Vec<u32>,
        triangles: &mut Vec<[u32; 4]>,
        wide_nodes: &mut Vec<CwBvhNode>,
    ) -> Self {
        // An even first slot: a slot's pair is then found from the slot alone.
        if triangles.len() % 2 == 1 {
            triangles.push([0; 4]);
        }
        align_positions(pool);
        let start = Room {
            pool_words: pool.len(),
            triangle_entries: triangles.len(),
            wide_nodes: wide_nodes.len(),
        };
        let merge = Self::placed(&geometry, start, geometry.room());
        pool.extend_from_slice(&geometry.positions);
        triangles.extend_from_slice(&geometry.entries);
        wide_nodes.extend_from_slice(&geometry.nodes);
        merge
    }

    fn placed(geometry: &MergedGeometry, start: Room, room: Room) -> Self {
        let mesh = GpuMesh {
            blas_root: start.wide_nodes as u32 | WIDE_BLAS,
            triangle_offset: start.triangle_entries as u32,
            position_offset: start.pool_words as u32,
            normal_offset: NONE,
            tangent_offset: NONE,
            uv0_offset: NONE,
            uv1_offset: NONE,
            color_offset: NONE,
        };
        Self {
            members: geometry.members.clone(),
            mesh,
            origins: (start.triangle_entries as u32 + geometry.triangles)
                - start.triangle_entries as u32 / 2,
            triangles: geometry.triangles,
            bounds: geometry.bounds,
            bytes: geometry.bytes(),
            quality: geometry.quality,
            start,
            room,
        }
    }

    /// The same merge over fewer members, written into the room of this one: `None` when it does not fit.
    pub fn rebuilt(
        &self,
        ctx: &crate::gpu::GpuContext,
        buffers: [&wgpu::Buffer; 3],
        geometry: MergedGeometry,
    ) -> Option<Self> {
        let needed = geometry.room();
        if needed.pool_words > self.room.pool_words
            || needed.triangle_entries > self.room.triangle_entries
            || needed.wide_nodes > self.room.wide_nodes
        {
            return None;
        }
        let [pool, triangles, wide_nodes] = buffers;
        let writes: [(&wgpu::Buffer, usize, &[u8]); 3] = [
            (
                pool,
                self.start.pool_words * 4,
                bytemuck::cast_slice(&geometry.positions),
            ),
            (
                triangles,
                self.start.triangle_entries * 16,
                bytemuck::cast_slice(&geometry.entries),
            ),
            (
                wide_nodes,
                self.start.wide_nodes * 80,
                bytemuck::cast_slice(&geometry.nodes),
            ),
        ];
        for (buffer, offset, bytes) in writes {
            if !bytes.is_empty() {
                ctx.queue.write_buffer(buffer, offset as u64, bytes);
            }
        }
        Some(Self::placed(&geometry, self.start, self.room))
    }
}

/// Whether two placements are the same up to the rounding of composing a node's transforms another way.
pub fn same_placement(a: Mat4, b: Mat4) -> bool {
    let scale = a.abs().to_cols_array().into_iter().fold(1.0f32, f32::max);
    (a - b)
        .abs()
        .to_cols_array()
        .into_iter()
        .all(|d| d <= 1e-6 * scale)
}

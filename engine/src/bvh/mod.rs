//! Bounding volume hierarchies: one bottom-level BVH per mesh, a top-level BVH over instances.
//!
//! Built with obvhs (PLOC + reinsertion), then flattened to a "child-pair" BVH2 (see [`GpuBvhNode`]): each GPU
//! node holds the boxes of both its children, so traversal tests two boxes per node fetch, and a refit is one
//! reverse sweep over the array (children always sit after their parent). Deformed meshes are refit in place;
//! [`MeshBvh::sah_cost`] against the cost at build time tells when a refit has degraded and a rebuild is due.

mod balanced;
pub mod refit;
pub mod tlas;
pub mod wide;
pub mod wide_refit;

pub use wide::{WideBvh, WideBvhError};
pub use wide_refit::RefitWideBvh;

use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec3A};
use obvhs::{BvhBuildParams, aabb::Aabb, bvh2::Bvh2, triangle::Triangle};

/// Deepest BVH the GPU traversal stack holds (`TLAS_STACK_SIZE`, `BLAS_STACK_SIZE` in the WGSL constants).
pub const MAX_TRAVERSAL_DEPTH: u32 = 64;
/// Deepest top-level BVH [`build_tlas`] returns: the top-level stack in `shaders/bvh.wgsl` `trace` holds 32
/// entries (deeper trees lost whole subtrees of instances without a word).
pub const MAX_TLAS_DEPTH: u32 = 64;

/// One child of a GPU node: its box, and either an inner node index (`count == 0`) or a leaf's first
/// primitive and primitive count.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuBvhChild {
    pub min: [f32; 3],
    pub index: u32,
    pub max: [f32; 3],
    pub count: u32,
}

impl GpuBvhChild {
    /// The second child of a single-leaf tree, and both children of an empty tree's root: index `NONE` (for
    /// the CPU and the refit), and a box that every slab test rejects, so the traversals need no check of their
    /// own. An inverted box would not do (the slab test swaps each axis' entry and exit, so it accepts it for
    /// rays starting inside), nor a point far away (an object-space ray of a scaled-down instance can reach it):
    /// a point at +infinity is entered at t = +infinity, or left at t = -infinity on an axis the ray moves
    /// away along, so `t_enter <= min(t_exit, t_max)` never holds.
    pub const EMPTY: Self = Self {
        min: [f32::INFINITY; 3],
        index: u32::MAX,
        max: [f32::INFINITY; 3],
        count: 0,
    };

    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    pub fn is_empty(&self) -> bool {
        self.count == 0 && self.index == u32::MAX
    }

    fn set_bounds(&mut self, lo: Vec3, hi: Vec3) {
        self.min = lo.to_array();
        self.max = hi.to_array();
    }

    fn half_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        half_area(Vec3::from(self.max) - Vec3::from(self.min))
    }
}

/// Half the surface area of a box of extent `d` (a negative extent counts as 0).
fn half_area(d: Vec3) -> f32 {
    let d = d.max(Vec3::ZERO);
    d.x * d.y + d.y * d.z + d.z * d.x
}

/// The union of boxes; an inverted box (`lo > hi`) for none.
fn union_boxes(boxes: impl Iterator<Item = (Vec3, Vec3)>) -> (Vec3, Vec3) {
    boxes.fold((Vec3::MAX, Vec3::MIN), |(lo, hi), (a, b)| {
        (lo.min(a), hi.max(b))
    })
}

/// The box of a triangle's three vertices.
fn triangle_box([a, b, c]: [Vec3; 3]) -> (Vec3, Vec3) {
    (a.min(b).min(c), a.max(b).max(c))
}

/// 64 bytes: two children. Node 0 is the root.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuBvhNode {
    pub children: [GpuBvhChild; 2],
}

impl GpuBvhNode {
    /// A node no ray enters: padding of reserved node ranges, and the root of an empty tree.
    pub const EMPTY: Self = Self {
        children: [GpuBvhChild::EMPTY; 2],
    };

    /// An inner node's box: the union of its two children (inner nodes always have both; the root of a
    /// single-leaf tree is the one node with an empty child, and [`FlatBvh::root_bounds`] handles it).
    fn inner_box(&self) -> (Vec3, Vec3) {
        let [a, b] = self.children;
        (
            Vec3::from(a.min).min(Vec3::from(b.min)),
            Vec3::from(a.max).max(Vec3::from(b.max)),
        )
    }
}

/// Build effort, from obvhs's presets.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum BvhQuality {
    Fastest,
    VeryFast,
    Fast,
    #[default]
    Medium,
    Slow,
    VerySlow,
}

impl BvhQuality {
    /// Every preset, fastest build first (the bench charts build time against trace time over these).
    pub const ALL: [BvhQuality; 6] = [
        Self::Fastest,
        Self::VeryFast,
        Self::Fast,
        Self::Medium,
        Self::Slow,
        Self::VerySlow,
    ];

    /// The preset for a tree that may be refit: no spatial splits.
    fn params(self) -> BvhBuildParams {
        BvhBuildParams {
            pre_split: false,
            ..self.static_params()
        }
    }

    /// The preset as obvhs defines it (spatial splits in `Slow` and `VerySlow`), for trees never refit.
    fn static_params(self) -> BvhBuildParams {
        let mut p = match self {
            Self::Fastest => BvhBuildParams::fastest_build(),
            Self::VeryFast => BvhBuildParams::very_fast_build(),
            Self::Fast => BvhBuildParams::fast_build(),
            Self::Medium => BvhBuildParams::medium_build(),
            Self::Slow => BvhBuildParams::slow_build(),
            Self::VerySlow => BvhBuildParams::very_slow_build(),
        };
        // Spatial splits duplicate triangles across leaves, which refit cannot maintain (`params` turns them
        // off); leaves of at most 4 triangles keep the GPU's per-leaf loop short.
        p.max_prims_per_leaf = p.max_prims_per_leaf.min(4);
        p
    }
}

#[derive(Debug, thiserror::Error)]
#[error(
    "BVH depth {depth} exceeds the GPU traversal stack ({MAX_TRAVERSAL_DEPTH}); the geometry is degenerate"
)]
pub struct BvhTooDeep {
    pub depth: u32,
}

/// A flattened BVH and the order its leaves expect primitives in.
#[derive(Clone, Debug, Default)]
pub struct FlatBvh {
    pub nodes: Vec<GpuBvhNode>,
    /// Slot `i` of the GPU primitive array holds original primitive `order[i]`.
    pub order: Vec<u32>,
    pub depth: u32,
}

impl FlatBvh {
    fn from_obvhs(bvh: &Bvh2) -> Result<Self, BvhTooDeep> {
        let mut flat = FlatBvh::default();
        if bvh.nodes.is_empty() {
            flat.nodes.push(GpuBvhNode::EMPTY);
            return Ok(flat);
        }
        let leaf = |flat: &mut FlatBvh, n: &obvhs::bvh2::node::Bvh2Node| {
            let start = flat.order.len() as u32;
            let first = n.first_index as usize;
            flat.order
                .extend_from_slice(&bvh.primitive_indices[first..first + n.prim_count as usize]);
            child_from(n.aabb(), start, n.prim_count)
        };
        let root = &bvh.nodes[0];
        if root.is_leaf() {
            let c = leaf(&mut flat, root);
            flat.nodes.push(GpuBvhNode {
                children: [c, GpuBvhChild::EMPTY],
            });
            flat.depth = 1;
            return Ok(flat);
        }
        flat.nodes.push(GpuBvhNode::EMPTY);
        let mut stack = vec![(0usize, 0usize, 1u32)];
        while let Some((src, slot, depth)) = stack.pop() {
            flat.depth = flat.depth.max(depth);
            let first = bvh.nodes[src].first_index as usize;
            for k in 0..2 {
                let child = &bvh.nodes[first + k];
                flat.nodes[slot].children[k] = if child.is_leaf() {
                    leaf(&mut flat, child)
                } else {
                    let new_slot = flat.nodes.len();
                    flat.nodes.push(GpuBvhNode::EMPTY);
                    stack.push((first + k, new_slot, depth + 1));
                    child_from(child.aabb(), new_slot as u32, 0)
                };
            }
        }
        if flat.depth > MAX_TRAVERSAL_DEPTH {
            return Err(BvhTooDeep { depth: flat.depth });
        }
        Ok(flat)
    }

    /// Surface-area-heuristic cost (traversal and intersection both cost 1), relative to the root's area.
    pub fn sah_cost(&self) -> f32 {
        let root = &self.nodes[0].children;
        let root_area = union_half_area(&root[0], &root[1]).max(f32::MIN_POSITIVE);
        let mut cost = 0.0;
        for node in &self.nodes {
            let [a, b] = &node.children;
            cost += union_half_area(a, b);
            for c in [a, b] {
                if c.is_leaf() {
                    cost += c.half_area() * c.count as f32;
                }
            }
        }
        cost / root_area
    }

    /// Bottom-up box update after primitives moved; `prim_bounds(i)` bounds GPU primitive slot `i`. Returns
    /// the refit tree's [`Self::sah_cost`], summed in the same sweep (every term is a box just updated).
    pub fn refit(&mut self, prim_bounds: impl Fn(usize) -> (Vec3, Vec3)) -> f32 {
        let mut cost = 0.0;
        let (mut root_lo, mut root_hi) = (Vec3::MAX, Vec3::MIN);
        for i in (0..self.nodes.len()).rev() {
            // The union of the node's children, and the leaves' area x count, as `sah_cost` sums them.
            let (mut union_lo, mut union_hi) = (Vec3::MAX, Vec3::MIN);
            for k in 0..2 {
                let c = self.nodes[i].children[k];
                if c.is_empty() {
                    continue;
                }
                let (lo, hi) = if c.is_leaf() {
                    let (lo, hi) = union_boxes(
                        (c.index as usize..(c.index + c.count) as usize).map(&prim_bounds),
                    );
                    cost += half_area(hi - lo) * c.count as f32;
                    (lo, hi)
                } else {
                    self.nodes[c.index as usize].inner_box()
                };
                self.nodes[i].children[k].set_bounds(lo, hi);
                union_lo = union_lo.min(lo);
                union_hi = union_hi.max(hi);
            }
            if union_lo.x <= union_hi.x {
                cost += half_area(union_hi - union_lo);
            }
            (root_lo, root_hi) = (union_lo, union_hi);
        }
        let root_area = if root_lo.x <= root_hi.x {
            half_area(root_hi - root_lo)
        } else {
            0.0
        };
        cost / root_area.max(f32::MIN_POSITIVE)
    }

    pub fn root_bounds(&self) -> (Vec3, Vec3) {
        let [a, b] = self.nodes[0].children;
        let mut lo = Vec3::from(a.min);
        let mut hi = Vec3::from(a.max);
        if !b.is_empty() {
            lo = lo.min(Vec3::from(b.min));
            hi = hi.max(Vec3::from(b.max));
        }
        (lo, hi)
    }
}

fn child_from(aabb: &Aabb, index: u32, count: u32) -> GpuBvhChild {
    GpuBvhChild {
        min: Vec3::from(aabb.min).to_array(),
        index,
        max: Vec3::from(aabb.max).to_array(),
        count,
    }
}

fn union_half_area(a: &GpuBvhChild, b: &GpuBvhChild) -> f32 {
    if b.is_empty() {
        return a.half_area();
    }
    let lo = Vec3::from(a.min).min(Vec3::from(b.min));
    let hi = Vec3::from(a.max).max(Vec3::from(b.max));
    half_area(hi - lo)
}

/// A mesh's BVH over its triangles, with its SAH cost at build time for the refit quality guard, and for a
/// deforming mesh the wide tree collapsed from it that the kernels traverse ([`RefitWideBvh`]).
#[derive(Clone, Debug)]
pub struct MeshBvh {
    pub flat: FlatBvh,
    pub build_sah: f32,
    pub wide: Option<RefitWideBvh>,
}

impl MeshBvh {
    pub fn build(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        quality: BvhQuality,
    ) -> Result<Self, BvhTooDeep> {
        let tris = obvhs_triangles(positions, triangles);
        let mut core = std::time::Duration::ZERO;
        let bvh = obvhs::bvh2::builder::build_bvh2_from_tris(&tris, quality.params(), &mut core);
        let flat = FlatBvh::from_obvhs(&bvh).or_else(|_| {
            let boxes: Vec<Aabb> = tris.iter().map(obvhs::Boundable::aabb).collect();
            FlatBvh::from_obvhs(&balanced::median_split(&boxes))
        })?;
        let build_sah = flat.sah_cost();
        Ok(Self {
            flat,
            build_sah,
            wide: None,
        })
    }

    /// [`Self::build`], and with `wide` the wide tree collapsed from it (where it fits the traversal's stack),
    /// which renumbers the BVH2's triangle order to the wide leaves'.
    pub fn build_refittable(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        quality: BvhQuality,
        wide: bool,
    ) -> Result<Self, BvhTooDeep> {
        let mut bvh = Self::build(positions, triangles, quality)?;
        if wide {
            let order = bvh.flat.order.clone();
            bvh.wide = RefitWideBvh::collapse(&mut bvh.flat, |i| {
                triangle_box(
                    triangles[order[i] as usize].map(|v| finite_point(positions[v as usize])),
                )
            });
        }
        Ok(bvh)
    }

    /// Refits to moved vertices; `gpu_triangles` are the mesh's triangles in [`FlatBvh::order`]. Returns the
    /// new [`Self::sah_ratio`].
    pub fn refit(&mut self, positions: &[Vec3], gpu_triangles: &[[u32; 3]]) -> f32 {
        let bounds = |i: usize| triangle_box(gpu_triangles[i].map(|v| positions[v as usize]));
        let cost = self.flat.refit(bounds);
        if let Some(wide) = &mut self.wide {
            wide.refit(&self.flat, bounds);
        }
        cost / self.build_sah.max(f32::MIN_POSITIVE)
    }

    /// `triangles` (a mesh's, in file order) rearranged into this BVH's leaf order.
    pub fn ordered_triangles(&self, triangles: &[[u32; 3]]) -> Vec<[u32; 3]> {
        ordered_triangles(&self.flat.order, triangles)
    }

    /// Current SAH cost over the cost at build: 1 after a build, rising as a refit degrades the tree.
    pub fn sah_ratio(&self) -> f32 {
        self.flat.sah_cost() / self.build_sah.max(f32::MIN_POSITIVE)
    }
}

/// How static meshes' BVHs are laid out on the GPU. Deformable meshes always get a refittable BVH2.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum StaticLayout {
    /// Compressed 8-wide nodes ([`WideBvh`]): fewer, smaller node fetches per ray.
    #[default]
    Wide,
    /// The child-pair BVH2 deformable meshes use ([`MeshBvh`]).
    Binary,
}

/// One mesh's bottom-level BVH, in the layout it is traced in.
#[derive(Clone, Debug)]
pub enum Blas {
    /// Child-pair BVH2: refit in place when the mesh deforms.
    Binary(MeshBvh),
    /// Compressed wide BVH of a static mesh.
    Wide(WideBvh),
}

impl Blas {
    /// Builds a static mesh's tree in `layout`, or a refittable one when the mesh deforms: its BVH2, with the
    /// wide tree collapsed from it where `layout` is wide and `wide_deformable` holds.
    pub fn build(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        quality: BvhQuality,
        layout: StaticLayout,
        deformable: bool,
        wide_deformable: bool,
    ) -> Result<Self, BvhTooDeep> {
        let wide = layout == StaticLayout::Wide;
        if deformable {
            return Ok(Self::Binary(MeshBvh::build_refittable(
                positions,
                triangles,
                quality,
                wide && wide_deformable,
            )?));
        }
        // Where the wide build fails, traversal gives the same image through the BVH2, which is never too deep.
        if wide && let Ok(tree) = WideBvh::build(positions, triangles, quality) {
            return Ok(Self::Wide(tree));
        }
        Ok(Self::Binary(MeshBvh::build(positions, triangles, quality)?))
    }

    /// Slot `i` of the mesh's GPU triangle range holds original triangle `order()[i]`.
    pub fn order(&self) -> &[u32] {
        match self {
            Self::Binary(b) => &b.flat.order,
            Self::Wide(w) => &w.order,
        }
    }

    /// Object-space box of the mesh as the tree currently bounds it.
    pub fn root_bounds(&self) -> (Vec3, Vec3) {
        match self {
            Self::Binary(b) => b.flat.root_bounds(),
            Self::Wide(w) => w.bounds,
        }
    }

    /// The refittable tree, for meshes that have one.
    pub fn binary(&self) -> Option<&MeshBvh> {
        match self {
            Self::Binary(b) => Some(b),
            Self::Wide(_) => None,
        }
    }

    pub fn binary_mut(&mut self) -> Option<&mut MeshBvh> {
        match self {
            Self::Binary(b) => Some(b),
            Self::Wide(_) => None,
        }
    }
}

struct InstanceBox(Aabb);
impl obvhs::Boundable for InstanceBox {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

/// Instance world-space boxes as obvhs primitives (clamped finite: its builders panic on infinite boxes), and
/// the top levels' build settings: obvhs's fast preset (they are rebuilt every frame anything moves, on the
/// render thread), one instance per leaf.
fn instance_boxes(boxes: &[(Vec3, Vec3)]) -> (Vec<InstanceBox>, BvhBuildParams) {
    let prims = boxes
        .iter()
        .map(|(lo, hi)| InstanceBox(Aabb::new(finite(*lo), finite(*hi))))
        .collect();
    let mut params = BvhBuildParams::fast_build();
    params.max_prims_per_leaf = 1;
    (prims, params)
}

/// Builds the top-level BVH over instance world-space boxes; leaves hold one instance each. At most
/// [`MAX_TLAS_DEPTH`] levels for up to 2^31 instances: where obvhs's tree is deeper (degenerate placements),
/// a balanced one replaces it.
pub fn build_tlas(boxes: &[(Vec3, Vec3)]) -> Result<FlatBvh, BvhTooDeep> {
    if boxes.is_empty() {
        return FlatBvh::from_obvhs(&Bvh2::default());
    }
    let (prims, params) = instance_boxes(boxes);
    let mut core = std::time::Duration::ZERO;
    let bvh = obvhs::bvh2::builder::build_bvh2(&prims, params, &mut core);
    match FlatBvh::from_obvhs(&bvh) {
        Ok(flat) if flat.depth <= MAX_TLAS_DEPTH => Ok(flat),
        _ => {
            let boxes: Vec<Aabb> = prims.iter().map(|p| p.0).collect();
            FlatBvh::from_obvhs(&balanced::median_split(&boxes))
        }
    }
}

/// `triangles` (a mesh's, in file order) rearranged into a BVH's leaf `order` (BVH2 or wide).
pub fn ordered_triangles(order: &[u32], triangles: &[[u32; 3]]) -> Vec<[u32; 3]> {
    order.iter().map(|&t| triangles[t as usize]).collect()
}

/// The mesh's triangles as obvhs builds take them.
pub(crate) fn obvhs_triangles(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Triangle> {
    triangles
        .iter()
        .map(|t| Triangle {
            v0: finite(positions[t[0] as usize]),
            v1: finite(positions[t[1] as usize]),
            v2: finite(positions[t[2] as usize]),
        })
        .collect()
}

/// Build coordinates are clamped to this magnitude. obvhs's PLOC builder merges neighbours whose union
/// has the smallest half area; once those areas overflow to infinity (coordinates above about 5e18) they
/// no longer compare, a pass merges almost nothing and the build turns quadratic, as a fuzzed file with
/// garbage positions (a misaligned accessor) showed. At 1e16 the largest half area, 1.2e33, stays far
/// from f32::MAX.
const BUILD_COORDINATE_LIMIT: f32 = 1e16;

/// A point obvhs can build over. Its PLOC builder asserts (debug) or merges a node with itself (release)
/// on infinite or NaN boxes, which an overflowing transform or deformation can produce, and never ends when
/// areas overflow (above). Geometry beyond the limit cannot be rendered usefully in f32 anyway, and the box
/// of the clamped vertices is the real box cut to the limit cube, so every hit inside the cube is still
/// found (traversal tests the real coordinates).
fn finite_point(p: Vec3) -> Vec3 {
    Vec3::from(finite(p))
}

fn finite(p: Vec3) -> Vec3A {
    let clamp = |v: f32| {
        if v.is_nan() {
            0.0
        } else {
            v.clamp(-BUILD_COORDINATE_LIMIT, BUILD_COORDINATE_LIMIT)
        }
    };
    Vec3A::new(clamp(p.x), clamp(p.y), clamp(p.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// obvhs's PLOC chains identical boxes (100 of them gave 99 levels): the top level falls back to a
    /// balanced tree and keeps every instance.
    #[test]
    fn coincident_instances_keep_a_shallow_top_level() {
        let boxes = vec![(Vec3::ZERO, Vec3::ONE); 500];
        let tlas = build_tlas(&boxes).unwrap();
        assert!(tlas.depth <= 10, "{}", tlas.depth);
        // Nested boxes (one level per box from PLOC) and a geometric series stay within the WGSL stack.
        for grow in [1.3f32, 1.5] {
            let nested: Vec<(Vec3, Vec3)> = (0..120)
                .map(|k| (Vec3::splat(-grow.powi(k)), Vec3::splat(grow.powi(k))))
                .collect();
            assert!(build_tlas(&nested).unwrap().depth <= MAX_TLAS_DEPTH);
            let series: Vec<(Vec3, Vec3)> = (0..120)
                .map(|k| (Vec3::X * grow.powi(k), Vec3::X * grow.powi(k) + Vec3::ONE))
                .collect();
            assert!(build_tlas(&series).unwrap().depth <= MAX_TLAS_DEPTH);
        }
        let mut order = tlas.order.clone();
        order.sort();
        assert_eq!(order, (0..500).collect::<Vec<u32>>());
        let positions: Vec<Vec3> = (0..300)
            .flat_map(|_| [Vec3::ZERO, Vec3::X, Vec3::Y])
            .collect();
        let triangles: Vec<[u32; 3]> = (0..300).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        let bvh = MeshBvh::build(&positions, &triangles, BvhQuality::Fast).unwrap();
        assert!(bvh.flat.depth <= MAX_TRAVERSAL_DEPTH);
    }

    /// obvhs's PLOC builder panics on infinite boxes (e.g. an instance placed at 2^129 by an overflowing
    /// transform); the builds clamp them instead.
    #[test]
    fn non_finite_boxes_and_vertices_build() {
        let boxes: Vec<(Vec3, Vec3)> = (0..50)
            .map(|k| {
                let x = if k % 7 == 0 { f32::INFINITY } else { k as f32 };
                (
                    Vec3::new(x - 1.0, f32::NAN, 0.0),
                    Vec3::new(x + 1.0, 1.0, 0.0),
                )
            })
            .collect();
        assert!(build_tlas(&boxes).is_ok());
        let positions = [
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(f32::INFINITY, 0.0, 0.0),
            Vec3::new(0.0, f32::NAN, 1.0),
        ];
        assert!(MeshBvh::build(&positions, &[[0, 1, 2], [0, 1, 3]], BvhQuality::Fast).is_ok());
    }

    /// Triangles with coordinates near f32::MAX (garbage read through a misaligned accessor) made every
    /// PLOC merge cost overflow to infinity: the builder then merged a pair or so per pass, a quadratic
    /// build (seconds per mesh, minutes for the fuzzed file's 98 meshes) into a tree whose SAH cost is
    /// infinite. With the clamp, costs stay comparable.
    #[test]
    fn overflowing_areas_keep_the_build_cost_finite() {
        // Magnitudes spread log-uniformly over f32's range, as reinterpreted mesh data comes out.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut coordinate = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let exponent = (state % 76) as i32 - 37;
            let sign = if state & (1 << 40) == 0 { 1.0 } else { -1.0 };
            sign * 3.4f32 * 10f32.powi(exponent)
        };
        let positions: Vec<Vec3> = (0..5400)
            .map(|_| Vec3::new(coordinate(), coordinate(), coordinate()))
            .collect();
        let triangles: Vec<[u32; 3]> = (0..1800).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        let bvh = MeshBvh::build(&positions, &triangles, BvhQuality::Fast).unwrap();
        assert!(bvh.build_sah.is_finite(), "SAH cost {}", bvh.build_sah);
        assert!(bvh.flat.depth <= MAX_TRAVERSAL_DEPTH);
    }
}

//! Compressed 8-wide BVHs (Ylitie, Karras and Laine 2017, "Efficient Incoherent Ray Traversal on GPUs Through
//! Compressed Wide BVHs") for static meshes: 80-byte nodes whose eight child boxes are quantised to 8 bits per
//! plane against the node's own box. A ray visits about a third as many nodes as in a BVH2 and fetches less
//! memory per child, which is what incoherent bounce rays are bound by. Such a tree cannot be refit in place
//! (the quantisation grid would move), so deformable meshes keep the child-pair BVH2 of [`super::MeshBvh`].
//!
//! obvhs builds the tree (PLOC + reinsertion, then the paper's SAH-optimal BVH2-to-BVH8 conversion); its node
//! layout is uploaded as is and traversed by `trace_blas_wide` in `shaders/traversal/cwbvh.wgsl`.

use super::{BvhQuality, BvhTooDeep};
use glam::Vec3;
use obvhs::cwbvh::{CwBvh, node::CwBvhNode};

/// Deepest wide tree the GPU's node-group stack holds (one entry per level: `WIDE_STACK_SIZE` in the WGSL constants).
pub const MAX_WIDE_DEPTH: u32 = 32;

/// A static mesh's compressed wide BVH and the triangle order its leaves expect.
#[derive(Clone, Debug)]
pub struct WideBvh {
    pub nodes: Vec<CwBvhNode>,
    /// Slot `i` of the mesh's GPU triangle range holds original triangle `order[i]`.
    pub order: Vec<u32>,
    /// Box of the whole mesh (object space).
    pub bounds: (Vec3, Vec3),
    pub depth: u32,
}

impl WideBvh {
    pub fn build(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        quality: BvhQuality,
    ) -> Result<Self, WideBvhError> {
        Self::build_with(positions, triangles, quality.params())
    }

    /// As [`Self::build`] with the preset's spatial splits (obvhs's pre-splits: large triangles first cut into
    /// several boxes, in the slower presets), so one triangle may sit in several leaves and `order` repeats it.
    /// Only for trees that are never refit and whose slots map back to their triangles (the static merge's
    /// origin pairs).
    pub fn build_static(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        quality: BvhQuality,
    ) -> Result<Self, WideBvhError> {
        Self::build_with(positions, triangles, quality.static_params())
    }

    fn build_with(
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        mut params: obvhs::BvhBuildParams,
    ) -> Result<Self, WideBvhError> {
        if triangles.is_empty() {
            // A node without children: every ray misses it.
            return Ok(Self {
                nodes: vec![CwBvhNode::default()],
                order: Vec::new(),
                bounds: (Vec3::ZERO, Vec3::ZERO),
                depth: 1,
            });
        }
        let tris = super::obvhs_triangles(positions, triangles);
        if !sah_costs_stay_finite(&tris) {
            return Err(WideBvhError::TooLarge);
        }
        // A wide leaf holds at most 3 triangles (the unary count in a child's meta byte).
        params.max_prims_per_leaf = 3;
        let mut core = std::time::Duration::ZERO;
        let cw: CwBvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(&tris, params, &mut core);
        let depth = tree_depth(&cw.nodes);
        if depth > MAX_WIDE_DEPTH {
            return Err(WideBvhError::TooDeep(BvhTooDeep { depth }));
        }
        let bounds = (Vec3::from(cw.total_aabb.min), Vec3::from(cw.total_aabb.max));
        Ok(Self {
            nodes: cw.nodes,
            order: cw.primitive_indices,
            bounds,
            depth,
        })
    }
}

/// Why a mesh has no wide BVH; [`super::Blas::build`] then gives it the BVH2 (the same image).
#[derive(Debug, thiserror::Error)]
pub enum WideBvhError {
    #[error(transparent)]
    TooDeep(#[from] BvhTooDeep),
    /// The mesh is so large and so finely cut that the conversion's SAH costs would overflow f32.
    #[error("the mesh is too large for the wide BVH's cost arithmetic")]
    TooLarge,
}

/// Whether obvhs's BVH2-to-CWBVH conversion can compare its SAH costs. They are sums of node half-areas
/// (at most one per node, each at most the root's, 2n - 1 nodes for n triangles) in f32; once they overflow
/// to infinity every candidate costs the same, no split is chosen, and obvhs 0.4 indexes its decision table
/// with an unset (255) child slot: an out-of-bounds panic in `get_children` (or a wrong tree where the index
/// happens to fit). Computed in f64 with a factor 2 margin for f32 rounding.
fn sah_costs_stay_finite(tris: &[obvhs::triangle::Triangle]) -> bool {
    let (mut lo, mut hi) = (glam::DVec3::splat(f64::MAX), glam::DVec3::splat(f64::MIN));
    for t in tris {
        for v in [t.v0, t.v1, t.v2] {
            let v = glam::DVec3::new(v.x as f64, v.y as f64, v.z as f64);
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    let d = (hi - lo).max(glam::DVec3::ZERO);
    let half_area = d.x * d.y + d.y * d.z + d.z * d.x;
    let nodes = 2.0 * tris.len() as f64;
    (half_area * nodes * 2.0).is_finite() && half_area * nodes * 2.0 < f32::MAX as f64
}

/// Levels of inner nodes on the longest root-to-leaf path.
pub(super) fn tree_depth(nodes: &[CwBvhNode]) -> u32 {
    let mut deepest = 0;
    let mut stack = vec![(0u32, 1u32)];
    while let Some((index, depth)) = stack.pop() {
        deepest = deepest.max(depth);
        let node = &nodes[index as usize];
        for child in 0..8 {
            if node.imask & (1 << child) != 0 {
                stack.push((node.child_node_index(child), depth + 1));
            }
        }
    }
    deepest
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid of small triangles: every triangle sits in exactly one leaf, and every child box (dequantised)
    /// contains its triangles, which is what the GPU traversal relies on.
    #[test]
    fn leaves_cover_every_triangle_once_and_boxes_contain_them() {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for i in 0..40u32 {
            for j in 0..25u32 {
                let base = positions.len() as u32;
                let p = Vec3::new(i as f32, (i * j % 7) as f32 * 0.3, j as f32);
                positions.extend([p, p + Vec3::X * 0.9, p + Vec3::Z * 0.9]);
                triangles.push([base, base + 1, base + 2]);
            }
        }
        let bvh = WideBvh::build(&positions, &triangles, BvhQuality::Medium).unwrap();
        let mut seen = vec![0u32; triangles.len()];
        for_each_leaf_slot(&bvh, |slot, lo, hi| {
            let t = bvh.order[slot as usize] as usize;
            seen[t] += 1;
            for v in triangles[t] {
                let p = positions[v as usize];
                let eps = 1e-4 * (1.0 + p.abs().max_element());
                assert!(
                    p.cmpge(lo - eps).all() && p.cmple(hi + eps).all(),
                    "vertex {p} outside its leaf box {lo}..{hi}"
                );
            }
        });
        assert!(seen.iter().all(|&n| n == 1), "each triangle in one leaf");
        assert!(bvh.depth >= 2 && bvh.depth <= MAX_WIDE_DEPTH);
    }

    /// Calls `visit` with each leaf slot of the tree and its leaf's (dequantised) box.
    fn for_each_leaf_slot(bvh: &WideBvh, mut visit: impl FnMut(u32, Vec3, Vec3)) {
        let mut stack = vec![0u32];
        while let Some(index) = stack.pop() {
            let node = &bvh.nodes[index as usize];
            for child in 0..8 {
                if node.is_child_empty(child) {
                    continue;
                }
                if node.imask & (1 << child) != 0 {
                    stack.push(node.child_node_index(child));
                    continue;
                }
                let aabb = node.child_aabb(child);
                let (first, count) = node.child_primitives(child);
                for slot in first..first + count {
                    visit(slot, Vec3::from(aabb.min), Vec3::from(aabb.max));
                }
            }
        }
    }

    /// The static build's spatial splits: long triangles across a grid of small ones sit in several leaves
    /// (`order` repeats them), every triangle in at least one, every slot reached from the root once, and each
    /// leaf box overlaps its triangle's box (a split box is a part of it).
    #[test]
    fn static_trees_split_long_triangles_across_leaves() {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for i in 0..32u32 {
            for j in 0..32u32 {
                let base = positions.len() as u32;
                let p = Vec3::new(i as f32, 0.0, j as f32);
                positions.extend([p, p + Vec3::X * 0.9, p + Vec3::Z * 0.9]);
                triangles.push([base, base + 1, base + 2]);
            }
        }
        for k in 0..4u32 {
            let base = positions.len() as u32;
            let y = 0.5 + k as f32;
            positions.extend([
                Vec3::new(0.0, y, 0.0),
                Vec3::new(32.0, y, 31.0),
                Vec3::new(31.0, y + 0.2, 32.0),
            ]);
            triangles.push([base, base + 1, base + 2]);
        }
        let bvh = WideBvh::build_static(&positions, &triangles, BvhQuality::VerySlow).unwrap();
        assert!(bvh.order.len() > triangles.len(), "nothing was split");
        let mut seen = vec![0u32; triangles.len()];
        let mut slots = vec![0u32; bvh.order.len()];
        for_each_leaf_slot(&bvh, |slot, lo, hi| {
            slots[slot as usize] += 1;
            let t = bvh.order[slot as usize] as usize;
            seen[t] += 1;
            let ps = triangles[t].map(|v| positions[v as usize]);
            let (tlo, thi) = (ps[0].min(ps[1]).min(ps[2]), ps[0].max(ps[1]).max(ps[2]));
            assert!(
                lo.cmple(thi + 1e-3).all() && hi.cmpge(tlo - 1e-3).all(),
                "leaf box misses its triangle"
            );
        });
        assert!(slots.iter().all(|&n| n == 1), "each slot in one leaf");
        assert!(seen.iter().all(|&n| n >= 1), "every triangle in a leaf");
        assert!(
            seen[triangles.len() - 4..].iter().any(|&n| n > 1),
            "the long triangles were not split"
        );
        // The refittable build of the same mesh never repeats a triangle.
        let plain = WideBvh::build(&positions, &triangles, BvhQuality::VerySlow).unwrap();
        assert_eq!(plain.order.len(), triangles.len());
    }

    /// obvhs 0.4 panics converting a BVH over geometry whose SAH costs overflow f32. Build coordinates are
    /// clamped to 1e16 (a quad 2e19 wide now builds, cut to the clamp cube), so the overflow needs a wide
    /// mesh with many triangles: such a mesh gets no wide tree, and `Blas::build` falls back to the BVH2
    /// (not built here: 300k coincident triangles make a slow PLOC build).
    #[test]
    fn meshes_whose_costs_overflow_are_refused_not_a_panic() {
        let positions = [
            Vec3::new(-1e19, -1e19, 0.0),
            Vec3::new(1e19, -1e19, 0.0),
            Vec3::new(1e19, 1e19, 0.0),
            Vec3::new(-1e19, 1e19, 0.0),
        ];
        let triangles = [[0, 1, 2], [0, 2, 3]];
        assert!(WideBvh::build(&positions, &triangles, BvhQuality::Medium).is_ok());
        // Half area 4e32 (the clamped quad) times 4 per triangle passes f32::MAX above 2.1e5 triangles.
        let many: Vec<[u32; 3]> = triangles.iter().copied().cycle().take(300_000).collect();
        let tris = super::super::obvhs_triangles(&positions, &many);
        assert!(!sah_costs_stay_finite(&tris));
        assert!(sah_costs_stay_finite(&tris[..100_000]));
        // Large but representable scenes keep the wide tree.
        let small: Vec<Vec3> = positions.iter().map(|p| *p * 1e-5).collect();
        assert!(WideBvh::build(&small, &triangles, BvhQuality::Medium).is_ok());
    }

    #[test]
    fn empty_mesh_gives_a_node_without_children() {
        let bvh = WideBvh::build(&[], &[], BvhQuality::Fast).unwrap();
        assert_eq!(bvh.nodes.len(), 1);
        assert!((0..8).all(|c| bvh.nodes[0].is_child_empty(c)));
    }
}

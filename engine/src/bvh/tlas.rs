//! The top level as a compressed 8-wide tree (the layout of [`super::WideBvh`]) for the wavefront's traversal,
//! beside the BVH2 every kernel reads: the waves' extend kernel is bound by dependent node fetches, and a bounce
//! ray visits 2-2.5 wide top-level nodes where it visited 4.6-6.7 child-pair nodes (docs/BENCHMARKS.md, "The top
//! level as a wide tree"), while the megakernel, which shades between traversals, is faster with the BVH2.

use super::wide::tree_depth;
use super::{BvhTooDeep, balanced, instance_boxes};
use glam::Vec3;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::{CwBvh, node::CwBvhNode};

/// Deepest wide top-level tree [`build_wide_tlas`] returns: the node-group stack of
/// `shaders/traversal/tlas.wgsl` `trace_wide_top_level` holds one entry per level (`WIDE_TLAS_STACK_SIZE`).
/// Balanced, 32 levels of 8-wide nodes hold far more than 2^32 instances.
pub const MAX_WIDE_TLAS_DEPTH: u32 = 32;

/// The wide top-level tree and the instance box each leaf slot holds.
#[derive(Clone, Debug)]
pub struct WideTlas {
    pub nodes: Vec<CwBvhNode>,
    /// Leaf slot `primitive_base_idx + k` of a node holds instance box `order[primitive_base_idx + k]`.
    pub order: Vec<u32>,
    pub depth: u32,
}

/// Builds the wide top-level tree over instance world-space boxes, one instance per leaf slot, with the BVH2's
/// settings (it is rebuilt with the BVH2 whenever a placement or a deformed mesh's box changes). Where obvhs's tree
/// is deeper than [`MAX_WIDE_TLAS_DEPTH`] (degenerate placements: coincident, nested or geometrically spaced
/// boxes chain its PLOC builder), a balanced tree is converted instead.
pub fn build_wide_tlas(boxes: &[(Vec3, Vec3)]) -> Result<WideTlas, BvhTooDeep> {
    if boxes.is_empty() {
        // A node without children: every ray misses it.
        return Ok(WideTlas {
            nodes: vec![CwBvhNode::default()],
            order: Vec::new(),
            depth: 1,
        });
    }
    let (prims, params) = instance_boxes(boxes);
    let mut core = std::time::Duration::ZERO;
    let tlas = from_cwbvh(obvhs::cwbvh::builder::build_cwbvh(
        &prims, params, &mut core,
    ));
    if tlas.depth <= MAX_WIDE_TLAS_DEPTH {
        return Ok(tlas);
    }
    let boxes: Vec<Aabb> = prims.iter().map(|p| p.0).collect();
    let balanced = balanced::median_split(&boxes);
    let tlas = from_cwbvh(obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh(
        &balanced, 1, true, false,
    ));
    if tlas.depth > MAX_WIDE_TLAS_DEPTH {
        return Err(BvhTooDeep { depth: tlas.depth });
    }
    Ok(tlas)
}

fn from_cwbvh(cw: CwBvh) -> WideTlas {
    WideTlas {
        depth: tree_depth(&cw.nodes),
        nodes: cw.nodes,
        order: cw.primitive_indices,
    }
}

impl WideTlas {
    /// The tree as the kernels read it, in 16-byte words from word `base` of the top level's buffer: the
    /// nodes (5 words each), then one 32-bit word per leaf slot, `instance_of(order[slot])`, which each node's
    /// `primitive_base_idx` indexes from the buffer's start (in 32-bit words).
    pub fn packed(&self, base: u32, instance_of: impl Fn(u32) -> u32) -> Vec<[u32; 4]> {
        let node_words = 5 * self.nodes.len() as u32;
        let slots_from = 4 * (base + node_words);
        let mut words: Vec<[u32; 4]> =
            Vec::with_capacity(self.nodes.len() * 5 + self.order.len() / 4 + 1);
        for node in &self.nodes {
            let mut node = *node;
            node.primitive_base_idx += slots_from;
            let bytes: [u32; 20] = bytemuck::cast(node);
            words.extend(bytes.chunks_exact(4).map(|w| [w[0], w[1], w[2], w[3]]));
        }
        let slots: Vec<u32> = self.order.iter().map(|&i| instance_of(i)).collect();
        words.extend(slots.chunks(4).map(|w| {
            let mut word = [0; 4];
            word[..w.len()].copy_from_slice(w);
            word
        }));
        words
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Instance `i`'s leaf slots, found by walking the tree: every instance sits in exactly one slot, and
    /// every node's dequantised child box holds the boxes below it.
    fn check(tlas: &WideTlas, boxes: &[(Vec3, Vec3)]) {
        let mut seen = vec![0u32; boxes.len()];
        let mut stack = vec![0usize];
        while let Some(index) = stack.pop() {
            let node = &tlas.nodes[index];
            for slot in 0..8 {
                let meta = node.child_meta[slot];
                if meta == 0 {
                    continue;
                }
                let scale = |axis: usize| f32::from_bits((node.e[axis] as u32) << 23);
                let origin = node.p;
                let q = |v: [u8; 8]| v[slot] as f32;
                let lo = origin
                    + Vec3::new(
                        q(node.child_min_x) * scale(0),
                        q(node.child_min_y) * scale(1),
                        q(node.child_min_z) * scale(2),
                    );
                let hi = origin
                    + Vec3::new(
                        q(node.child_max_x) * scale(0),
                        q(node.child_max_y) * scale(1),
                        q(node.child_max_z) * scale(2),
                    );
                if node.imask & (1 << slot) != 0 {
                    stack.push(node.child_node_index(slot) as usize);
                    continue;
                }
                let count = (meta >> 5).count_ones();
                assert_eq!(count, 1, "one instance per leaf slot");
                let first = node.primitive_base_idx + (meta & 0x1f) as u32;
                let instance = tlas.order[first as usize] as usize;
                seen[instance] += 1;
                let (blo, bhi) = boxes[instance];
                let tol = (bhi - blo).abs().max_element() * 1e-3 + 1e-4;
                assert!(
                    lo.cmple(blo + tol).all() && hi.cmpge(bhi - tol).all(),
                    "instance {instance}: {blo}..{bhi} outside its slot {lo}..{hi}"
                );
            }
        }
        assert!(seen.iter().all(|&n| n == 1), "{seen:?}");
    }

    #[test]
    fn every_instance_sits_in_one_slot_inside_its_box() {
        let boxes: Vec<(Vec3, Vec3)> = (0..97)
            .map(|k| {
                let p = Vec3::new((k % 10) as f32 * 3.0, (k / 10) as f32 * 2.0, (k % 7) as f32);
                (p, p + Vec3::new(1.0, 2.0, 0.5))
            })
            .collect();
        let tlas = build_wide_tlas(&boxes).unwrap();
        assert!(tlas.depth <= 4, "{}", tlas.depth);
        check(&tlas, &boxes);
        for n in [1, 2, 9] {
            let tlas = build_wide_tlas(&boxes[..n]).unwrap();
            check(&tlas, &boxes[..n]);
        }
        let empty = build_wide_tlas(&[]).unwrap();
        assert_eq!((empty.nodes.len(), empty.order.len()), (1, 0));
    }

    /// The packed words: each node's five words as obvhs lays it out, its leaf slots' first word moved past the
    /// nodes (counted from the buffer's start), and there each slot's instance.
    #[test]
    fn packed_slots_name_each_slots_instance() {
        let boxes: Vec<(Vec3, Vec3)> = (0..21)
            .map(|k| {
                (
                    Vec3::X * k as f32 * 2.0,
                    Vec3::X * k as f32 * 2.0 + Vec3::ONE,
                )
            })
            .collect();
        let tlas = build_wide_tlas(&boxes).unwrap();
        let base = 12;
        let words = tlas.packed(base, |i| 1000 + i);
        let flat: Vec<u32> = words.iter().flatten().copied().collect();
        let word = |i: u32| flat[(i - 4 * base) as usize];
        let mut found = Vec::new();
        for (n, node) in tlas.nodes.iter().enumerate() {
            let packed_base = word(4 * base + 20 * n as u32 + 5);
            assert_eq!(
                packed_base,
                node.primitive_base_idx + 4 * (base + 5 * tlas.nodes.len() as u32)
            );
            for slot in 0..8 {
                let meta = node.child_meta[slot];
                if meta != 0 && node.imask & (1 << slot) == 0 {
                    let first = node.primitive_base_idx + (meta & 0x1f) as u32;
                    assert_eq!(
                        word(packed_base + (meta & 0x1f) as u32),
                        1000 + tlas.order[first as usize]
                    );
                    found.push(tlas.order[first as usize]);
                }
            }
        }
        found.sort();
        assert_eq!(found, (0..21).collect::<Vec<u32>>());
    }

    /// obvhs's PLOC chains identical boxes (100 of them gave 99 levels), nested boxes and a geometric
    /// series: the top level falls back to a balanced tree within the WGSL stack and keeps every instance.
    #[test]
    fn degenerate_placements_keep_a_shallow_wide_top_level() {
        let coincident = vec![(Vec3::ZERO, Vec3::ONE); 500];
        let tlas = build_wide_tlas(&coincident).unwrap();
        assert!(tlas.depth <= 8, "{}", tlas.depth);
        check(&tlas, &coincident);
        for grow in [1.3f32, 1.5] {
            let nested: Vec<(Vec3, Vec3)> = (0..120)
                .map(|k| (Vec3::splat(-grow.powi(k)), Vec3::splat(grow.powi(k))))
                .collect();
            let tlas = build_wide_tlas(&nested).unwrap();
            assert!(tlas.depth <= MAX_WIDE_TLAS_DEPTH);
            let series: Vec<(Vec3, Vec3)> = (0..120)
                .map(|k| (Vec3::X * grow.powi(k), Vec3::X * grow.powi(k) + Vec3::ONE))
                .collect();
            let tlas = build_wide_tlas(&series).unwrap();
            assert!(tlas.depth <= MAX_WIDE_TLAS_DEPTH);
            assert_eq!(tlas.order.len(), 120);
        }
    }
}

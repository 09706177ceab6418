//! Compressed 8-wide trees for deforming meshes, refit every frame beside their BVH2.
//!
//! A wide node's child boxes are quantised against the node's own box, so moving a vertex moves the grid: the
//! tree cannot be refit in place the way a BVH2 is. It can be re-quantised, though, as long as each slot knows
//! where its box comes from. Here the wide tree is collapsed from the mesh's child-pair BVH2 ([`super::FlatBvh`]):
//! every wide node stands for one BVH2 node, every inner slot for an unopened BVH2 inner node, every leaf slot
//! for (part of) a BVH2 leaf. After the BVH2 is refit, a wide node's boxes are the union of its inner slots' BVH2
//! nodes' children and of its leaf slots' triangles: every wide node is independent of the others, so the GPU
//! refits them all in one flat pass (`refit_wide` in `render/passes/refit/refit.wgsl`, which [`RefitWideBvh::refit`]
//! mirrors operation for operation).
//!
//! Both trees read one triangle order: the collapse renumbers the BVH2's leaves so that each wide node's leaf
//! triangles are contiguous (at most 24 from its `primitive_base_idx`), which keeps every BVH2 leaf contiguous too.

use super::wide::{MAX_WIDE_DEPTH, tree_depth};
use super::{FlatBvh, GpuBvhChild, half_area, union_boxes};
use glam::Vec3;
use obvhs::cwbvh::node::CwBvhNode;

/// The most triangles a wide leaf slot holds (the unary count in its meta byte).
const SLOT_TRIANGLES: u32 = 3;
/// Grid cells per node axis (8-bit planes).
const CELLS: f32 = 255.0;

/// A deforming mesh's wide tree: the nodes as the kernels read them, and the BVH2 node each one stands for.
#[derive(Clone, Debug, PartialEq)]
pub struct RefitWideBvh {
    pub nodes: Vec<CwBvhNode>,
    /// Wide node `i` was collapsed from BVH2 node `bvh2_node[i]` (relative to the BVH2's root): an inner slot's
    /// box is the union of that node's children.
    pub bvh2_node: Vec<u32>,
    pub depth: u32,
}

/// One child of a wide node being collapsed: an unopened BVH2 inner node, or a run of a BVH2 leaf's triangles.
#[derive(Clone, Copy)]
enum Item {
    Inner { node: u32, lo: Vec3, hi: Vec3 },
    Leaf { first: u32, count: u32 },
}

impl Item {
    fn from_child(c: &GpuBvhChild) -> Option<Self> {
        if c.is_empty() {
            None
        } else if c.is_leaf() {
            Some(Self::Leaf {
                first: c.index,
                count: c.count,
            })
        } else {
            Some(Self::Inner {
                node: c.index,
                lo: Vec3::from(c.min),
                hi: Vec3::from(c.max),
            })
        }
    }

    fn slots(&self) -> u32 {
        match self {
            Self::Inner { .. } => 1,
            Self::Leaf { count, .. } => count.div_ceil(SLOT_TRIANGLES),
        }
    }
}

impl RefitWideBvh {
    /// Collapses `flat` into a wide tree and renumbers `flat`'s triangle slots to the wide leaves' order
    /// (`flat.order` and its leaves' first slots change; its topology and boxes do not). Each wide node starts
    /// from its BVH2 node's two children and opens the largest inner one while the slots fit in eight. The
    /// quantised boxes come from `refit`; `slot_bounds(i)` bounds the triangle in BVH2 slot `i` (before the
    /// renumbering), for ordering the slots. `None` (and `flat` untouched) where the wide tree would be deeper
    /// than the traversal's stack.
    pub fn collapse(
        flat: &mut FlatBvh,
        slot_bounds: impl Fn(usize) -> (Vec3, Vec3),
    ) -> Option<Self> {
        let mut nodes = vec![CwBvhNode::default()];
        let mut bvh2_node = vec![0u32];
        // Old slot of each new slot, and the new first slot of each old one.
        let mut new_order: Vec<u32> = Vec::with_capacity(flat.order.len());
        let mut stack = vec![0usize];
        while let Some(w) = stack.pop() {
            let items = Self::open(flat, bvh2_node[w]);
            let item_bounds = |item: &Item| -> (Vec3, Vec3) {
                match *item {
                    Item::Inner { lo, hi, .. } => (lo, hi),
                    Item::Leaf { first, count } => {
                        union_boxes((first..first + count).map(|i| slot_bounds(i as usize)))
                    }
                }
            };
            // Leaf runs of more than three triangles take several slots, split evenly.
            let mut slots: Vec<Item> = Vec::with_capacity(8);
            for item in items {
                match item {
                    Item::Leaf { first, count } if count > SLOT_TRIANGLES => {
                        let parts = item.slots();
                        let mut start = first;
                        for p in 0..parts {
                            let n = (count - (start - first)).div_ceil(parts - p);
                            slots.push(Item::Leaf {
                                first: start,
                                count: n,
                            });
                            start += n;
                        }
                    }
                    _ => slots.push(item),
                }
            }
            let boxes: Vec<(Vec3, Vec3)> = slots.iter().map(item_bounds).collect();
            let assignment = order_slots(&boxes);
            let mut node = CwBvhNode {
                child_base_idx: nodes.len() as u32,
                primitive_base_idx: new_order.len() as u32,
                ..Default::default()
            };
            // Triangles in item order, so that the parts of one BVH2 leaf stay one contiguous run.
            let mut inner_children = Vec::new();
            let mut by_slot = [None; 8];
            for (k, item) in slots.iter().enumerate() {
                by_slot[assignment[k]] = Some(*item);
                if let Item::Leaf { first, count } = *item {
                    let offset = new_order.len() as u32 - node.primitive_base_idx;
                    node.child_meta[assignment[k]] = offset as u8 | unary_count(count);
                    new_order.extend(first..first + count);
                }
            }
            for (slot, item) in by_slot.iter().enumerate() {
                if let Some(Item::Inner { node: child, .. }) = item {
                    node.imask |= 1 << slot;
                    node.child_meta[slot] = (24 + slot as u8) | 0b0010_0000;
                    inner_children.push(*child);
                }
            }
            nodes[w] = node;
            let base = nodes.len();
            for &child in &inner_children {
                nodes.push(CwBvhNode::default());
                bvh2_node.push(child);
            }
            // Depth first, the first child on top.
            stack.extend((base..nodes.len()).rev());
        }
        let depth = tree_depth(&nodes);
        if depth > MAX_WIDE_DEPTH {
            return None;
        }
        // Renumber the BVH2's leaves: each run of old slots now starts where the wide leaves put it.
        let mut new_slot_of = vec![0u32; new_order.len()];
        for (new, &old) in new_order.iter().enumerate() {
            new_slot_of[old as usize] = new as u32;
        }
        for n in &mut flat.nodes {
            for c in &mut n.children {
                if c.is_leaf() {
                    c.index = new_slot_of[c.index as usize];
                }
            }
        }
        flat.order = new_order
            .iter()
            .map(|&old| flat.order[old as usize])
            .collect();
        let mut tree = Self {
            nodes,
            bvh2_node,
            depth,
        };
        tree.refit(flat, |i| slot_bounds(new_order[i] as usize));
        Some(tree)
    }

    /// The children of BVH2 node `node`, with the largest inner child opened while the slots fit in eight.
    fn open(flat: &FlatBvh, node: u32) -> Vec<Item> {
        let mut items: Vec<Item> = flat.nodes[node as usize]
            .children
            .iter()
            .filter_map(Item::from_child)
            .collect();
        loop {
            let used: u32 = items.iter().map(Item::slots).sum();
            let mut best: Option<(usize, f32, Vec<Item>)> = None;
            for (k, item) in items.iter().enumerate() {
                let Item::Inner { node, lo, hi } = *item else {
                    continue;
                };
                let children: Vec<Item> = flat.nodes[node as usize]
                    .children
                    .iter()
                    .filter_map(Item::from_child)
                    .collect();
                let needed: u32 = children.iter().map(Item::slots).sum();
                let area = half_area(hi - lo);
                if used - 1 + needed <= 8 && best.as_ref().is_none_or(|b| area > b.1) {
                    best = Some((k, area, children));
                }
            }
            let Some((k, _, children)) = best else {
                return items;
            };
            items.splice(k..=k, children);
        }
    }

    /// Re-quantises every node from `flat`'s (refit) boxes and the triangles: `slot_bounds(i)` bounds the
    /// triangle in slot `i` of the shared order. The same operations as `refit_wide` in `render/passes/refit/refit.wgsl`,
    /// so both give the same bits.
    pub fn refit(&mut self, flat: &FlatBvh, slot_bounds: impl Fn(usize) -> (Vec3, Vec3)) {
        for node in &mut self.nodes {
            let mut boxes = [None; 8];
            let mut inner = 0;
            for (slot, b) in boxes.iter_mut().enumerate() {
                let meta = node.child_meta[slot];
                if meta == 0 {
                    continue;
                }
                *b = Some(if node.imask & (1 << slot) != 0 {
                    let child = node.child_base_idx + inner;
                    inner += 1;
                    // An inner slot's BVH2 node is never the root, so it has both children.
                    flat.nodes[self.bvh2_node[child as usize] as usize].inner_box()
                } else {
                    let first = node.primitive_base_idx + (meta & 0x1f) as u32;
                    let count = (meta >> 5).count_ones();
                    union_boxes((first..first + count).map(|i| slot_bounds(i as usize)))
                });
            }
            quantise(node, &boxes);
        }
    }
}

/// The most wide nodes [`RefitWideBvh::collapse`] makes for `triangles` triangles, which a deforming mesh reserves
/// so that any rebuilt tree fits. Leaf slots hold at least a triangle each, so there are `L <= triangles` of them.
/// A node left with an inner slot could not open it, so it has at least 6 slots (opening replaces one slot by at
/// most 4: two BVH2 children of at most 4 triangles, 2 slots each); a node without one has at least 2 leaf slots
/// (the root may have 1). With `A` and `B` nodes of each kind and `A + B - 1` inner slots, counting slots gives
/// `L >= 5A + B` and `L >= 2B - 1`, so `A + B <= 0.6 L + 0.4`.
pub fn node_capacity(triangles: usize) -> usize {
    (3 * triangles).div_ceil(5) + 1
}

fn unary_count(count: u32) -> u8 {
    match count {
        1 => 0b0010_0000,
        2 => 0b0110_0000,
        _ => 0b1110_0000,
    }
}

/// Slot of each child, so that the traversal, which visits slot `s ^ octant` in descending order, meets near
/// children first: slot `s` holds a child far along the axes whose bit in `s` is set (x = 4, y = 2, z = 1).
/// Greedy: the cheapest (child, slot) pair first, cost the child centre's offset against the slot's direction.
fn order_slots(boxes: &[(Vec3, Vec3)]) -> [usize; 8] {
    let (lo, hi) = union_boxes(boxes.iter().copied());
    let centre = (lo + hi) * 0.5;
    let direction = |s: usize| {
        Vec3::new(
            if s & 4 != 0 { -1.0 } else { 1.0 },
            if s & 2 != 0 { -1.0 } else { 1.0 },
            if s & 1 != 0 { -1.0 } else { 1.0 },
        )
    };
    let mut assignment = [usize::MAX; 8];
    let mut taken = [false; 8];
    for _ in 0..boxes.len() {
        let mut best = (f32::MAX, usize::MAX, usize::MAX);
        for (c, (a, b)) in boxes.iter().enumerate() {
            if assignment[c] != usize::MAX {
                continue;
            }
            let offset = (*a + *b) * 0.5 - centre;
            for (s, &t) in taken.iter().enumerate() {
                let cost = direction(s).dot(offset);
                // Non-finite boxes (NaN centres) still get a slot.
                if !t && (cost < best.0 || best.1 == usize::MAX) {
                    best = (cost, c, s);
                }
            }
        }
        assignment[best.1] = best.2;
        taken[best.2] = true;
    }
    assignment
}

/// The node's grid from its children's boxes: origin at their union's minimum, per axis the smallest power of
/// two that spans the union in 255 cells, each child rounded outwards onto it. Integer exponent arithmetic (no
/// `log2`), so the GPU's copy gives the same bits.
fn quantise(node: &mut CwBvhNode, boxes: &[Option<(Vec3, Vec3)>; 8]) {
    let (lo, hi) = union_boxes(boxes.iter().flatten().copied());
    if lo.x > hi.x {
        return;
    }
    let extent = (hi - lo).max(Vec3::splat(1e-20));
    let mut e = [0u8; 3];
    let mut inverse = [0f32; 3];
    for axis in 0..3 {
        let exponent = cell_exponent(extent[axis]);
        e[axis] = exponent as u8;
        inverse[axis] = f32::from_bits((254 - exponent) << 23);
    }
    node.p = lo;
    node.e = e;
    let inverse = Vec3::from(inverse);
    for (slot, b) in boxes.iter().enumerate() {
        let Some((a, b)) = b else { continue };
        let qlo = ((*a - lo) * inverse)
            .floor()
            .clamp(Vec3::ZERO, Vec3::splat(CELLS));
        let qhi = ((*b - lo) * inverse)
            .ceil()
            .clamp(Vec3::ZERO, Vec3::splat(CELLS));
        node.child_min_x[slot] = qlo.x as u8;
        node.child_min_y[slot] = qlo.y as u8;
        node.child_min_z[slot] = qlo.z as u8;
        node.child_max_x[slot] = qhi.x as u8;
        node.child_max_y[slot] = qhi.y as u8;
        node.child_max_z[slot] = qhi.z as u8;
    }
}

/// Biased exponent of the smallest power of two `c` with `255 c >= extent` (extent > 0, finite or not), within
/// what both the cell size and its inverse can hold.
pub fn cell_exponent(extent: f32) -> u32 {
    let cell = extent * (1.0 / CELLS);
    let bits = cell.to_bits();
    let mut exponent = (bits >> 23) + u32::from(bits & 0x7f_ffff != 0);
    if f32::from_bits(exponent.min(254) << 23) * CELLS < extent {
        exponent += 1;
    }
    exponent.clamp(1, 253)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{BvhQuality, MeshBvh};

    /// A wavy sheet of small triangles with some long ones across it.
    fn sheet() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for i in 0..30u32 {
            for j in 0..20u32 {
                let base = positions.len() as u32;
                let p = Vec3::new(i as f32, ((i * j) % 5) as f32 * 0.2, j as f32);
                positions.extend([p, p + Vec3::X * 0.8, p + Vec3::Z * 0.8]);
                triangles.push([base, base + 1, base + 2]);
            }
        }
        for k in 0..8u32 {
            let base = positions.len() as u32;
            let p = Vec3::new(0.0, 2.0 + k as f32, k as f32 * 2.0);
            positions.extend([p, p + Vec3::X * 29.0, p + Vec3::new(0.0, 0.5, 0.5)]);
            triangles.push([base, base + 1, base + 2]);
        }
        (positions, triangles)
    }

    fn slot_bounds<'a>(
        positions: &'a [Vec3],
        triangles: &'a [[u32; 3]],
        order: &'a [u32],
    ) -> impl Fn(usize) -> (Vec3, Vec3) + 'a {
        move |i| {
            let [a, b, c] = triangles[order[i] as usize].map(|v| positions[v as usize]);
            (a.min(b).min(c), a.max(b).max(c))
        }
    }

    /// Walks the tree: every triangle slot in exactly one leaf slot, every vertex inside its dequantised
    /// leaf box and every leaf box inside its ancestors' slots.
    fn check(tree: &RefitWideBvh, positions: &[Vec3], triangles: &[[u32; 3]], order: &[u32]) {
        let mut seen = vec![0u32; order.len()];
        let mut stack = vec![(0u32, Vec3::splat(f32::MIN), Vec3::splat(f32::MAX))];
        while let Some((index, outer_lo, outer_hi)) = stack.pop() {
            let node = &tree.nodes[index as usize];
            for slot in 0..8 {
                if node.is_child_empty(slot) {
                    continue;
                }
                let aabb = node.child_aabb(slot);
                let (lo, hi) = (Vec3::from(aabb.min), Vec3::from(aabb.max));
                // Rounded outwards on the node's own grid: within one of its cells of the parent's slot.
                let cell = Vec3::from(node.e.map(|e| f32::from_bits((e as u32) << 23)));
                assert!(
                    lo.cmpge(outer_lo - cell).all() && hi.cmple(outer_hi + cell).all(),
                    "slot {lo}..{hi} outside its parent's {outer_lo}..{outer_hi}"
                );
                if node.imask & (1 << slot) != 0 {
                    stack.push((node.child_node_index(slot), lo, hi));
                    continue;
                }
                let (first, count) = node.child_primitives(slot);
                assert!((1..=3).contains(&count));
                for s in first..first + count {
                    seen[s as usize] += 1;
                    for v in triangles[order[s as usize] as usize] {
                        let p = positions[v as usize];
                        let eps = 1e-4 * (1.0 + p.abs().max_element());
                        assert!(
                            p.cmpge(lo - eps).all() && p.cmple(hi + eps).all(),
                            "vertex {p} outside its leaf box {lo}..{hi}"
                        );
                    }
                }
            }
        }
        assert!(
            seen.iter().all(|&n| n == 1),
            "each slot in one leaf: {seen:?}"
        );
    }

    #[test]
    fn collapsed_trees_hold_every_triangle_and_refit_to_moved_vertices() {
        let (mut positions, triangles) = sheet();
        let mut bvh = MeshBvh::build(&positions, &triangles, BvhQuality::Medium).unwrap();
        let before = bvh.flat.clone();
        let order = bvh.flat.order.clone();
        let mut tree =
            RefitWideBvh::collapse(&mut bvh.flat, slot_bounds(&positions, &triangles, &order))
                .unwrap();
        assert!(tree.nodes.len() <= node_capacity(triangles.len()));
        assert!(
            tree.depth < before.depth,
            "{} vs {}",
            tree.depth,
            before.depth
        );
        assert!(
            tree.nodes.len() * 3 < before.nodes.len(),
            "{}",
            tree.nodes.len()
        );
        // The BVH2 keeps its topology and boxes; its leaves name the same triangles through the new order.
        for (a, b) in before.nodes.iter().zip(&bvh.flat.nodes) {
            for (ca, cb) in a.children.iter().zip(&b.children) {
                assert_eq!((ca.min, ca.max, ca.count), (cb.min, cb.max, cb.count));
                if ca.is_leaf() {
                    let old: Vec<u32> = (0..ca.count)
                        .map(|k| before.order[(ca.index + k) as usize])
                        .collect();
                    let new: Vec<u32> = (0..cb.count)
                        .map(|k| bvh.flat.order[(cb.index + k) as usize])
                        .collect();
                    assert_eq!(old, new);
                }
            }
        }
        check(&tree, &positions, &triangles, &bvh.flat.order);

        // Move the vertices (a twist and a lift), refit both trees: the wide boxes follow.
        for p in &mut positions {
            *p = Vec3::new(p.x + 0.3 * p.z, p.y + 0.1 * p.x * p.x, p.z - 0.2 * p.x);
        }
        let gpu_triangles = bvh.ordered_triangles(&triangles);
        bvh.refit(&positions, &gpu_triangles);
        let order = bvh.flat.order.clone();
        let stale = tree.clone();
        tree.refit(&bvh.flat, slot_bounds(&positions, &triangles, &order));
        assert_ne!(stale.nodes, tree.nodes);
        check(&tree, &positions, &triangles, &order);
    }

    /// No triangle, one, a pile of coincident ones, non-finite vertices: a tree (or none, never a panic) whose
    /// leaves still hold every slot once.
    #[test]
    fn degenerate_meshes_collapse() {
        let nan = Vec3::splat(f32::NAN);
        let cases: Vec<(Vec<Vec3>, Vec<[u32; 3]>)> = vec![
            (vec![], vec![]),
            (vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]),
            (vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]; 50]),
            (
                vec![Vec3::ZERO, Vec3::X, nan, Vec3::splat(f32::INFINITY)],
                (0..40).map(|k| [k % 4, (k + 1) % 4, (k + 2) % 4]).collect(),
            ),
        ];
        for (positions, triangles) in cases {
            let mut bvh =
                MeshBvh::build_refittable(&positions, &triangles, BvhQuality::Fast, true).unwrap();
            let tree = bvh.wide.clone().expect("a shallow tree");
            assert!(tree.nodes.len() <= node_capacity(triangles.len()));
            let mut seen = vec![0u32; bvh.flat.order.len()];
            for node in &tree.nodes {
                for slot in 0..8 {
                    if !node.is_child_empty(slot) && node.imask & (1 << slot) == 0 {
                        let (first, count) = node.child_primitives(slot);
                        (first..first + count).for_each(|s| seen[s as usize] += 1);
                    }
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "{seen:?}");
            let gpu_triangles = bvh.ordered_triangles(&triangles);
            bvh.refit(&positions, &gpu_triangles);
        }
    }

    /// The reservation holds the largest trees the collapse makes: BVH2s of one triangle a leaf, of up to 4, and
    /// chains (every node with a leaf and an inner child), over every preset.
    #[test]
    fn reserved_nodes_hold_every_collapsed_tree() {
        let (positions, triangles) = sheet();
        let chain_positions: Vec<Vec3> = (0..300)
            .flat_map(|k| {
                let p = Vec3::splat(1.5f32.powi(k % 40) * if k % 2 == 0 { 1.0 } else { -1.0 });
                [p, p + Vec3::X, p + Vec3::Y]
            })
            .collect();
        let chain: Vec<[u32; 3]> = (0..300u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        let mut worst = 0.0f64;
        for quality in BvhQuality::ALL {
            for (p, t) in [(&positions, &triangles), (&chain_positions, &chain)] {
                for n in [1, 2, 3, 5, 8, 17, 64, t.len()] {
                    let bvh = MeshBvh::build_refittable(p, &t[..n], quality, true).unwrap();
                    let Some(tree) = bvh.wide else { continue };
                    assert!(tree.nodes.len() <= node_capacity(n), "{quality:?} {n}");
                    if n >= 64 {
                        worst = worst.max(tree.nodes.len() as f64 / n as f64);
                    }
                }
            }
        }
        eprintln!("most wide nodes per triangle from 64 triangles: {worst:.3}");
    }

    #[test]
    fn cell_exponents_span_the_extent() {
        for extent in [1e-20f32, 1e-6, 0.3, 1.0, 255.0, 256.0, 1000.0, 3.3e6, 1e30] {
            let e = cell_exponent(extent);
            let cell = f32::from_bits(e << 23);
            assert!(cell * 255.0 >= extent, "{extent}: {cell}");
            assert!(
                cell * 0.5 * 255.0 < extent || e == 1,
                "{extent}: {cell} is not the smallest"
            );
        }
    }
}

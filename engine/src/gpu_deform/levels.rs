//! A BVH's nodes grouped by depth, deepest level first: the order in which the GPU refit processes them
//! (`render/passes/refit/refit.wgsl`), so that every inner child is refit before its parent reads it.

use crate::bvh::{FlatBvh, MAX_TRAVERSAL_DEPTH};

/// Slots per mesh in the level-start table: a refused build is deeper than the traversal stack, so every
/// installed tree has at most [`MAX_TRAVERSAL_DEPTH`] levels.
pub const LEVEL_SLOTS: usize = MAX_TRAVERSAL_DEPTH as usize + 1;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct LevelOrder {
    /// Node indices (relative to the tree's root), deepest level first.
    pub order: Vec<u32>,
    /// `levels + 1` offsets into `order`: level `l` (counted from the deepest) is `starts[l]..starts[l + 1]`.
    pub starts: Vec<u32>,
}

impl LevelOrder {
    pub fn of(flat: &FlatBvh) -> Self {
        // Children follow their parents, so one forward sweep assigns every depth.
        let mut depth = vec![0u32; flat.nodes.len()];
        for i in 0..flat.nodes.len() {
            for c in flat.nodes[i].children {
                if !c.is_leaf() && !c.is_empty() {
                    depth[c.index as usize] = depth[i] + 1;
                }
            }
        }
        let levels = depth.iter().max().map_or(0, |d| d + 1) as usize;
        // Counting sort by level (deepest first), stable in node order.
        let mut starts = vec![0u32; levels + 1];
        for &d in &depth {
            starts[levels - d as usize] += 1;
        }
        for l in 0..levels {
            starts[l + 1] += starts[l];
        }
        let mut next: Vec<u32> = starts[..levels].to_vec();
        let mut order = vec![0u32; depth.len()];
        for (node, &d) in depth.iter().enumerate() {
            let slot = &mut next[levels - 1 - d as usize];
            order[*slot as usize] = node as u32;
            *slot += 1;
        }
        Self { order, starts }
    }

    pub fn levels(&self) -> usize {
        self.starts.len().saturating_sub(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{BvhQuality, MeshBvh};
    use glam::Vec3;

    #[test]
    fn children_come_in_earlier_levels_than_parents() {
        let positions: Vec<Vec3> = (0..300)
            .map(|i| Vec3::new((i % 17) as f32, (i / 17) as f32, ((i * 7) % 5) as f32))
            .collect();
        let triangles: Vec<[u32; 3]> = (0..298).map(|i| [i, i + 1, i + 2]).collect();
        let bvh = MeshBvh::build(&positions, &triangles, BvhQuality::Medium).unwrap();
        let levels = LevelOrder::of(&bvh.flat);
        assert_eq!(levels.order.len(), bvh.flat.nodes.len());
        assert_eq!(
            *levels.starts.last().unwrap() as usize,
            bvh.flat.nodes.len()
        );
        assert_eq!(levels.levels(), bvh.flat.depth as usize);
        let mut level_of = vec![usize::MAX; bvh.flat.nodes.len()];
        for l in 0..levels.levels() {
            for &n in &levels.order[levels.starts[l] as usize..levels.starts[l + 1] as usize] {
                level_of[n as usize] = l;
            }
        }
        // Every node appears once; the root is processed last.
        assert!(level_of.iter().all(|&l| l != usize::MAX));
        assert_eq!(level_of[0], levels.levels() - 1);
        for (i, node) in bvh.flat.nodes.iter().enumerate() {
            for c in node.children {
                if !c.is_leaf() && !c.is_empty() {
                    assert!(level_of[c.index as usize] < level_of[i]);
                }
            }
        }
    }
}

//! A BVH2 that is never deep: recursive median split of the boxes' centres along their widest axis. obvhs's
//! PLOC builder is much better on ordinary input but chains degenerate input: 100 instances with the same
//! box gave a 99-level tree, boxes spaced along a geometric series or nested at growing scales about one
//! level per box, past the GPU traversal stack. The builds fall back to this tree, at most
//! ceil(log2 n) + 1 levels, instead of refusing the scene.

use obvhs::{aabb::Aabb, bvh2::Bvh2, bvh2::node::Bvh2Node};

/// A BVH2 over `boxes` with one primitive per leaf.
pub fn median_split(boxes: &[Aabb]) -> Bvh2 {
    if boxes.is_empty() {
        return Bvh2::default();
    }
    let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
    let mut nodes = vec![Bvh2Node::new(Aabb::empty(), 0, 0)];
    // (node, first slot of `order`, end) still to fill in.
    let mut stack = vec![(0usize, 0usize, boxes.len())];
    while let Some((node, start, end)) = stack.pop() {
        let range = &mut order[start..end];
        let bounds = range
            .iter()
            .fold(Aabb::empty(), |b, &i| b.union(&boxes[i as usize]));
        if range.len() == 1 {
            nodes[node] = Bvh2Node::new(bounds, 1, start as u32);
            continue;
        }
        let centres = range.iter().fold(Aabb::empty(), |mut b, &i| {
            b.extend(boxes[i as usize].center());
            b
        });
        let axis = centres.largest_axis();
        let half = range.len() / 2;
        // Ties (identical boxes) split by index, so they still halve.
        range.select_nth_unstable_by(half, |&a, &b| {
            let key = |i: u32| boxes[i as usize].center_axis(axis);
            key(a).total_cmp(&key(b)).then(a.cmp(&b))
        });
        let first = nodes.len();
        nodes.push(Bvh2Node::new(Aabb::empty(), 0, 0));
        nodes.push(Bvh2Node::new(Aabb::empty(), 0, 0));
        nodes[node] = Bvh2Node::new(bounds, 0, first as u32);
        stack.push((first, start, start + half));
        stack.push((first + 1, start + half, end));
    }
    Bvh2 {
        nodes,
        primitive_indices: order,
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;

    /// Every primitive in exactly one leaf, every child inside its parent, depth ceil(log2 n) + 1 at most.
    #[test]
    fn identical_boxes_give_a_balanced_tree() {
        for n in [1usize, 2, 3, 100, 1000] {
            let boxes = vec![Aabb::new(Vec3A::ZERO, Vec3A::ONE); n];
            let bvh = median_split(&boxes);
            let mut seen = vec![0; n];
            let mut deepest = 0;
            let mut stack = vec![(0usize, 1u32)];
            while let Some((i, depth)) = stack.pop() {
                deepest = deepest.max(depth);
                let node = &bvh.nodes[i];
                if node.prim_count > 0 {
                    seen[bvh.primitive_indices[node.first_index as usize] as usize] += 1;
                    continue;
                }
                for c in [node.first_index as usize, node.first_index as usize + 1] {
                    let (inner, outer) = (bvh.nodes[c].aabb(), node.aabb());
                    assert!(inner.min.cmpge(outer.min).all() && inner.max.cmple(outer.max).all());
                    stack.push((c, depth + 1));
                }
            }
            assert!(seen.iter().all(|&k| k == 1), "n {n}: {seen:?}");
            let bound = (n as f64).log2().ceil() as u32 + 1;
            assert!(deepest <= bound, "n {n}: depth {deepest} > {bound}");
        }
    }
}

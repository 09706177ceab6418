//! The spatially aware light sampler's tree: a bounding volume hierarchy over the lights at finite distance
//! (emissive triangles, point and spot lights), after pbrt-v4's `BVHLightSampler` (Conty Estevez & Kulla,
//! "Importance Sampling of Many Lights with Adaptive Tree Splitting", 2018). Each node bounds its lights'
//! positions, their emission directions (a cone of normals `w, cos_theta_o` and the spread `cos_theta_e`
//! around them) and their intensity; `shaders/lights/light_tree.wgsl` descends it, picking a child in
//! proportion to an upper bound of what it can send to the shading point, and computes the probability of a
//! given light from the path to its leaf (the bit trail in `GpuLight::flags`).
//!
//! `phi` here is a radiant intensity bound (per steradian, luminance): point and spot I, a triangle L A (its
//! intensity along the normal), so `phi cos / d^2` bounds the irradiance a node gives, whatever kinds it holds.
//! Built on the CPU with pbrt-v4's surface-area-orientation heuristic over 12 buckets per axis.

use crate::render::layout::*;
use glam::Vec3;
use std::f32::consts::PI;

/// The deepest tree the bit trails (32 bits) can address.
pub const MAX_LIGHT_TREE_DEPTH: usize = 32;

/// What a light (or a group of lights) can send where.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    pub lo: Vec3,
    pub hi: Vec3,
    pub phi: f32,
    /// Axis of the cone holding the emitters' normals (point lights: any).
    pub w: Vec3,
    pub cos_theta_o: f32,
    /// How far beyond the normal cone light leaves (a Lambertian surface: 90 degrees).
    pub cos_theta_e: f32,
    pub two_sided: bool,
}

impl LightBounds {
    /// An emissive triangle of radiance luminance `luminance`.
    pub fn triangle(p: [Vec3; 3], luminance: f32, two_sided: bool) -> Self {
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        let area = 0.5 * n.length();
        Self {
            lo: p[0].min(p[1]).min(p[2]),
            hi: p[0].max(p[1]).max(p[2]),
            phi: luminance * area,
            w: n.normalize_or(Vec3::Z),
            cos_theta_o: 1.0,
            cos_theta_e: 0.0,
            two_sided,
        }
    }

    /// A point light (`cos_outer` = -1) or a spot whose light falls off between its inner and outer cones.
    pub fn punctual(light: &GpuLight) -> Self {
        let p = Vec3::from(light.position);
        let intensity = Vec3::from(light.radiance).dot(Vec3::new(0.2126, 0.7152, 0.0722));
        let (w, cos_o, cos_e) = if light.kind == LIGHT_SPOT {
            let (inner, outer) = (
                light.cos_inner.clamp(-1.0, 1.0),
                light.cos_outer.clamp(-1.0, 1.0),
            );
            (
                Vec3::from(light.direction),
                inner,
                (outer.acos() - inner.acos()).max(0.0).cos(),
            )
        } else {
            (Vec3::Z, -1.0, 0.0)
        };
        Self {
            lo: p,
            hi: p,
            phi: intensity,
            w,
            cos_theta_o: cos_o,
            cos_theta_e: cos_e,
            two_sided: false,
        }
    }

    fn centroid(&self) -> Vec3 {
        0.5 * (self.lo + self.hi)
    }

    /// The bounds of both (pbrt-v4 `Union`: boxes, powers, merged normal cones).
    pub fn union(&self, other: &Self) -> Self {
        if self.phi == 0.0 {
            return *other;
        }
        if other.phi == 0.0 {
            return *self;
        }
        let (w, cos_theta_o) = union_cones(self.w, self.cos_theta_o, other.w, other.cos_theta_o);
        Self {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
            phi: self.phi + other.phi,
            w,
            cos_theta_o,
            cos_theta_e: self.cos_theta_e.min(other.cos_theta_e),
            two_sided: self.two_sided || other.two_sided,
        }
    }

    /// pbrt-v4's orientation measure M_omega (the solid angle the emission can reach, weighted by cosine).
    fn orientation_measure(&self) -> f32 {
        let theta_o = self.cos_theta_o.clamp(-1.0, 1.0).acos();
        let theta_e = self.cos_theta_e.clamp(-1.0, 1.0).acos();
        let theta_w = (theta_o + theta_e).min(PI);
        let sin_o = theta_o.sin();
        2.0 * PI * (1.0 - self.cos_theta_o)
            + PI / 2.0
                * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o
                    + self.cos_theta_o)
    }

    /// What splitting into this node costs: power x orientation measure x surface area.
    fn cost(&self, regularizer: f32) -> f32 {
        let d = self.hi - self.lo;
        let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
        self.phi * self.orientation_measure() * area.max(1e-12) * regularizer
    }
}

/// The smallest cone holding both cones (pbrt-v4 `Union(DirectionCone, DirectionCone)`).
fn union_cones(wa: Vec3, cos_a: f32, wb: Vec3, cos_b: f32) -> (Vec3, f32) {
    let theta_a = cos_a.clamp(-1.0, 1.0).acos();
    let theta_b = cos_b.clamp(-1.0, 1.0).acos();
    let theta_d = wa.angle_between(wb);
    if (theta_d + theta_b).min(PI) <= theta_a {
        return (wa, cos_a);
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return (wb, cos_b);
    }
    let theta_o = 0.5 * (theta_a + theta_d + theta_b);
    if theta_o >= PI {
        return (Vec3::Z, -1.0);
    }
    let axis = wa.cross(wb);
    if axis.length_squared() == 0.0 {
        return (Vec3::Z, -1.0);
    }
    let w = glam::Quat::from_axis_angle(axis.normalize(), theta_o - theta_a) * wa;
    (w.normalize(), theta_o.cos())
}

/// A built tree: its nodes, and each light's (index, bit trail to its leaf).
pub type BuiltTree = (Vec<GpuLightTreeNode>, Vec<(u32, u32)>);

/// The tree over `lights` (light index, bounds); `trails[k]` is the bit path to light `lights[k].0`'s leaf
/// (bit d set: the second child at depth d). `None` for no lights or a tree deeper than the trails address.
pub fn build(lights: &[(u32, LightBounds)]) -> Option<BuiltTree> {
    let mut items: Vec<(u32, LightBounds)> =
        lights.iter().filter(|l| l.1.phi > 0.0).copied().collect();
    if items.is_empty() {
        return None;
    }
    let mut nodes = Vec::with_capacity(2 * items.len());
    let mut trails = Vec::with_capacity(items.len());
    let depth = build_range(&mut items, 0, 0, &mut nodes, &mut trails);
    (depth <= MAX_LIGHT_TREE_DEPTH).then_some((nodes, trails))
}

/// Builds the subtree over `items` at `depth` with `trail`; returns its depth.
fn build_range(
    items: &mut [(u32, LightBounds)],
    trail: u32,
    depth: usize,
    nodes: &mut Vec<GpuLightTreeNode>,
    trails: &mut Vec<(u32, u32)>,
) -> usize {
    let bounds = items[1..].iter().fold(items[0].1, |b, i| b.union(&i.1));
    let index = nodes.len();
    nodes.push(node(&bounds, 0, 0));
    if items.len() == 1 || depth >= MAX_LIGHT_TREE_DEPTH {
        nodes[index] = node(&bounds, items[0].0, LIGHT_TREE_LEAF);
        trails.push((items[0].0, trail));
        // Lights beyond the addressable depth make the tree unusable (reported by the depth).
        return depth + items.len() - 1;
    }
    let split = split_point(items, &bounds);
    let (first, second) = items.split_at_mut(split);
    let d0 = build_range(first, trail, depth + 1, nodes, trails);
    nodes[index].child_or_light = nodes.len() as u32;
    let d1 = build_range(second, trail | (1 << depth), depth + 1, nodes, trails);
    d0.max(d1)
}

fn node(b: &LightBounds, child_or_light: u32, flags: u32) -> GpuLightTreeNode {
    GpuLightTreeNode {
        lo: b.lo.to_array(),
        phi: b.phi,
        hi: b.hi.to_array(),
        cos_theta_o: b.cos_theta_o,
        w: b.w.to_array(),
        cos_theta_e: b.cos_theta_e,
        child_or_light,
        flags: flags | if b.two_sided { LIGHT_TREE_TWO_SIDED } else { 0 },
        _pad: [0; 2],
    }
}

/// Sorts `items` for the best of 12 bucket boundaries per axis by the surface-area-orientation cost (pbrt-v4's
/// `BVHLightSampler::buildBVH`) and returns how many go to the first child (never 0 or all).
fn split_point(items: &mut [(u32, LightBounds)], bounds: &LightBounds) -> usize {
    const BUCKETS: usize = 12;
    let (clo, chi) = items.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), i| {
        (lo.min(i.1.centroid()), hi.max(i.1.centroid()))
    });
    let extent = bounds.hi - bounds.lo;
    let max_extent = extent.max_element().max(1e-12);
    let mut best: Option<(f32, usize, f32)> = None;
    for axis in 0..3 {
        let (lo, hi) = (clo[axis], chi[axis]);
        if hi <= lo {
            continue;
        }
        let bucket_of =
            |c: Vec3| (((c[axis] - lo) / (hi - lo) * BUCKETS as f32) as usize).min(BUCKETS - 1);
        let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
        for i in items.iter() {
            let b = &mut buckets[bucket_of(i.1.centroid())];
            *b = Some(b.map_or(i.1, |x| x.union(&i.1)));
        }
        // Long thin boxes split across their length.
        let regularizer = max_extent / extent[axis].max(1e-12);
        for cut in 1..BUCKETS {
            let side = |range: std::ops::Range<usize>| {
                buckets[range]
                    .iter()
                    .flatten()
                    .fold(None::<LightBounds>, |acc, b| {
                        Some(acc.map_or(*b, |a| a.union(b)))
                    })
            };
            let (Some(a), Some(b)) = (side(0..cut), side(cut..BUCKETS)) else {
                continue;
            };
            let cost = a.cost(regularizer) + b.cost(regularizer);
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, lo + (hi - lo) * cut as f32 / BUCKETS as f32));
            }
        }
    }
    let split = match best {
        Some((_, axis, at)) => {
            items.sort_by(|a, b| a.1.centroid()[axis].total_cmp(&b.1.centroid()[axis]));
            items.partition_point(|i| i.1.centroid()[axis] < at)
        }
        None => 0,
    };
    // Coincident centroids (or a degenerate cut): halve by count.
    if split == 0 || split == items.len() {
        items.len() / 2
    } else {
        split
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(p: Vec3, phi: f32) -> LightBounds {
        LightBounds {
            lo: p,
            hi: p,
            phi,
            w: Vec3::Z,
            cos_theta_o: -1.0,
            cos_theta_e: 0.0,
            two_sided: false,
        }
    }

    #[test]
    fn cone_union_holds_both_cones() {
        let (w, c) = union_cones(Vec3::X, 1.0, Vec3::Y, 1.0);
        assert!((c - std::f32::consts::FRAC_PI_4.cos()).abs() < 1e-5);
        assert!(w.dot(Vec3::X) >= c - 1e-5 && w.dot(Vec3::Y) >= c - 1e-5);
        let (_, c) = union_cones(Vec3::X, 1.0, Vec3::NEG_X, 1.0);
        assert_eq!(c, -1.0);
    }

    #[test]
    fn every_light_gets_a_leaf_its_trail_reaches() {
        let lights: Vec<(u32, LightBounds)> = (0..300)
            .map(|i| {
                (
                    i,
                    point(
                        Vec3::new((i % 17) as f32, (i / 17) as f32, (i % 5) as f32),
                        1.0 + (i % 3) as f32,
                    ),
                )
            })
            .collect();
        let (nodes, trails) = build(&lights).expect("a tree");
        assert_eq!(trails.len(), 300);
        for (light, trail) in trails {
            let mut n = 0usize;
            let mut depth = 0;
            while nodes[n].flags & LIGHT_TREE_LEAF == 0 {
                n = if trail & (1 << depth) != 0 {
                    nodes[n].child_or_light as usize
                } else {
                    n + 1
                };
                depth += 1;
            }
            assert_eq!(nodes[n].child_or_light, light);
        }
        // Balanced enough for 32-bit trails with room to spare.
        let root = nodes[0];
        assert!((root.phi - lights.iter().map(|l| l.1.phi).sum::<f32>()).abs() < 1e-3);
    }
}

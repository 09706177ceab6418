//! Conservative bounds of a GPU-deformed mesh, computed on the CPU from the pose alone (no readback), for
//! the top-level BVH.
//!
//! Why this holds: a skinned vertex is `sum_j w_j M_j p` with normalised weights, a convex combination of
//! the points `M_j p`. If `p` (the morphed rest position) lies in joint `j`'s bind-space box `B_j` (the box
//! of every vertex `j` influences, grown by the morph deltas those vertices can receive at the current
//! weights), `M_j p` lies in the box of the transformed corners of `B_j`, and so the vertex lies in the union
//! of those boxes (a box is convex). Vertices without usable weights follow the node's world matrix, which
//! gets its own group; morph-only meshes have one group in object space. The CPU reference's last-resort
//! fallback (a non-finite result becomes the rest position) adds the rest box when it can happen.

use crate::render::gpu_scene::transform_box;
use crate::scene::MeshData;
use glam::{Mat4, Vec3};

/// Which matrix moves a group of vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Mover {
    Joint(usize),
    /// The skinned node's world matrix (vertices without usable weights, and non-finite joints).
    NodeWorld,
    /// Object space (morph-only meshes).
    Identity,
}

#[derive(Clone, Debug)]
struct Group {
    mover: Mover,
    lo: Vec3,
    hi: Vec3,
    /// Per morph target: the box of this group's finite deltas.
    deltas: Vec<(Vec3, Vec3)>,
}

impl Group {
    fn new(mover: Mover, targets: usize) -> Self {
        Self {
            mover,
            lo: Vec3::MAX,
            hi: Vec3::MIN,
            deltas: vec![(Vec3::MAX, Vec3::MIN); targets],
        }
    }

    fn add(&mut self, mesh: &MeshData, v: usize) {
        self.lo = self.lo.min(mesh.positions[v]);
        self.hi = self.hi.max(mesh.positions[v]);
        for (t, target) in mesh.morph_targets.iter().enumerate() {
            if let Some(d) = target.positions.get(v).filter(|d| d.is_finite()) {
                self.deltas[t].0 = self.deltas[t].0.min(*d);
                self.deltas[t].1 = self.deltas[t].1.max(*d);
            } else {
                // A missing delta is zero.
                self.deltas[t].0 = self.deltas[t].0.min(Vec3::ZERO);
                self.deltas[t].1 = self.deltas[t].1.max(Vec3::ZERO);
            }
        }
    }

    fn is_empty(&self) -> bool {
        self.lo.x > self.hi.x
    }

    /// The group's bind-space box at these morph weights (interval arithmetic per target).
    fn morphed(&self, weights: &[f32]) -> (Vec3, Vec3) {
        let (mut lo, mut hi) = (self.lo, self.hi);
        for (&(dlo, dhi), &w) in self.deltas.iter().zip(weights) {
            if w == 0.0 || !w.is_finite() {
                continue;
            }
            let (a, b) = (dlo * w, dhi * w);
            lo += a.min(b);
            hi += a.max(b);
        }
        (lo, hi)
    }
}

/// Per-mesh bound model: built once from the rest data, evaluated per pose.
#[derive(Clone, Debug)]
pub struct DeformBounds {
    groups: Vec<Group>,
    rest: (Vec3, Vec3),
    /// Targets with a non-finite delta: at a non-zero weight the CPU reference sends those vertices to rest.
    nonfinite_targets: Vec<bool>,
}

impl DeformBounds {
    /// `joints`: the skin's joint count when the mesh is skinned on its node.
    pub fn new(mesh: &MeshData, joints: Option<usize>) -> Self {
        let targets = mesh.morph_targets.len();
        let mut groups: Vec<Group> = Vec::new();
        match (joints, &mesh.skin_weights) {
            (Some(joint_count), Some(sw)) => {
                let mut by_joint: Vec<Group> = (0..joint_count)
                    .map(|j| Group::new(Mover::Joint(j), targets))
                    .collect();
                let mut rigid = Group::new(Mover::NodeWorld, targets);
                let sets = sw.sets.max(1) as usize;
                for v in 0..mesh.positions.len() {
                    let mut sum = 0.0f32;
                    for i in v * sets..((v + 1) * sets).min(sw.joints.len()) {
                        for k in 0..4 {
                            let (w, j) = (sw.weights[i][k], sw.joints[i][k] as usize);
                            if w > 0.0 && j < joint_count {
                                by_joint[j].add(mesh, v);
                                sum += w;
                            }
                        }
                    }
                    if !(sum > 0.0 && sum.is_finite()) {
                        rigid.add(mesh, v);
                    }
                }
                groups.extend(by_joint);
                groups.push(rigid);
            }
            _ => {
                let mut all = Group::new(Mover::Identity, targets);
                (0..mesh.positions.len()).for_each(|v| all.add(mesh, v));
                groups.push(all);
            }
        }
        groups.retain(|g| !g.is_empty());
        Self {
            groups,
            rest: mesh.bounds(),
            nonfinite_targets: mesh
                .morph_targets
                .iter()
                .map(|t| t.positions.iter().any(|d| !d.is_finite()))
                .collect(),
        }
    }

    /// A box containing every deformed vertex at this pose (world space when skinned, object space for
    /// morph-only meshes), padded for the GPU's float rounding.
    pub fn bounds(&self, skin: Option<(&[Mat4], Mat4)>, weights: &[f32]) -> (Vec3, Vec3) {
        let mut out = (Vec3::MAX, Vec3::MIN);
        let include = |out: &mut (Vec3, Vec3), (a, b): (Vec3, Vec3)| {
            out.0 = out.0.min(a);
            out.1 = out.1.max(b);
        };
        let node_world = skin.map_or(Mat4::IDENTITY, |s| s.1);
        let identity = [Mat4::IDENTITY];
        let joints = skin.map_or(&identity[..], |s| s.0);
        for g in &self.groups {
            let (a, b) = g.morphed(weights);
            let matrix = match g.mover {
                Mover::Joint(j) => joints.get(j).copied().unwrap_or(Mat4::IDENTITY),
                Mover::NodeWorld => node_world,
                Mover::Identity => Mat4::IDENTITY,
            };
            let moved = transform_box(matrix, a, b);
            if moved.0.is_finite() && moved.1.is_finite() {
                include(&mut out, moved);
            }
            // A non-finite blend falls back to the node's world matrix on the GPU, as on the CPU.
            if !matrix.is_finite() || !moved.0.is_finite() || !moved.1.is_finite() {
                let rigid = transform_box(node_world, a, b);
                if rigid.0.is_finite() && rigid.1.is_finite() {
                    include(&mut out, rigid);
                }
            }
        }
        let fallback_possible = !node_world.is_finite()
            || self
                .nonfinite_targets
                .iter()
                .zip(weights)
                .any(|(&bad, &w)| bad && w != 0.0 && w.is_finite());
        if fallback_possible || out.0.x > out.1.x {
            include(&mut out, self.rest);
        }
        let (lo, hi) = out;
        let pad = 1e-5 * ((hi - lo).max_element() + lo.abs().max(hi.abs()).max_element());
        (lo - Vec3::splat(pad), hi + Vec3::splat(pad))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{MorphTarget, SkinWeights};
    use glam::Quat;

    fn contains(b: (Vec3, Vec3), p: Vec3) -> bool {
        p.cmpge(b.0).all() && p.cmple(b.1).all()
    }

    #[test]
    fn bounds_contain_every_deformed_vertex() {
        // A bar of vertices shared between two joints, with a morph target, posed far from bind.
        let mut mesh = MeshData::default();
        for i in 0..50 {
            let x = i as f32 / 49.0 * 4.0 - 2.0;
            mesh.positions
                .push(Vec3::new(x, (i % 3) as f32 * 0.1, (i % 5) as f32 * 0.1));
        }
        let weights: Vec<[f32; 4]> = mesh
            .positions
            .iter()
            .map(|p| {
                let w = ((p.x + 2.0) / 4.0).clamp(0.0, 1.0);
                [1.0 - w, w, 0.0, 0.0]
            })
            .collect();
        mesh.skin_weights = Some(SkinWeights {
            joints: vec![[0, 1, 0, 0]; 50],
            weights,
            sets: 1,
        });
        mesh.morph_targets.push(MorphTarget {
            positions: (0..50)
                .map(|i| Vec3::new(0.0, (i as f32).sin(), 0.3))
                .collect(),
            normals: None,
            tangents: None,
        });
        let joints = [
            Mat4::from_rotation_translation(Quat::from_rotation_z(0.7), Vec3::new(1.0, 2.0, 0.0)),
            Mat4::from_scale_rotation_translation(
                Vec3::splat(1.5),
                Quat::from_rotation_y(-1.2),
                Vec3::new(-3.0, 0.5, 1.0),
            ),
        ];
        let world = Mat4::from_translation(Vec3::new(0.0, 0.0, 5.0));
        let weights = [0.8];
        let model = DeformBounds::new(&mesh, Some(2));
        let b = model.bounds(Some((&joints, world)), &weights);
        let deformed =
            crate::animation::deform_mesh(&mesh, Some((&joints, world)), &weights).positions;
        for p in &deformed {
            assert!(contains(b, *p), "{p} outside {b:?}");
        }
        // Tight enough to be useful: not more than a few times the true extent.
        let (lo, hi) = deformed
            .iter()
            .fold((Vec3::MAX, Vec3::MIN), |(l, h), p| (l.min(*p), h.max(*p)));
        let area = |d: Vec3| d.x * d.y + d.y * d.z + d.z * d.x;
        assert!(area(b.1 - b.0) < 4.0 * area(hi - lo));
    }
}

//! Refit with a quality guard.
//!
//! A deformed mesh's BVH is refit every frame it moves (one reverse sweep, see [`super::FlatBvh::refit`]).
//! Refitting keeps the topology chosen for the build pose, so when parts of the mesh move far from where
//! they were built (a fold, a twist, limbs scattering), boxes overlap and traversal slows. The guard
//! compares the refit tree's SAH cost with its cost at build ([`crate::bvh::MeshBvh::sah_ratio`]); above
//! [`DEFAULT_REBUILD_THRESHOLD`] the mesh's BVH is rebuilt in place (its GPU node range is reserved at
//! upload). At most [`BvhStats::max_rebuilds_per_frame`] rebuilds run per frame, the worst ratios
//! first, so a crowd crossing the threshold together spreads its rebuilds over frames instead of hitching;
//! meshes that wait keep a correct (only slower) refit tree. docs/ANIMATION.md has the measurements.
//!
//! That schedule makes a mesh's tree depend on the poses seen before (which frame rebuilt it). A recording
//! needs frame k to re-render alone bit-identically, so [`RebuildPolicy::PoseDetermined`] makes the tree a
//! function of the current pose only: each pose starts again from the tree built at upload.

use bevy_ecs::prelude::Resource;

/// SAH-ratio above which a refit BVH is rebuilt (chosen from measured ratio curves, docs/ANIMATION.md).
pub const DEFAULT_REBUILD_THRESHOLD: f32 = 1.5;

/// When deformed meshes' BVHs are rebuilt.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RebuildPolicy {
    /// Refit the current tree each frame; rebuild at most [`BvhStats::max_rebuilds_per_frame`] meshes past
    /// the threshold, worst first (no frame hitch). The tree depends on the history of poses.
    #[default]
    Amortised,
    /// Each new pose refits the tree built at upload, and every mesh past the threshold is rebuilt in the
    /// same frame: the tree, and so the image, depends only on the current pose (recordings).
    PoseDetermined,
}

/// Refit quality and rebuild counters, for the editor and benches.
#[derive(Resource, Clone, Debug)]
pub struct BvhStats {
    pub threshold: f32,
    pub policy: RebuildPolicy,
    pub max_rebuilds_per_frame: usize,
    /// Current SAH cost over cost at build, per mesh (1 for static meshes).
    pub sah_ratio: Vec<f32>,
    /// Rebuilds per mesh since upload.
    pub mesh_rebuilds: Vec<u32>,
    /// Rebuilds over all meshes since upload.
    pub rebuilds: u64,
    /// Mesh refits since upload.
    pub refits: u64,
    /// CPU seconds of the last frame's refits (CPU backend) and rebuilds (run or installed).
    pub last_refit_seconds: f64,
    pub last_rebuild_seconds: f64,
    /// CPU seconds of the last frame's uploads of deformation results (CPU backend: vertices and nodes) or
    /// inputs (GPU backend: joint matrices, morph weights, flags).
    pub last_upload_seconds: f64,
    /// CPU seconds of the last frame's top-level BVH build and instance upload (0 when nothing moved).
    pub last_tlas_seconds: f64,
}

impl Default for BvhStats {
    fn default() -> Self {
        Self {
            threshold: DEFAULT_REBUILD_THRESHOLD,
            policy: RebuildPolicy::Amortised,
            max_rebuilds_per_frame: 1,
            sah_ratio: Vec::new(),
            mesh_rebuilds: Vec::new(),
            rebuilds: 0,
            refits: 0,
            last_refit_seconds: 0.0,
            last_rebuild_seconds: 0.0,
            last_upload_seconds: 0.0,
            last_tlas_seconds: 0.0,
        }
    }
}

impl BvhStats {
    /// Meshes due for a rebuild this frame among those `eligible` (each backend rebuilds its own): ratio
    /// above the threshold, worst first, at most the per-frame cap (no cap under
    /// [`RebuildPolicy::PoseDetermined`]).
    pub fn due(&self, eligible: impl Fn(usize) -> bool) -> Vec<usize> {
        let mut due: Vec<usize> = (0..self.sah_ratio.len())
            .filter(|&m| self.sah_ratio[m] > self.threshold && eligible(m))
            .collect();
        due.sort_by(|&a, &b| {
            self.sah_ratio[b]
                .total_cmp(&self.sah_ratio[a])
                .then(a.cmp(&b))
        });
        if self.policy == RebuildPolicy::Amortised {
            due.truncate(self.max_rebuilds_per_frame);
        }
        due
    }

    pub fn ensure_len(&mut self, meshes: usize) {
        if self.sah_ratio.len() < meshes {
            self.sah_ratio.resize(meshes, 1.0);
            self.mesh_rebuilds.resize(meshes, 0);
        }
    }
}

/// Upper bound of a child-pair BVH's node count over `triangles` triangles (>= 1 triangle per leaf):
/// a binary tree with L <= T leaves has L - 1 inner nodes, and a single leaf still takes one node.
pub fn node_capacity(triangles: usize) -> usize {
    triangles.max(1)
}

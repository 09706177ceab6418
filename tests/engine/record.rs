//! The recorder's guarantees that need no binary (`raykin record` itself is tested in tests/cli/record.rs).

use crate::common::{gpu, shared_assets};
use raykin::bvh::refit::RebuildPolicy;
use raykin::camera::CameraChoice;
use raykin::headless::HeadlessApp;
use std::sync::Arc;

/// Under the recorder's policy a deformed mesh's BVH (nodes and triangle order) after any history of poses
/// equals the one made by posing directly: what makes frame k re-render alone bit-identically. The
/// interactive policy keeps history (a tree rebuilt at an earlier pose), which is why the recorder switches.
#[test]
fn pose_determined_bvh_does_not_depend_on_earlier_poses() {
    let (ctx, _gpu) = gpu();
    let scene = Arc::new(
        raykin::scene::load_gltf(
            shared_assets().join("CesiumMan/glTF/CesiumMan.gltf"),
            &Default::default(),
        )
        .unwrap(),
    );
    let settings = raykin::render::RenderSettings {
        width: 16,
        height: 16,
        spp_per_frame: 1,
        ..Default::default()
    };
    let posed = |policy: RebuildPolicy, times: &[f32]| {
        let mut app = HeadlessApp::new(
            ctx.clone(),
            scene.clone(),
            settings.clone(),
            &CameraChoice::Auto,
        )
        .unwrap();
        app.set_rebuild_policy(policy);
        for &t in times {
            app.pose(Some(0), t, &CameraChoice::Auto).unwrap();
            app.step();
        }
        let trees: Vec<_> = app
            .gpu_scene()
            .mesh_slots
            .iter()
            .map(|s| {
                (
                    s.blas.binary().map(|b| b.flat.nodes.clone()),
                    s.gpu_triangles.clone(),
                )
            })
            .collect();
        (trees, app.bvh_stats().rebuilds)
    };
    // CesiumMan's refit passes the 1.5 SAH ratio mid-stride (0.3 s and 1.3 s, docs/ANIMATION.md).
    let history = [0.0, 0.3, 1.3, 1.6];
    let (after_history, rebuilds) = posed(RebuildPolicy::PoseDetermined, &history);
    let (direct, _) = posed(RebuildPolicy::PoseDetermined, &[1.6]);
    assert!(
        rebuilds > 0,
        "the history must rebuild a tree for this test to mean anything"
    );
    assert!(
        after_history == direct,
        "the BVH after other poses differs from posing directly"
    );
    let (after_history, _) = posed(RebuildPolicy::Amortised, &history);
    let (direct, _) = posed(RebuildPolicy::Amortised, &[1.6]);
    assert!(
        after_history != direct,
        "the interactive policy keeps history (else this test checks nothing)"
    );
}

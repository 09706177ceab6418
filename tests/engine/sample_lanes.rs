//! Sample lanes (GPUs' trace kernel, `passes::trace::sample_lanes`): a dispatch's samples of a pixel spread over
//! up to 16 invocations of a workgroup, each lane's sums added in workgroup memory. Every sample is the same path
//! as in the one-invocation sample loop, so the image and the denoisers' inputs differ from the loop's only by
//! the order the sums are added. CI has only a CPU adapter (where the lanes are off), so both forms run here.

use crate::common::*;
use raykin::camera::CameraChoice;
use raykin::headless::HeadlessApp;
use raykin::render::{Environment, RenderSettings};

#[test]
fn sample_lanes_give_the_sample_loops_image() {
    let (ctx, _gpu) = gpu();
    // The Cornell box: emitters, Russian roulette, paths leaving through its open side. Alpha blending: paths
    // that pass through surfaces.
    for file in [
        "CornellBox/CornellBox.glb",
        "AlphaBlendModeTest/glTF-Binary/AlphaBlendModeTest.glb",
    ] {
        let scene = shared_scene(file);
        let render = |lanes: bool| {
            let mut form = ctx.clone();
            form.path_regeneration = false;
            form.sample_lanes = lanes;
            // Sides that are no multiple of the tiles (8x8 pixels down to 2x2): workgroups past the edges.
            let settings = RenderSettings {
                width: 27,
                height: 19,
                environment: Environment::Sky,
                ..Default::default()
            };
            let mut app = HeadlessApp::new(form, scene.clone(), settings, &CameraChoice::Auto)
                .expect("scene uploads");
            app.set_hit_aov(true);
            // 16 samples (16 lanes of one sample), then 7 (4 lanes: three of two samples, one of one), then 3
            // (2 lanes) and 1 (the loop).
            app.accumulate(16, 16, |_| {});
            app.accumulate(7, 7, |_| {});
            app.accumulate(4, 3, |_| {});
            (
                app.radiance(),
                app.aovs(),
                app.primary_hits(),
                app.samples(),
            )
        };
        let (lanes, lane_aovs, lane_hits, lane_samples) = render(true);
        let (looped, looped_aovs, looped_hits, looped_samples) = render(false);
        assert_eq!(lane_samples, 27, "{file}: samples accumulated");
        assert_eq!(lane_samples, looped_samples, "{file}");
        assert!(
            mean_rgb(&looped).iter().all(|&m| m > 1e-3),
            "{file}: a black image"
        );
        assert_all_finite(&lanes, file);
        let differ = worst_relative_difference(&lanes, &looped);
        assert!(
            differ < 1e-5,
            "{file}: radiance differs by {differ} (relative)"
        );
        for (what, a, b) in [
            ("albedo", &lane_aovs.albedo, &looped_aovs.albedo),
            ("normal", &lane_aovs.normal, &looped_aovs.normal),
        ] {
            assert!(b.iter().any(|n| *n != [0.0; 3]), "{file}: no {what}");
            let differ = worst_relative_difference(a, b);
            assert!(differ < 1e-5, "{file}: {what} differs by {differ}");
        }
        let depths = |d: &[f32]| d.iter().map(|&d| [d; 3]).collect::<Vec<_>>();
        let differ =
            worst_relative_difference(&depths(&lane_aovs.depth), &depths(&looped_aovs.depth));
        assert!(differ < 1e-5, "{file}: depth differs by {differ}");
        assert!(
            looped_hits.iter().any(|h| h.instance.is_some()),
            "{file}: no primary hits"
        );
        assert_eq!(lane_hits, looped_hits, "{file}: primary hits");
    }
}

//! Path regeneration (the CPU adapters' trace kernel, `PATH_REGENERATION` in shaders/integrator/path.wgsl) runs a
//! pixel's samples in one path loop and starts the next sample as soon as a path ends. Every sample is the same
//! path as in the sample loop GPUs run, added in the same order, so the image and the denoisers' inputs are the
//! same bit for bit. CI has only a CPU adapter, so both forms run here.

use crate::common::*;
use raykin::camera::CameraChoice;
use raykin::headless::HeadlessApp;
use raykin::render::{Environment, RenderSettings};

#[test]
fn regenerated_paths_give_the_sample_loops_image() {
    let (ctx, _gpu) = gpu();
    // The Cornell box: emitters (next-event estimation, MIS on emissive hits), Russian roulette, paths leaving
    // through its open side; with and without the denoisers' inputs (two kernels). Alpha blending: paths that
    // pass through surfaces. Attenuation: transmission and volumes (the medium a new path must not inherit).
    for (file, keep_aovs) in [
        ("CornellBox/CornellBox.glb", true),
        ("CornellBox/CornellBox.glb", false),
        (
            "AlphaBlendModeTest/glTF-Binary/AlphaBlendModeTest.glb",
            true,
        ),
        ("AttenuationTest/glTF/AttenuationTest.gltf", true),
    ] {
        let scene = shared_scene(file);
        let render = |regenerate: bool| {
            let mut form = ctx.clone();
            form.path_regeneration = regenerate;
            let settings = RenderSettings {
                width: 24,
                height: 24,
                environment: Environment::Sky,
                ..Default::default()
            };
            let mut app = HeadlessApp::new(form, scene.clone(), settings, &CameraChoice::Auto)
                .expect("scene uploads");
            app.set_keep_denoiser_inputs(keep_aovs);
            // 7 samples in dispatches of 3, 3 and 1: sample bases and counts other than the first's.
            app.accumulate(7, 3, |_| {});
            (app.radiance(), app.aovs())
        };
        let ((regenerated, regenerated_aovs), (looped, looped_aovs)) =
            (render(true), render(false));
        let what = format!("{file} (denoiser inputs kept: {keep_aovs})");
        assert_forms_render_the_same_image(&regenerated, &looped, &what);
        if keep_aovs {
            assert!(
                looped_aovs.normal.iter().any(|n| *n != [0.0; 3]),
                "{what}: no normals recorded"
            );
            assert_eq!(
                regenerated_aovs.albedo, looped_aovs.albedo,
                "{what}: albedo"
            );
            assert_eq!(
                regenerated_aovs.normal, looped_aovs.normal,
                "{what}: normal"
            );
            assert_eq!(regenerated_aovs.depth, looped_aovs.depth, "{what}: depth");
        }
    }
}

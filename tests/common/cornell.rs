//! The Mitsuba reference set-up (tests/reference/cornell/, made by make_reference.py): the Cornell box from the
//! shared assets, its classic camera, a black environment, raykin depth 8 (= Mitsuba max_depth 9), and the
//! reference's two independent 64x64 halves.

use super::{repo_root, shared_assets};
use raykin::camera::CameraChoice;
use raykin::gpu::GpuContext;
use raykin::headless::HeadlessApp;
use raykin::render::{Environment, RenderSettings};
use raykin::scene::SceneAsset;
use std::sync::Arc;

/// The reference's size.
pub const SIZE: u32 = 64;
/// raykin depth = Mitsuba max_depth - 1 (reference.json records 9).
pub const DEPTH: u32 = 8;
/// The relMSE denominator's epsilon, as in reference.json (keeps dark pixels from dominating).
pub const EPS: f64 = 1e-2;

pub fn camera() -> CameraChoice {
    CameraChoice::LookAt {
        eye: glam::Vec3::new(-278.0, 273.0, 800.0),
        target: glam::Vec3::new(-278.0, 273.0, 0.0),
        yfov: 39.3077f32.to_radians(),
    }
}

/// `size` pixels square, the reference's depth and environment.
pub fn settings(size: u32, seed: u32) -> RenderSettings {
    RenderSettings {
        width: size,
        height: size,
        max_depth: DEPTH,
        environment: Environment::Constant([0.0; 3]),
        seed,
        ..Default::default()
    }
}

/// The box as the file has it (its light double-sided).
pub fn scene() -> Arc<SceneAsset> {
    Arc::new(
        raykin::scene::load_gltf(
            shared_assets().join("CornellBox/CornellBox.glb"),
            &Default::default(),
        )
        .expect("CornellBox loads"),
    )
}

/// The box with its light double-sided (as the file has it) or single-sided.
pub fn scene_with_light(double_sided: bool) -> Arc<SceneAsset> {
    let mut scene = (*scene()).clone();
    scene.materials[0].double_sided = double_sided;
    Arc::new(scene)
}

/// The box seen from the reference's camera, `size` pixels square.
pub fn app(ctx: GpuContext, double_sided_light: bool, size: u32, seed: u32) -> HeadlessApp {
    HeadlessApp::new(
        ctx,
        scene_with_light(double_sided_light),
        settings(size, seed),
        &camera(),
    )
    .expect("the Cornell box uploads")
}

/// Mitsuba 3 with the exact glTF BRDF: the two independent halves (65536 spp each).
pub fn reference_halves() -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
    let dir = repo_root().join("tests/reference/cornell");
    let read = |name: &str| {
        let (w, h, pixels) = raykin::image_io::read_exr(&dir.join(name)).expect(name);
        assert_eq!((w, h), (SIZE, SIZE), "{name}");
        pixels
    };
    (read("cornell_64_a.exr"), read("cornell_64_b.exr"))
}

/// Per-pixel mean of two images of the same size.
pub fn mean_of(a: &[[f32; 3]], b: &[[f32; 3]]) -> Vec<[f32; 3]> {
    a.iter()
        .zip(b)
        .map(|(x, y)| [0, 1, 2].map(|c| 0.5 * (x[c] + y[c])))
        .collect()
}

/// Two estimates, each the mean of two independent halves, agree within the noise of both: the expected relMSE
/// of two unbiased estimates is the sum of their variances (Var of a mean of two halves = E[(a-b)^2] / 4, in
/// relMSE units), so the bound is that sum with a 1.5x margin for the estimate's own scatter, plus 1e-4; and
/// each channel's image mean agrees within 2%. A bias of a few percent exceeds the bound by orders of
/// magnitude. `what` names the comparison in the messages.
pub fn assert_agree_within_noise(
    what: &str,
    (a, b): (&[[f32; 3]], &[[f32; 3]]),
    (ra, rb): (&[[f32; 3]], &[[f32; 3]]),
) {
    use super::{mean_rgb, rel_mse};
    let (ours, reference) = (mean_of(a, b), mean_of(ra, rb));
    let ours_noise = rel_mse(a, b, EPS) / 4.0;
    let ref_noise = rel_mse(ra, rb, EPS) / 4.0;
    let measured = rel_mse(&ours, &reference, EPS);
    let bound = 1.5 * (ours_noise + ref_noise) + 1e-4;
    let (mo, mr) = (mean_rgb(&ours), mean_rgb(&reference));
    eprintln!(
        "{what}: relMSE vs reference {measured:.3e}; noise ours {ours_noise:.3e} ref {ref_noise:.3e}; bound {bound:.3e}; mean ours {mo:?} ref {mr:?}"
    );
    super::assert_channel_means_within(what, mo, mr, 0.02);
    assert!(
        measured < bound,
        "{what}: relMSE {measured:.3e} exceeds the noise bound {bound:.3e}"
    );
}

/// The log-log slope of relative RMSE against spp (4 to 64) of `settings(7)`'s accumulation, against a
/// reference of two independent 512-spp halves (`settings(100)`, `settings(200)`) whose own noise is
/// subtracted; with the measured points, for the messages. -0.5 is the Monte Carlo rate of a finite-variance
/// estimator.
pub fn convergence_slope(
    ctx: &GpuContext,
    scene: Arc<SceneAsset>,
    settings: impl Fn(u32) -> RenderSettings,
    camera: &CameraChoice,
) -> (f64, Vec<(f64, f64)>) {
    use super::{assert_all_finite, log_log_slope, rel_mse, render};
    let half_a = render(ctx, &scene, settings(100), camera, 512);
    let half_b = render(ctx, &scene, settings(200), camera, 512);
    let reference = mean_of(&half_a, &half_b);
    let reference_noise = rel_mse(&half_a, &half_b, EPS) / 4.0;
    let mut app = HeadlessApp::new(ctx.clone(), scene, settings(7), camera).unwrap();
    let mut points = Vec::new();
    let mut done = 0;
    for spp in [4u32, 8, 16, 32, 64] {
        app.accumulate(spp - done, 64, |_| {});
        done = spp;
        let img = app.radiance();
        assert_all_finite(&img, "convergence render");
        let rmse = (rel_mse(&img, &reference, EPS) - reference_noise)
            .max(1e-12)
            .sqrt();
        points.push((spp as f64, rmse));
    }
    eprintln!("rel RMSE vs spp {points:?}, reference noise {reference_noise:.2e}");
    (log_log_slope(&points), points)
}

/// The reference: the mean of its halves.
pub fn reference() -> Vec<[f32; 3]> {
    let (a, b) = reference_halves();
    mean_of(&a, &b)
}

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

/// The reference: the mean of its halves.
pub fn reference() -> Vec<[f32; 3]> {
    let (a, b) = reference_halves();
    mean_of(&a, &b)
}

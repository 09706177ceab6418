//! Every asset under ../shared/assets loads without error (all variants: .gltf with external or embedded
//! buffers, .glb), and every static one renders a finite, non-black image.

use crate::common::*;
use raykin::camera::CameraChoice;
use raykin::render::{Environment, RenderSettings};
use std::sync::Arc;

#[test]
fn every_asset_loads_and_every_static_one_renders() {
    let files = gltf_files_under(&shared_assets());
    assert!(
        files.len() >= 20,
        "expected the shared assets beside the repo, found {}",
        files.len()
    );
    let (ctx, _gpu) = gpu();
    let mut rendered = 0;
    for path in &files {
        let scene =
            raykin::scene::load_gltf(path, &Default::default()).unwrap_or_else(|e| panic!("{e}"));
        assert!(scene.triangle_count() > 0, "{}", path.display());
        let is_static = scene.skins.is_empty() && scene.animations.is_empty();
        if !is_static {
            continue;
        }
        let settings = RenderSettings {
            width: 16,
            height: 16,
            max_depth: 2,
            environment: Environment::Sky,
            ..Default::default()
        };
        let img = render(&ctx, &Arc::new(scene), settings, &CameraChoice::Auto, 1);
        assert_all_finite(&img, &path.display().to_string());
        let mean = mean_rgb(&img);
        assert!(
            mean.iter().sum::<f64>() > 0.01,
            "{}: black image",
            path.display()
        );
        rendered += 1;
    }
    eprintln!(
        "{} files loaded, {rendered} static ones rendered",
        files.len()
    );
    assert!(rendered >= 13);
}

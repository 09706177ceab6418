//! Shared by the denoiser tests (svgf: tests/engine/denoise.rs, OIDN: tests/engine/oidn.rs): the edge measure
//! with its blind-blur control, and the checker-textured scene.

use raykin::camera::CameraChoice;
use raykin::gpu::GpuContext;
use raykin::headless::HeadlessApp;
use raykin::render::{Environment, RenderSettings};
use raykin::scene::{Image, Material, NodeTransform, SceneAsset, Texture, TextureRef, procedural};
use std::sync::Arc;

pub fn luminance(c: [f32; 3]) -> f64 {
    0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64
}

/// A 5x5 box blur that knows nothing of edges: the control that shows an edge metric can fail.
pub fn box_blur(img: &[[f32; 3]], size: u32) -> Vec<[f32; 3]> {
    let s = size as i32;
    (0..s * s)
        .map(|i| {
            let (x, y) = (i % s, i / s);
            let mut sum = [0.0f32; 3];
            let mut n = 0.0;
            for dy in -2..=2 {
                for dx in -2..=2 {
                    let (qx, qy) = (x + dx, y + dy);
                    if qx >= 0 && qy >= 0 && qx < s && qy < s {
                        let q = img[(qy * s + qx) as usize];
                        (0..3).for_each(|c| sum[c] += q[c]);
                        n += 1.0;
                    }
                }
            }
            sum.map(|v| v / n)
        })
        .collect()
}

/// Mean absolute luminance difference across the given pixel pairs.
pub fn edge_contrast(img: &[[f32; 3]], pairs: &[(usize, usize)]) -> f64 {
    pairs
        .iter()
        .map(|&(a, b)| (luminance(img[a]) - luminance(img[b])).abs())
        .sum::<f64>()
        / pairs.len() as f64
}

pub struct EdgeImages<'a> {
    pub reference: &'a [[f32; 3]],
    pub noisy: &'a [[f32; 3]],
    pub denoised: &'a [[f32; 3]],
    pub size: u32,
}

/// The denoised contrast across `pairs` is within `bound` of the reference's, while a blind 5x5 blur of the
/// noisy input loses at least 20% of it (the metric can see blur).
pub fn assert_edges_kept(what: &str, pairs: &[(usize, usize)], images: &EdgeImages, bound: f64) {
    let expected = edge_contrast(images.reference, pairs);
    let ratio = |img: &[[f32; 3]]| edge_contrast(img, pairs) / expected;
    let denoised = ratio(images.denoised);
    let blurred = ratio(&box_blur(images.noisy, images.size));
    eprintln!(
        "{} {what} pairs: contrast / reference: denoised {denoised:.3}, noisy {:.3}, 5x5 blur {blurred:.3}",
        pairs.len(),
        ratio(images.noisy)
    );
    assert!(
        (denoised - 1.0).abs() < bound,
        "{what}s: denoised contrast is {denoised:.3} of the reference's"
    );
    assert!(
        blurred < 0.8,
        "control: a blind blur keeps {blurred:.3} of the {what} contrast; the metric cannot see blur"
    );
}

/// Horizontally and vertically adjacent pixel pairs for which `is_edge` holds.
pub fn adjacent_pairs(
    size: u32,
    mut is_edge: impl FnMut(usize, usize) -> bool,
) -> Vec<(usize, usize)> {
    let s = size as usize;
    let mut pairs = Vec::new();
    for y in 0..s {
        for x in 0..s {
            let i = y * s + x;
            if x + 1 < s && is_edge(i, i + 1) {
                pairs.push((i, i + 1));
            }
            if y + 1 < s && is_edge(i, i + s) {
                pairs.push((i, i + s));
            }
        }
    }
    pairs
}

/// A checker-textured plane (7:1 albedo contrast, nearest filtering) with a sphere on it, under a sky.
pub fn checker_scene() -> Arc<SceneAsset> {
    let checks = 8;
    let mut rgba8 = Vec::new();
    for y in 0..checks {
        for x in 0..checks {
            let v = if (x + y) % 2 == 0 { 220 } else { 90 };
            rgba8.extend_from_slice(&[v, v, v, 255]);
        }
    }
    let plane = Material {
        name: "checker".into(),
        base_color_texture: Some(TextureRef::new(0, 0)),
        metallic: 0.0,
        roughness: 0.8,
        ..Default::default()
    };
    let ball = Material {
        name: "ball".into(),
        base_color: glam::Vec4::new(0.8, 0.8, 0.8, 1.0),
        metallic: 0.0,
        roughness: 0.5,
        ..Default::default()
    };
    let sphere_at = NodeTransform {
        translation: glam::Vec3::new(0.6, 0.5, 0.0),
        ..Default::default()
    };
    let mut scene = procedural::scene_from_meshes(
        "checker plane",
        vec![
            (procedural::ground_quad(4.0, 0), NodeTransform::default()),
            (procedural::uv_sphere(0.5, 32, 16, 1), sphere_at),
        ],
        vec![plane, ball],
    );
    scene.images.push(Image {
        name: "checker".into(),
        width: checks,
        height: checks,
        rgba8,
    });
    scene.textures.push(Texture {
        image: 0,
        wrap_s: Default::default(),
        wrap_t: Default::default(),
        nearest: true,
    });
    Arc::new(scene)
}

pub const CHECKER_SIZE: u32 = 32;

pub fn checker_settings(seed: u32) -> RenderSettings {
    RenderSettings {
        width: CHECKER_SIZE,
        height: CHECKER_SIZE,
        max_depth: 3,
        environment: Environment::Sky,
        seed,
        ..Default::default()
    }
}

pub fn checker_camera() -> CameraChoice {
    CameraChoice::LookAt {
        eye: glam::Vec3::new(0.0, 1.6, 2.8),
        target: glam::Vec3::new(0.2, 0.3, 0.0),
        yfov: 40f32.to_radians(),
    }
}

/// `scene` (the checker scene) seen from [`checker_camera`] at [`checker_settings`]`(seed)`.
pub fn checker_app(ctx: GpuContext, scene: &Arc<SceneAsset>, seed: u32) -> HeadlessApp {
    HeadlessApp::new(
        ctx,
        scene.clone(),
        checker_settings(seed),
        &checker_camera(),
    )
    .expect("uploads")
}

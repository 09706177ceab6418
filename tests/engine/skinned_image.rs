//! GPU (tiny images): a skinned CesiumMan posed at T renders like a static mesh built from the reference's
//! skinned positions, `--time` is deterministic, and accumulation does not ghost after a pose change.

use crate::common::gpu_context as gpu;
use crate::common::repo_root;

use glam::Vec3;
use raykin::camera::CameraChoice;
use raykin::gpu_deform::DeformBackend;
use raykin::headless::HeadlessApp;
use raykin::render::{Environment, RenderSettings};
use raykin::scene::{LoadOptions, NodeTransform, SceneAsset, load_gltf, procedural};
use serde_json::Value;
use std::sync::Arc;

const SIZE: u32 = 40;
const SPP: u32 = 8;

fn settings() -> RenderSettings {
    RenderSettings {
        width: SIZE,
        height: SIZE,
        spp_per_frame: SPP,
        max_depth: 3,
        environment: Environment::Sky,
        seed: 7,
        ..Default::default()
    }
}

fn cesium() -> Arc<SceneAsset> {
    Arc::new(
        load_gltf(
            repo_root().join("../shared/assets/CesiumMan/glTF-Binary/CesiumMan.glb"),
            &LoadOptions::default(),
        )
        .unwrap(),
    )
}

fn camera() -> CameraChoice {
    // CesiumMan stands about 1.5 units tall on the XZ plane after its Z_UP node.
    CameraChoice::LookAt {
        eye: Vec3::new(0.0, 0.8, 3.2),
        target: Vec3::new(0.0, 0.75, 0.0),
        yfov: 40f32.to_radians(),
    }
}

fn render(scene: Arc<SceneAsset>, pose: Option<(usize, f32)>) -> Vec<[f32; 3]> {
    render_with(scene, pose, DeformBackend::Auto)
}

fn render_with(
    scene: Arc<SceneAsset>,
    pose: Option<(usize, f32)>,
    deform: DeformBackend,
) -> Vec<[f32; 3]> {
    let settings = RenderSettings {
        deform,
        ..settings()
    };
    let mut app = HeadlessApp::new(gpu(), scene, settings, &camera()).unwrap();
    if let Some((clip, t)) = pose {
        app.set_time(clip, t).unwrap();
    }
    app.accumulate(SPP, SPP, |_| {});
    let r = app.radiance();
    assert!(r.iter().flatten().all(|v| v.is_finite()));
    r
}

fn mean_abs_diff(a: &[[f32; 3]], b: &[[f32; 3]]) -> (f64, f64) {
    let d: f64 = a
        .iter()
        .zip(b)
        .flat_map(|(x, y)| (0..3).map(move |k| (x[k] - y[k]).abs() as f64))
        .sum();
    let m: f64 = a.iter().flatten().map(|v| v.abs() as f64).sum();
    let n = (a.len() * 3) as f64;
    (d / n, m / n)
}

#[test]
fn skinned_cesium_man_matches_static_reference_mesh() {
    // The device's lock: these tests compile pipelines, which other tests count.
    let _device = crate::common::gpu().1;
    let fixtures: Value = serde_json::from_str(
        &std::fs::read_to_string(repo_root().join("tests/reference/skinning/fixtures.json"))
            .unwrap(),
    )
    .unwrap();
    let case = fixtures["cases"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| {
            c["asset"].as_str().unwrap().contains("CesiumMan")
                && c["note"].as_str().unwrap_or("").contains("between")
        })
        .or_else(|| {
            fixtures["cases"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|c| c["asset"].as_str().unwrap().contains("CesiumMan"))
                .nth(2)
        })
        .unwrap();
    let time = case["time"].as_f64().unwrap() as f32;
    let scene = cesium();

    // Engine: skinned on the CPU, uploaded into the vertex pool, refit, drawn with an identity instance.
    let skinned = render(scene.clone(), Some((0, time)));

    // Reference: a static mesh at identity holding the numpy reference's world-space vertices (the fixture
    // stores every 2nd vertex; the others, and the normals, come from the engine's CPU skinning, which the
    // fixture tests check against the reference).
    let mut posed = raykin::animation::cpu_app(scene.clone());
    {
        let world = posed.world_mut();
        let root = world.query_filtered::<bevy_ecs::entity::Entity, bevy_ecs::query::With<raykin::scene::SceneRoot>>().single(world).unwrap();
        world
            .entity_mut(root)
            .insert(raykin::animation::AnimationPlayer::paused_at(0, time));
    }
    posed.update();
    let node = &case["nodes"][0];
    let n = node["node"].as_u64().unwrap() as usize;
    let mesh_index = scene.nodes[n].mesh.unwrap();
    let deformed = posed
        .world()
        .resource::<raykin::animation::DeformedMeshes>()
        .meshes[mesh_index]
        .clone()
        .unwrap();
    let mut mesh = scene.meshes[mesh_index].clone();
    mesh.positions = deformed.positions.clone();
    let range = &mesh.primitives[0];
    let prim = &node["primitives"][0];
    for (v, p) in prim["vertex_indices"]
        .as_array()
        .unwrap()
        .iter()
        .zip(prim["positions"].as_array().unwrap())
    {
        let p: Vec<f32> = p
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap() as f32)
            .collect();
        mesh.positions[range.vertex_offset as usize + v.as_u64().unwrap() as usize] =
            Vec3::new(p[0], p[1], p[2]);
    }
    mesh.normals = deformed.normals.clone();
    mesh.tangents = deformed.tangents.clone();
    mesh.skin_weights = None;
    let mut reference = procedural::scene_from_meshes(
        "static CesiumMan",
        vec![(mesh, NodeTransform::default())],
        scene.materials.clone(),
    );
    reference.images = scene.images.clone();
    reference.textures = scene.textures.clone();
    let fixed = render(Arc::new(reference), None);

    let (diff, mean) = mean_abs_diff(&skinned, &fixed);
    eprintln!("skinned vs static reference: mean |diff| {diff:.5}, mean {mean:.5}");
    assert!(mean > 0.01);
    assert!(diff < 0.01 * mean, "mean |diff| {diff} vs mean {mean}");

    // And the pose differs visibly from the rest pose (so the comparison is not vacuous).
    let rest = render(scene.clone(), None);
    let (rest_diff, _) = mean_abs_diff(&skinned, &rest);
    assert!(
        rest_diff > 5.0 * diff.max(1e-4),
        "rest {rest_diff} vs {diff}"
    );
}

#[test]
fn same_time_same_image_and_no_ghosting() {
    let _device = crate::common::gpu().1;
    let scene = cesium();
    let a = render(scene.clone(), Some((0, 1.0)));
    let b = render(scene.clone(), Some((0, 1.0)));
    assert_eq!(a, b, "the same --time and seed give the same image");

    // Accumulate at one pose, move to another: the result equals a fresh render of the new pose.
    let mut app = HeadlessApp::new(gpu(), scene.clone(), settings(), &camera()).unwrap();
    app.set_time(0, 0.3).unwrap();
    app.accumulate(SPP, SPP, |_| {});
    app.set_time(0, 1.0).unwrap();
    app.accumulate(SPP, SPP, |_| {});
    assert_eq!(
        app.samples(),
        SPP,
        "accumulation restarted on the pose change"
    );
    let moved = app.radiance();
    let (ghost, mean) = mean_abs_diff(&moved, &a);
    eprintln!("ghosting: mean |diff| {ghost:.6} (mean {mean:.4})");
    assert!(ghost <= 1e-3 * mean, "ghosting {ghost}");
}

/// The GPU deform + refit passes and the CPU reference give the same image (same seed), and the GPU
/// path is as reproducible as the CPU path.
#[test]
fn gpu_and_cpu_deformation_render_the_same_image() {
    let _device = crate::common::gpu().1;
    let scene = cesium();
    for t in [0.4, 1.3] {
        let cpu = render_with(scene.clone(), Some((0, t)), DeformBackend::Cpu);
        let gpu_a = render_with(scene.clone(), Some((0, t)), DeformBackend::Gpu);
        let gpu_b = render_with(scene.clone(), Some((0, t)), DeformBackend::Gpu);
        assert_eq!(gpu_a, gpu_b, "t={t}: the GPU path is deterministic");
        let (diff, mean) = mean_abs_diff(&gpu_a, &cpu);
        eprintln!("t={t}: GPU vs CPU deformation: mean |diff| {diff:.6} (mean {mean:.4})");
        assert!(mean > 0.01);
        assert!(
            diff <= 1e-3 * mean,
            "t={t}: mean |diff| {diff} vs mean {mean}"
        );
    }
}

/// A deforming mesh traced through its wide tree (collapsed from its BVH2, re-quantised at every refit) gives
/// the image its BVH2 gives, on either deformation backend, refit from the rest pose's trees (no rebuild) or
/// (on the CPU backend) rebuilt for the pose: the same triangles in the same order, so with the same seed every path takes the same
/// hits, but for equal-distance ties (a stray pixel at most). A wide box that lost a triangle shows as a hole,
/// far more.
#[test]
fn wide_and_binary_trees_of_deforming_meshes_render_the_same_image() {
    let _device = crate::common::gpu().1;
    let scene = cesium();
    for (deform, rebuild) in [
        (DeformBackend::Cpu, true),
        (DeformBackend::Cpu, false),
        // The GPU backend's rebuilds land frames later (tests/engine/gpu_deform.rs checks their wide trees).
        (DeformBackend::Gpu, false),
    ] {
        for t in [0.4, 1.3] {
            let image = |wide: bool| {
                let mut ctx = gpu();
                ctx.wide_deformed = wide;
                let settings = RenderSettings {
                    deform,
                    ..settings()
                };
                let mut app = HeadlessApp::new(ctx, scene.clone(), settings, &camera()).unwrap();
                assert_eq!(app.gpu_scene().has_wide_deformed(), wide);
                if !rebuild {
                    app.app
                        .world_mut()
                        .resource_mut::<raykin::bvh::refit::BvhStats>()
                        .threshold = f32::INFINITY;
                }
                app.set_time(0, t).unwrap();
                app.accumulate(SPP, SPP, |_| {});
                let rebuilds = app.bvh_stats().rebuilds;
                assert_eq!(
                    rebuilds > 0,
                    rebuild,
                    "{deform:?} t={t}: {rebuilds} rebuilds"
                );
                app.radiance()
            };
            let (wide, binary) = (image(true), image(false));
            let differing = wide.iter().zip(&binary).filter(|(a, b)| a != b).count();
            let (diff, mean) = mean_abs_diff(&wide, &binary);
            eprintln!(
                "{deform:?} rebuild {rebuild} t={t}: wide vs BVH2: {differing} of {} pixels differ, mean |diff| {diff:.2e} (mean {mean:.4})",
                wide.len()
            );
            assert!(mean > 0.01);
            assert!(
                differing * 200 <= wide.len(),
                "{deform:?} t={t}: {differing} pixels differ"
            );
            assert!(
                diff <= 1e-3 * mean,
                "{deform:?} t={t}: mean |diff| {diff} vs mean {mean}"
            );
        }
    }
}

#[test]
fn time_on_scene_without_animation_is_an_error() {
    let _device = crate::common::gpu().1;
    let scene = Arc::new(procedural::scene_from_meshes(
        "quad",
        vec![(procedural::ground_quad(1.0, 0), NodeTransform::default())],
        vec![Default::default()],
    ));
    let mut app = HeadlessApp::new(gpu(), scene, settings(), &camera()).unwrap();
    let e = app.set_time(0, 1.0).unwrap_err();
    assert!(e.contains("no animations"), "{e}");
}

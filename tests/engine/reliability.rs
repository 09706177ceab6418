//! Issue 18, the library side: no panic, no silent wrong image and no unbounded read under malformed input.
//! The malformed corpus (tests/fixtures/malformed, hand-made cases and fuzzer findings) runs whole: every
//! file is a clear error naming it, or loads and renders finite, non-negative pixels. The other tests check
//! what each case must say or draw.

use crate::common::*;
use raykin::camera::CameraChoice;
use raykin::gpu_deform::DeformBackend;
use raykin::render::{Environment, RenderSettings};
use raykin::scene::{LoadOptions, MeshInstance, SceneAsset, SceneError, load_gltf};
use std::path::{Path, PathBuf};
use std::sync::Arc;

fn corpus() -> PathBuf {
    repo_root().join("tests/fixtures/malformed")
}

fn load_with(name: &str, options: &LoadOptions) -> Result<SceneAsset, SceneError> {
    load_gltf(corpus().join(name), options)
}

fn load(name: &str) -> Result<SceneAsset, SceneError> {
    load_with(name, &LoadOptions::default())
}

fn error_of(name: &str) -> String {
    let err = load(name)
        .err()
        .unwrap_or_else(|| panic!("{name} must not load"));
    let msg = err.to_string();
    assert!(
        msg.contains(name),
        "the error does not name the file: {msg}"
    );
    assert!(
        !matches!(err, SceneError::Internal { .. }),
        "a decoder panicked: {msg}"
    );
    msg
}

/// Loads `name` and returns its warnings, which must include one containing every word of `words`.
fn warnings_of(name: &str, words: &[&str]) -> (SceneAsset, Vec<String>) {
    let scene = load(name).unwrap_or_else(|e| panic!("{name} must load: {e}"));
    let warnings = scene.warnings.clone();
    assert!(
        warnings
            .iter()
            .any(|w| words.iter().all(|word| w.contains(word))),
        "{name}: no warning with {words:?}: {warnings:?}"
    );
    (scene, warnings)
}

fn tiny_settings() -> RenderSettings {
    RenderSettings {
        width: 16,
        height: 16,
        max_depth: 2,
        environment: Environment::Sky,
        ..Default::default()
    }
}

fn assert_physical(img: &[[f32; 3]], what: &str) {
    assert_all_finite(img, what);
    let negative = img.iter().flatten().filter(|v| **v < 0.0).count();
    assert_eq!(negative, 0, "{what}: {negative} negative pixel values");
}

#[test]
fn malformed_corpus_is_a_clear_error_or_a_clean_render() {
    let (ctx, _gpu) = gpu();
    let mut files: Vec<PathBuf> = std::fs::read_dir(corpus())
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")))
        .collect();
    files.sort();
    assert!(files.len() >= 30, "the corpus is missing: {}", files.len());
    let mut failures = Vec::new();
    let (mut refused, mut rendered) = (0, 0);
    for file in &files {
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        let scene = match load_gltf(file, &LoadOptions::default()) {
            Err(SceneError::Internal { message, .. }) => {
                failures.push(format!("{name}: decoder panic: {message}"));
                continue;
            }
            Err(e) if !e.to_string().contains(&name) => {
                failures.push(format!("{name}: the error does not name the file: {e}"));
                continue;
            }
            Err(_) => {
                refused += 1;
                continue;
            }
            Ok(scene) => Arc::new(scene),
        };
        // What `raykin render` checks before the GPU: these refusals must name the file too.
        if let Err(e) = raykin::camera::check_camera_choice(&scene, &CameraChoice::Auto) {
            if !e.to_string().contains(&name) {
                failures.push(format!("{name}: camera error without the file: {e}"));
            }
            refused += 1;
            continue;
        }
        let app = raykin::headless::HeadlessApp::new(
            ctx.clone(),
            scene,
            tiny_settings(),
            &CameraChoice::Auto,
        );
        let mut app = match app {
            Ok(app) => app,
            Err(e) => {
                failures.push(format!("{name}: loads but does not upload: {e}"));
                continue;
            }
        };
        app.accumulate(2, 2, |_| {});
        let img = app.radiance();
        let bad = img
            .iter()
            .flatten()
            .filter(|v| !v.is_finite() || **v < 0.0)
            .count();
        if bad > 0 {
            failures.push(format!("{name}: {bad} non-finite or negative pixel values"));
        }
        rendered += 1;
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(
        refused > 0 && rendered > 0,
        "{refused} refused, {rendered} rendered"
    );
}

/// Each input the gltf crate used to panic on (reported as Rust internals) is now an error naming the
/// problem, or the broken piece is skipped with a warning while the rest loads.
#[test]
fn gltf_crate_panic_paths_are_clear_errors_or_skipped_pieces() {
    warnings_of(
        "stride_smaller_than_element.gltf",
        &["primitive 1 skipped", "byteStride 4"],
    );
    warnings_of(
        "indices_float.gltf",
        &["primitive 1 skipped", "indices", "SCALAR FLOAT"],
    );
    let (scene, _) = warnings_of("joints_float.gltf", &["JOINTS_0", "ignored"]);
    assert!(scene.meshes[0].skin_weights.is_none());
    let msg = error_of("position_accessor_out_of_range.gltf");
    assert!(msg.contains("POSITION names accessor 99"), "{msg}");
    let msg = error_of("normal_accessor_out_of_range.gltf");
    assert!(msg.contains("accessor 99"), "{msg}");
    let (scene, _) = warnings_of(
        "image_without_source.gltf",
        &["image 0", "neither a uri nor a bufferView"],
    );
    assert!(scene.materials[0].base_color_texture.is_none());
    let (scene, _) = warnings_of(
        "animation_target_node_out_of_range.gltf",
        &["channel 0", "node 7", "skipped"],
    );
    assert!(scene.animations[0].channels.is_empty());
    warnings_of(
        "animation_unknown_path.gltf",
        &["channel 0", "property", "skipped"],
    );
    warnings_of(
        "animation_rotation_as_vec3.gltf",
        &["channel 0", "keyframe values", "VEC4"],
    );
    // The only primitive is unreadable: nothing is left to render, and the error says why.
    assert!(error_of("accessor_count_zero.gltf").contains("count 0"));
    assert!(error_of("accessor_count_2_62.gltf").contains("lies outside"));
    assert!(error_of("sparse_count_over_count.gltf").contains("sparse count 9"));
    warnings_of("camera_type_mismatch.gltf", &["camera 0", "orthographic"]);
    warnings_of(
        "image_view_without_mime_type.gltf",
        &["image 0", "mimeType"],
    );
}

/// A POSITION accessor of another format used to be read as float VEC3 (garbage geometry).
#[test]
fn position_of_the_wrong_format_is_refused() {
    for (file, format) in [
        ("position_vec2_float.gltf", "VEC2 FLOAT"),
        ("position_scalar_float.gltf", "SCALAR FLOAT"),
        ("position_mat4_float.gltf", "MAT4 FLOAT"),
        ("position_vec3_ubyte.gltf", "VEC3 UNSIGNED_BYTE"),
    ] {
        let (scene, _) = warnings_of(file, &["primitive 1 skipped", "POSITION", format]);
        assert_eq!(
            scene.triangle_count(),
            2,
            "{file}: only the valid quad loads"
        );
    }
}

#[test]
fn asset_versions_other_than_2_x_are_refused() {
    assert!(error_of("version_3_0.gltf").contains("asset.version is 3.0"));
    assert!(error_of("version_1_0.gltf").contains("not a glTF 2.x file"));
    assert!(error_of("version_2_0_min_2_1.gltf").contains("greater than asset.version"));
    assert!(error_of("version_2_1_min_2_1.gltf").contains("minVersion is 2.1"));
    // A later 2.x without minVersion loads: minor versions are backward compatible.
    let mut doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(corpus().join("negative_base_color.gltf")).unwrap())
            .unwrap();
    doc["asset"]["version"] = "2.1".into();
    let file = std::env::temp_dir().join(format!("raykin-v21-{}.gltf", std::process::id()));
    std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
    load_gltf(&file, &LoadOptions::default()).expect("glTF 2.1 without minVersion loads");
}

/// Mesh instances an app spawns for `scene`, by mesh index.
fn drawn_meshes(scene: SceneAsset) -> Vec<usize> {
    let mut app = raykin::animation::cpu_app(Arc::new(scene));
    app.update();
    let world = app.world_mut();
    let mut meshes: Vec<usize> = world
        .query::<&MeshInstance>()
        .iter(world)
        .map(|m| m.mesh)
        .collect();
    meshes.sort();
    meshes
}

/// The Khronos MultipleScenes model: scene 0 holds node 0 (mesh 0), scene 1 (the default) node 1 (mesh 1).
#[test]
fn only_the_chosen_scene_is_drawn() {
    let file = shared_assets().join("MultipleScenes/glTF/MultipleScenes.gltf");
    let with = |scene: Option<usize>| {
        load_gltf(
            &file,
            &LoadOptions {
                scene,
                ..Default::default()
            },
        )
    };
    assert_eq!(
        drawn_meshes(with(None).unwrap()),
        vec![1],
        "the default scene"
    );
    assert_eq!(drawn_meshes(with(Some(0)).unwrap()), vec![0]);
    assert_eq!(drawn_meshes(with(Some(1)).unwrap()), vec![1]);
    let scene = with(Some(0)).unwrap();
    let (lo, hi) = scene.rest_bounds().unwrap();
    let only = &scene.meshes[0].bounds();
    assert!((lo - only.0).abs().max_element() < 1e-5 && (hi - only.1).abs().max_element() < 1e-5);
    let msg = with(Some(5)).unwrap_err().to_string();
    assert!(
        msg.contains("MultipleScenes.gltf")
            && msg.contains("no scene 5")
            && msg.contains("2 scene(s)"),
        "{msg}"
    );
    let msg = error_of("empty_default_scene.gltf");
    assert!(
        msg.contains("scene 0 `empty`") && msg.contains("1 `full`") && msg.contains("--scene"),
        "{msg}"
    );
    let scene = load_with(
        "empty_default_scene.gltf",
        &LoadOptions {
            scene: Some(1),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(drawn_meshes(scene), vec![0]);
}

#[test]
fn a_camera_of_scale_zero_is_a_clear_error_not_a_black_image() {
    let (ctx, _gpu) = gpu();
    let (scene, _) = warnings_of("camera_zero_scale.gltf", &["singular"]);
    let scene = Arc::new(scene);
    let msg = raykin::camera::check_camera_choice(&scene, &CameraChoice::Auto)
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("camera_zero_scale.gltf") && msg.contains("singular"),
        "{msg}"
    );
    let err =
        raykin::headless::HeadlessApp::new(ctx, scene, tiny_settings(), &CameraChoice::Index(0))
            .err()
            .expect("the renderer refuses the camera too");
    assert!(err.to_string().contains("singular"), "{err}");
}

#[test]
fn non_physical_materials_are_clamped_with_a_warning_and_render_clean() {
    let (ctx, _gpu) = gpu();
    let (scene, _) = warnings_of("negative_base_color.gltf", &["baseColorFactor", "clamped"]);
    assert!(scene.materials[0].base_color.min_element() >= 0.0);
    let img = render(
        &ctx,
        &Arc::new(scene),
        tiny_settings(),
        &CameraChoice::Auto,
        4,
    );
    assert_physical(&img, "negative base colour");
    for file in ["emissive_3e38.gltf", "emissive_strength_1e38.gltf"] {
        let (scene, _) = warnings_of(file, &["emitted radiance", "capped"]);
        let settings = RenderSettings {
            environment: Environment::Constant([0.0; 3]),
            ..tiny_settings()
        };
        let img = render(&ctx, &Arc::new(scene), settings, &CameraChoice::Auto, 2);
        assert_physical(&img, file);
        // The camera frames the emitting quad: its centre pixel sees the capped emitter, not black.
        let centre = img[8 * 16 + 8];
        assert!(
            centre.iter().all(|c| *c > 1e6),
            "{file}: the emitter renders {centre:?}"
        );
    }
}

/// A skin with no joints vanished under `--deform gpu` while the CPU path drew it rigidly: now the loader
/// detaches it, and both paths draw the same rigid quad.
#[test]
fn a_skin_without_joints_draws_the_same_rigid_mesh_on_both_deform_paths() {
    let (ctx, _gpu) = gpu();
    let (scene, _) = warnings_of("skin_zero_joints.gltf", &["skin 0 has no joints"]);
    assert!(scene.nodes[0].skin.is_none() && scene.meshes[0].skin_weights.is_none());
    let scene = Arc::new(scene);
    let image = |deform| {
        let settings = RenderSettings {
            deform,
            environment: Environment::Constant([1.0; 3]),
            max_depth: 0,
            ..tiny_settings()
        };
        render(&ctx, &scene, settings, &CameraChoice::Auto, 1)
    };
    let (cpu, gpu) = (image(DeformBackend::Cpu), image(DeformBackend::Gpu));
    // With depth 0 a pixel is the environment (1) where it misses and black where it hits the quad.
    let covered = |img: &[[f32; 3]]| img.iter().filter(|p| p[0] < 0.5).count();
    assert!(covered(&cpu) > 16, "the quad is drawn on the CPU path");
    assert_eq!(
        covered(&cpu),
        covered(&gpu),
        "both paths draw the same quad"
    );
}

#[test]
fn reads_are_confined_to_the_scene_folder_and_bounded() {
    let msg = error_of("buffer_dev_zero.gltf");
    assert!(
        msg.contains("absolute path") && msg.contains("--allow-external-files"),
        "{msg}"
    );
    let msg = error_of("buffer_escapes_folder.gltf");
    assert!(msg.contains("outside the scene's folder"), "{msg}");
    let msg = error_of("buffer_file_scheme.gltf");
    assert!(msg.contains("scheme `file:`"), "{msg}");
    warnings_of("image_absolute_path.gltf", &["image 0", "absolute path"]);
    let msg = error_of("buffer_byte_length_1tib.gltf");
    assert!(msg.contains("truncated"), "{msg}");
    // Trusted: the path is allowed, but a device is still not a file.
    let trusted = LoadOptions {
        allow_external_files: true,
        ..Default::default()
    };
    let msg = load_with("buffer_dev_zero.gltf", &trusted)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("not a regular file"), "{msg}");

    // A buffer file longer than byteLength is read that far; a shorter one is an error.
    let dir = std::env::temp_dir().join(format!("raykin-bounded-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let source = shared_assets().join("Box/glTF");
    std::fs::copy(source.join("Box.gltf"), dir.join("Box.gltf")).unwrap();
    let bin = std::fs::read(source.join("Box0.bin")).unwrap();
    let mut longer = bin.clone();
    longer.extend(std::iter::repeat_n(0xAB, 1 << 20));
    std::fs::write(dir.join("Box0.bin"), &longer).unwrap();
    let scene = load_gltf(dir.join("Box.gltf"), &LoadOptions::default()).unwrap();
    assert_eq!(scene.triangle_count(), 12);
    let names: Vec<String> = scene
        .files
        .iter()
        .map(|f| f.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names,
        ["Box.gltf", "Box0.bin"],
        "the files the scene was read from"
    );
    std::fs::write(dir.join("Box0.bin"), &bin[..bin.len() - 1]).unwrap();
    let msg = load_gltf(dir.join("Box.gltf"), &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("Box0.bin") && msg.contains("truncated"),
        "{msg}"
    );
}

/// A scene file that is not a regular file (a FIFO would block, a device never ends).
#[cfg(unix)]
#[test]
fn the_scene_itself_must_be_a_regular_file() {
    let err = load_gltf(Path::new("/dev/zero"), &LoadOptions::default()).unwrap_err();
    assert!(err.to_string().contains("not a regular file"), "{err}");
}

/// Geometry about 1e19 units wide made obvhs's wide-BVH conversion panic; the build now clamps it to the
/// 1e16 cube (whatever can be rendered in f32 lies inside) and gets a tree with finite bounds.
#[test]
fn enormous_geometry_builds_a_bvh() {
    let scene = load("geometry_1e19.gltf").unwrap();
    let mesh = &scene.meshes[0];
    let blas = raykin::bvh::Blas::build(
        &mesh.positions,
        &mesh.triangles,
        raykin::bvh::BvhQuality::Medium,
        raykin::bvh::StaticLayout::Wide,
        false,
        false,
    )
    .unwrap();
    let (lo, hi) = blas.root_bounds();
    assert!(lo.is_finite() && hi.is_finite(), "{lo} {hi}");
}

/// A primitive's positions and triangle indices.
type Primitive = (Vec<[f32; 3]>, Vec<u32>);

/// A square frame (outer half-size 1, inner 0.8) as 8 vertices and 8 triangles, scaled by `s` in x and y.
fn frame(s: f32) -> Primitive {
    let mut p = Vec::new();
    for r in [1.0f32, 0.8] {
        p.extend(
            [[-r, -r, 0.0], [r, -r, 0.0], [r, r, 0.0], [-r, r, 0.0]]
                .map(|v| [v[0] * s, v[1] * s, 0.0]),
        );
    }
    let mut i = Vec::new();
    for k in 0..4u32 {
        let (o0, o1, i0, i1) = (k, (k + 1) % 4, k + 4, (k + 1) % 4 + 4);
        i.extend([o0, o1, i1, o0, i1, i0]);
    }
    (p, i)
}

/// A glTF of one mesh per `primitives` entry, `nodes` as (mesh, scale); buffers in a data URI.
fn scene_json(meshes: &[Vec<Primitive>], nodes: &[(usize, f32)]) -> serde_json::Value {
    use base64::Engine as _;
    let (mut bin, mut views, mut accessors, mut json_meshes) = (Vec::new(), vec![], vec![], vec![]);
    for prims in meshes {
        let mut primitives = vec![];
        for (p, i) in prims {
            let at = bin.len();
            p.iter().flatten().for_each(|c| bin.extend(c.to_le_bytes()));
            let lo: Vec<f32> = (0..3)
                .map(|c| p.iter().map(|v| v[c]).fold(f32::MAX, f32::min))
                .collect();
            let hi: Vec<f32> = (0..3)
                .map(|c| p.iter().map(|v| v[c]).fold(f32::MIN, f32::max))
                .collect();
            views.push(
                serde_json::json!({"buffer": 0, "byteOffset": at, "byteLength": p.len() * 12}),
            );
            accessors.push(
                serde_json::json!({"bufferView": views.len() - 1, "componentType": 5126,
                "count": p.len(), "type": "VEC3", "min": lo, "max": hi}),
            );
            let at = bin.len();
            i.iter().for_each(|v| bin.extend(v.to_le_bytes()));
            views.push(
                serde_json::json!({"buffer": 0, "byteOffset": at, "byteLength": i.len() * 4}),
            );
            accessors.push(
                serde_json::json!({"bufferView": views.len() - 1, "componentType": 5125,
                "count": i.len(), "type": "SCALAR"}),
            );
            primitives.push(
                serde_json::json!({"attributes": {"POSITION": accessors.len() - 2},
                "indices": accessors.len() - 1}),
            );
        }
        json_meshes.push(serde_json::json!({"primitives": primitives}));
    }
    let json_nodes: Vec<serde_json::Value> = nodes
        .iter()
        .map(|(m, s)| serde_json::json!({"mesh": m, "scale": [s, s, 1.0]}))
        .collect();
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    serde_json::json!({"asset": {"version": "2.0"}, "scene": 0,
        "scenes": [{"nodes": (0..nodes.len()).collect::<Vec<_>>()}], "nodes": json_nodes,
        "meshes": json_meshes, "bufferViews": views, "accessors": accessors,
        "buffers": [{"byteLength": bin.len(), "uri": uri}]})
}

/// 40 nested frames, two instances each, scaled by 1.3^k: obvhs's PLOC builds a 40-level top-level tree over
/// such boxes, past the 32-entry WGSL stack, which lost whole subtrees of instances without a word.
/// The top level is now balanced there; the image equals that of one mesh holding all frames (no top-level
/// tree to speak of), pixel for pixel up to edge rounding.
#[test]
fn degenerate_instance_placements_lose_no_instance() {
    let (ctx, _gpu) = gpu();
    // Two instances per scale: PLOC pairs them, then chains the pairs, so every level of the chain has two
    // inner children a ray through the frames enters both of, and each pushes a stack entry.
    let scales: Vec<f32> = (0..80).map(|k| 1.3f32.powi(k / 2)).collect();
    let instanced = scene_json(
        &[vec![frame(1.0)]],
        &scales.iter().map(|&s| (0, s)).collect::<Vec<_>>(),
    );
    let merged = scene_json(&[scales.iter().map(|&s| frame(s)).collect()], &[(0, 1.0)]);
    let visibility = |doc: &serde_json::Value, name: &str| {
        let file = std::env::temp_dir().join(format!("raykin-{name}-{}.gltf", std::process::id()));
        std::fs::write(&file, serde_json::to_vec(doc).unwrap()).unwrap();
        let scene = Arc::new(load_gltf(&file, &LoadOptions::default()).unwrap());
        let settings = RenderSettings {
            width: 96,
            height: 96,
            max_depth: 0,
            environment: Environment::Constant([1.0; 3]),
            ..Default::default()
        };
        // Depth 0: a pixel is black where the camera ray hits a frame and 1 where it misses.
        let img = render(&ctx, &scene, settings, &CameraChoice::Auto, 1);
        img.iter().map(|p| p[0] < 0.5).collect::<Vec<bool>>()
    };
    let (a, b) = (
        visibility(&instanced, "instanced"),
        visibility(&merged, "merged"),
    );
    let hits = b.iter().filter(|h| **h).count();
    let differing = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    assert!(hits > 1000, "the frames cover the image: {hits} hits");
    assert!(
        differing * 100 <= a.len(),
        "{differing} of {} pixels differ",
        a.len()
    );
}

/// File > Save as embeds the scene's buffers and images in a GLB: it reads only what the load was allowed
/// to read, so a texture URI naming a file outside the scene's folder never ends up inside the saved file.
#[test]
fn save_as_embeds_no_file_the_load_could_not_read() {
    let file = corpus().join("image_absolute_path.gltf");
    let (scene, _) = warnings_of("image_absolute_path.gltf", &["absolute path"]);
    let out = std::env::temp_dir().join(format!("raykin-save-{}.glb", std::process::id()));
    let err = raykin::scene::save_with_materials(
        &std::fs::read(&file).unwrap(),
        file.parent().unwrap(),
        "image_absolute_path.gltf",
        LoadOptions::default().access(),
        &scene.materials,
        &out,
    )
    .unwrap_err();
    assert!(err.to_string().contains("absolute path"), "{err}");
    assert!(!out.exists());
}

/// Save as .gltf into another folder copies the buffer beside the output (so the saved scene loads under the
/// confined reads) and never replaces a file already there.
#[test]
fn save_as_gltf_copies_outside_files_without_replacing_any() {
    let source = shared_assets().join("Box/glTF/Box.gltf");
    let scene = load_gltf(&source, &LoadOptions::default()).unwrap();
    let dir = std::env::temp_dir().join(format!("raykin-save-copy-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let unrelated = b"someone else's Box0.bin".to_vec();
    std::fs::write(dir.join("Box0.bin"), &unrelated).unwrap();
    let out = dir.join("edited.gltf");
    raykin::scene::save_with_materials(
        &std::fs::read(&source).unwrap(),
        source.parent().unwrap(),
        "Box.gltf",
        LoadOptions::default().access(),
        &scene.materials,
        &out,
    )
    .unwrap();
    assert_eq!(std::fs::read(dir.join("Box0.bin")).unwrap(), unrelated);
    let saved = load_gltf(&out, &LoadOptions::default()).expect("the saved scene loads confined");
    assert_eq!(saved.triangle_count(), scene.triangle_count());
    let names: Vec<String> = saved
        .files
        .iter()
        .map(|f| f.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names,
        ["edited.gltf", "Box0-1.bin"],
        "the scene file, then what it read"
    );
}

/// Readbacks keep their staging buffer for the next one: each still returns exactly its own bytes, whether the
/// kept buffer is larger (a stale tail must not show), smaller (it is replaced) or read in place.
#[test]
fn readbacks_reuse_their_staging_buffer_without_stale_bytes() {
    let (ctx, _lock) = gpu();
    let big: Vec<u8> = (0..4096u32).map(|i| (i * 7 + 3) as u8).collect();
    let small: Vec<u8> = (0..256u32).map(|i| (i * 13 + 1) as u8).collect();
    let big_buffer = raykin::gpu::bind::storage_with(&ctx, "big", &big);
    let small_buffer = raykin::gpu::bind::storage_with(&ctx, "small", &small);
    assert_eq!(ctx.read_buffer(&small_buffer, 256), small);
    assert_eq!(ctx.read_buffer(&big_buffer, 4096), big);
    assert_eq!(ctx.read_buffer(&small_buffer, 256), small);
    assert_eq!(
        ctx.read_buffer_range(&big_buffer, 1024, 512),
        big[1024..1536]
    );
    let both = ctx.read_buffers_with(&[&small_buffer, &big_buffer], |bytes| bytes.to_vec());
    assert_eq!(both.len(), 256 + 4096);
    assert_eq!(both[..256], small);
    assert_eq!(both[256..], big);
    assert_eq!(ctx.read_buffer(&small_buffer, 256), small);
}

/// Far from the origin a float's spacing grows (2^-10 at 1e4), and so do the offsets that keep rays off their
/// surfaces: a scene there must still render the image it renders at the origin. The grazing-light bench scene
/// (contact shadows, light at 1-5 degrees, smooth spheres' terminators) around (1e4, 1e4, -1e4) and around 0,
/// with the same samples: their relative squared difference must be a small fraction of one render's noise (two
/// seeds apart). Measured on lavapipe, 96x54 at 4096 spp: 3e-5-7e-5 against 1.2e-3.
#[test]
fn a_scene_far_from_the_origin_renders_as_at_the_origin() {
    let (ctx, _gpu) = gpu();
    let render_around = |o: glam::Vec3, seed: u32| {
        let camera = CameraChoice::LookAt {
            eye: o + glam::Vec3::new(300.0, 250.0, 450.0),
            target: o + glam::Vec3::new(-20.0, 20.0, -40.0),
            yfov: 40f32.to_radians(),
        };
        let settings = RenderSettings {
            width: 64,
            height: 36,
            max_depth: 6,
            environment: Environment::Constant([0.03; 3]),
            seed,
            ..Default::default()
        };
        let scene = Arc::new(raykin::scene::procedural::grazing_light_at(o));
        render(&ctx, &scene, settings, &camera, 1024)
    };
    let far = raykin::scene::procedural::GRAZING_LIGHT_ORIGIN;
    let (near_a, near_b, far_a) = (
        render_around(glam::Vec3::ZERO, 1),
        render_around(glam::Vec3::ZERO, 2),
        render_around(far, 1),
    );
    assert_all_finite(&far_a, "the scene at 1e4");
    let noise = rel_mse(&near_a, &near_b, 1e-2);
    let apart = rel_mse(&far_a, &near_a, 1e-2);
    eprintln!("at 1e4 against at 0: relMSE {apart:.2e}; two seeds at 0: {noise:.2e}");
    assert!(noise > 0.0, "two seeds rendered the same image");
    assert!(
        apart < 0.2 * noise,
        "the scene at 1e4 differs from the scene at 0 by relMSE {apart:.2e}, {:.2}x one render's noise",
        apart / noise
    );
}
